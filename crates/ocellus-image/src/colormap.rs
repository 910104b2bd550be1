//! Colour maps for people to look at: scalar maps (saliency, surprise, disparity) as heat
//! maps, and heat maps blended over the photograph they were computed from.

use crate::convert::luma;
use crate::resample::{resize, ResampleMethod};
use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, Plane, Result};

/// The colour map's stops, evenly spaced over [0, 1], RGB in [0, 1].
const STOPS: [[f32; 3]; 5] =
    [[0.05, 0.03, 0.25], [0.10, 0.35, 0.80], [0.20, 0.80, 0.75], [0.98, 0.85, 0.20], [0.85, 0.10, 0.05]];

/// `v.round()` for `v >= 0` without a libm call (the portable build has no rounding
/// instruction, and overlays round three values per pixel): truncation of `v + 0.5`.
#[inline(always)]
fn round_non_negative(v: f32) -> f32 {
    (v + 0.5) as i32 as f32
}

/// [`round_non_negative`] as the build computes it best: where the CPU has a rounding
/// instruction (the AVX2 builds) `floor(v + 0.5)`, which vectorizes; elsewhere the
/// truncating conversion. The two agree for every `v >= 0` below 2^31.
#[inline(always)]
fn round_up_half<M: Madd>(v: f32) -> f32 {
    if M::AVX2 {
        (v + 0.5).floor()
    } else {
        round_non_negative(v)
    }
}

/// Channel `k` of the colour at `t` already clamped to [0, 1], in [0, 255] before rounding:
/// the first stop plus one clamped ramp per segment. No table index, so loops over pixels
/// vectorize; [`heat_color`] and the overlays share it.
#[inline(always)]
fn heat_channel<M: Madd>(t: f32, k: usize) -> f32 {
    const SEGMENTS: usize = STOPS.len() - 1;
    let u = t * SEGMENTS as f32;
    let mut c = STOPS[0][k] * 255.0;
    for j in 0..SEGMENTS {
        c = M::madd((u - j as f32).clamp(0.0, 1.0), (STOPS[j + 1][k] - STOPS[j][k]) * 255.0, c);
    }
    c
}

/// A perceptually ordered colour map (dark blue → cyan → yellow → red), `t` in [0, 1]
/// (clamped; NaN gives the colour of 0).
pub fn heat_color(t: f32) -> [u8; 3] {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    [0, 1, 2].map(|k| round_non_negative(heat_channel::<crate::simd::Plain>(t, k)) as u8)
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
    overlay_with_scale(Backend::Auto, img, map, if mx > 0.0 { 1.0 / mx } else { 0.0 })
}

/// [`overlay`] with the colour-map position `map * s` (clamped to [0, 1]).
fn overlay_with_scale(backend: Backend, img: &Plane<[u8; 3]>, map: &Plane<f32>, s: f32) -> Plane<[u8; 3]> {
    let mut out = Plane::new(img.width(), img.height());
    let zeros = vec![0.0f32; img.width()];
    for y in 0..img.height() {
        let m = if y < map.height() { map.row(y) } else { &zeros[..] };
        overlay_row(backend, img.row(y), m, s, out.row_mut(y));
    }
    out
}

/// One row of [`overlay_with_scale`]; pixels past the end of `map` blend a map value of 0.
/// The colour map is evaluated as a sum of clamped ramps, one per segment, rather than by
/// looking up the segment, and the arithmetic runs on chunks of planar scratch arrays: no
/// table index, no libm call (see [`round_non_negative`]) and no interleaved bytes in the hot
/// loops, so they vectorize. An overlay video of a 640x480 stream blends three such panels
/// per frame.
#[inline(always)]
fn overlay_row_generic<M: Madd>(img: &[[u8; 3]], map: &[f32], s: f32, out: &mut [[u8; 3]]) {
    const C: usize = 64;
    let n = out.len().min(img.len());
    let mut x0 = 0;
    while x0 < n {
        let len = C.min(n - x0);
        let (mut grey, mut t) = ([0f32; C], [0f32; C]);
        for i in 0..len {
            let p = img[x0 + i].map(f32::from);
            grey[i] = luma(p) * 0.6;
            let v = map.get(x0 + i).copied().unwrap_or(0.0) * s;
            // NaN compares false and becomes 0, as in heat_color.
            t[i] = if v > 0.0 { v.min(1.0) } else { 0.0 };
        }
        let mut planes = [[0f32; C]; 3];
        for (k, plane) in planes.iter_mut().enumerate() {
            for i in 0..C {
                let c = heat_channel::<M>(t[i], k);
                let a = 0.25 + 0.6 * t[i];
                plane[i] = round_up_half::<M>(grey[i] * (1.0 - a) + round_up_half::<M>(c) * a).min(255.0);
            }
        }
        for (i, o) in out[x0..x0 + len].iter_mut().enumerate() {
            *o = [planes[0][i] as u8, planes[1][i] as u8, planes[2][i] as u8];
        }
        x0 += len;
    }
}

dispatch_kernel!(fn overlay_row => overlay_row_generic(img: &[[u8; 3]], map: &[f32], s: f32, out: &mut [[u8; 3]]));

/// Like [`overlay`], with `map` (any size) stretched over `img` (bilinear, cell centres on
/// pixel centres) and scaled so that `full` (or the map's max if larger) is the top of the
/// colour map.
pub fn overlay_scaled(backend: Backend, img: &Plane<[u8; 3]>, map: &Plane<f32>, full: f32) -> Result<Plane<[u8; 3]>> {
    let up = resize(backend, map, img.width(), img.height(), ResampleMethod::Bilinear)?;
    let top = map.min_max().1.max(full);
    Ok(overlay_with_scale(backend, img, &up, if top > 0.0 { 1.0 / top } else { 0.0 }))
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
    fn the_fast_blend_is_the_rounded_float_formula() {
        // Every grey level against a ramp of map values, including a map narrower than the image.
        let img = Plane::from_fn(256, 3, |x, y| [x as u8, (x as u8).wrapping_mul(7), (y * 90) as u8]);
        let map = Plane::from_fn(200, 3, |x, y| x as f32 / 150.0 - 0.1 * y as f32);
        for b in Backend::available() {
            let o = overlay_with_scale(b, &img, &map, 1.0);
            for y in 0..3 {
                for x in 0..256 {
                    let p = img.get(x, y).map(f64::from);
                    let grey = (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) * 0.6;
                    let t = if x < 200 { map.get(x, y) as f64 } else { 0.0 }.clamp(0.0, 1.0);
                    // The colour unrounded, in f64: the blend rounds it (at most 0.5 a off),
                    // then itself.
                    let u = t * 4.0;
                    let i = (u.floor() as usize).min(3);
                    let a = 0.25 + 0.6 * t;
                    for k in 0..3 {
                        let (s0, s1) = (STOPS[i][k] as f64, STOPS[i + 1][k] as f64);
                        let c = (s0 + (u - i as f64) * (s1 - s0)) * 255.0;
                        let want = grey * (1.0 - a) + c * a;
                        let err = (o.get(x, y)[k] as f64 - want).abs();
                        assert!(err <= 0.5 + 0.5 * a + 1e-3, "{b:?} ({x}, {y}) {k}: {err}");
                    }
                }
            }
        }
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
        assert_eq!(
            overlay_with_scale(Backend::Scalar, &img, &Plane::from_fn(8, 8, |_, _| f32::NAN), 1.0).get(0, 0),
            o.get(0, 0)
        );
        assert_eq!((h.get(0, 0), h.get(1, 0)), ([0, 0, 0], heat_color(1.0)));
    }
}
