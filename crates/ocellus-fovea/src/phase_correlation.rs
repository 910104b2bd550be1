//! Phase correlation: the cyclic shift between two equal-size arrays, to a fraction of a cell
//! (Kuglin & Hines 1975; sub-cell peak of Foroosh, Zerubia & Berthod 2002).
//!
//! With F the 2D DFT, the normalized cross-power spectrum `conj(F a) F b / |conj(F a) F b|`
//! transforms back to a delta at the shift (dx, dy) for which b(x, y) = a(x - dx, y - dy)
//! (cyclically). For a shift between cells the surface is a sampled Dirichlet kernel, and
//! along each axis the peak's larger neighbour c1 and the peak c0 give the fraction
//! `c1 / (c1 + c0)`.

use crate::{FoveaError, Result};
use ocellus_image::Plane;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

/// A shift estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shift {
    /// Shift along x (columns), cells, in (-width/2, width/2].
    pub dx: f64,
    /// Shift along y (rows), cells, in (-height/2, height/2].
    pub dy: f64,
    /// Height of the correlation peak (1 for identical arrays up to the shift; near 0 for
    /// unrelated ones).
    pub peak: f64,
}

/// In-place 2D DFT of a row-major `w` x `h` array (`inverse` unnormalized).
pub(crate) fn fft2(data: &mut [Complex<f32>], w: usize, h: usize, inverse: bool, planner: &mut FftPlanner<f32>) {
    let (fr, fc) = if inverse {
        (planner.plan_fft_inverse(w), planner.plan_fft_inverse(h))
    } else {
        (planner.plan_fft_forward(w), planner.plan_fft_forward(h))
    };
    fr.process(data);
    let mut col = vec![Complex::new(0.0, 0.0); h];
    for x in 0..w {
        for y in 0..h {
            col[y] = data[y * w + x];
        }
        fc.process(&mut col);
        for y in 0..h {
            data[y * w + x] = col[y];
        }
    }
}

/// Multiplies by a Hann window along x (when `along_x`) and y (when `along_y`), after
/// removing the mean: a non-cyclic axis must fade to 0 at its ends, or the jump at the wrap
/// correlates with itself at shift 0.
pub fn hann(img: &Plane<f32>, along_x: bool, along_y: bool) -> Plane<f32> {
    let (w, h) = img.size();
    let mean = (img.sum() / (w * h).max(1) as f64) as f32;
    let win = |i: usize, n: usize, on: bool| {
        if !on || n < 2 {
            1.0
        } else {
            (0.5 - 0.5 * (std::f64::consts::TAU * (i as f64 + 0.5) / n as f64).cos()) as f32
        }
    };
    Plane::from_fn(w, h, |x, y| (img.get(x, y) - mean) * win(x, w, along_x) * win(y, h, along_y))
}

