//! Pictures of a learned retina: receptive fields, their layout, motor fields, predictors.
//! Each returns an 8-bit RGB plane; the caller writes it (the binary writes PNGs).

use crate::disc::Disc;
use crate::layout::Layout;
use crate::{Real, Result, RetinaError};
use ocellus_image::colormap::heat_color;
use ocellus_image::draw::{dot, line};
use ocellus_image::Plane;

const BACKGROUND: [u8; 3] = [40, 40, 40];

/// Tiles in a near-square grid with a 2-pixel gap; `tile(i, x, y)` colours pixel (x, y) of
/// tile i (`w` x `h`).
fn tiles(count: usize, w: usize, h: usize, tile: impl Fn(usize, usize, usize) -> [u8; 3]) -> Plane<[u8; 3]> {
    let cols = (count as f64).sqrt().ceil().max(1.0) as usize;
    let rows = count.div_ceil(cols).max(1);
    let gap = 2;
    Plane::from_fn(cols * (w + gap) + gap, rows * (h + gap) + gap, |x, y| {
        let (cx, cy) = ((x.saturating_sub(gap)) / (w + gap), (y.saturating_sub(gap)) / (h + gap));
        let (lx, ly) = (x.saturating_sub(gap) % (w + gap), y.saturating_sub(gap) % (h + gap));
        let i = cy * cols + cx;
        if x < gap || y < gap || lx >= w || ly >= h || i >= count {
            [255, 255, 255]
        } else {
            tile(i, lx, ly)
        }
    })
}

/// The disc's pixel index at each square position (`None` outside the disc).
fn disc_index(disc: &Disc) -> (usize, Vec<Option<usize>>) {
    let h = disc.half_width();
    let side = 2 * h + 1;
    let mut idx = vec![None; side * side];
    for (j, &[x, y]) in disc.offsets().iter().enumerate() {
        idx[(y + h as i32) as usize * side + (x + h as i32) as usize] = Some(j);
    }
    (side, idx)
}

/// A black disc on a grey square, each pixel magnified `scale` times, and the map from a
/// pixel offset (x right, y down from the gaze point) to the canvas.
fn disc_canvas(disc: &Disc, scale: usize) -> (Plane<[u8; 3]>, impl Fn([f64; 2]) -> [f64; 2]) {
    let (side, idx) = disc_index(disc);
    let scale = scale.max(1);
    let img = Plane::from_fn(side * scale, side * scale, |x, y| {
        if idx[(y / scale) * side + x / scale].is_some() {
            [0, 0, 0]
        } else {
            BACKGROUND
        }
    });
    let (h, s) = (disc.half_width() as f64, scale as f64);
    (img, move |v: [f64; 2]| [(v[0] + h) * s + 0.5 * (s - 1.0), (v[1] + h) * s + 0.5 * (s - 1.0)])
}

fn check_s<T>(disc: &Disc, s: &[T], fields: usize) -> Result<()> {
    if fields == 0 || s.len() != fields * disc.len() {
        return Err(RetinaError::Invalid(format!(
            "S has {} entries, not {fields} fields x {} pixels",
            s.len(),
            disc.len()
        )));
    }
    Ok(())
}

/// Every receptive field as its weight image on the disc (heat colours, each field scaled to
/// its own maximum), magnified `scale` times, in a grid.
pub fn receptive_fields<T: Real>(disc: &Disc, s: &[T], fields: usize, scale: usize) -> Result<Plane<[u8; 3]>> {
    check_s(disc, s, fields)?;
    let n = disc.len();
    let (side, idx) = disc_index(disc);
    let scale = scale.max(1);
    let peaks: Vec<f64> =
        (0..fields).map(|i| s[i * n..(i + 1) * n].iter().map(|v| v.to_f64()).fold(0.0, f64::max)).collect();
    Ok(tiles(fields, side * scale, side * scale, |i, x, y| match idx[(y / scale) * side + x / scale] {
        Some(j) if peaks[i] > 0.0 => heat_color((s[i * n + j].to_f64() / peaks[i]) as f32),
        Some(_) => heat_color(0.0),
        None => BACKGROUND,
    }))
}

