//! Robust mode, beyond the seed: sub-pixel flow with its own uncertainty per window, and one
//! robust fit of the camera motion over all windows.
//!
//! 1. Every window's integer SAD match ([`crate::sad_flow::window_flows`]) is refined by
//!    Gauss-Newton steps of Lucas-Kanade (Lucas & Kanade 1981, [`crate::lucas_kanade`]) over
//!    a `lk_support` square about the block, on both frames smoothed by a Gaussian of
//!    `smooth_sigma_px`: with the image gradients g of frame n at the matched square, the
//!    correction solves `(sum g g^T) d = -sum g (I_n - I_n-1)`. The 2x2 structure tensor
//!    `sum g g^T` over the window's own noise (the variance its residual leaves per pixel) is
//!    the window's information: a square on a straight mortar line constrains the flow across
//!    the line only (the aperture problem), and a flat one nothing. Windows whose flow is
//!    uncertain by more than `max_flow_sigma_px` across their weakest direction are dropped:
//!    a test relative to the noise, which an absolute texture threshold is not (a dim,
//!    low-contrast floor has gradients below one grey level per pixel and is still usable).
//! 2. The camera's planar motion (right, forward, turn) is fitted to all the windows at once
//!    with the exact rigid model ([`fit_rigid`], in [`crate::rigid_fit`]).

use crate::gain_field::GainField;
use crate::lucas_kanade::{lk_sums, lk_sums_gain, sums_at_gain};
pub use crate::rigid_fit::{fit_rigid, RigidMotion};
use crate::sad_flow::{window_flows, SadFlowConfig};
use crate::spline::{SmoothedFrame, DEFAULT_SMOOTH_SIGMA_PX};
use crate::{OdometryError, Result};
use nalgebra::{Matrix3, Vector3};
use ocellus_image::{Backend, Plane};

/// Parameters of the robust measurement.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobustConfig {
    /// The integer search (all windows are used; none is dropped for being on the border).
    pub flow: SadFlowConfig,
    /// Lucas-Kanade steps per window (of the final pass; the gain field's pass takes one).
    pub lk_steps: usize,
    /// Side of the square that Lucas-Kanade refines each window's flow over, centred on the
    /// matched block, pixels: at least the block, with the same parity, at most the window.
    #[serde(default = "default_lk_support")]
    pub lk_support: usize,
    /// Sigma of the Gaussian both frames are smoothed with before Lucas-Kanade, pixels, in
    /// [0, 5] (0: none; see [`crate::lucas_kanade`]).
    #[serde(default = "default_smooth_sigma")]
    pub smooth_sigma_px: f32,
    /// Largest standard deviation of a window's flow across its weakest direction, pixels:
    /// windows that cannot pin their flow better are dropped (see [`window_measurements`]).
    #[serde(default = "default_max_flow_sigma")]
    pub max_flow_sigma_px: f64,
    /// Scale of the Cauchy weights, pixels.
    pub cauchy_px: f64,
    /// Residual beyond which a window is dropped after the first fit, pixels.
    pub reject_px: f64,
    /// How much of its offset from the calibrated camera height the followed height loses
    /// per frame, in [0, 1]. The height is followed through the image-scale change k each
    /// fit gives (frame n is frame n-1 magnified by 1 + k: the camera came down by the factor
    /// 1 / (1 + k)); integrating k alone would let its noise wander without bound, so the
    /// estimate is pulled back toward the calibrated height (0.002: a time constant of 500
    /// frames; 1: the height is fixed at the calibrated value, the seed's assumption; 0: pure
    /// integration). On the hard generated floors, whose camera height oscillates by 1 %
    /// over 37 frames, following it took the mean drift from 0.083 % to 0.057 % (7 floors x 3
    /// seeds, `odometry_table` example; 0.01 gave 0.068 %); on the easy ones, whose height is
    /// constant, it went from 0.025 % to 0.028 %, the noise of k integrated, until
    /// [`Self::height_noise_frames`] shrank each k by its measured signal-to-noise ratio.
    #[serde(default = "default_height_pull")]
    pub height_pull: f64,
    /// Window, frames, of the running noise and power of the image-scale change by whose
    /// ratio each change is shrunk before the height follows it (see [`crate::height`]):
    /// 0 or at least 1 (0: no shrinkage, every change followed whole). With 32 against 0,
    /// on the 42 real-camera runs (7 floors, easy and hard, 3 seeds, lens undistorted) the
    /// summed final drift went from 0.604 % to 0.545 % (easy) and from 1.378 % to 1.199 %
    /// (hard); 8 frames gave 0.554 % and 1.242 % (a throwaway program over this crate).
    #[serde(default = "default_height_noise_frames")]
    pub height_noise_frames: f64,
    /// Whether the brightness ratio between the frames is a smooth field over the image
    /// instead of one global gain. A lens darkens its image toward the corners (vignetting),
    /// so a floor point moving across the frame changes brightness by a ratio that depends on
    /// where it is, and one gain for the whole frame reads that difference as flow (most on a
    /// low-contrast floor, whose gradients are small beside its brightness; vignetting of 25 %
    /// at the corners moved the fitted shift of the test pattern below by 0.06 %). With the
    /// field, every other window first fits its own gain beside its flow (a third unknown of
    /// Lucas-Kanade), a quadratic in the position is fitted through those gains weighted by
    /// their information, and every window is refined from its integer match with the field's
    /// gain: a free gain per window would add its noise to every flow on a noisy, low-contrast
    /// floor (on the 42 real-camera runs it cut the summed drift of the easy ones from 0.545 to
    /// 0.510 % but raised the hard ones' from 1.199 to 1.284 %).
    #[serde(default = "default_gain_field")]
    pub gain_field: bool,
}

