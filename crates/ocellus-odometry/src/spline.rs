//! The smoothed frame as a cubic B-spline, what Lucas-Kanade ([`crate::lucas_kanade`]) reads.
//!
//! Lucas-Kanade compares the square of frame n-1 at its pixels with frame n resampled at a
//! fractional offset, and how it resamples decides the flow's bias:
//!
//! - **Bilinear resampling** low-passes the texture by an amount that depends on the fraction
//!   (nothing at 0, most at one half), and shifts its phase by a fraction-dependent error (a
//!   linear interpolator's phase error is `a (1 - a) (1 - 2a) w^3 / 6` at fraction a and
//!   frequency w). On raw frames the first pulled every flow toward whole pixels: the rotation
//!   came out 0.7 % short on the generated fine-grained floor. Smoothing both frames first (a
//!   Gaussian) removed most of that, but what was left, the phase error, pushed flows away
//!   from whole pixels by up to 8-15 thousandths of a pixel. It is systematic: a robot that
//!   drives straight has flows near whole pixels sideways, and every small turn was
//!   over-estimated by 1.7-3 %, a heading error that grows with the path (the largest error
//!   left on the easy real-camera floors; `tests/ground_sequences.rs` checks it).
//! - **The cubic B-spline** (Unser, Aldroubi & Eden 1991; Unser 1999) through the smoothed
//!   frame is exact for its samples and has a phase error about 80 times smaller at w = 0.5
//!   and 18 times at w = 1, where a smoothed frame's texture lives. Its coefficients come from
//!   the 8-bit frame in one separable filter (the Gaussian convolved with the spline's inverse
//!   filter, [`spline_kernel`]), and the smoothed pixels from them by the spline's 3-tap
//!   kernel, so the pixels and the spline between them agree exactly. On the 42 real-camera
//!   runs (with the smoothing at 1 px) it took the summed drift of the easy runs from 0.481
//!   to 0.325 % and of the hard ones from 1.046 to 0.794 %.
//!
//! The frames are smoothed in f32, not rounded back to 8 bits: a low-contrast floor has
//! gradients below one grey level per pixel, which rounding would erase.

use crate::{OdometryError, Result};
use ocellus_image::filter::{gaussian_kernel, sep_filter_u8, Border, FilterScratch};
use ocellus_image::simd::Madd;
use ocellus_image::{Backend, Plane};

/// Default sigma of the smoothing before Lucas-Kanade, pixels. With the spline, 1 px did best
/// on the 42 real-camera runs (summed drift of the easy runs 0.33 %, hard 0.79 %): 1.5 px
/// gave the easy runs 0.21 % but the hard ones 0.91 %, where the noise and motion blur call
/// for more of the texture's own detail; 0.75 px 0.47 and 0.87 %, 2 px 0.25 and 1.05 %.
pub const DEFAULT_SMOOTH_SIGMA_PX: f32 = 1.0;

/// A frame in f32 grey levels smoothed by a Gaussian, over the part of it that Lucas-Kanade reads: a
/// rectangle of the frame plus the kernel's half-width, so that inside the rectangle the values
/// are those of the whole frame smoothed (the filter's border rule only acts where the
/// rectangle meets the frame's edge). Why not the whole frame: the windows cover the central
/// 400x400 of a 640x480 frame, and smoothing the rest was 40 % of a robust step. The buffers
/// are kept, so a stream smooths without allocating.
#[derive(Clone, Debug, Default)]
pub struct SmoothedFrame {
    plane: Plane<f32>,
    /// Cubic B-spline coefficients of `plane` (same origin and size): the spline through them
    /// takes the values of `plane` at the pixels (see [`spline_kernel`]).
    coeffs: Plane<f32>,
    /// One row of the vertical pass of [`spline_at_pixels`].
    row: Vec<f32>,
    origin: (usize, usize),
    frame_size: (usize, usize),
    scratch: FilterScratch,
}

