//! Gaussian dyadic pyramid (SPEC 1.2).
//!
//! One level: correlate with a small separable kernel and keep every other sample, on both
//! axes. Output sample `j` of a row of length `n` is `sum_t k[t] * x[2j + t - origin]`; the
//! output length is `floor(n / 2)`. Where taps fall outside the image they are dropped and
//! the remaining taps renormalized to sum 1 (the seed's [10 10 5 1]/26 rule, generalized).

use crate::filter::accumulate_rows_best;
use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, ImageError, Plane, Result};
use serde::{Deserialize, Serialize};

/// The 1D low-pass kernel of a pyramid and where its origin lies.
///
/// Read from a configuration file, the taps are checked and normalized to sum 1 like
/// [`PyramidKernel::new`] does (`taps = [1, 5, 10, 10, 5, 1]` is the seed's kernel, not one
/// with a gain of 32).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawPyramidKernel")]
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

/// A kernel as written in a file, before checking and normalization.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPyramidKernel {
    taps: Vec<f32>,
    origin: usize,
    #[serde(default)]
    stb_size3_rule: bool,
}

impl TryFrom<RawPyramidKernel> for PyramidKernel {
    type Error = ImageError;

    fn try_from(r: RawPyramidKernel) -> Result<Self> {
        // Checked before normalizing, so that a zero or non-finite sum never divides.
        let raw = PyramidKernel { taps: r.taps, origin: r.origin, stb_size3_rule: r.stb_size3_rule };
        raw.validate()?;
        Ok(Self::new(&raw.taps, raw.origin, raw.stb_size3_rule))
    }
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
            || self.taps.len() > MAX_TAPS
            || self.origin >= self.taps.len()
            || self.taps.iter().any(|t| !t.is_finite() || *t < 0.0)
            || s <= 0.0
            || !s.is_finite()
        {
            return Err(ImageError::InvalidParameter(format!(
                "pyramid kernel {:?} with origin {} must have 1..=16 non-negative finite taps, with the origin inside",
                self.taps, self.origin
            )));
        }
        Ok(())
    }

    /// Taps (input index, weight) for output `j` of a dimension of length `n`, renormalized
    /// to sum 1 where the kernel is truncated at a border (SPEC 1.2); written into `out`.
    /// Other backends (the GPU's) build their tap tables from this one rule.
    pub fn taps_for(&self, j: usize, n: usize, out: &mut Vec<(usize, f32)>) {
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
    taps2: Vec<(usize, f32)>,
    row3: Vec<f32>,
    even3: [Vec<f32>; 3],
    odd3: [Vec<f32>; 3],
    row16: Vec<u16>,
    itaps: Vec<(usize, u16)>,
    itaps_interior: Vec<(usize, u16)>,
    border: BorderTaps,
}

/// The taps of the outputs of a decimated row of `w` samples that reach past its ends
/// (outputs `j < lo` and `j >= hi` of [`PyramidKernel::interior`]), the same for every row of
/// a level: built once per level, not per row and output (the renormalized taps cost about
/// as much as the row's arithmetic on the small levels, where a row is a few vectors).
#[derive(Default, Debug, Clone)]
struct BorderTaps {
    taps: Vec<(usize, f32)>,
    /// (output j, start, end) of its taps in `taps`.
    outputs: Vec<(usize, usize, usize)>,
}

impl BorderTaps {
    fn build(&mut self, kernel: &PyramidKernel, w: usize, scratch: &mut Vec<(usize, f32)>) {
        self.taps.clear();
        self.outputs.clear();
        let (lo, hi) = kernel.interior(w);
        for j in (0..lo).chain(hi.max(lo)..w / 2) {
            kernel.taps_for(j, w, scratch);
            let start = self.taps.len();
            self.taps.extend_from_slice(scratch);
            self.outputs.push((j, start, self.taps.len()));
        }
    }
}

/// The taps of output `j` of a dimension of `n` samples into `out`: for an interior output
/// (all taps inside), `interior` (the taps of output `lo`) shifted by `2 (j - lo)` samples,
/// the same weights as [`PyramidKernel::taps_for`] computes for it; otherwise that.
#[inline(always)]
fn taps_at<T: Copy>(
    j: usize,
    (lo, hi): (usize, usize),
    interior: &[(usize, T)],
    out: &mut Vec<(usize, T)>,
    border: impl FnOnce(&mut Vec<(usize, T)>),
) {
    if (lo..hi).contains(&j) {
        out.clear();
        out.extend(interior.iter().map(|&(i, w)| (i + 2 * (j - lo), w)));
    } else {
        border(out);
    }
}