/// The shift of `b` relative to `a` (see the module doc). Both arrays must have the same
/// size; they are used as given (window them first with [`hann`] where an axis is not cyclic).
pub fn phase_correlate(a: &Plane<f32>, b: &Plane<f32>) -> Result<Shift> {
    ocellus_image::check::same_size("second image (against the first)", b.size(), a.size())?;
    let (w, h) = a.size();
    if w < 2 || h < 1 {
        return Err(FoveaError::Invalid(format!("{w}x{h} is too small to correlate")));
    }
    if !(a.all_finite() && b.all_finite()) {
        return Err(FoveaError::Invalid("non-finite values".into()));
    }
    let mut planner = FftPlanner::new();
    let to_c = |p: &Plane<f32>| -> Vec<Complex<f32>> { p.rows().flatten().map(|&v| Complex::new(v, 0.0)).collect() };
    let (mut fa, mut fb) = (to_c(a), to_c(b));
    fft2(&mut fa, w, h, false, &mut planner);
    fft2(&mut fb, w, h, false, &mut planner);
    let mut total = 0.0f64;
    for (x, y) in fa.iter_mut().zip(&fb) {
        let c = x.conj() * y;
        let m = c.norm();
        total += m as f64;
        *x = c;
    }
    // Bins with (almost) no energy carry no phase: they are dropped, not amplified.
    let floor = (1e-6 * total / (w * h) as f64) as f32;
    let mut kept = 0usize;
    for v in fa.iter_mut() {
        let m = v.norm();
        if m > floor {
            *v /= m;
            kept += 1;
        } else {
            *v = Complex::new(0.0, 0.0);
        }
    }
    if kept == 0 {
        return Err(FoveaError::NoEstimate("the arrays are flat".into()));
    }
    fft2(&mut fa, w, h, true, &mut planner);
    let n = (w * h) as f32;
    let surf: Vec<f32> = fa.iter().map(|v| v.re / n).collect();
    let (mut best, mut at) = (f32::MIN, 0usize);
    for (i, &v) in surf.iter().enumerate() {
        if v > best {
            best = v;
            at = i;
        }
    }
    let (px, py) = (at % w, at / w);
    let get = |x: isize, y: isize| surf[(y.rem_euclid(h as isize) as usize) * w + x.rem_euclid(w as isize) as usize];
    let frac = |c0: f32, cm: f32, cp: f32| -> f64 {
        // Foroosh et al. 2002 on each side: for a true offset only the neighbour on its side
        // is positive; a symmetric pedestal (bins without energy, e.g. Nyquist) cancels.
        let side = |c: f32| if c > 0.0 && c0 > 0.0 { (c / (c + c0)) as f64 } else { 0.0 };
        side(cp) - side(cm)
    };
    let (pxi, pyi) = (px as isize, py as isize);
    let fx = frac(best, get(pxi - 1, pyi), get(pxi + 1, pyi));
    let fy = if h > 1 { frac(best, get(pxi, pyi - 1), get(pxi, pyi + 1)) } else { 0.0 };
    let wrap = |p: usize, n: usize| if p > n / 2 { p as f64 - n as f64 } else { p as f64 };
    Ok(Shift { dx: wrap(px, w) + fx, dy: wrap(py, h) + fy, peak: best as f64 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::rng::SplitMix64;

    #[test]
    fn integer_and_fractional_cyclic_shifts_are_found() {
        let mut rng = SplitMix64::new(3);
        // A periodic pattern with energy in every frequency below Nyquist (as a real image
        // has), so a fractional shift is exact and the surface a full Dirichlet kernel.
        let (w, h) = (32usize, 24usize);
        let mut waves = Vec::new();
        for kx in 0..w as i64 / 2 {
            for ky in -(h as i64) / 2 + 1..h as i64 / 2 {
                if kx == 0 && ky <= 0 {
                    continue;
                }
                waves.push((kx as f64, ky as f64, rng.unit() * std::f64::consts::TAU, rng.unit() + 0.2));
            }
        }
        let img = |sx: f64, sy: f64| {
            Plane::from_fn(w, h, |x, y| {
                let (x, y) = (x as f64 - sx, y as f64 - sy);
                waves
                    .iter()
                    .map(|&(kx, ky, ph, amp)| {
                        amp * (std::f64::consts::TAU * (kx * x / w as f64 + ky * y / h as f64) + ph).cos()
                    })
                    .sum::<f64>() as f32
            })
        };
        let a = img(0.0, 0.0);
        for &(dx, dy) in &[(5.0, -3.0), (-13.0, 9.0), (2.3, -4.6), (0.5, 0.25)] {
            let s = phase_correlate(&a, &img(dx, dy)).unwrap();
            assert!((s.dx - dx).abs() < 0.08 && (s.dy - dy).abs() < 0.08, "{dx} {dy}: {s:?}");
        }
        let s = phase_correlate(&a, &a).unwrap();
        // The pattern has no energy at Nyquist and DC: 7 % of the bins, hence the peak of 0.93.
        assert!(s.dx.abs() < 1e-6 && s.dy.abs() < 1e-6 && s.peak > 0.9, "{s:?}");
        let flat = Plane::from_fn(w, h, |_, _| 0.0f32);
        assert!(phase_correlate(&flat, &flat).is_err());
        assert!(phase_correlate(&a, &Plane::new(w, h + 1)).is_err());
    }
}