impl RobustConfig {
    /// Checks the Lucas-Kanade settings (the search's are checked against each frame).
    pub fn check(&self) -> Result<()> {
        let b = self.flow.block;
        if self.lk_support < b || self.lk_support > self.flow.window || !(self.lk_support - b).is_multiple_of(2) {
            return Err(OdometryError::Invalid(format!(
                "Lucas-Kanade support {}: from the block ({b}) to the window ({}), with the block's parity",
                self.lk_support, self.flow.window
            )));
        }
        if !(self.smooth_sigma_px.is_finite() && (0.0..=5.0).contains(&self.smooth_sigma_px)) {
            return Err(OdometryError::Invalid(format!("smoothing sigma {} px: 0..=5", self.smooth_sigma_px)));
        }
        if !(self.max_flow_sigma_px.is_finite() && self.max_flow_sigma_px > 0.0) {
            return Err(OdometryError::Invalid(format!(
                "largest flow sigma {} px must be finite and positive",
                self.max_flow_sigma_px
            )));
        }
        if !(self.height_pull.is_finite() && (0.0..=1.0).contains(&self.height_pull)) {
            return Err(OdometryError::Invalid(format!("height pull {}: 0..=1 per frame", self.height_pull)));
        }
        let w = self.height_noise_frames;
        if !(w.is_finite() && (w == 0.0 || w >= 1.0)) {
            return Err(OdometryError::Invalid(format!("height noise window {w} frames: 0 (off) or at least 1")));
        }
        Ok(())
    }
}

impl Default for RobustConfig {
    /// The seed's search, 2 Lucas-Kanade steps over 16 x 16 pixels of frames smoothed by a
    /// Gaussian of sigma 1 px ([`DEFAULT_SMOOTH_SIGMA_PX`]), windows whose flow is uncertain by more than 0.1 px dropped,
    /// Cauchy scale 0.3 px, rejection at 1 px.
    fn default() -> Self {
        Self {
            flow: SadFlowConfig::default(),
            lk_steps: 2,
            lk_support: default_lk_support(),
            smooth_sigma_px: default_smooth_sigma(),
            max_flow_sigma_px: default_max_flow_sigma(),
            cauchy_px: 0.3,
            reject_px: 1.0,
            height_pull: default_height_pull(),
            height_noise_frames: default_height_noise_frames(),
            gain_field: default_gain_field(),
        }
    }
}

fn default_lk_support() -> usize {
    16
}

fn default_height_pull() -> f64 {
    0.002
}

fn default_height_noise_frames() -> f64 {
    32.0
}

fn default_gain_field() -> bool {
    true
}

fn default_max_flow_sigma() -> f64 {
    0.1
}

/// Floor of the noise variance per pixel difference, grey levels squared: a noiseless
/// synthetic frame must not give a window infinite information.
const MIN_NOISE_VAR: f64 = 0.01;