/// Longest pyramid kernel supported (taps).
pub const MAX_TAPS: usize = 16;

/// `out[j] = sum_t k[t] x[2 (lo + j) + t - origin]` where `x[2i] = even[i]`, `x[2i+1] = odd[i]`;
/// all taps must fall inside the row.
#[inline(always)]
fn decimate_interior_generic<M: Madd>(even: &[f32], odd: &[f32], k: &[f32], origin: usize, lo: usize, out: &mut [f32]) {
    // Per tap: which half-row it reads and at which offset from j.
    let mut plan = [(false, 0usize, 0f32); MAX_TAPS];
    for (t, &kt) in k.iter().enumerate().take(MAX_TAPS) {
        let i = 2 * lo as isize + t as isize - origin as isize; // input index for j = 0
        plan[t] = (i.rem_euclid(2) == 1, i.div_euclid(2) as usize, kt);
    }
    let plan = &plan[..k.len().min(MAX_TAPS)];
    let n = out.len();
    let mut j = 0;
    // The taps alternate between the halves: tap 0's half first.
    let (a, b) = if plan.first().is_some_and(|p| p.0) { (odd, even) } else { (even, odd) };
    // 128 outputs at a time with AVX-512: eight independent 512-bit chains, enough to hide
    // the multiply-add latency over a kernel of six taps; then 64 and 32. With 256-bit
    // registers 128 outputs are sixteen accumulators, all the registers there are, and were
    // spilled (a store and a load around multiply-adds): 64 at most there, the first level
    // 1-2 % faster on an AMD EPYC (Zen 3; the same values).
    while M::AVX512 && j + 128 <= n {
        decimate_chunk::<M, 128>(a, b, plan, j, out);
        j += 128;
    }
    while j + 64 <= n {
        decimate_chunk::<M, 64>(a, b, plan, j, out);
        j += 64;
    }
    while j + 32 <= n {
        decimate_chunk::<M, 32>(a, b, plan, j, out);
        j += 32;
    }
    if j < n && n >= 32 {
        // The rest as one 32-wide chunk aligned to the end (recomputing a few outputs, with
        // the same values): 8 outputs at a time, each a chain of one multiply-add per tap,
        // waited on the multiply-add latency and had cost a tenth of a pyramid level.
        decimate_chunk::<M, 32>(a, b, plan, n - 32, out);
        j = n;
    }
    // Short rows: 8 at a time, then one 8-wide chunk aligned to the end.
    while j < n && n >= 8 {
        let j0 = if j + 8 <= n { j } else { n - 8 };
        let mut acc = [0f32; 8];
        for &(is_odd, base, kt) in plan {
            let src = if is_odd { odd } else { even };
            let s: &[f32; 8] = src[base + j0..base + j0 + 8].try_into().unwrap_or(&[0.0; 8]);
            for l in 0..8 {
                acc[l] = M::madd(kt, s[l], acc[l]);
            }
        }
        out[j0..j0 + 8].copy_from_slice(&acc);
        j = j0 + 8;
    }
    while j < n {
        let mut acc = 0f32;
        for &(is_odd, base, kt) in plan {
            acc = M::madd(kt, if is_odd { odd[base + j] } else { even[base + j] }, acc);
        }
        out[j] = acc;
        j += 1;
    }
}

/// `C` outputs of [`decimate_interior_generic`] from `j`; even taps read `a`, odd taps `b`
/// (the halves alternate from tap to tap), taken two at a time so that no tap chooses its
/// half at run time.
#[inline(always)]
fn decimate_chunk<M: Madd, const C: usize>(
    a: &[f32],
    b: &[f32],
    plan: &[(bool, usize, f32)],
    j: usize,
    out: &mut [f32],
) {
    let mut acc = [0f32; C];
    for pair in plan.chunks(2) {
        let (_, base, kt) = pair[0];
        let Ok(s) = <&[f32; C]>::try_from(&a[base + j..base + j + C]) else { return };
        for l in 0..C {
            acc[l] = M::madd(kt, s[l], acc[l]);
        }
        if let Some(&(_, base, kt)) = pair.get(1) {
            let Ok(s) = <&[f32; C]>::try_from(&b[base + j..base + j + C]) else { return };
            for l in 0..C {
                acc[l] = M::madd(kt, s[l], acc[l]);
            }
        }
    }
    out[j..j + C].copy_from_slice(&acc);
}

