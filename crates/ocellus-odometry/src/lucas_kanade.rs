//! Lucas-Kanade refinement of one window's flow (Lucas & Kanade 1981) on pre-smoothed frames.
//!
//! Why the frames are smoothed first: Lucas-Kanade compares the block of frame n-1 at integer
//! pixels with frame n resampled bilinearly at a fractional offset, and bilinear resampling
//! low-passes the texture by an amount that depends on that fraction (nothing at 0, most at
//! one half). On texture with energy near the pixel scale (fine grain, a floor seen through
//! area-integrating pixels) the mismatch pulls every flow toward whole pixels. The pull is
//! systematic, so a fit over 400 windows does not average it away: on the generated
//! fine-grained and repetitive floors the rotation came out 0.7 % short, a heading error of
//! 0.11-0.13 degrees after 200 frames, and grass drifted 0.058 %. A Gaussian of sigma
//! [`DEFAULT_SMOOTH_SIGMA_PX`] on both frames leaves little energy where bilinear
//! interpolation is wrong. The frames are smoothed in f32, not rounded back to 8 bits: a
//! low-contrast floor has gradients below one grey level per pixel, which rounding would erase.
//!
//! The square the flow is refined over (`support`) may be larger than the block the integer
//! search matched: on a floor with little texture, the flow's noise falls with the number of
//! pixels summed.

use crate::{OdometryError, Result};
use ocellus_image::{Backend, Plane};

/// Default sigma of the smoothing before Lucas-Kanade, pixels.
pub const DEFAULT_SMOOTH_SIGMA_PX: f32 = 1.5;

/// `frame` in f32 grey levels, smoothed by a Gaussian of `sigma_px` (0: converted only).
pub fn smooth(frame: &Plane<u8>, sigma_px: f32) -> Result<Plane<f32>> {
    let f = frame.map(f32::from);
    if sigma_px == 0.0 {
        return Ok(f);
    }
    ocellus_image::filter::gaussian_blur(Backend::Auto, &f, sigma_px)
        .map_err(|e| OdometryError::Invalid(format!("smoothing sigma {sigma_px}: {e}")))
}

/// Bilinear sample with clamping.
fn at(img: &Plane<f32>, x: f64, y: f64) -> f32 {
    let (w, h) = (img.width() as f64, img.height() as f64);
    let (x, y) = (x.clamp(0.0, w - 1.0), y.clamp(0.0, h - 1.0));
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(img.width() - 1), (y0 + 1).min(img.height() - 1));
    let (ax, ay) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
    let top = img.get(x0, y0) + ax * (img.get(x1, y0) - img.get(x0, y0));
    let bot = img.get(x0, y1) + ax * (img.get(x1, y1) - img.get(x0, y1));
    top + ay * (bot - top)
}