fn default_smooth_sigma() -> f32 {
    DEFAULT_SMOOTH_SIGMA_PX
}

/// One window's sub-pixel measurement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowMeasurement {
    /// Block centre in frame n-1 relative to the principal point, pixels.
    pub u: f64,
    /// Block centre relative to the principal point, pixels (y down).
    pub v: f64,
    /// Flow, pixels.
    pub du: f64,
    /// Flow, pixels.
    pub dv: f64,
    /// Information of (du, dv): the structure tensor over the noise variance (1 / px^2).
    pub info: [[f64; 2]; 2],
}

/// Mean grey level of the central `region` x `region` pixels, over every other row and
/// column (40,000 samples for the defaults: plenty for a gain).
fn region_mean(backend: Backend, img: &Plane<u8>, region: usize) -> f64 {
    let (w, h) = img.size();
    let (rw, rh) = (region.min(w), region.min(h));
    let (x0, y0) = ((w - rw) / 2, (h - rh) / 2);
    let avx2 = backend.has_avx2();
    let s: u64 = (y0..y0 + rh).step_by(2).map(|y| even_sum(avx2, &img.row(y)[x0..x0 + rw])).sum();
    let n = rh.div_ceil(2) as u64 * rw.div_ceil(2) as u64;
    s as f64 / n.max(1) as f64
}

/// The sum of a row's pixels at even indices (`avx2`: the CPU has AVX2, see [`x86`]).
fn even_sum(avx2: bool, row: &[u8]) -> u64 {
    #[cfg(target_arch = "x86_64")]
    if avx2 {
        // SAFETY: the caller passes `avx2` true only on CPUs with AVX2.
        return unsafe { x86::even_sum_avx2(row) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = avx2;
    even_sum_plain(row)
}

/// [`even_sum`] in plain Rust.
fn even_sum_plain(row: &[u8]) -> u64 {
    // Pairs, not `step_by(2)`: the same pixels and the same integer sum, but a loop the
    // compiler vectorizes (a row of fewer than 2^24 pixels of at most 255 sums within a u32).
    let (pairs, rest) = row.split_at(row.len() / 2 * 2);
    let even: u32 =
        pairs.chunks_exact(2).map(|p| u32::from(p[0])).sum::<u32>() + rest.iter().map(|&v| u32::from(v)).sum::<u32>();
    u64::from(even)
}

/// [`even_sum_plain`] by hand in AVX2: the compiler's vector code for the pairs shuffles the even
/// bytes out; here a mask keeps them and `vpsadbw` against zero sums 32 bytes in one
/// instruction (the same integer; the two region means went from 2.5 to 0.8-1.0 % of a robust
/// step's profile on a Zen 3 core, about 19 to 6 us).
#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn even_sum_avx2(row: &[u8]) -> u64 {
        let chunks = row.len() / 32;
        let mask = _mm256_set1_epi16(0x00ff);
        let mut acc = _mm256_setzero_si256();
        for c in 0..chunks {
            // SAFETY: (c + 1) 32 <= row.len().
            let v = unsafe { _mm256_loadu_si256(row.as_ptr().add(32 * c) as *const __m256i) };
            acc = _mm256_add_epi64(acc, _mm256_sad_epu8(_mm256_and_si256(v, mask), _mm256_setzero_si256()));
        }
        let mut lanes = [0u64; 4];
        // SAFETY: `lanes` holds 32 bytes.
        unsafe { _mm256_storeu_si256(lanes.as_mut_ptr() as *mut __m256i, acc) };
        // The chunks end at an even index, so the rest's even pixels are its own even ones.
        lanes.iter().sum::<u64>() + super::even_sum_plain(&row[32 * chunks..])
    }
}