/// Splits `row` into even- and odd-indexed samples.
#[inline(always)]
fn deinterleave(row: &[f32], even: &mut Vec<f32>, odd: &mut Vec<f32>) {
    let n = row.len();
    even.resize(n.div_ceil(2), 0.0);
    odd.resize(n / 2, 0.0);
    let (e, o): (&mut [f32], &mut [f32]) = (&mut even[..], &mut odd[..]);
    for (i, pair) in row.chunks_exact(2).enumerate() {
        e[i] = pair[0];
        o[i] = pair[1];
    }
    if n % 2 == 1 {
        e[n / 2] = row[n - 1];
    }
}

/// One decimated row: `out[j] = sum_t k[t] x[2j + t - origin]`, renormalized at the borders,
/// from the even/odd halves of a row of length `w`.
#[inline(always)]
fn decimate_one<M: Madd>(
    even: &[f32],
    odd: &[f32],
    w: usize,
    kernel: &PyramidKernel,
    border: &BorderTaps,
    out: &mut [f32],
) {
    let (lo, hi) = kernel.interior(w);
    if hi > lo {
        decimate_interior_generic::<M>(even, odd, &kernel.taps, kernel.origin, lo, &mut out[lo..hi]);
    }
    for &(j, a, b) in &border.outputs {
        let taps = &border.taps[a..b];
        if let Some(o) = out.get_mut(j) {
            *o = taps.iter().map(|&(i, wt)| wt * if i % 2 == 0 { even[i / 2] } else { odd[i / 2] }).sum();
        }
    }
}

/// A next level exists only for images of at least 2x2.
fn check_decimable(w: usize, h: usize) -> Result<()> {
    if w < 2 || h < 2 {
        return Err(ImageError::InvalidParameter(format!(
            "cannot decimate a {w}x{h} image: both sides must be at least 2"
        )));
    }
    Ok(())
}

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
    check_decimable(w, h)?;
    pyr_down_kernel(backend, src, dst, kernel, s);
    Ok(())
}

#[inline(always)]
fn pyr_down_generic<M: Madd>(src: &Plane<f32>, dst: &mut Plane<f32>, kernel: &PyramidKernel, s: &mut PyrScratch) {
    let (w, h) = src.size();
    let (ow, oh) = next_size(w, h);
    // Vertical first: full-width rows vectorize without shuffles.
    s.vert.resize(w, oh);
    let inner = kernel.interior(h);
    if inner.1 > inner.0 {
        kernel.taps_for(inner.0, h, &mut s.taps2);
    }
    for j in 0..oh {
        taps_at(j, inner, &s.taps2, &mut s.taps, |t| kernel.taps_for(j, h, t));
        accumulate_rows_best::<M>(src, &s.taps, s.vert.row_mut(j));
    }
    dst.resize(ow, oh);
    s.border.build(kernel, w, &mut s.taps);
    decimate_rows::<M>(&s.vert, dst, kernel, &mut s.even, &mut s.odd, &s.border);
}

dispatch_kernel!(fn pyr_down_kernel => pyr_down_generic(src: &Plane<f32>, dst: &mut Plane<f32>, kernel: &PyramidKernel, s: &mut PyrScratch));

/// Horizontal low-pass and decimation of every row of `vert` into `dst` (already sized).
#[inline(always)]
fn decimate_rows<M: Madd>(
    vert: &Plane<f32>,
    dst: &mut Plane<f32>,
    kernel: &PyramidKernel,
    even: &mut Vec<f32>,
    odd: &mut Vec<f32>,
    border: &BorderTaps,
) {
    let w = vert.width();
    for y in 0..dst.height() {
        deinterleave(vert.row(y), even, odd);
        decimate_one::<M>(even, odd, w, kernel, border, dst.row_mut(y));
    }
}

/// First pyramid level straight from 8-bit interleaved RGB: `dst[c]` becomes level 1 of
/// channel c with values in [0, 1]. The same result as converting to float planes and
/// calling [`pyr_down`] on each, without writing the full-resolution float planes.
pub fn pyr_down_rgb8(
    backend: Backend,
    src: &Plane<[u8; 3]>,
    dst: [&mut Plane<f32>; 3],
    kernel: &PyramidKernel,
    s: &mut PyrScratch,
) -> Result<()> {
    let (w, h) = src.size();
    check_decimable(w, h)?;
    let (ow, oh) = next_size(w, h);
    let [d0, d1, d2] = dst;
    for d in [&mut *d0, &mut *d1, &mut *d2] {
        d.resize(ow, oh);
    }
    pyr_down_rgb8_kernel(backend, src, [d0, d1, d2], kernel, s);
    Ok(())
}

