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
    let s = if mx > 0.0 { 1.0 / mx } else { 0.0 };
    Plane::from_fn(img.width(), img.height(), |x, y| {
        let p = img.get(x, y);
        let grey = (0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32) * 0.6;
        let t = map.get(x, y) * s;
        let c = heat_color(t);
        let a = 0.25 + 0.6 * t;
        [0, 1, 2].map(|k| (grey * (1.0 - a) + c[k] as f32 * a).round().clamp(0.0, 255.0) as u8)
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