/// The rectangle `[x0, y0, x1, y1]` (end exclusive) of a `w` x `h` frame that Lucas-Kanade
/// reads with `cfg`: the searched region, grown by what the support adds beyond the block and
/// by the largest flow's reach (the search margin, one Lucas-Kanade pixel, the patch border
/// and the spline's neighbours; worked out in a comment inside). Errors as the search does for a
/// frame smaller than the region or a bad configuration.
pub fn lk_rect(w: usize, h: usize, cfg: &RobustConfig) -> Result<[usize; 4]> {
    cfg.check()?;
    cfg.flow.check(w, h)?;
    // A window's Lucas-Kanade square starts (support - block) / 2 left of its block, which
    // starts the search margin m right of the window. The flow is within m + 1 px of zero, and
    // the patch adds a border pixel and the spline's two neighbours on either side: reads
    // reach from x0 - (support - block) / 2 - 3 to x0 + region + (support - block) / 2 + 3,
    // inclusive.
    let grow = (cfg.lk_support - cfg.flow.block) / 2 + 4;
    let (x0, y0) = ((w - cfg.flow.region) / 2, (h - cfg.flow.region) / 2);
    Ok([
        x0.saturating_sub(grow),
        y0.saturating_sub(grow),
        (x0 + cfg.flow.region + grow).min(w),
        (y0 + cfg.flow.region + grow).min(h),
    ])
}

/// Sub-pixel flows of all textured windows between `prev` and `cur` (smoothing both for
/// Lucas-Kanade, see [`crate::lucas_kanade`]).
pub fn window_measurements(prev: &Plane<u8>, cur: &Plane<u8>, cfg: &RobustConfig) -> Result<Vec<WindowMeasurement>> {
    let rect = lk_rect(prev.width(), prev.height(), cfg)?;
    let (mut ps, mut cs) = (SmoothedFrame::default(), SmoothedFrame::default());
    ps.update(cfg.flow.backend, prev, cfg.smooth_sigma_px, rect)?;
    cs.update(cfg.flow.backend, cur, cfg.smooth_sigma_px, rect)?;
    window_measurements_smoothed(prev, cur, &ps, &cs, cfg)
}