#[inline(always)]
fn pyr_down_rgb8_generic<M: Madd>(
    src: &Plane<[u8; 3]>,
    dst: [&mut Plane<f32>; 3],
    kernel: &PyramidKernel,
    s: &mut PyrScratch,
) {
    let (w, h) = src.size();
    let [d0, d1, d2] = dst;
    for c in 0..3 {
        s.even3[c].resize(w.div_ceil(2), 0.0);
        s.odd3[c].resize(w / 2, 0.0);
    }
    let integer = kernel.integer_taps();
    let inner = kernel.interior(h);
    let mut d_inner = 1;
    if let Some(ik) = &integer {
        s.row16.resize(3 * w, 0);
        if inner.1 > inner.0 {
            d_inner = ik.taps_for(kernel, inner.0, h, &mut s.taps, &mut s.itaps_interior);
        }
    } else {
        s.row3.resize(3 * w, 0.0);
    }
    s.border.build(kernel, w, &mut s.taps);
    for j in 0..d0.height() {
        let [e0, e1, e2] = &mut s.even3;
        let [o0, o1, o2] = &mut s.odd3;
        let (e0, e1, e2): (&mut [f32], &mut [f32], &mut [f32]) = (e0, e1, e2);
        let (o0, o1, o2): (&mut [f32], &mut [f32], &mut [f32]) = (o0, o1, o2);
        if let Some(ik) = &integer {
            // Exact integer sums of bytes (see `IntegerTaps`), then one scaling to [0, 1] as
            // the samples are split into even/odd per channel.
            let mut d = d_inner;
            taps_at(j, inner, &s.itaps_interior, &mut s.itaps, |t| d = ik.taps_for(kernel, j, h, &mut s.taps, t));
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `M::AVX512` (`M::AVX2`) is true only inside kernels compiled for AVX-512
            // F/BW/VL/DQ (AVX2 and FMA), which `dispatch_kernel!` calls only on CPUs that have it.
            let done = unsafe {
                if M::AVX512 {
                    x86::vertical_bytes_u16_avx512(src, &s.itaps, &mut s.row16)
                } else {
                    M::AVX2 && x86::vertical_bytes_u16_avx2(src, &s.itaps, &mut s.row16)
                }
            };
            #[cfg(not(target_arch = "x86_64"))]
            let done = false;
            if !done {
                vertical_bytes_u16(src, &s.itaps, &mut s.row16);
            }
            let scale = 1.0 / (d as f32 * 255.0);
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            let split = unsafe {
                let (even, odd) = ([&mut *e0, &mut *e1, &mut *e2], [&mut *o0, &mut *o1, &mut *o2]);
                if M::AVX512 {
                    x86::split_even_odd_avx512(&s.row16, scale, even, odd)
                } else {
                    M::AVX2 && x86::split_even_odd_avx2(&s.row16, scale, even, odd)
                }
            };
            #[cfg(not(target_arch = "x86_64"))]
            let split = false;
            if !split {
                split_even_odd(&s.row16, scale, [e0, e1, e2], [o0, o1, o2]);
            }
        } else {
            vertical_bytes::<M>(src, j, h, kernel, &mut s.taps, &mut s.row3);
            // Scaling by 1 is exact: the same values as a plain split.
            split_even_odd(&s.row3, 1.0, [e0, e1, e2], [o0, o1, o2]);
        }
        for (c, d) in [&mut *d0, &mut *d1, &mut *d2].into_iter().enumerate() {
            decimate_one::<M>(&s.even3[c], &s.odd3[c], w, kernel, &s.border, d.row_mut(j));
        }
    }
}

