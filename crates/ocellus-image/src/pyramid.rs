//! Gaussian dyadic pyramid (SPEC 1.2).
//!
//! One level: correlate with a small separable kernel and keep every other sample, on both
//! axes. Output sample `j` of a row of length `n` is `sum_t k[t] * x[2j + t - origin]`; the
//! output length is `floor(n / 2)`. Where taps fall outside the image they are dropped and
//! the remaining taps renormalized to sum 1 (the seed's [10 10 5 1]/26 rule, generalized).

use crate::filter::accumulate_rows;
use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, ImageError, Plane, Result};
use serde::{Deserialize, Serialize};

/// The 1D low-pass kernel of a pyramid and where its origin lies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PyramidKernel {
    /// Taps (any positive weights; normalized to sum 1 on construction).
    pub taps: Vec<f32>,
    /// Index of the tap that multiplies `x[2j]` for output `j`.
    pub origin: usize,
    /// SaliencyToolbox rule for a dimension of exactly 3 samples: one output,
    /// `(x0 + 2 x1 + x2) / 4` (its `gaussianSubsample`). Off: the general rule.
    #[serde(default)]
    pub stb_size3_rule: bool,
}

impl PyramidKernel {
    /// Itti et al. 1998 / the seed: `[1 5 10 10 5 1] / 32`, taps at offsets -2..=3, so output
    /// `j` is centred on input position `2j + 0.5` (pixel-centre aligned decimation).
    pub fn itti() -> Self {
        Self::new(&[1.0, 5.0, 10.0, 10.0, 5.0, 1.0], 2, false)
    }

    /// SaliencyToolbox: `[1 5 10 10 5 1 1] / 33` convolved (flipped) with MATLAB's `'same'`
    /// alignment, i.e. correlation taps `[1 1 5 10 10 5 1]/33` at offsets -3..=3.
    pub fn stb() -> Self {
        Self::new(&[1.0, 1.0, 5.0, 10.0, 10.0, 5.0, 1.0], 3, true)
    }

    /// A kernel from raw taps, normalized to sum 1.
    pub fn new(taps: &[f32], origin: usize, stb_size3_rule: bool) -> Self {
        let s: f32 = taps.iter().sum();
        Self { taps: taps.iter().map(|t| t / s).collect(), origin, stb_size3_rule }
    }

    /// Checks the kernel: non-empty, finite, non-negative, origin inside.
    pub fn validate(&self) -> Result<()> {
        let s: f32 = self.taps.iter().sum();
        if self.taps.is_empty()
            || self.origin >= self.taps.len()
            || self.taps.iter().any(|t| !t.is_finite() || *t < 0.0)
            || s <= 0.0
        {
            return Err(ImageError::InvalidParameter(format!(
                "pyramid kernel {:?} with origin {} must be non-empty, non-negative, finite, with the origin inside",
                self.taps, self.origin
            )));
        }
        Ok(())
    }

    /// Taps (input index, weight) for output `j` of a dimension of length `n`, renormalized.
    fn taps_for(&self, j: usize, n: usize, out: &mut Vec<(usize, f32)>) {
        out.clear();
        if self.stb_size3_rule && n == 3 {
            out.extend_from_slice(&[(0, 0.25), (1, 0.5), (2, 0.25)]);
            return;
        }
        let mut s = 0.0;
        for (t, &k) in self.taps.iter().enumerate() {
            let i = (2 * j + t) as isize - self.origin as isize;
            if i >= 0 && (i as usize) < n {
                out.push((i as usize, k));
                s += k;
            }
        }
        if s > 0.0 {
            out.iter_mut().for_each(|(_, w)| *w /= s);
        }
    }

    /// Range of outputs `j` whose taps all fall inside a dimension of length `n`.
    fn interior(&self, n: usize) -> (usize, usize) {
        if self.stb_size3_rule && n == 3 {
            return (0, 0);
        }
        let lo = self.origin.div_ceil(2);
        let reach = self.taps.len() - 1 - self.origin;
        // need 2j + reach <= n - 1
        let hi = if n > reach { (n - 1 - reach) / 2 + 1 } else { 0 };
        (lo.min(n / 2), hi.min(n / 2).max(lo.min(n / 2)))
    }
}

/// Size of the next pyramid level: `(floor(w / 2), floor(h / 2))`.
pub fn next_size(width: usize, height: usize) -> (usize, usize) {
    (width / 2, height / 2)
}