/// [`window_measurements`] with both frames already smoothed for Lucas-Kanade
/// ([`SmoothedFrame::update`] with `cfg.smooth_sigma_px` over at least [`lk_rect`]; a stream
/// smooths each frame once).
pub fn window_measurements_smoothed(
    prev: &Plane<u8>,
    cur: &Plane<u8>,
    prev_smooth: &SmoothedFrame,
    cur_smooth: &SmoothedFrame,
    cfg: &RobustConfig,
) -> Result<Vec<WindowMeasurement>> {
    let [x0, y0, x1, y1] = lk_rect(prev.width(), prev.height(), cfg)?;
    for s in [prev_smooth, cur_smooth] {
        ocellus_image::check::same_size("smoothed frame", s.frame_size(), prev.size())?;
        let (ox, oy) = s.origin();
        let (sw, sh) = s.plane().size();
        if ox > x0 || oy > y0 || ox + sw < x1 || oy + sh < y1 {
            return Err(OdometryError::Invalid(format!(
                "the smoothed part of the frame ({sw}x{sh} at {ox},{oy}) does not cover what Lucas-Kanade reads ({x0}..{x1} x {y0}..{y1})"
            )));
        }
    }
    if prev_smooth.origin() != cur_smooth.origin() {
        return Err(OdometryError::Invalid("the two frames were smoothed over different parts".into()));
    }
    let (ox, oy) = prev_smooth.origin();
    let windows = window_flows(prev, cur, &cfg.flow)?;
    let (cx, cy) = ((prev.width() as f64 - 1.0) / 2.0, (prev.height() as f64 - 1.0) / 2.0);
    // Brightness robustness: a global gain between the frames (exposure or lighting change),
    // the ratio of the mean grey levels of the searched region.
    let backend = cfg.flow.backend;
    let gain = region_mean(backend, prev, cfg.flow.region) / region_mean(backend, cur, cfg.flow.region).max(1e-9);
    let gain = if gain.is_finite() && gain > 0.0 { gain } else { 1.0 };
    let b = cfg.lk_support;
    let half = (b as f64 - 1.0) / 2.0;
    let frames = LkFrames { prev: prev_smooth, cur: cur_smooth, cfg };
    let mut patch = Vec::new();
    // (window, the support's top-left pixel in the smoothed planes, the integer flow).
    let mut todo = Vec::with_capacity(windows.len());
    for wf in &windows {
        let Some((fx, fy)) = wf.flow else { continue };
        // The support's top-left pixel: the block's centre less half the support (an integer,
        // support and block having the same parity).
        let (bx, by) = ((wf.x - half).round().max(0.0) as usize, (wf.y - half).round().max(0.0) as usize);
        todo.push((wf, bx.saturating_sub(ox), by.saturating_sub(oy), (fx as f64, fy as f64)));
    }
    // The gain pass's sums at each window's integer match, kept: the final pass's first step
    // starts from the same match, and its sums follow from these at any gain.
    let mut first: Vec<Option<[f64; 10]>> = vec![None; todo.len()];
    // The gain field (see `RobustConfig::gain_field`): each window's own gain beside its flow
    // first, then one smooth field through those gains; every window is then refined from its
    // integer match again, as without the field, only with the field's gain.
    let field = if cfg.gain_field {
        let mut own = Vec::with_capacity(todo.len());
        // Every other window, in a checkerboard over the grid: about 200 gains fit the six
        // coefficients as well as 400 and cost half (the field pass costs a whole second
        // Lucas-Kanade pass otherwise).
        let pitch = cfg.flow.window as f64;
        for (k, &(wf, bx, by, start)) in todo.iter().enumerate() {
            if ((wf.x / pitch).floor() + (wf.y / pitch).floor()) as i64 % 2 != 0 {
                continue;
            }
            if let Some(r) = frames.refine(bx, by, start, gain, true, None, &mut patch) {
                own.push([wf.x - cx, wf.y - cy, r.gain / gain, r.gain_info]);
                first[k] = Some(r.first_sums);
            }
        }
        GainField::fit(&own)
    } else {
        GainField::flat()
    };
    let mut out = Vec::with_capacity(todo.len());
    for (&(wf, bx, by, start), first) in todo.iter().zip(&first) {
        let (u, v) = (wf.x - cx, wf.y - cy);
        let known = first.as_ref().map(|s| (s, gain));
        let Some(r) = frames.refine(bx, by, start, gain * field.at(u, v), false, known, &mut patch) else {
            continue;
        };
        // The noise per pixel difference, from this window's own residual, and the flow's
        // standard deviation across the weakest direction of the structure tensor: a window
        // that cannot pin its flow to `max_flow_sigma_px` is dropped; the others weigh by
        // their information, the tensor over the noise.
        let n = (b * b) as f64;
        let noise = (r.residual.max(0.0) / (n - 2.0).max(1.0)).max(MIN_NOISE_VAR);
        let [[a11, a12], [_, a22]] = r.tensor;
        let lmin = 0.5 * (a11 + a22 - ((a11 - a22).powi(2) + 4.0 * a12 * a12).sqrt());
        if !(lmin > 0.0 && noise / lmin <= cfg.max_flow_sigma_px * cfg.max_flow_sigma_px) {
            continue;
        }
        out.push(WindowMeasurement {
            u,
            v,
            du: r.flow.0,
            dv: r.flow.1,
            info: [[a11 / noise, a12 / noise], [a12 / noise, a22 / noise]],
        });
    }
    if out.len() < 3 {
        return Err(OdometryError::NoTexture(format!("only {} textured windows", out.len())));
    }
    Ok(out)
}

/// The two smoothed frames a window is refined on.
struct LkFrames<'a> {
    prev: &'a SmoothedFrame,
    cur: &'a SmoothedFrame,
    cfg: &'a RobustConfig,
}

/// One window refined by Lucas-Kanade.
#[derive(Clone, Copy, Debug)]
struct Refined {
    /// Flow, pixels.
    flow: (f64, f64),
    /// The structure tensor (the gain fixed; not filled with the gain free).
    tensor: [[f64; 2]; 2],
    /// What the last linearized step leaves of the squared differences.
    residual: f64,
    /// The gain the window ends with.
    gain: f64,
    /// Information of the relative gain (free gain only), over the noise per pixel.
    gain_info: f64,
    /// The sums of the first step (free gain only; see [`sums_at_gain`]).
    first_sums: [f64; 10],
}

/// Gauss-Newton steps of the gain pass (see [`RobustConfig::gain_field`]). Only its gains are
/// used, and one step from the integer match gives better ones than two: on the 42 real-camera
/// runs one step lowered the summed drift from 0.522 to 0.481 % (easy) and from 1.182 to
/// 1.046 % (hard), the summed ATE from 0.874 to 0.816 and from 2.615 to 2.461 mm, at half the
/// pass's cost.
const GAIN_PASS_STEPS: usize = 1;

