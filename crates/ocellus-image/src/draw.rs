//! Drawing on 8-bit RGB images for figures: rings, line segments, dots, panels. Coordinates
//! are pixels with integer centres (the crate's convention); whatever falls outside the
//! image is clipped.

use crate::Plane;

/// Sets pixel (x, y) when it lies inside `img`.
fn put(img: &mut Plane<[u8; 3]>, x: i64, y: i64, color: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as usize) < img.width() && (y as usize) < img.height() {
        img.set(x as usize, y as usize, color);
    }
}

/// A ring of radius `r` pixels (2 px thick) centred at (cx, cy).
pub fn ring(img: &mut Plane<[u8; 3]>, cx: f32, cy: f32, r: f32, color: [u8; 3]) {
    if !(cx.is_finite() && cy.is_finite() && r.is_finite()) {
        return;
    }
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (x0, x1) = (((cx - r - 2.0).floor() as i64).max(0), ((cx + r + 2.0).ceil() as i64).min(w - 1));
    let (y0, y1) = (((cy - r - 2.0).floor() as i64).max(0), ((cy + r + 2.0).ceil() as i64).min(h - 1));
    for y in y0..=y1 {
        for x in x0..=x1 {
            let d = ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
            if (d - r).abs() <= 1.0 {
                put(img, x, y, color);
            }
        }
    }
}

/// A one-pixel line segment from `a` to `b` (pixels), sampled finely enough to leave no gap.
pub fn line(img: &mut Plane<[u8; 3]>, a: [f64; 2], b: [f64; 2], color: [u8; 3]) {
    if !a.iter().chain(&b).all(|v| v.is_finite()) {
        return;
    }
    let n = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).clamp(1, 100_000);
    for s in 0..=n {
        let t = s as f64 / n as f64;
        put(img, (a[0] + t * (b[0] - a[0])).round() as i64, (a[1] + t * (b[1] - a[1])).round() as i64, color);
    }
}

/// A plus-shaped dot (5 pixels) at `p`.
pub fn dot(img: &mut Plane<[u8; 3]>, p: [f64; 2], color: [u8; 3]) {
    if !(p[0].is_finite() && p[1].is_finite()) {
        return;
    }
    let (x, y) = (p[0].round() as i64, p[1].round() as i64);
    for (dx, dy) in [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)] {
        put(img, x + dx, y + dy, color);
    }
}

/// Four panels in a 2x2 grid (top-left, top-right, bottom-left, bottom-right), each cell the
/// size of the first panel (smaller panels are padded with black, larger ones cut).
pub fn grid2x2(panels: [&Plane<[u8; 3]>; 4]) -> Plane<[u8; 3]> {
    let (w, h) = panels[0].size();
    let mut out = Plane::new(2 * w, 2 * h);
    for (i, p) in panels.iter().enumerate() {
        let (ox, oy) = ((i % 2) * w, (i / 2) * h);
        let n = p.width().min(w);
        for y in 0..p.height().min(h) {
            out.row_mut(oy + y)[ox..ox + n].copy_from_slice(&p.row(y)[..n]);
        }
    }
    out
}