/// Reusable buffers of [`pyr_down`].
#[derive(Default, Debug, Clone)]
pub struct PyrScratch {
    vert: Plane<f32>,
    even: Vec<f32>,
    odd: Vec<f32>,
    taps: Vec<(usize, f32)>,
}

#[inline(always)]
fn decimate_interior_generic<M: Madd>(even: &[f32], odd: &[f32], k: &[f32], origin: usize, lo: usize, out: &mut [f32]) {
    // x[2j + d] is even[j + d/2] for even d and odd[j + (d-1)/2] for odd d.
    const C: usize = 8;
    let n = out.len();
    let mut j = 0;
    while j + C <= n {
        let mut acc = [0f32; C];
        for (t, &kt) in k.iter().enumerate() {
            let d = t as isize - origin as isize;
            let (src, base) = if d.rem_euclid(2) == 0 { (even, d.div_euclid(2)) } else { (odd, (d - 1).div_euclid(2)) };
            let s0 = (lo + j) as isize + base;
            let s: &[f32; C] = src[s0 as usize..s0 as usize + C].try_into().unwrap_or(&[0.0; C]);
            for l in 0..C {
                acc[l] = M::madd(kt, s[l], acc[l]);
            }
        }
        out[j..j + C].copy_from_slice(&acc);
        j += C;
    }
    while j < n {
        let mut acc = 0f32;
        for (t, &kt) in k.iter().enumerate() {
            let d = t as isize - origin as isize;
            let i = (2 * (lo + j)) as isize + d;
            let v = if i % 2 == 0 { even[(i / 2) as usize] } else { odd[(i / 2) as usize] };
            acc = M::madd(kt, v, acc);
        }
        out[j] = acc;
        j += 1;
    }
}

dispatch_kernel!(fn decimate_interior => decimate_interior_generic(
    even: &[f32], odd: &[f32], k: &[f32], origin: usize, lo: usize, out: &mut [f32]
));

/// One pyramid level: `dst` becomes the low-passed, decimated `src` (`floor(w/2)` x `floor(h/2)`).
///
/// Errors if `src` is smaller than 2x2 (no next level exists).
pub fn pyr_down(
    backend: Backend,
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
    kernel: &PyramidKernel,
    s: &mut PyrScratch,
) -> Result<()> {
    let (w, h) = src.size();
    if w < 2 || h < 2 {
        return Err(ImageError::InvalidParameter(format!(
            "cannot decimate a {w}x{h} image: both sides must be at least 2"
        )));
    }
    let (ow, oh) = next_size(w, h);
    // Vertical first: full-width rows vectorize without shuffles.
    s.vert.resize(w, oh);
    for j in 0..oh {
        kernel.taps_for(j, h, &mut s.taps);
        accumulate_rows(backend, src, &s.taps, s.vert.row_mut(j));
    }
    dst.resize(ow, oh);
    let (lo, hi) = kernel.interior(w);
    for y in 0..oh {
        let row = s.vert.row(y);
        s.even.clear();
        s.odd.clear();
        s.even.extend(row.iter().step_by(2));
        s.odd.extend(row.iter().skip(1).step_by(2));
        let out = dst.row_mut(y);
        if hi > lo {
            decimate_interior(backend, &s.even, &s.odd, &kernel.taps, kernel.origin, lo, &mut out[lo..hi]);
        }
        for j in (0..lo).chain(hi.max(lo)..ow) {
            kernel.taps_for(j, w, &mut s.taps);
            out[j] = s.taps.iter().map(|&(i, wt)| wt * row[i]).sum();
        }
    }
    Ok(())
}

/// Allocating convenience wrapper of [`pyr_down`] (auto-detected backend).
pub fn pyr_down_alloc(src: &Plane<f32>, kernel: &PyramidKernel) -> Result<Plane<f32>> {
    let mut dst = Plane::default();
    pyr_down(Backend::Auto, src, &mut dst, kernel, &mut PyrScratch::default())?;
    Ok(dst)
}

/// Smallest image side that yields `levels` levels (level 0 = input): `2^(levels-1)`.
pub fn min_side_for_levels(levels: usize) -> usize {
    1usize << levels.saturating_sub(1)
}

/// Level sizes 0..levels for a `w` x `h` input.
pub fn level_sizes(w: usize, h: usize, levels: usize) -> Vec<(usize, usize)> {
    let mut v = Vec::with_capacity(levels);
    let (mut cw, mut ch) = (w, h);
    for _ in 0..levels {
        v.push((cw, ch));
        (cw, ch) = next_size(cw, ch);
    }
    v
}
