//! Bilinear sampling of RGB textures, shared by the generators.

use ocellus_image::Plane;

/// Bilinear sample of `t` at (x, y) in pixel coordinates (pixel centres at integers); along
/// each axis the texture wraps around (`wrap_x`, `wrap_y`) or is clamped at its border.
pub fn sample(t: &Plane<[f32; 3]>, x: f64, y: f64, wrap_x: bool, wrap_y: bool) -> [f32; 3] {
    let (w, h) = (t.width() as i64, t.height() as i64);
    let (fx, fy) = (x.floor(), y.floor());
    let (ax, ay) = ((x - fx) as f32, (y - fy) as f32);
    let idx = |i: i64, n: i64, wrap: bool| if wrap { i.rem_euclid(n) as usize } else { i.clamp(0, n - 1) as usize };
    let (x0, y0) = (fx as i64, fy as i64);
    let (c0, c1) = (idx(x0, w, wrap_x), idx(x0 + 1, w, wrap_x));
    let (r0, r1) = (idx(y0, h, wrap_y), idx(y0 + 1, h, wrap_y));
    let (a, b, c, d) = (t.get(c0, r0), t.get(c1, r0), t.get(c0, r1), t.get(c1, r1));
    std::array::from_fn(|k| {
        let top = a[k] + ax * (b[k] - a[k]);
        let bot = c[k] + ax * (d[k] - c[k]);
        top + ay * (bot - top)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_wraps_and_clamps() {
        let t = Plane::from_fn(4, 2, |x, y| [x as f32, y as f32, 0.0]);
        assert_eq!(sample(&t, 1.5, 0.5, false, false), [1.5, 0.5, 0.0]);
        assert_eq!(sample(&t, 3.5, 0.0, true, false), [1.5, 0.0, 0.0], "wraps to column 0");
        assert_eq!(sample(&t, 3.5, 0.0, false, false), [3.0, 0.0, 0.0], "clamps");
        assert_eq!(sample(&t, 0.0, 1.5, false, true), [0.0, 0.5, 0.0]);
    }
}