impl SmoothedFrame {
    /// Smooths `rect` = `[x0, y0, x1, y1]` (frame pixels, end exclusive) of `frame` by a
    /// Gaussian of `sigma_px` ([`ocellus_image::filter::gaussian_blur`]'s kernel; below 0.3 px:
    /// not smoothed) and makes the cubic B-spline through the result: its coefficients
    /// ([`Self::coeffs`], by [`spline_kernel`]) and its values at the pixels ([`Self::plane`],
    /// within 0.02 grey levels of the Gaussian alone inside the frame; at the frame's edge the
    /// spline clamps its coefficients rather than the pixels).
    pub fn update(&mut self, backend: Backend, frame: &Plane<u8>, sigma_px: f32, rect: [usize; 4]) -> Result<()> {
        let (w, h) = frame.size();
        let [x0, y0, x1, y1] = rect;
        if !(x0 < x1 && y0 < y1 && x1 <= w && y1 <= h) {
            return Err(OdometryError::Invalid(format!("smoothing rectangle {rect:?} on a {w}x{h} frame")));
        }
        if !(sigma_px.is_finite() && sigma_px >= 0.0) {
            return Err(OdometryError::Invalid(format!("smoothing sigma {sigma_px} must be finite and >= 0")));
        }
        let kernel = spline_kernel(sigma_px);
        // One more pixel than the kernel reaches: the smoothed plane is the coefficients
        // filtered by the spline's 3-tap kernel.
        let reach = kernel.len() / 2 + 1;
        let (cx0, cy0) = (x0.saturating_sub(reach), y0.saturating_sub(reach));
        let (cx1, cy1) = ((x1 + reach).min(w), (y1 + reach).min(h));
        let crop = [cx0, cy0, cx1, cy1];
        sep_filter_u8(backend, frame, crop, &mut self.coeffs, &kernel, &kernel, Border::Clamp, &mut self.scratch)
            .map_err(|e| OdometryError::Invalid(format!("smoothing sigma {sigma_px}: {e}")))?;
        self.plane.resize(self.coeffs.width(), self.coeffs.height());
        self.row.resize(self.coeffs.width(), 0.0);
        spline_at_pixels(backend, &self.coeffs, &mut self.plane, &mut self.row);
        self.origin = (cx0, cy0);
        self.frame_size = (w, h);
        Ok(())
    }

    /// The smoothed pixels; pixel (x, y) here is frame pixel `origin + (x, y)`.
    pub fn plane(&self) -> &Plane<f32> {
        &self.plane
    }

    /// The cubic B-spline coefficients of [`Self::plane`], on the same pixels.
    pub fn coeffs(&self) -> &Plane<f32> {
        &self.coeffs
    }

    /// The frame pixel of this plane's pixel (0, 0).
    pub fn origin(&self) -> (usize, usize) {
        self.origin
    }

    /// The size of the frame it was taken from, pixels.
    pub fn frame_size(&self) -> (usize, usize) {
        self.frame_size
    }
}

ocellus_image::dispatch_kernel!(
    /// The cubic B-spline with coefficients `coeffs` at their pixels, into `out` (the same
    /// size): `(c[k-1] + 4 c[k] + c[k+1]) / 6` down the columns, then along the rows, the
    /// coefficients clamped at the edges. `row` (the width) holds one row of the vertical pass.
    /// A pass of its own, not the general separable filter: three taps in one sweep over the
    /// rows cost a third of what that filter's two passes with padded rows did.
    fn spline_at_pixels => spline_at_pixels_generic(coeffs: &Plane<f32>, out: &mut Plane<f32>, row: &mut [f32])
);

