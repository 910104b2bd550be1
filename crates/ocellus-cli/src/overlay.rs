//! Heat-map rendering of saliency maps for people to look at.

use ocellus_image::Plane;

/// A perceptually ordered colour map (dark blue → cyan → yellow → red), `t` in [0, 1].
pub fn heat_color(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 5] =
        [[0.05, 0.03, 0.25], [0.10, 0.35, 0.80], [0.20, 0.80, 0.75], [0.98, 0.85, 0.20], [0.85, 0.10, 0.05]];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f32;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f32;
    let c = |k: usize| ((STOPS[i][k] + f * (STOPS[i + 1][k] - STOPS[i][k])) * 255.0).round() as u8;
    [c(0), c(1), c(2)]
}

/// Blends the colour-mapped `map` (same size as `img`, scaled by its max) over a dimmed
/// grey version of `img`: where saliency is low the photo shows through.
pub fn overlay(img: &Plane<[u8; 3]>, map: &Plane<f32>) -> Plane<[u8; 3]> {
    let (_, mx) = map.min_max();
    overlay_with_scale(img, map, if mx > 0.0 { 1.0 / mx } else { 0.0 })
}

/// [`overlay`] with the colour-map position `map * s` (clamped to [0, 1]).
fn overlay_with_scale(img: &Plane<[u8; 3]>, map: &Plane<f32>, s: f32) -> Plane<[u8; 3]> {
    Plane::from_fn(img.width(), img.height(), |x, y| {
        let p = img.get(x, y);
        let grey = (0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32) * 0.6;
        let t = (map.get(x, y) * s).clamp(0.0, 1.0);
        let c = heat_color(t);
        let a = 0.25 + 0.6 * t;
        [0, 1, 2].map(|k| (grey * (1.0 - a) + c[k] as f32 * a).round().clamp(0.0, 255.0) as u8)
    })
}

/// `img` reduced by 2 in each direction (2x2 box average; odd last row/column dropped).
pub fn half_size(img: &Plane<[u8; 3]>) -> Plane<[u8; 3]> {
    let (w, h) = (img.width() / 2, img.height() / 2);
    Plane::from_fn(w.max(1), h.max(1), |x, y| {
        let (x0, y0) = ((2 * x).min(img.width() - 1), (2 * y).min(img.height() - 1));
        let (x1, y1) = ((x0 + 1).min(img.width() - 1), (y0 + 1).min(img.height() - 1));
        let p = [img.get(x0, y0), img.get(x1, y0), img.get(x0, y1), img.get(x1, y1)];
        [0, 1, 2].map(|k| ((p.iter().map(|q| q[k] as u32).sum::<u32>() + 2) / 4) as u8)
    })
}

/// Like [`overlay`], with `map` (any size) stretched over `img` and scaled so that `full`
/// (or the map's max if larger) is the top of the colour map.
pub fn overlay_scaled(img: &Plane<[u8; 3]>, map: &Plane<f32>, full: f32) -> anyhow::Result<Plane<[u8; 3]>> {
    use ocellus_image::resample::{resize, ResampleMethod};
    let up = resize(map, img.width(), img.height(), ResampleMethod::Bilinear)?;
    let top = map.min_max().1.max(full);
    Ok(overlay_with_scale(img, &up, if top > 0.0 { 1.0 / top } else { 0.0 }))
}

/// Draws a ring of radius `r` pixels (2 px thick) centred at (cx, cy).
pub fn draw_ring(img: &mut Plane<[u8; 3]>, cx: f32, cy: f32, r: f32, color: [u8; 3]) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (x0, x1) = (((cx - r - 2.0).floor() as i64).max(0), ((cx + r + 2.0).ceil() as i64).min(w - 1));
    let (y0, y1) = (((cy - r - 2.0).floor() as i64).max(0), ((cy + r + 2.0).ceil() as i64).min(h - 1));
    for y in y0..=y1 {
        for x in x0..=x1 {
            let d = ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
            if (d - r).abs() <= 1.0 {
                img.set(x as usize, y as usize, color);
            }
        }
    }
}

/// Four same-size panels in a 2x2 grid (top-left, top-right, bottom-left, bottom-right).
pub fn grid2x2(panels: [&Plane<[u8; 3]>; 4]) -> Plane<[u8; 3]> {
    let (w, h) = panels[0].size();
    Plane::from_fn(2 * w, 2 * h, |x, y| {
        let p = panels[(y / h) * 2 + x / w];
        let (px, py) = (x % w, y % h);
        if px < p.width() && py < p.height() {
            p.get(px, py)
        } else {
            [0, 0, 0]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn colours_are_ordered_and_total() {
        assert_eq!(heat_color(f32::NAN), heat_color(0.0));
        let lum = |c: [u8; 3]| c[0] as u32 + c[1] as u32 + c[2] as u32;
        assert!(lum(heat_color(0.0)) < lum(heat_color(0.75)));
        assert_eq!(heat_color(2.0), heat_color(1.0));
    }
}