impl LkFrames<'_> {
    /// Gauss-Newton steps of Lucas-Kanade (`lk_steps`) from the integer match `start` with
    /// `gain` on the current frame; with `free_gain` the window's relative gain is a third
    /// unknown, the model g (1 - s_g) cur(x + d - s), in [`GAIN_PASS_STEPS`] steps. `None`
    /// when a step fails or leaves the pixel around `start`. `known`: the ten sums of
    /// [`lk_sums_gain`] at `start` with another gain, from which the first step's sums follow
    /// without reading the frames.
    #[allow(clippy::too_many_arguments)]
    fn refine(
        &self,
        bx: usize,
        by: usize,
        start: (f64, f64),
        gain: f64,
        free_gain: bool,
        known: Option<(&[f64; 10], f64)>,
        patch: &mut Vec<f32>,
    ) -> Option<Refined> {
        let (b, cfg) = (self.cfg.lk_support, self.cfg);
        let (mut dx, mut dy) = start;
        let mut g = gain;
        let mut r =
            Refined { flow: start, tensor: [[0.0; 2]; 2], residual: 0.0, gain, gain_info: 0.0, first_sums: [0.0; 10] };
        let steps = if free_gain { GAIN_PASS_STEPS } else { cfg.lk_steps.max(1) };
        for step in 0..steps {
            let all = match known {
                Some((s, g0)) if step == 0 && !free_gain => sums_at_gain(s, g / g0),
                _ => {
                    let sums = if free_gain { lk_sums_gain } else { lk_sums };
                    sums(
                        cfg.flow.backend,
                        self.prev.plane(),
                        self.cur.plane(),
                        self.cur.coeffs(),
                        bx,
                        by,
                        b,
                        dx,
                        dy,
                        g,
                        patch,
                    )
                }
            };
            if step == 0 && free_gain {
                r.first_sums = all;
            }
            let [a11, a12, a22, b1, b2, ee, c1, c2, c3, b3] = all;
            let (sx, sy);
            if free_gain {
                let h = Matrix3::new(a11, a12, c1, a12, a22, c2, c1, c2, c3);
                let step = h.cholesky()?.solve(&Vector3::new(b1, b2, b3));
                (sx, sy) = (step[0], step[1]);
                r.residual = ee - (b1 * sx + b2 * sy + b3 * step[2]);
                g *= 1.0 - step[2];
                if !(g.is_finite() && g > 0.5 * gain && g < 2.0 * gain) {
                    return None;
                }
                // The gain's information once the flow is free (only the gain is used from
                // this pass).
                let det = a11 * a22 - a12 * a12;
                r.gain_info = c3 - (a22 * c1 * c1 - 2.0 * a12 * c1 * c2 + a11 * c2 * c2) / det;
            } else {
                r.tensor = [[a11, a12], [a12, a22]];
                let det = a11 * a22 - a12 * a12;
                if det.is_nan() || det <= 0.0 {
                    return None;
                }
                (sx, sy) = ((a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det);
                r.residual = ee - (b1 * sx + b2 * sy);
            }
            dx -= sx;
            dy -= sy;
            if (dx - start.0).abs() > 1.0 || (dy - start.1).abs() > 1.0 {
                return None;
            }
        }
        let n = (b * b) as f64;
        if free_gain {
            let noise = (r.residual.max(0.0) / (n - 3.0).max(1.0)).max(MIN_NOISE_VAR);
            r.gain_info /= noise;
        }
        r.flow = (dx, dy);
        r.gain = g;
        Some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_region_mean_is_the_same_on_every_backend() {
        let mut rng = ocellus_image::rng::SplitMix64::new(3);
        for (w, h, region) in [(640, 480, 400), (101, 77, 61), (40, 33, 40), (7, 5, 3)] {
            let img = Plane::from_fn(w, h, |_, _| (rng.next_u64() % 256) as u8);
            let (rw, rh) = (region.min(w), region.min(h));
            let (x0, y0) = ((w - rw) / 2, (h - rh) / 2);
            let (mut s, mut n) = (0.0, 0.0);
            for y in (y0..y0 + rh).step_by(2) {
                for x in (x0..x0 + rw).step_by(2) {
                    s += f64::from(img.get(x, y));
                    n += 1.0;
                }
            }
            for backend in [Backend::Scalar, Backend::Auto] {
                assert_eq!(region_mean(backend, &img, region), s / n, "{w}x{h} {region} {backend:?}");
            }
        }
    }

    #[test]
    fn bad_lucas_kanade_settings_are_refused() {
        let ok = RobustConfig::default();
        assert!(ok.check().is_ok());
        for bad in [
            RobustConfig { lk_support: 6, ..ok },
            RobustConfig { lk_support: 15, ..ok },
            RobustConfig { lk_support: 22, ..ok },
            RobustConfig { smooth_sigma_px: f32::NAN, ..ok },
            RobustConfig { smooth_sigma_px: -1.0, ..ok },
            RobustConfig { max_flow_sigma_px: 0.0, ..ok },
            RobustConfig { height_pull: -0.1, ..ok },
            RobustConfig { height_pull: f64::NAN, ..ok },
            RobustConfig { height_noise_frames: 0.5, ..ok },
            RobustConfig { height_noise_frames: f64::INFINITY, ..ok },
            RobustConfig { height_noise_frames: -1.0, ..ok },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
            let f = Plane::from_fn(640, 480, |x, y| ((x * 7 + y * 13) % 256) as u8);
            assert!(window_measurements(&f, &f, &bad).is_err());
        }
    }

    #[test]
    fn a_gain_field_keeps_vignetting_out_of_the_flow() {
        // A dim, low-contrast texture (smoothed noise, 60 +- 4 grey levels) moved by a known
        // sub-pixel offset under a lens that darkens toward the corners by 50 %: a floor point
        // that moves changes brightness by a ratio that depends on where it is.
        let mut rng = ocellus_image::rng::SplitMix64::new(7);
        let noise = Plane::from_fn(700, 540, |_, _| rng.normal() as f32);
        let tex = ocellus_image::filter::gaussian_blur(ocellus_image::Backend::Auto, &noise, 1.2).unwrap();
        let sd = (tex.rows().flatten().map(|v| v * v).sum::<f32>() / (700.0 * 540.0)).sqrt();
        let (sx, sy) = (3.4f32, -2.3f32);
        let frame = |ox: f32, oy: f32, vignetting: f32| {
            Plane::from_fn(640, 480, |x, y| {
                let r2 =
                    ((x as f32 - 319.5).powi(2) + (y as f32 - 239.5).powi(2)) / (319.5f32.powi(2) + 239.5f32.powi(2));
                let t = ocellus_image::resample::sample_bilinear(&tex, x as f32 + 30.0 - ox, y as f32 + 30.0 - oy);
                ((1.0 - vignetting * r2) * (60.0 + 4.0 * t / sd)).round() as u8
            })
        };
        // The fitted shift under vignetting less that without, as a share of the shift.
        let fitted = |vignetting: f32, gain_field: bool| {
            // Steps enough to converge: 2 leave about 0.006 px of the sub-pixel offset here,
            // which would hide what the gain does.
            let cfg = RobustConfig { gain_field, lk_steps: 6, ..RobustConfig::default() };
            let m = window_measurements(&frame(0.0, 0.0, vignetting), &frame(sx, sy, vignetting), &cfg).unwrap();
            assert!(m.len() > 300, "{} windows", m.len());
            let f = fit_rigid(&m, &cfg).unwrap();
            [-f.right_px, f.forward_px]
        };
        let change = |gain_field: bool| {
            let (a, b) = (fitted(0.5, gain_field), fitted(0.0, gain_field));
            (a[0] - b[0]).hypot(a[1] - b[1]) / sx.hypot(sy) as f64
        };
        let (global, own) = (change(false), change(true));
        println!(
            "vignetting changes the fitted shift by {:.4} % with one gain, {:.4} % with the gain field",
            100.0 * global,
            100.0 * own
        );
        // With bilinear resampling (before the spline) and 25 % vignetting: 0.060 % with one
        // gain, 0.012 % with the field. Through the spline one gain already does better
        // (0.013 % at 25 %), and at 50 % the field takes 0.054 % to 0.035 %.
        assert!(own < 0.8 * global && own < 5e-4, "gain field {own}, one gain {global}");
    }
}