#[inline(always)]
fn spline_at_pixels_generic<M: Madd>(coeffs: &Plane<f32>, out: &mut Plane<f32>, row: &mut [f32]) {
    let (w, h) = coeffs.size();
    if w == 0 || h == 0 || out.size() != (w, h) || row.len() != w {
        return;
    }
    let (edge, centre) = (1.0f32 / 6.0, 4.0f32 / 6.0);
    for y in 0..h {
        let (a, b, c) = (coeffs.row(y.saturating_sub(1)), coeffs.row(y), coeffs.row((y + 1).min(h - 1)));
        for (((o, &a), &b), &c) in row.iter_mut().zip(a).zip(b).zip(c) {
            *o = M::madd(centre, b, edge * (a + c));
        }
        let o = out.row_mut(y);
        o[0] = M::madd(centre, row[0], edge * (row[0] + row[1.min(w - 1)]));
        if w > 1 {
            o[w - 1] = M::madd(centre, row[w - 1], edge * (row[w - 2] + row[w - 1]));
        }
        if w > 2 {
            for (((o, &l), &m), &r) in o[1..w - 1].iter_mut().zip(&row[..w - 2]).zip(&row[1..w - 1]).zip(&row[2..]) {
                *o = M::madd(centre, m, edge * (l + r));
            }
        }
    }
}

/// The kernel that turns 8-bit pixels into the cubic B-spline coefficients of the frame
/// smoothed by a Gaussian of `sigma_px` (none below 0.3 px): the Gaussian convolved with the
/// B-spline's inverse filter, `sqrt(3) z^|k|` with `z = sqrt(3) - 2` (Unser, Aldroubi & Eden
/// 1991), cut where its taps fall below [`SPLINE_KERNEL_CUT`] of the centre one (1e-4
/// unsmoothed) and renormalized to a sum of 1.
pub fn spline_kernel(sigma_px: f32) -> Vec<f32> {
    let base = gaussian_kernel(sigma_px).unwrap_or_else(|| vec![1.0]);
    let hb = base.len() as i64 / 2;
    let z = 3f64.sqrt() - 2.0;
    // The inverse filter's taps beyond 24 are below 1e-13 of its centre.
    let inv = |k: i64| if k.abs() > 24 { 0.0 } else { 3f64.sqrt() * z.powi(k.abs() as i32) };
    let tap = |k: i64| (-hb..=hb).map(|j| f64::from(base[(j + hb) as usize]) * inv(k - j)).sum::<f64>();
    let centre = tap(0);
    // Grown from the Gaussian's reach (not cut inside it, where a tap may pass near zero).
    let mut r = hb;
    // Unsmoothed (sigma below 0.3 px), the spline must pass through the pixels themselves.
    let cut = if base.len() == 1 { 1e-4 } else { SPLINE_KERNEL_CUT };
    while tap(r + 1).abs() >= cut * centre {
        r += 1;
    }
    // Mirrored, not computed on each side: the two sides then agree to the last bit.
    let outer: Vec<f64> = (0..=r).map(tap).collect();
    let sum = outer[0] + 2.0 * outer[1..].iter().sum::<f64>();
    outer.iter().rev().chain(&outer[1..]).map(|t| (t / sum) as f32).collect()
}

/// Where [`spline_kernel`] is cut, relative to its centre tap (1e-4 without smoothing, where
/// the spline must pass through the 8-bit pixels). What is cut changes the smoothing, not
/// the spline: the smoothed pixels are computed from the coefficients, so the spline passes
/// through them whatever the cut. At 1e-3 the kernel for sigma 1 px has 7
/// taps, against 11 at 1e-4 (the taps beyond: -3.9e-4 and 1.0e-4 of a sum of 1), and the
/// smoothing costs 0.11 instead of 0.16 ms per frame (this Zen 3 core); the smoothed
/// pixels move by at most a few tenths of a grey level on a checkerboard-fine pattern, and
/// far less on a floor's texture.
pub const SPLINE_KERNEL_CUT: f64 = 1e-3;