/// `img` reduced by 2 in each direction (2x2 box average; odd last row/column dropped).
/// Pixel (x, y) of the result covers pixels 2x..=2x+1, 2y..=2y+1, so a point p of `img` is at
/// (p - 0.5) / 2 in it.
pub fn half_size(img: &Plane<[u8; 3]>) -> Plane<[u8; 3]> {
    let (w, h) = (img.width() / 2, img.height() / 2);
    if w == 0 || h == 0 {
        // A 1-pixel-wide or -high image: its first pixel(s), clamped as the 2x2 rule reads them.
        return Plane::from_fn(w.max(1), h.max(1), |x, y| {
            let (x0, y0) = ((2 * x).min(img.width() - 1), (2 * y).min(img.height() - 1));
            let (x1, y1) = ((x0 + 1).min(img.width() - 1), (y0 + 1).min(img.height() - 1));
            let p = [img.get(x0, y0), img.get(x1, y0), img.get(x0, y1), img.get(x1, y1)];
            [0, 1, 2].map(|k| ((p.iter().map(|q| q[k] as u32).sum::<u32>() + 2) / 4) as u8)
        });
    }
    let mut out = Plane::new(w, h);
    for y in 0..h {
        // Row pairs as flat bytes: the loop is plain arithmetic on slices.
        let (a, b) = (img.row(2 * y).as_flattened(), img.row(2 * y + 1).as_flattened());
        let o = out.row_mut(y).as_flattened_mut();
        for (x, o) in o.chunks_exact_mut(3).enumerate() {
            let (pa, pb) = (&a[6 * x..6 * x + 6], &b[6 * x..6 * x + 6]);
            for k in 0..3 {
                let sum = pa[k] as u32 + pa[k + 3] as u32 + pb[k] as u32 + pb[k + 3] as u32;
                o[k] = ((sum + 2) / 4) as u8;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_size_is_the_rounded_mean_of_each_2x2_block() {
        for (w, h) in [(7, 5), (1, 4), (6, 1), (1, 1), (8, 6)] {
            let img = Plane::from_fn(w, h, |x, y| [(x * 37 + y * 11) as u8, (x * y * 5) as u8, 255 - (x + y) as u8]);
            let half = half_size(&img);
            assert_eq!(half.size(), ((w / 2).max(1), (h / 2).max(1)));
            for y in 0..half.height() {
                for x in 0..half.width() {
                    let at = |dx: usize, dy: usize| img.get((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                    let want = [0, 1, 2].map(|k| {
                        let s: u32 = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)].iter().map(|p| p[k] as u32).sum();
                        (s as f64 / 4.0).round() as u8
                    });
                    assert_eq!(half.get(x, y), want, "{w}x{h} at ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn the_grid_places_each_panel_in_its_quarter() {
        let a = Plane::from_fn(3, 2, |x, y| [x as u8, y as u8, 1]);
        let small = Plane::from_fn(2, 1, |_, _| [9u8; 3]);
        let big = Plane::from_fn(5, 5, |_, _| [7u8; 3]);
        let g = grid2x2([&a, &small, &big, &a]);
        assert_eq!(g.size(), (6, 4));
        assert_eq!((g.get(2, 1), g.get(5, 3)), ([2, 1, 1], [2, 1, 1]));
        assert_eq!((g.get(3, 0), g.get(5, 0), g.get(3, 1)), ([9; 3], [0; 3], [0; 3]));
        assert_eq!((g.get(0, 2), g.get(2, 3)), ([7; 3], [7; 3]));
    }

    #[test]
    fn shapes_land_where_asked_and_clip() {
        let mut img = Plane::new(20, 10);
        line(&mut img, [2.0, 3.0], [12.0, 3.0], [1, 2, 3]);
        assert!((2..=12).all(|x| img.get(x, 3) == [1, 2, 3]) && img.get(13, 3) == [0, 0, 0]);
        dot(&mut img, [0.0, 0.0], [9, 9, 9]);
        assert_eq!((img.get(0, 0), img.get(1, 0), img.get(0, 1)), ([9; 3], [9; 3], [9; 3]));
        ring(&mut img, 10.0, 5.0, 4.0, [7; 3]);
        assert_eq!((img.get(14, 5), img.get(10, 5)), ([7; 3], [0; 3]));
        line(&mut img, [-50.0, -50.0], [f64::NAN, 0.0], [5; 3]);
        ring(&mut img, 1e30, 0.0, 1.0, [5; 3]);
        let g = grid2x2([&img, &img, &img, &img]);
        assert_eq!((g.size(), g.get(22, 13)), ((40, 20), img.get(2, 3)));
        let half = half_size(&Plane::from_fn(4, 2, |x, _| [if x < 2 { 10 } else { 20 }; 3]));
        assert_eq!((half.size(), half.get(0, 0), half.get(1, 0)), ((2, 1), [10; 3], [20; 3]));
    }
}
