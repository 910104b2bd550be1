//! Rotation and scale between two images by phase correlation in log-polar space
//! (SPEC 4.3; Reddy & Chatterji 1996 for the Fourier-Mellin form).
//!
//! If b is a rotated by theta and scaled by s about the centre, a point at polar (r, phi) of
//! a is at (s r, phi + theta) in b, so b's cortical image is a's shifted by theta / (2 pi / S)
//! columns (cyclically) and log(s) / log(a) log rings: one phase correlation of the two
//! cortical images gives both.
//!
//! - [`Mode::Direct`]: the log-polar maps of the images themselves, about their centres. The
//!   rotation and scale must be about the centre (a fixating camera), and the answer covers the
//!   full turn.
//! - [`Mode::Spectrum`]: the log-polar maps of the (windowed, log) magnitude spectra of the
//!   central squares: a translation changes only the phase, so it drops out; a rotation turns
//!   the spectrum by theta, a scaling scales it by 1 / s. The spectrum's symmetry leaves theta
//!   and theta + 180 degrees: both are undone on b and the one whose translation-only phase
//!   correlation with a peaks higher wins, which also gives the translation.

use crate::logpolar::{LogPolarConfig, LogPolarMap};
use crate::phase_correlation::{fft2, hann, phase_correlate};
use crate::{FoveaError, Result};
use ocellus_image::Plane;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::{PI, TAU};

/// How the images are compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// Log-polar images of the images about their centres (rotation and scale about the centre).
    Direct,
    /// Log-polar images of the magnitude spectra (translation-invariant; Fourier-Mellin).
    Spectrum,
}

/// Parameters of the registration.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegisterOptions {
    /// Direct or spectrum.
    pub mode: Mode,
    /// Log rings of the cortical images.
    pub rings: usize,
    /// Sectors of the cortical images (the angular resolution is 360 / sectors degrees before
    /// the sub-cell peak).
    pub sectors: usize,
    /// Ratio of the outer to the inner radius of the log rings.
    pub radius_ratio: f64,
}

impl Default for RegisterOptions {
    /// Direct mode, 256 rings x 512 sectors, radii over a factor of 40.
    fn default() -> Self {
        Self { mode: Mode::Direct, rings: 256, sectors: 512, radius_ratio: 40.0 }
    }
}

/// The estimated similarity of b relative to a.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RotationScale {
    /// Rotation of b relative to a about the centre, degrees, from +x towards +y (clockwise on
    /// the screen), in (-180, 180].
    pub angle_deg: f64,
    /// Scale of b relative to a (2: b shows a twice as large).
    pub scale: f64,
    /// Translation of b relative to a after the rotation and scale, pixels (spectrum mode
    /// only; (0, 0) in direct mode).
    pub translation: [f64; 2],
    /// Height of the log-polar correlation peak (1: a perfect match).
    pub peak: f64,
}

/// Rotation and scale of `b` relative to `a` (grey images of one size, any units).
///
/// ```
/// use ocellus_fovea::register::{register, warp_similarity, RegisterOptions};
/// // A photograph, and the same turned by 30 degrees and enlarged 1.2 times about its centre.
/// let photo = ocellus_io::read_image(ocellus_testdata::data_file("camera.png"))?;
/// let a = photo.to_luma8().map(|v| v as f32);
/// let b = warp_similarity(&a, 30f64.to_radians(), 1.2);
/// let r = register(&a, &b, &RegisterOptions::default())?;
/// assert!((r.angle_deg - 30.0).abs() < 0.5 && (r.scale - 1.2).abs() < 0.01, "{r:?}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn register(a: &Plane<f32>, b: &Plane<f32>, opts: &RegisterOptions) -> Result<RotationScale> {
    ocellus_image::check::same_size("second image (against the first)", b.size(), a.size())?;
    if a.width() < 16 || a.height() < 16 {
        return Err(FoveaError::Invalid(format!("{}x{} is too small to register", a.width(), a.height())));
    }
    if !(opts.radius_ratio.is_finite() && opts.radius_ratio > 1.0) {
        return Err(FoveaError::Invalid(format!("radius ratio {}", opts.radius_ratio)));
    }
    if !(a.all_finite() && b.all_finite()) {
        return Err(FoveaError::Invalid("non-finite pixels".into()));
    }
    match opts.mode {
        Mode::Direct => {
            let (w, h) = a.size();
            let cfg = cortex_config(w, h, opts);
            let map = LogPolarMap::new(&cfg, w, h)?;
            let (la, lb) = (map.sample_f32(a)?, map.sample_f32(b)?);
            let (angle, scale, peak) = from_shift(&la, &lb, &cfg)?;
            Ok(RotationScale { angle_deg: wrap_deg(angle.to_degrees()), scale, translation: [0.0, 0.0], peak })
        }
        Mode::Spectrum => spectrum_mode(a, b, opts),
    }
}