/// Splits an interleaved RGB row into even- and odd-indexed samples per channel (two RGB
/// pixels = 6 values at a time), each scaled by `scale`.
#[inline(always)]
fn split_even_odd<T: Copy + Into<f32>>(row: &[T], scale: f32, even: [&mut [f32]; 3], odd: [&mut [f32]; 3]) {
    let w = row.len() / 3;
    let half = w / 2;
    if even.iter().any(|e| e.len() < w.div_ceil(2)) || odd.iter().any(|o| o.len() < half) {
        return;
    }
    let [e0, e1, e2] = even;
    let [o0, o1, o2] = odd;
    // Slices of exactly `half` values: the loop then needs no bounds tests and vectorizes.
    let (f0, f1, f2) = (&mut e0[..half], &mut e1[..half], &mut e2[..half]);
    let (o0, o1, o2) = (&mut o0[..half], &mut o1[..half], &mut o2[..half]);
    for (k, px) in row.chunks_exact(6).take(half).enumerate() {
        f0[k] = px[0].into() * scale;
        f1[k] = px[1].into() * scale;
        f2[k] = px[2].into() * scale;
        o0[k] = px[3].into() * scale;
        o1[k] = px[4].into() * scale;
        o2[k] = px[5].into() * scale;
    }
    if w % 2 == 1 {
        let last = &row[3 * (w - 1)..];
        e0[w / 2] = last[0].into() * scale;
        e1[w / 2] = last[1].into() * scale;
        e2[w / 2] = last[2].into() * scale;
    }
}

/// A pyramid kernel whose taps are `n_t / D` with small integers `n_t` (the seed's
/// `[1 5 10 10 5 1] / 32`, the toolbox's `/ 33`): on 8-bit input its vertical pass is an
/// exact sum in 16-bit integers, three times cheaper than converting every byte to float for
/// each of the taps that reads it, and exact where the float sum rounds at every tap.
#[derive(Clone, Copy, Debug)]
struct IntegerTaps {
    n: [u16; MAX_TAPS],
}

impl PyramidKernel {
    /// The integer form of the taps, if every tap is within 1e-5 / D of `n_t / D` for integers
    /// with `D <= 256` (so that `255 D` fits 16 bits). Allocates nothing: it runs per frame.
    fn integer_taps(&self) -> Option<IntegerTaps> {
        let taps = self.taps.get(..self.taps.len().min(MAX_TAPS))?;
        (1..=256u32).find_map(|d| {
            let exact = taps.iter().all(|t| (t * d as f32 - (t * d as f32).round()).abs() < 1e-5);
            let sum: f32 = taps.iter().map(|t| (t * d as f32).round()).sum();
            (exact && sum == d as f32 && taps.len() == self.taps.len()).then(|| {
                let mut n = [0u16; MAX_TAPS];
                n.iter_mut().zip(taps).for_each(|(o, t)| *o = (t * d as f32).round() as u16);
                IntegerTaps { n }
            })
        })
    }
}

