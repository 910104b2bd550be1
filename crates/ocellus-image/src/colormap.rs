//! Colour maps for people to look at: scalar maps (saliency, surprise, disparity) as heat
//! maps, and heat maps blended over the photograph they were computed from.

use crate::convert::luma;
use crate::resample::{resize, ResampleMethod};
use crate::{Backend, Plane, Result};

/// A perceptually ordered colour map (dark blue → cyan → yellow → red), `t` in [0, 1]
/// (clamped; NaN gives the colour of 0).
pub fn heat_color(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 5] =
        [[0.05, 0.03, 0.25], [0.10, 0.35, 0.80], [0.20, 0.80, 0.75], [0.98, 0.85, 0.20], [0.85, 0.10, 0.05]];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f32;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f32;
    let c = |k: usize| ((STOPS[i][k] + f * (STOPS[i + 1][k] - STOPS[i][k])) * 255.0).round() as u8;
    [c(0), c(1), c(2)]
}

/// `map` as a heat map of `map / max` (values clamped to [0, 1]); non-finite pixels black
/// (invalid disparities, for instance).
pub fn heat_map(map: &Plane<f32>, max: f32) -> Plane<[u8; 3]> {
    let s = if max > 0.0 && max.is_finite() { 1.0 / max } else { 0.0 };
    map.map(|v| if v.is_finite() { heat_color(v * s) } else { [0, 0, 0] })
}

/// Blends the colour-mapped `map` (same size as `img`, scaled by its max) over a dimmed
/// grey version of `img`: where the map is low the photo shows through.
pub fn overlay(img: &Plane<[u8; 3]>, map: &Plane<f32>) -> Plane<[u8; 3]> {
    let (_, mx) = map.min_max();
    overlay_with_scale(img, map, if mx > 0.0 { 1.0 / mx } else { 0.0 })
}

/// [`overlay`] with the colour-map position `map * s` (clamped to [0, 1]).
fn overlay_with_scale(img: &Plane<[u8; 3]>, map: &Plane<f32>, s: f32) -> Plane<[u8; 3]> {
    Plane::from_fn(img.width(), img.height(), |x, y| {
        let grey = luma(img.get(x, y).map(f32::from)) * 0.6;
        let v = if x < map.width() && y < map.height() { map.get(x, y) } else { 0.0 };
        let t = (v * s).clamp(0.0, 1.0);
        let c = heat_color(t);
        let a = 0.25 + 0.6 * t;
        [0, 1, 2].map(|k| (grey * (1.0 - a) + c[k] as f32 * a).round().clamp(0.0, 255.0) as u8)
    })
}

/// Like [`overlay`], with `map` (any size) stretched over `img` (bilinear, cell centres on
/// pixel centres) and scaled so that `full` (or the map's max if larger) is the top of the
/// colour map.
pub fn overlay_scaled(backend: Backend, img: &Plane<[u8; 3]>, map: &Plane<f32>, full: f32) -> Result<Plane<[u8; 3]>> {
    let up = resize(backend, map, img.width(), img.height(), ResampleMethod::Bilinear)?;
    let top = map.min_max().1.max(full);
    Ok(overlay_with_scale(img, &up, if top > 0.0 { 1.0 / top } else { 0.0 }))
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

    #[test]
    fn overlays_show_the_map_where_it_is_high() {
        let img = Plane::from_fn(8, 8, |_, _| [100u8; 3]);
        let map = Plane::from_fn(8, 8, |x, _| if x == 3 { 1.0 } else { 0.0 });
        let o = overlay(&img, &map);
        assert_eq!(o.get(3, 2), {
            let c = heat_color(1.0);
            [0, 1, 2].map(|k| (60.0 * 0.15 + c[k] as f32 * 0.85).round() as u8)
        });
        // Where the map is 0: 75 % of the dimmed grey (0.6 * 100), 25 % of the coldest colour.
        let cold = heat_color(0.0);
        assert_eq!(o.get(0, 0), [0, 1, 2].map(|k| (60.0 * 0.75 + cold[k] as f32 * 0.25).round() as u8));
        let h = heat_map(&Plane::from_fn(2, 1, |x, _| if x == 0 { f32::NAN } else { 2.0 }), 2.0);
        assert_eq!((h.get(0, 0), h.get(1, 0)), ([0, 0, 0], heat_color(1.0)));
    }
}