/// A distinct colour for field `i` of `n` (hues around the circle, full saturation).
fn hue(i: usize, n: usize) -> [u8; 3] {
    let h = 6.0 * ((i as f64 * 0.618_034) % 1.0);
    let _ = n;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    let (r, g, b) = match h as usize {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    [(r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8]
}

/// All fields on one disc: the outline of each field's half-maximum region in its own colour
/// and its centre as a dot, magnified `scale` times; the disc's rim in grey.
pub fn layout_contours<T: Real>(disc: &Disc, s: &[T], layout: &Layout, scale: usize) -> Result<Plane<[u8; 3]>> {
    let fields = if disc.is_empty() { 0 } else { s.len() / disc.len() };
    check_s(disc, s, fields)?;
    let n = disc.len();
    let (side, idx) = disc_index(disc);
    let scale = scale.max(1);
    let (mut img, at) = disc_canvas(disc, scale);
    let inside = |i: usize, peak: f64, x: i64, y: i64| -> bool {
        if x < 0 || y < 0 || x >= side as i64 || y >= side as i64 {
            return false;
        }
        idx[y as usize * side + x as usize].is_some_and(|j| s[i * n + j].to_f64() >= 0.5 * peak)
    };
    for f in &layout.fields {
        let c = hue(f.index, fields);
        for y in 0..side as i64 {
            for x in 0..side as i64 {
                if !inside(f.index, f.peak, x, y) {
                    continue;
                }
                // Magnified pixel edges that border the outside of the region.
                let (px, py) = (x as usize * scale, y as usize * scale);
                let last = scale - 1;
                for k in 0..scale {
                    if !inside(f.index, f.peak, x - 1, y) {
                        img.set(px, py + k, c);
                    }
                    if !inside(f.index, f.peak, x + 1, y) {
                        img.set(px + last, py + k, c);
                    }
                    if !inside(f.index, f.peak, x, y - 1) {
                        img.set(px + k, py, c);
                    }
                    if !inside(f.index, f.peak, x, y + 1) {
                        img.set(px + k, py + last, c);
                    }
                }
            }
        }
        dot(&mut img, at(f.centre), c);
    }
    Ok(img)
}

/// Every motor field (a row of M over a `cells` x `cells` grid of motor cells, first axis to
/// the right) as a heat map scaled to its maximum, magnified `scale` times.
pub fn motor_fields<T: Real>(m: &[T], fields: usize, cells: usize, scale: usize) -> Result<Plane<[u8; 3]>> {
    if fields == 0 || cells == 0 || m.len() != fields * cells * cells {
        return Err(RetinaError::Invalid(format!("M has {} entries, not {fields} x {cells}^2", m.len())));
    }
    let q = cells * cells;
    let scale = scale.max(1);
    let peaks: Vec<f64> =
        (0..fields).map(|k| m[k * q..(k + 1) * q].iter().map(|v| v.to_f64()).fold(0.0, f64::max)).collect();
    Ok(tiles(fields, cells * scale, cells * scale, |k, x, y| {
        let v = m[k * q + (y / scale) * cells + x / scale].to_f64();
        heat_color(if peaks[k] > 0.0 { (v / peaks[k]) as f32 } else { 0.0 })
    }))
}

/// Predictor matrices (each R x R, row = the field predicted, column = the field it reads)
/// as heat maps scaled to their maxima, magnified `scale` times.
pub fn predictor_matrices<T: Real>(p: &[T], count: usize, fields: usize, scale: usize) -> Result<Plane<[u8; 3]>> {
    let rr = fields * fields;
    if count == 0 || fields == 0 || p.len() != count * rr {
        return Err(RetinaError::Invalid(format!("P has {} entries, not {count} x {fields}^2", p.len())));
    }
    let scale = scale.max(1);
    let peaks: Vec<f64> =
        (0..count).map(|k| p[k * rr..(k + 1) * rr].iter().map(|v| v.to_f64()).fold(0.0, f64::max)).collect();
    Ok(tiles(count, fields * scale, fields * scale, |k, x, y| {
        let v = p[k * rr + (y / scale) * fields + x / scale].to_f64();
        heat_color(if peaks[k] > 0.0 { (v / peaks[k]) as f32 } else { 0.0 })
    }))
}

/// A predictor as a flow on the disc: for each live field i, a line from the weighted mean of
/// the centres of the fields it reads (weights P_ij over the live fields) to its own centre,
/// with a dot at its centre. A zoom-out predictor points inward, a rotation around.
pub fn predictor_flow<T: Real>(
    disc: &Disc,
    layout: &Layout,
    p: &[T],
    fields: usize,
    scale: usize,
) -> Result<Plane<[u8; 3]>> {
    if p.len() != fields * fields {
        return Err(RetinaError::Invalid(format!("a predictor has {} entries, not {fields}^2", p.len())));
    }
    let (mut img, at) = disc_canvas(disc, scale);
    for f in &layout.fields {
        let (mut w, mut sx, mut sy) = (0.0, 0.0, 0.0);
        for g in &layout.fields {
            let v = p[f.index * fields + g.index].to_f64();
            w += v;
            sx += v * g.centre[0];
            sy += v * g.centre[1];
        }
        if w > 0.0 {
            line(&mut img, at([sx / w, sy / w]), at(f.centre), [120, 200, 255]);
        }
        dot(&mut img, at(f.centre), [255, 210, 60]);
    }
    Ok(img)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::measure;

    #[test]
    fn pictures_have_the_tiled_sizes_and_show_the_fields() {
        let disc = Disc::with_pixels(481).unwrap();
        let n = disc.len();
        // Field 0 covers the left half, field 1 a small centre, field 2 is dead.
        let mut s = vec![0.0f64; 3 * n];
        for (j, &[x, y]) in disc.offsets().iter().enumerate() {
            if x < 0 {
                s[j] = 1.0;
            }
            if x * x + y * y <= 4 {
                s[n + j] = 2.0;
            }
        }
        let img = receptive_fields(&disc, &s, 3, 2).unwrap();
        let side = 2 * disc.half_width() + 1;
        assert_eq!(img.size(), (2 * (2 * side + 2) + 2, 2 * (2 * side + 2) + 2));
        // Field 0's tile: hot on the left, cold on the right.
        let left = img.get(2 + 2 * 3, 2 + side);
        let right = img.get(2 + 2 * (side - 4), 2 + side);
        assert_eq!(left, heat_color(1.0));
        assert_eq!(right, heat_color(0.0));
        let layout = measure(&disc, &s, 3).unwrap();
        let c = layout_contours(&disc, &s, &layout, 3).unwrap();
        assert_eq!(c.size(), (3 * side, 3 * side));
        assert!(motor_fields(&[0.5f64; 8], 2, 2, 4).is_ok());
        assert!(motor_fields(&[0.5f64; 7], 2, 2, 4).is_err());
        assert!(predictor_matrices(&[1.0f64; 18], 2, 3, 4).is_ok());
        assert!(predictor_flow(&disc, &layout, &[1.0f64; 9], 3, 3).is_ok());
        assert!(receptive_fields(&disc, &s[..n], 3, 2).is_err());
    }
}