impl IntegerTaps {
    /// The taps of output `j` of a dimension of `n` samples: those `kernel.taps_for` keeps
    /// (its border rule, written once), with their integer weights, into `out` (`ftaps` is
    /// scratch); returns their sum, the divisor of the output.
    fn taps_for(
        &self,
        kernel: &PyramidKernel,
        j: usize,
        n: usize,
        ftaps: &mut Vec<(usize, f32)>,
        out: &mut Vec<(usize, u16)>,
    ) -> u32 {
        out.clear();
        if kernel.stb_size3_rule && n == 3 {
            // The toolbox's [1 2 1] / 4 for three samples, as `taps_for` has it.
            out.extend_from_slice(&[(0, 1), (1, 2), (2, 1)]);
            return 4;
        }
        kernel.taps_for(j, n, ftaps);
        // Input i of output j is tap t = i + origin - 2 j.
        out.extend(ftaps.iter().map(|&(i, _)| (i, self.n[i + kernel.origin - 2 * j])).filter(|&(_, k)| k > 0));
        out.iter().map(|&(_, k)| k as u32).sum::<u32>().max(1)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86;

/// The two rows below the last of `taps` (those that exist), which the next output row of
/// the first level reads for the first time. The vertical sums touch them one output row
/// ahead: on a frame that is not in cache (640x480 RGB is 0.9 MB) the first read of each row
/// waited on memory, about a third of the level's time on an AMD EPYC (Zen 4).
#[cfg(target_arch = "x86_64")]
fn rows_ahead<'a>(src: &'a Plane<[u8; 3]>, taps: &[(usize, u16)]) -> [Option<&'a [u8]>; 2] {
    let last = taps.iter().map(|&(r, _)| r).max().unwrap_or(0);
    [last + 1, last + 2].map(|r| (r < src.height()).then(|| src.row(r).as_flattened()))
}

/// `out[x] = sum_taps n * byte[x]` over the interleaved bytes of the rows in `taps` (at
/// most [`MAX_TAPS`]; sums of at most 255 * 256: no overflow), 64 values at a time.
#[inline(always)]
fn vertical_bytes_u16(src: &Plane<[u8; 3]>, taps: &[(usize, u16)], out: &mut [u16]) {
    const C: usize = 64;
    let mut rows: [(&[u8], u16); MAX_TAPS] = [(&[], 0); MAX_TAPS];
    for (slot, &(r, k)) in rows.iter_mut().zip(taps) {
        *slot = (src.row(r).as_flattened(), k);
    }
    let rows = &rows[..taps.len().min(MAX_TAPS)];
    let n = out.len();
    #[cfg(target_arch = "x86_64")]
    let ahead = rows_ahead(src, taps);
    // A function, not a closure: closures are not compiled with the caller's target features.
    #[inline(always)]
    fn chunk(rows: &[(&[u8], u16)], x: usize, out: &mut [u16; C]) {
        let mut acc = [0u16; C];
        for &(row, k) in rows {
            let Some(Ok(b)) = row.get(x..x + C).map(<&[u8; C]>::try_from) else { continue };
            for l in 0..C {
                acc[l] = acc[l].wrapping_add(k.wrapping_mul(b[l] as u16));
            }
        }
        *out = acc;
    }
    let mut x = 0;
    while x + C <= n {
        #[cfg(target_arch = "x86_64")]
        for r in ahead.iter().flatten() {
            if let Some(b) = r.get(x) {
                // SAFETY: a prefetch only hints the cache, and `b` is inside the row.
                unsafe {
                    std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(b as *const u8 as *const i8)
                };
            }
        }
        if let Ok(o) = <&mut [u16; C]>::try_from(&mut out[x..x + C]) {
            chunk(rows, x, o);
        }
        x += C;
    }
    if x < n && n >= C {
        // One chunk aligned to the end; recomputes a few values.
        if let Ok(o) = <&mut [u16; C]>::try_from(&mut out[n - C..]) {
            chunk(rows, n - C, o);
        }
        x = n;
    }
    for (xx, o) in out.iter_mut().enumerate().skip(x) {
        *o = rows.iter().map(|&(row, k)| k.wrapping_mul(row[xx] as u16)).fold(0, u16::wrapping_add);
    }
}

/// 32 values of `out` at `x` from interleaved byte rows: `sum_taps w * byte / 255`.
#[inline(always)]
fn bytes_chunk<M: Madd>(src: &Plane<[u8; 3]>, x: usize, taps: &[(usize, f32)], out: &mut [f32]) {
    const Z: [u8; 32] = [0; 32];
    let Ok(out) = <&mut [f32; 32]>::try_from(&mut out[x..x + 32]) else { return };
    let mut acc = [0f32; 32];
    for &(r, wt) in taps {
        let row: &[u8; 32] = src.row(r).as_flattened()[x..x + 32].try_into().unwrap_or(&Z);
        let wt = wt * (1.0 / 255.0);
        for l in 0..32 {
            acc[l] = M::madd(wt, row[l] as f32, acc[l]);
        }
    }
    *out = acc;
}

/// Vertical low-pass of output row `j` straight from the interleaved bytes into `row3`
/// (values in [0, 1]), truncated and renormalized at the borders.
#[inline(always)]
fn vertical_bytes<M: Madd>(
    src: &Plane<[u8; 3]>,
    j: usize,
    h: usize,
    kernel: &PyramidKernel,
    taps: &mut Vec<(usize, f32)>,
    row3: &mut [f32],
) {
    kernel.taps_for(j, h, taps);
    let n = row3.len();
    let mut x = 0;
    while x + 32 <= n {
        bytes_chunk::<M>(src, x, taps, row3);
        x += 32;
    }
    if x < n && n >= 32 {
        // One chunk aligned to the end; recomputes a few values.
        bytes_chunk::<M>(src, n - 32, taps, row3);
        x = n;
    }
    for (xx, o) in row3.iter_mut().enumerate().skip(x) {
        *o = taps.iter().map(|&(r, wt)| wt * (1.0 / 255.0) * src.row(r).as_flattened()[xx] as f32).sum();
    }
}

dispatch_kernel!(fn pyr_down_rgb8_kernel => pyr_down_rgb8_generic(src: &Plane<[u8; 3]>, dst: [&mut Plane<f32>; 3], kernel: &PyramidKernel, s: &mut PyrScratch));

/// Allocating convenience wrapper of [`pyr_down`].
pub fn pyr_down_alloc(backend: Backend, src: &Plane<f32>, kernel: &PyramidKernel) -> Result<Plane<f32>> {
    let mut dst = Plane::default();
    pyr_down(backend, src, &mut dst, kernel, &mut PyrScratch::default())?;
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