/// `x.floor()` without the library call that baseline x86-64 (no SSE4.1 `roundsd`) makes for
/// it; exact for |x| < 2^52, which covers every pixel coordinate.
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// The Lucas-Kanade normal equations of the `b` x `b` square with top-left pixel (bx, by)
/// (integers) of `prev`: `[sum gx^2, sum gx gy, sum gy^2, sum gx e, sum gy e, sum e^2]` with the
/// gradients g and differences e of `cur` (times `gain`) warped by (dx, dy) against `prev`.
/// The warp has one fractional part for the whole square, so `cur` is resampled once into a
/// patch with a one-pixel border (`patch`, reused between calls) and the gradients are central
/// differences there.
#[allow(clippy::too_many_arguments)]
pub(crate) fn lk_sums(
    prev: &Plane<f32>,
    cur: &Plane<f32>,
    bx: usize,
    by: usize,
    b: usize,
    dx: f64,
    dy: f64,
    gain: f64,
    patch: &mut Vec<f32>,
) -> [f64; 6] {
    let n = b + 2;
    let (sx, sy) = (bx as f64 - 1.0 + dx, by as f64 - 1.0 + dy);
    let (fx, fy) = (floor(sx), floor(sy));
    let (ax, ay) = ((sx - fx) as f32, (sy - fy) as f32);
    patch.clear();
    let inside = fx >= 0.0 && fy >= 0.0 && fx as usize + n < cur.width() && fy as usize + n < cur.height();
    if inside {
        let (ix, iy) = (fx as usize, fy as usize);
        // Along x, then y (the order of `at`), without scratch rows.
        let lerp = |r: &[f32], i: usize| r[i] + ax * (r[i + 1] - r[i]);
        for j in 0..n {
            let (r0, r1) = (&cur.row(iy + j)[ix..ix + n + 1], &cur.row(iy + j + 1)[ix..ix + n + 1]);
            patch.extend((0..n).map(|i| {
                let (t, d) = (lerp(r0, i), lerp(r1, i));
                t + ay * (d - t)
            }));
        }
    } else {
        for j in 0..n {
            for i in 0..n {
                patch.push(at(cur, sx + i as f64, sy + j as f64));
            }
        }
    }
    let g = gain as f32;
    let mut s = [0.0f64; 6];
    for j in 1..=b {
        let prow = prev.row((by + j - 1).min(prev.height() - 1));
        let x0 = bx.min(prev.width() - b);
        let prow = &prow[x0..x0 + b];
        let (up, mid, down) =
            (&patch[(j - 1) * n..j * n], &patch[j * n..(j + 1) * n], &patch[(j + 1) * n..(j + 2) * n]);
        // One row's sums in f32 (at most a few dozen terms of grey-level size), accumulated
        // in f64.
        let mut r = [0.0f32; 6];
        for i in 1..=b {
            let gx = 0.5 * g * (mid[i + 1] - mid[i - 1]);
            let gy = 0.5 * g * (down[i] - up[i]);
            let e = g * mid[i] - prow[i - 1];
            r[0] += gx * gx;
            r[1] += gx * gy;
            r[2] += gy * gy;
            r[3] += gx * e;
            r[4] += gy * e;
            r[5] += e * e;
        }
        for k in 0..6 {
            s[k] += r[k] as f64;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sums_are_the_definition() {
        // A smooth pattern; the sums at a fractional warp against a direct evaluation with
        // the clamped bilinear sampler.
        let img = Plane::from_fn(64, 48, |x, y| 100.0 + 30.0 * ((x as f32) * 0.3).sin() * ((y as f32) * 0.2).cos());
        let cur = Plane::from_fn(64, 48, |x, y| {
            100.0 + 30.0 * ((x as f32 - 0.4) * 0.3).sin() * ((y as f32 + 0.3) * 0.2).cos()
        });
        let mut patch = Vec::new();
        for (bx, by, b, dx, dy) in [(20, 15, 8, 0.4, -0.3), (10, 10, 16, 0.25, 0.0), (0, 0, 8, -1.5, 0.7)] {
            let got = lk_sums(&img, &cur, bx, by, b, dx, dy, 1.1, &mut patch);
            let mut want = [0.0f64; 6];
            for j in 0..b {
                for i in 0..b {
                    let (x, y) = ((bx + i) as f64 + dx, (by + j) as f64 + dy);
                    let c = |x: f64, y: f64| 1.1 * at(&cur, x, y) as f64;
                    let gx = 0.5 * (c(x + 1.0, y) - c(x - 1.0, y));
                    let gy = 0.5 * (c(x, y + 1.0) - c(x, y - 1.0));
                    let e = c(x, y) - img.get(bx + i, by + j) as f64;
                    for (k, v) in [gx * gx, gx * gy, gy * gy, gx * e, gy * e, e * e].into_iter().enumerate() {
                        want[k] += v;
                    }
                }
            }
            for k in 0..6 {
                assert!(
                    (got[k] - want[k]).abs() <= 1e-3 * want[k].abs().max(1.0),
                    "{bx} {by} {b}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn smoothing_keeps_the_mean_and_zero_is_a_copy() {
        let f = Plane::from_fn(40, 30, |x, y| ((x * 7 + y * 13) % 256) as u8);
        let s0 = smooth(&f, 0.0).unwrap();
        assert_eq!(s0.get(5, 7), f.get(5, 7) as f32);
        let s = smooth(&f, 1.0).unwrap();
        let mean = |p: &Plane<f32>| p.rows().flatten().sum::<f32>() / (40.0 * 30.0);
        assert!((mean(&s) - mean(&s0)).abs() < 1.0);
        assert!(smooth(&f, f32::NAN).is_err());
    }
}