/// The cubic B-spline's four weights for the pixels k-1, k, k+1, k+2 at `t` in [0, 1) past
/// pixel k.
#[inline(always)]
pub(crate) fn spline_weights(t: f32) -> [f32; 4] {
    let (t2, t3) = (t * t, t * t * t);
    let u = 1.0 - t;
    [u * u * u / 6.0, (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0, (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, t3 / 6.0]
}

/// The cubic B-spline with coefficients `c` at (x, y) (pixels of `c`), coordinates clamped
/// to the plane.
pub(crate) fn sample_spline(c: &Plane<f32>, x: f64, y: f64) -> f32 {
    let (fx, fy) = (floor(x), floor(y));
    let (wx, wy) = (spline_weights((x - fx) as f32), spline_weights((y - fy) as f32));
    let (w, h) = (c.width() as i64, c.height() as i64);
    let mut v = 0.0;
    for (j, wy) in wy.iter().enumerate() {
        let yy = (fy as i64 - 1 + j as i64).clamp(0, h - 1) as usize;
        let row = c.row(yy);
        let mut r = 0.0;
        for (i, wx) in wx.iter().enumerate() {
            r += wx * row[(fx as i64 - 1 + i as i64).clamp(0, w - 1) as usize];
        }
        v += wy * r;
    }
    v
}

/// `x.floor()` without the library call that baseline x86-64 (no SSE4.1 `roundsd`) makes for
/// it; exact for |x| < 2^52, which covers every pixel coordinate.
pub(crate) fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use ocellus_image::resample::sample_bilinear;

    /// The cubic B-spline by its definition (Unser 1999): piecewise cubic, support (-2, 2).
    pub(crate) fn bspline3(t: f64) -> f64 {
        let t = t.abs();
        if t < 1.0 {
            2.0 / 3.0 - t * t + t * t * t / 2.0
        } else if t < 2.0 {
            (2.0 - t).powi(3) / 6.0
        } else {
            0.0
        }
    }

    /// The spline with coefficients `c` at (x, y), directly over its 16 nearest coefficients,
    /// indices clamped to the plane.
    pub(crate) fn spline_direct(c: &Plane<f32>, x: f64, y: f64) -> f64 {
        let (ix, iy) = (x.floor() as i64, y.floor() as i64);
        let mut v = 0.0;
        for j in iy - 1..=iy + 2 {
            for i in ix - 1..=ix + 2 {
                let (ci, cj) = (i.clamp(0, c.width() as i64 - 1) as usize, j.clamp(0, c.height() as i64 - 1) as usize);
                v += bspline3(x - i as f64) * bspline3(y - j as f64) * f64::from(c.get(ci, cj));
            }
        }
        v
    }

    #[test]
    fn a_smoothed_rectangle_is_the_whole_frame_smoothed_there() {
        let f = Plane::from_fn(90, 70, |x, y| ((x * 37 + y * 101 + x * y) % 251) as u8);
        let whole = ocellus_image::filter::gaussian_blur(Backend::Auto, &f.map(f32::from), 1.5).unwrap();
        let mut part = SmoothedFrame::default();
        // Inside the frame, and against its edges (where both clamp).
        for rect in [[20, 15, 60, 50], [0, 0, 30, 25], [70, 40, 90, 70]] {
            part.update(Backend::Auto, &f, 1.5, rect).unwrap();
            let (ox, oy) = part.origin();
            assert_eq!(part.frame_size(), (90, 70));
            for y in rect[1]..rect[3] {
                for x in rect[0]..rect[2] {
                    // At the frame's edge the two clamp different things (the pixels before the
                    // Gaussian, the spline's coefficients here), so they agree from 8 px in.
                    if x < 8 || y < 8 || x + 8 >= 90 || y + 8 >= 70 {
                        continue;
                    }
                    let (a, b) = (part.plane().get(x - ox, y - oy), whole.get(x, y));
                    // The spline's kernel is cut where its taps fall below 1e-3 of its centre
                    // (a few thousandths of a grey level here; 2e-3 with the cut at 1e-4).
                    assert!((a - b).abs() <= 0.02, "{rect:?} ({x}, {y}): {a} vs {b}");
                    // The smoothed pixels are the spline through the coefficients, at the pixels.
                    let c = spline_direct(part.coeffs(), (x - ox) as f64, (y - oy) as f64);
                    assert!((f64::from(a) - c).abs() <= 1e-3, "{rect:?} ({x}, {y}): {a} vs spline {c}");
                }
            }
        }
        part.update(Backend::Auto, &f, 0.0, [20, 20, 30, 30]).unwrap();
        let (ox, oy) = part.origin();
        assert!((ox, oy) < (20, 20));
        // Unsmoothed, the spline passes through the pixels (up to the cut kernel).
        for (x, y) in [(20, 20), (25, 27), (29, 29)] {
            let (a, b) = (part.plane().get(x - ox, y - oy), f32::from(f.get(x, y)));
            assert!((a - b).abs() <= 0.05, "({x}, {y}): {a} vs {b}");
        }
        for rect in [[10, 10, 10, 20], [0, 0, 91, 10], [20, 5, 10, 30]] {
            assert!(part.update(Backend::Auto, &f, 1.5, rect).is_err(), "{rect:?}");
        }
        assert!(part.update(Backend::Auto, &f, f32::NAN, [0, 0, 10, 10]).is_err());
    }

    /// Why the spline: a smoothed sinusoid resampled between the pixels keeps its phase and
    /// amplitude through the spline, where bilinear resampling of the smoothed pixels loses a
    /// few grey levels (Lucas-Kanade reads that loss as flow).
    #[test]
    fn the_spline_resamples_a_smoothed_pattern_between_the_pixels() {
        let (omega, amp, sigma) = (0.7f64, 100.0f64, 1.0f32);
        let f = Plane::from_fn(80, 12, |x, _| (128.0 + amp * (omega * x as f64 + 0.3).sin()).round() as u8);
        let mut s = SmoothedFrame::default();
        s.update(Backend::Auto, &f, sigma, [20, 4, 60, 8]).unwrap();
        let (ox, oy) = s.origin();
        // The smoothed sinusoid: the same sinusoid scaled by the Gaussian's response at omega.
        let g = gaussian_kernel(sigma).unwrap();
        let h = g.len() as f64 / 2.0 - 0.5;
        let response: f64 = g.iter().enumerate().map(|(k, &w)| f64::from(w) * (omega * (k as f64 - h)).cos()).sum();
        let (mut worst_spline, mut worst_bilinear) = (0f64, 0f64);
        for x in 24..56 {
            for frac in [0.125, 0.25, 0.5, 0.75] {
                let at = x as f64 + frac;
                let want = 128.0 + amp * response * (omega * at + 0.3).sin();
                let (px, py) = (at - ox as f64, (6 - oy) as f64);
                worst_spline = worst_spline.max((spline_direct(s.coeffs(), px, py) - want).abs());
                let b = sample_bilinear(s.plane(), px as f32, py as f32);
                worst_bilinear = worst_bilinear.max((f64::from(b) - want).abs());
            }
        }
        // Rounding the pattern to 8 bits leaves at most half a grey level.
        assert!(worst_spline <= 0.6, "spline off by {worst_spline}");
        assert!(worst_bilinear >= 3.0, "bilinear off by only {worst_bilinear}");
    }

    #[test]
    fn smoothing_keeps_the_mean_and_zero_keeps_the_pixels() {
        let f = Plane::from_fn(40, 30, |x, y| ((x * 7 + y * 13) % 256) as u8);
        let smooth = |sigma: f32| {
            let mut s = SmoothedFrame::default();
            s.update(Backend::Auto, &f, sigma, [0, 0, 40, 30]).map(|_| s.plane().clone())
        };
        let s0 = smooth(0.0).unwrap();
        assert!((s0.get(15, 17) - f32::from(f.get(15, 17))).abs() <= 0.05);
        let s = smooth(1.0).unwrap();
        let mean = |p: &Plane<f32>| p.rows().flatten().sum::<f32>() / (40.0 * 30.0);
        assert!((mean(&s) - mean(&s0)).abs() < 1.0);
        assert!(smooth(f32::NAN).is_err());
    }
}