/// The cortical map used for registration: log rings only, about the centre of a `w` x `h`
/// array, from half the smaller side inwards by `radius_ratio`.
fn cortex_config(w: usize, h: usize, opts: &RegisterOptions) -> LogPolarConfig {
    let max_radius = w.min(h) as f64 / 2.0 - 1.0;
    LogPolarConfig {
        rings: opts.rings,
        sectors: opts.sectors,
        fovea_rings: 0,
        fovea_radius: max_radius / opts.radius_ratio,
        max_radius,
        centre: [(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0],
        ..LogPolarConfig::for_image(w, h)
    }
}

/// (angle rad, scale, peak) from the phase correlation of two cortical images.
fn from_shift(la: &Plane<f32>, lb: &Plane<f32>, cfg: &LogPolarConfig) -> Result<(f64, f64, f64)> {
    // The ring axis is not cyclic: fade it out; the sector axis is.
    let s = phase_correlate(&hann(la, false, true), &hann(lb, false, true))?;
    let angle = s.dx * TAU / cfg.sectors as f64;
    let scale = cfg.ring_ratio().powf(s.dy);
    Ok((angle, scale, s.peak))
}

fn wrap_deg(d: f64) -> f64 {
    let r = d.rem_euclid(360.0);
    if r > 180.0 {
        r - 360.0
    } else {
        r
    }
}

/// The log magnitude spectrum of the central `n` x `n` square, Hann-windowed, with DC at
/// (n / 2, n / 2).
fn log_spectrum(img: &Plane<f32>, n: usize, planner: &mut FftPlanner<f32>) -> Plane<f32> {
    let (x0, y0) = ((img.width() - n) / 2, (img.height() - n) / 2);
    let square = Plane::from_fn(n, n, |x, y| img.get(x0 + x, y0 + y));
    let win = hann(&square, true, true);
    let mut data: Vec<Complex<f32>> = win.rows().flatten().map(|&v| Complex::new(v, 0.0)).collect();
    fft2(&mut data, n, n, false, planner);
    Plane::from_fn(n, n, |x, y| {
        // fftshift, then a high-pass emphasis (Reddy & Chatterji 1996) that keeps the low
        // frequencies, common to every image, from dominating the correlation.
        let (u, v) = ((x + n / 2) % n, (y + n / 2) % n);
        let (fx, fy) = ((x as f64 - (n / 2) as f64) / n as f64, (y as f64 - (n / 2) as f64) / n as f64);
        let c = (PI * fx).cos() * (PI * fy).cos();
        let hp = (1.0 - c) * (2.0 - c);
        (hp * (data[v * n + u].norm() as f64).ln_1p()) as f32
    })
}

fn spectrum_mode(a: &Plane<f32>, b: &Plane<f32>, opts: &RegisterOptions) -> Result<RotationScale> {
    let n = a.width().min(a.height()) & !1;
    let mut planner = FftPlanner::new();
    let (sa, sb) = (log_spectrum(a, n, &mut planner), log_spectrum(b, n, &mut planner));
    let mut cfg = cortex_config(n, n, opts);
    // The spectrum's centre is the DC bin (n / 2, n / 2).
    cfg.centre = [(n / 2) as f64, (n / 2) as f64];
    let map = LogPolarMap::new(&cfg, n, n)?;
    let (la, lb) = (map.sample_f32(&sa)?, map.sample_f32(&sb)?);
    let (angle, spec_scale, peak) = from_shift(&la, &lb, &cfg)?;
    // The spectrum scales by 1 / s.
    let scale = 1.0 / spec_scale;
    let mut best: Option<RotationScale> = None;
    for theta in [angle, angle + PI] {
        let back = warp_similarity(b, -theta, 1.0 / scale);
        let t = phase_correlate(&hann(a, true, true), &hann(&back, true, true))?;
        if best.is_none_or(|r| t.peak > r.peak) {
            // The translation measured in the undone frame, mapped into b's frame.
            let (s, c) = theta.sin_cos();
            let tr = [scale * (c * t.dx - s * t.dy), scale * (s * t.dx + c * t.dy)];
            best =
                Some(RotationScale { angle_deg: wrap_deg(theta.to_degrees()), scale, translation: tr, peak: t.peak });
        }
    }
    best.map(|r| RotationScale { peak, ..r }).ok_or_else(|| FoveaError::NoEstimate("no candidate".into()))
}

/// `img` rotated by `angle` radians (from +x towards +y) and scaled by `scale` about its
/// centre ((w - 1) / 2, (h - 1) / 2), bilinear, 0 outside: out(p) = img(c + R(-angle)(p - c) / scale).
pub fn warp_similarity(img: &Plane<f32>, angle: f64, scale: f64) -> Plane<f32> {
    let (w, h) = img.size();
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let (s, c) = angle.sin_cos();
    Plane::from_fn(w, h, |x, y| {
        let (dx, dy) = (x as f64 - cx, y as f64 - cy);
        let (u, v) = ((c * dx + s * dy) / scale + cx, (-s * dx + c * dy) / scale + cy);
        // A hair of tolerance: a half turn maps the border onto itself up to rounding.
        let e = 1e-6;
        if u < -e || v < -e || u > (w - 1) as f64 + e || v > (h - 1) as f64 + e {
            0.0
        } else {
            ocellus_image::resample::sample_bilinear(img, u as f32, v as f32)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let a = Plane::from_fn(64, 48, |x, y| ((x * 7 + y * 3) % 50) as f32);
        let opts = RegisterOptions::default();
        assert!(register(&a, &Plane::new(64, 47), &opts).is_err());
        assert!(register(&Plane::new(8, 8), &Plane::new(8, 8), &opts).is_err());
        let mut nan = a.clone();
        nan.set(3, 3, f32::NAN);
        assert!(register(&a, &nan, &opts).is_err());
        assert!(register(&a, &a, &RegisterOptions { radius_ratio: 1.0, ..opts }).is_err());
        // Flat images have nothing to correlate.
        let flat = Plane::from_fn(64, 48, |_, _| 3.0f32);
        for mode in [Mode::Direct, Mode::Spectrum] {
            assert!(register(&flat, &flat, &RegisterOptions { mode, ..opts }).is_err(), "{mode:?}");
        }
    }

    #[test]
    fn a_warp_by_zero_is_the_identity_and_a_half_turn_reverses() {
        let a = Plane::from_fn(31, 21, |x, y| (x * 3 + y * 5) as f32);
        let same = warp_similarity(&a, 0.0, 1.0);
        let half = warp_similarity(&a, PI, 1.0);
        for y in 0..21 {
            for x in 0..31 {
                assert!((same.get(x, y) - a.get(x, y)).abs() < 1e-3);
                assert!((half.get(x, y) - a.get(30 - x, 20 - y)).abs() < 1e-2, "{x} {y}");
            }
        }
    }
}
