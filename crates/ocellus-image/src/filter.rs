//! Separable correlation with explicit border rules, and the energy-preserving variant
//! (kernel truncated at the border and renormalized so the edge creates no false maxima).
//!
//! Kernels are correlated, not flipped: `out[x] = sum_t k[t] * in[x + t - hw]` with
//! `hw = (len - 1) / 2`. For the symmetric and antisymmetric kernels used in ocellus the
//! difference to convolution is at most a sign.

use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, ImageError, Plane, Result};

/// What lies outside the image for a filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Border {
    /// Zeros (MATLAB's `conv2(..., 'same')`).
    Zero,
    /// The nearest edge pixel ("clamp to edge", as the seed's texture fetch).
    Clamp,
}

/// Reusable buffers for the separable filters (grow once, then no allocation).
#[derive(Default, Debug, Clone)]
pub struct FilterScratch {
    padded: Vec<f32>,
    tmp: Plane<f32>,
    rows: Vec<(usize, f32)>,
}

const CHUNK: usize = 32;

/// Sum over taps `i` of `w(i) * s(i)[0..8]` with four independent chains (taps dealt in
/// groups of four), so the multiply-add latency does not serialize short rows.
#[inline(always)]
fn dot8<'a, M: Madd>(n: usize, w: impl Fn(usize) -> f32, s: impl Fn(usize) -> &'a [f32; 8]) -> [f32; 8] {
    let (mut a0, mut a1, mut a2, mut a3) = ([0f32; 8], [0f32; 8], [0f32; 8], [0f32; 8]);
    let mut t = 0;
    while t + 4 <= n {
        let (s0, s1, s2, s3) = (s(t), s(t + 1), s(t + 2), s(t + 3));
        let (w0, w1, w2, w3) = (w(t), w(t + 1), w(t + 2), w(t + 3));
        for l in 0..8 {
            a0[l] = M::madd(w0, s0[l], a0[l]);
            a1[l] = M::madd(w1, s1[l], a1[l]);
            a2[l] = M::madd(w2, s2[l], a2[l]);
            a3[l] = M::madd(w3, s3[l], a3[l]);
        }
        t += 4;
    }
    while t < n {
        let (s0, w0) = (s(t), w(t));
        for l in 0..8 {
            a0[l] = M::madd(w0, s0[l], a0[l]);
        }
        t += 1;
    }
    let mut out = [0f32; 8];
    for l in 0..8 {
        out[l] = (a0[l] + a1[l]) + (a2[l] + a3[l]);
    }
    out
}

/// Sum over taps `i` of `w(i) * s(i)[0..32]` (four 256-bit chains).
#[inline(always)]
fn dot32<'a, M: Madd>(n: usize, w: impl Fn(usize) -> f32, s: impl Fn(usize) -> &'a [f32; CHUNK]) -> [f32; CHUNK] {
    let mut acc = [0f32; CHUNK];
    for t in 0..n {
        let (st, wt) = (s(t), w(t));
        for l in 0..CHUNK {
            acc[l] = M::madd(wt, st[l], acc[l]);
        }
    }
    acc
}

/// `out[x] = sum_t k[t] * p[x + t]` for `x < out.len()`; `p.len() >= out.len() + k.len() - 1`.
#[inline(always)]
pub(crate) fn correlate_padded_generic<M: Madd>(p: &[f32], k: &[f32], out: &mut [f32]) {
    const Z32: [f32; CHUNK] = [0.0; CHUNK];
    const Z8: [f32; 8] = [0.0; 8];
    let n = out.len();
    let mut x = 0;
    while x + CHUNK <= n {
        let acc = dot32::<M>(k.len(), |t| k[t], |t| p[x + t..x + t + CHUNK].try_into().unwrap_or(&Z32));
        out[x..x + CHUNK].copy_from_slice(&acc);
        x += CHUNK;
    }
    // 8 at a time, the last chunk aligned to the end (recomputes a few outputs).
    while x < n && n >= 8 {
        let x0 = if x + 8 <= n { x } else { n - 8 };
        let acc = dot8::<M>(k.len(), |t| k[t], |t| p[x0 + t..x0 + t + 8].try_into().unwrap_or(&Z8));
        out[x0..x0 + 8].copy_from_slice(&acc);
        x = x0 + 8;
    }
    while x < n {
        let mut acc = 0f32;
        for (t, &kt) in k.iter().enumerate() {
            acc = M::madd(kt, p[x + t], acc);
        }
        out[x] = acc;
        x += 1;
    }
}

dispatch_kernel!(
    /// `out[x] = sum_t k[t] * p[x + t]`: correlation of a pre-padded row.
    pub fn correlate_padded => correlate_padded_generic(p: &[f32], k: &[f32], out: &mut [f32])
);

/// `out[x] = sum_i w_i * src.row(r_i)[x]` over `rows = [(r_i, w_i)]`.
#[inline(always)]
pub(crate) fn accumulate_rows_generic<M: Madd>(src: &Plane<f32>, rows: &[(usize, f32)], out: &mut [f32]) {
    const Z32: [f32; CHUNK] = [0.0; CHUNK];
    const Z8: [f32; 8] = [0.0; 8];
    let n = out.len();
    let mut x = 0;
    while x + CHUNK <= n {
        let acc =
            dot32::<M>(rows.len(), |i| rows[i].1, |i| src.row(rows[i].0)[x..x + CHUNK].try_into().unwrap_or(&Z32));
        out[x..x + CHUNK].copy_from_slice(&acc);
        x += CHUNK;
    }
    while x < n && n >= 8 {
        let x0 = if x + 8 <= n { x } else { n - 8 };
        let acc = dot8::<M>(rows.len(), |i| rows[i].1, |i| src.row(rows[i].0)[x0..x0 + 8].try_into().unwrap_or(&Z8));
        out[x0..x0 + 8].copy_from_slice(&acc);
        x = x0 + 8;
    }
    while x < n {
        let mut acc = 0f32;
        for &(r, w) in rows {
            acc = M::madd(w, src.row(r)[x], acc);
        }
        out[x] = acc;
        x += 1;
    }
}

dispatch_kernel!(
    /// `out[x] = sum_i w_i * src.row(r_i)[x]`: a weighted sum of rows.
    pub fn accumulate_rows => accumulate_rows_best(src: &Plane<f32>, rows: &[(usize, f32)], out: &mut [f32])
);

/// Symmetry of a centred kernel: `k[h+t] = k[h-t]` (even) or `k[h+t] = -k[h-t]` (odd).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symmetry {
    /// Even: `k[h+t] == k[h-t]`.
    Even,
    /// Odd: `k[h+t] == -k[h-t]` (and `k[h] == 0`).
    Odd,
    /// Neither.
    None,
}

/// The symmetry of `k` (exact comparison; odd length assumed).
pub fn symmetry(k: &[f32]) -> Symmetry {
    let h = k.len() / 2;
    if (1..=h).all(|t| k[h + t] == k[h - t]) {
        Symmetry::Even
    } else if k[h] == 0.0 && (1..=h).all(|t| k[h + t] == -k[h - t]) {
        Symmetry::Odd
    } else {
        Symmetry::None
    }
}

/// Output x of a folded correlation over `n` outputs, reading value `i` of pair `t` through
/// `plus(t, x0)` / `minus(t, x0)` slices of length L: `k[h] c + sum_t k[h+t] (plus ± minus)`.
#[inline(always)]
fn fold_chunk<'a, M: Madd, const L: usize>(
    k: &[f32],
    odd: bool,
    centre: &'a [f32; L],
    plus: impl Fn(usize) -> &'a [f32; L],
    minus: impl Fn(usize) -> &'a [f32; L],
) -> [f32; L] {
    let h = k.len() / 2;
    let mut acc = [0f32; L];
    if !odd {
        for l in 0..L {
            acc[l] = k[h] * centre[l];
        }
    }
    for t in 1..=h {
        let (sp, sm, kt) = (plus(t), minus(t), k[h + t]);
        if odd {
            for l in 0..L {
                acc[l] = M::madd(kt, sp[l] - sm[l], acc[l]);
            }
        } else {
            for l in 0..L {
                acc[l] = M::madd(kt, sp[l] + sm[l], acc[l]);
            }
        }
    }
    acc
}

/// Folded correlation of a padded row: `out[x] = sum_t k[t] p[x + t]` for an even or odd `k`.
#[inline(always)]
fn correlate_folded_generic<M: Madd>(p: &[f32], k: &[f32], odd: bool, out: &mut [f32]) {
    const Z32: [f32; CHUNK] = [0.0; CHUNK];
    const Z8: [f32; 8] = [0.0; 8];
    let h = k.len() / 2;
    let n = out.len();
    let mut x = 0;
    while x + CHUNK <= n {
        let c: &[f32; CHUNK] = p[x + h..x + h + CHUNK].try_into().unwrap_or(&Z32);
        let acc = fold_chunk::<M, CHUNK>(
            k,
            odd,
            c,
            |t| p[x + h + t..x + h + t + CHUNK].try_into().unwrap_or(&Z32),
            |t| p[x + h - t..x + h - t + CHUNK].try_into().unwrap_or(&Z32),
        );
        out[x..x + CHUNK].copy_from_slice(&acc);
        x += CHUNK;
    }
    while x < n && n >= 8 {
        let x0 = if x + 8 <= n { x } else { n - 8 };
        let c: &[f32; 8] = p[x0 + h..x0 + h + 8].try_into().unwrap_or(&Z8);
        let acc = fold_chunk::<M, 8>(
            k,
            odd,
            c,
            |t| p[x0 + h + t..x0 + h + t + 8].try_into().unwrap_or(&Z8),
            |t| p[x0 + h - t..x0 + h - t + 8].try_into().unwrap_or(&Z8),
        );
        out[x0..x0 + 8].copy_from_slice(&acc);
        x = x0 + 8;
    }
    while x < n {
        out[x] = k.iter().enumerate().map(|(t, &kt)| kt * p[x + t]).sum();
        x += 1;
    }
}

/// Any kernel on a padded row, folded when it is even or odd.
#[inline(always)]
pub(crate) fn correlate_any_generic<M: Madd>(p: &[f32], k: &[f32], sym: Symmetry, out: &mut [f32]) {
    match sym {
        Symmetry::Even => correlate_folded_generic::<M>(p, k, false, out),
        Symmetry::Odd => correlate_folded_generic::<M>(p, k, true, out),
        Symmetry::None => correlate_padded_generic::<M>(p, k, out),
    }
}

pub(crate) fn check_kernel(k: &[f32], what: &str) -> Result<()> {
    if k.is_empty() || k.len().is_multiple_of(2) {
        return Err(ImageError::InvalidParameter(format!(
            "{what} kernel has {} taps: a centred kernel needs an odd number",
            k.len()
        )));
    }
    if k.iter().any(|v| !v.is_finite()) {
        return Err(ImageError::InvalidParameter(format!("{what} kernel has a non-finite tap")));
    }
    Ok(())
}

/// Fills `p` with `row` (as f32) padded by `hw` values on each side according to `border`.
/// Inlined so that the conversion is compiled with the calling kernel's features.
#[inline(always)]
fn pad_row<T: Copy + Into<f32>>(row: &[T], hw: usize, border: Border, p: &mut Vec<f32>) {
    // Resized, not cleared and refilled: every element is written below, and zeroing the
    // whole row first was a tenth of a smoothing pass.
    p.resize(row.len() + 2 * hw, 0.0);
    pad_into(row, hw, border, p);
}

/// [`pad_row`] into a slice of exactly `row.len() + 2 hw` values.
#[inline(always)]
fn pad_into<T: Copy + Into<f32>>(row: &[T], hw: usize, border: Border, p: &mut [f32]) {
    let w = row.len();
    for (o, &v) in p[hw..hw + w].iter_mut().zip(row) {
        *o = v.into();
    }
    let (first, last) = match border {
        Border::Clamp if w > 0 => (row[0].into(), row[w - 1].into()),
        _ => (0.0, 0.0),
    };
    p[..hw].fill(first);
    p[hw + w..].fill(last);
}

/// Sizes `padded` for a row of `w` values padded by `hw` on each side and returns where the
/// padded row starts in it: output 0's centre (`start + hw`) on a cache-line boundary, with
/// room for the aligned vectors the AVX-512 folded kernels read on both sides.
fn aligned_padding(padded: &mut Vec<f32>, w: usize, hw: usize) -> usize {
    padded.resize(w + 2 * hw + 96, 0.0);
    let first = padded.as_ptr() as usize / 4 + hw;
    16 + (16 - first % 16) % 16
}

/// Row list for output row `y` of a vertical pass with kernel `k` (centred).
pub(crate) fn vertical_taps(y: usize, h: usize, k: &[f32], border: Border, rows: &mut Vec<(usize, f32)>) {
    let hw = (k.len() - 1) / 2;
    rows.clear();
    for (t, &kt) in k.iter().enumerate() {
        let yy = y as isize + t as isize - hw as isize;
        let r = match border {
            Border::Zero if yy < 0 || yy >= h as isize => continue,
            Border::Zero => yy as usize,
            Border::Clamp => yy.clamp(0, h as isize - 1) as usize,
        };
        rows.push((r, kt));
    }
}

/// Every row of the rectangle `[x0, y0, x1, y1]` (checked) of `src`, converted to f32 as it
/// is padded, through `kx` into row `y - y0` of `dst`: the row pass of [`filter_rows`] (the
/// whole plane) and of [`sep_filter_u8`] (a rectangle of bytes).
#[inline(always)]
fn rows_pass<M: Madd, T: Copy + Default + Into<f32>>(
    src: &Plane<T>,
    [x0, y0, x1, y1]: [usize; 4],
    dst: &mut Plane<f32>,
    kx: &[f32],
    border: Border,
    padded: &mut Vec<f32>,
) {
    let hwx = (kx.len() - 1) / 2;
    let sym = symmetry(kx);
    #[cfg(target_arch = "x86_64")]
    if M::AVX512 && sym != Symmetry::None && hwx <= x86::FOLDED_512_MAX_HALF {
        let w = x1 - x0;
        let start = aligned_padding(padded, w, hwx);
        for y in y0..y1 {
            pad_into(&src.row(y)[x0..x1], hwx, border, &mut padded[start..start + w + 2 * hwx]);
            // SAFETY: `M::AVX512` is true only inside kernels compiled for AVX-512, which
            // `dispatch_kernel!` calls only on CPUs that have it.
            let done =
                unsafe { x86::correlate_folded_avx512(padded, start, kx, sym == Symmetry::Odd, dst.row_mut(y - y0)) };
            if !done {
                correlate_row::<M>(&padded[start..start + w + 2 * hwx], kx, sym, dst.row_mut(y - y0));
            }
        }
        return;
    }
    for y in y0..y1 {
        pad_row(&src.row(y)[x0..x1], hwx, border, padded);
        correlate_row::<M>(padded, kx, sym, dst.row_mut(y - y0));
    }
}

#[inline(always)]
fn filter_rows_generic<M: Madd>(
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
    kx: &[f32],
    border: Border,
    padded: &mut Vec<f32>,
) {
    rows_pass::<M, f32>(src, [0, 0, src.width(), src.height()], dst, kx, border, padded);
}

/// One padded row through `kx` (of symmetry `sym`): the hand-written kernel where it applies.
#[inline(always)]
fn correlate_row<M: Madd>(padded: &[f32], kx: &[f32], sym: Symmetry, out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if M::AVX2 && sym != Symmetry::None {
        // SAFETY: as in `filter_cols_generic`.
        if unsafe { x86::correlate_folded_avx2(padded, kx, sym == Symmetry::Odd, out) } {
            return;
        }
    }
    correlate_any_generic::<M>(padded, kx, sym, out);
}

dispatch_kernel!(fn filter_rows_kernel => filter_rows_generic(
    src: &Plane<f32>, dst: &mut Plane<f32>, kx: &[f32], border: Border, padded: &mut Vec<f32>
));

#[inline(always)]
fn filter_rows_u8_generic<M: Madd>(
    src: &Plane<u8>,
    rect: [usize; 4],
    dst: &mut Plane<f32>,
    kx: &[f32],
    border: Border,
    padded: &mut Vec<f32>,
) {
    rows_pass::<M, u8>(src, rect, dst, kx, border, padded);
}

dispatch_kernel!(fn filter_rows_u8_kernel => filter_rows_u8_generic(
    src: &Plane<u8>, rect: [usize; 4], dst: &mut Plane<f32>, kx: &[f32], border: Border, padded: &mut Vec<f32>
));

#[inline(always)]
fn filter_cols_generic<M: Madd>(
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
    ky: &[f32],
    border: Border,
    rows: &mut Vec<(usize, f32)>,
) {
    let h = src.height();
    #[cfg(target_arch = "x86_64")]
    if border == Border::Clamp {
        // SAFETY: `M::AVX512` (`M::AVX2`) is true only inside kernels compiled for AVX-512
        // (AVX2 and FMA), which `dispatch_kernel!` calls only on CPUs that have them.
        let done = if M::AVX512 {
            unsafe { column_pairs::cols_clamp_avx512(src, dst, ky) }
        } else {
            M::AVX2 && unsafe { column_pairs::cols_clamp_avx2(src, dst, ky) }
        };
        if done {
            return;
        }
    }
    for y in 0..h {
        vertical_taps(y, h, ky, border, rows);
        accumulate_rows_best::<M>(src, rows, dst.row_mut(y));
    }
}

/// [`accumulate_rows_generic`] through the hand-written kernel of the build where one
/// applies (the same results bit for bit).
#[inline(always)]
pub(crate) fn accumulate_rows_best<M: Madd>(src: &Plane<f32>, rows: &[(usize, f32)], out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if M::AVX512 {
        // SAFETY: `M::AVX512` is true only inside kernels compiled for AVX-512 (with AVX2
        // and FMA), which `dispatch_kernel!` calls only on CPUs that have them.
        if unsafe { x86::accumulate_rows_avx512(src, rows, out) } {
            return;
        }
    }
    #[cfg(target_arch = "x86_64")]
    if M::AVX2 {
        // SAFETY: `M::AVX2` is true only inside kernels compiled for AVX2 and FMA, which
        // `dispatch_kernel!` calls only on CPUs that have both.
        if unsafe { x86::accumulate_rows_avx2(src, rows, out) } {
            return;
        }
    }
    accumulate_rows_generic::<M>(src, rows, out);
}

dispatch_kernel!(fn filter_cols_kernel => filter_cols_generic(
    src: &Plane<f32>, dst: &mut Plane<f32>, ky: &[f32], border: Border, rows: &mut Vec<(usize, f32)>
));

#[cfg(target_arch = "x86_64")]
mod bank;
mod column_pairs;
pub use bank::filter_rows_bank;
#[cfg(target_arch = "x86_64")]
mod x86;

/// Correlates every row of `src` with `kx` (centred), `dst` resized to `src`.
pub fn filter_rows(
    backend: Backend,
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
    kx: &[f32],
    border: Border,
    scratch: &mut FilterScratch,
) -> Result<()> {
    check_kernel(kx, "horizontal")?;
    dst.resize(src.width(), src.height());
    filter_rows_kernel(backend, src, dst, kx, border, &mut scratch.padded);
    Ok(())
}

/// Correlates every column of `src` with `ky` (centred), `dst` resized to `src`.
pub fn filter_cols(
    backend: Backend,
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
    ky: &[f32],
    border: Border,
    scratch: &mut FilterScratch,
) -> Result<()> {
    check_kernel(ky, "vertical")?;
    dst.resize(src.width(), src.height());
    filter_cols_kernel(backend, src, dst, ky, border, &mut scratch.rows);
    Ok(())
}

/// Separable correlation: rows with `kx`, then columns with `ky`, `dst` resized to `src`.
pub fn sep_filter(
    backend: Backend,
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
    kx: &[f32],
    ky: &[f32],
    border: Border,
    scratch: &mut FilterScratch,
) -> Result<()> {
    let mut tmp = std::mem::take(&mut scratch.tmp);
    let r = filter_rows(backend, src, &mut tmp, kx, border, scratch)
        .and_then(|_| filter_cols(backend, &tmp, dst, ky, border, scratch));
    scratch.tmp = tmp;
    r
}

/// [`sep_filter`] of the rectangle `rect` = `[x0, y0, x1, y1]` (pixels, end exclusive) of an
/// 8-bit plane, as if that rectangle were a plane of its own converted to f32 grey levels
/// (the border rule acts at the rectangle's edges); `dst` resized to the rectangle. The same
/// values as converting first, without the converted copy.
#[allow(clippy::too_many_arguments)]
pub fn sep_filter_u8(
    backend: Backend,
    src: &Plane<u8>,
    rect: [usize; 4],
    dst: &mut Plane<f32>,
    kx: &[f32],
    ky: &[f32],
    border: Border,
    scratch: &mut FilterScratch,
) -> Result<()> {
    let [x0, y0, x1, y1] = rect;
    let (w, h) = src.size();
    if !(x0 < x1 && y0 < y1 && x1 <= w && y1 <= h) {
        return Err(ImageError::InvalidParameter(format!("rectangle {rect:?} is empty or outside the {w}x{h} plane")));
    }
    check_kernel(kx, "horizontal")?;
    check_kernel(ky, "vertical")?;
    let mut tmp = std::mem::take(&mut scratch.tmp);
    tmp.resize(x1 - x0, y1 - y0);
    filter_rows_u8_kernel(backend, src, rect, &mut tmp, kx, border, &mut scratch.padded);
    let r = filter_cols(backend, &tmp, dst, ky, border, scratch);
    scratch.tmp = tmp;
    r
}

/// Separable Gaussian blur (clamped border, kernel cut at 3 sigma, normalized to sum 1);
/// `sigma` in pixels; sigma < 0.3 returns a copy (the kernel would be a single tap).
pub fn gaussian_blur(backend: Backend, src: &Plane<f32>, sigma: f32) -> Result<Plane<f32>> {
    if !(sigma.is_finite() && sigma >= 0.0) {
        return Err(ImageError::InvalidParameter(format!("blur sigma {sigma} must be finite and >= 0")));
    }
    let Some(k) = gaussian_kernel(sigma) else {
        return Ok(src.clone());
    };
    let mut out = Plane::default();
    sep_filter(backend, src, &mut out, &k, &k, Border::Clamp, &mut FilterScratch::default())?;
    Ok(out)
}

/// The taps of [`gaussian_blur`]'s kernel for `sigma` (pixels): half-width `ceil(3 sigma)`,
/// summing to 1; `None` below 0.3 px, where the blur is a copy (and for a sigma that is not
/// finite and >= 0).
pub fn gaussian_kernel(sigma: f32) -> Option<Vec<f32>> {
    if !(sigma.is_finite() && sigma >= 0.3) {
        return None;
    }
    let hw = (3.0 * sigma).ceil() as i32;
    let mut k: Vec<f32> = (-hw..=hw).map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp()).collect();
    let s: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    Some(k)
}

/// Direct 2D correlation (slow reference): `out(x,y) = sum k(i,j) in(x+i-hw, y+j-hh)`.
/// `k` is row-major `kw` x `kh`, both odd.
pub fn correlate_2d_direct(src: &Plane<f32>, k: &[f32], kw: usize, kh: usize, border: Border) -> Plane<f32> {
    let (w, h) = src.size();
    let (hx, hy) = ((kw as isize - 1) / 2, (kh as isize - 1) / 2);
    Plane::from_fn(w, h, |x, y| {
        let mut acc = 0f64;
        for j in 0..kh as isize {
            for i in 0..kw as isize {
                let (xx, yy) = (x as isize + i - hx, y as isize + j - hy);
                let v = match border {
                    Border::Zero if xx < 0 || yy < 0 || xx >= w as isize || yy >= h as isize => 0.0,
                    Border::Zero => src.get(xx as usize, yy as usize),
                    Border::Clamp => {
                        src.get(xx.clamp(0, w as isize - 1) as usize, yy.clamp(0, h as isize - 1) as usize)
                    }
                };
                acc += k[(j * kw as isize + i) as usize] as f64 * v as f64;
            }
        }
        acc as f32
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hand-written AVX2 and AVX-512 passes give the generic kernels' results bit for bit (the same
    /// fused multiply-add chain per output), over widths around every chunk size and kernels
    /// even, odd and longer than the hand-written column pass takes.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn hand_written_passes_equal_the_generic_kernels_bit_for_bit() {
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            return;
        }
        let mut rng = crate::rng::SplitMix64::new(11);
        for taps in [1usize, 3, 5, 11, 29, 31, 33, 67] {
            let h = taps / 2;
            let half: Vec<f32> = (0..=h).map(|_| rng.unit() as f32 - 0.3).collect();
            let even: Vec<f32> = (0..taps).map(|t| half[t.abs_diff(h)]).collect();
            let odd: Vec<f32> = (0..taps)
                .map(|t| {
                    if t < h {
                        -half[h - t]
                    } else if t == h {
                        0.0
                    } else {
                        half[t - h]
                    }
                })
                .collect();
            for w in [7usize, 8, 9, 15, 16, 17, 31, 32, 33, 36, 63, 64, 65, 100, 129, 160, 424] {
                let src = Plane::from_fn(w, taps + 3, |_, _| (rng.unit() * 255.0) as f32);
                let mut rows = Vec::new();
                // The whole column pass as the AVX2 and AVX-512 builds run it (two rows at a
                // time).
                let whole = |b: Backend| {
                    let mut all = Plane::default();
                    if b.resolve() == b {
                        filter_cols(b, &src, &mut all, &even, Border::Clamp, &mut FilterScratch::default())
                            .unwrap_or_else(|e| panic!("{e}"));
                    }
                    all
                };
                let (all256, all) = (whole(Backend::Avx2), whole(Backend::Avx512));
                // The same rows at a stride that is not a multiple of 16 floats: each row starts
                // at another offset within a cache line.
                let mut strided = vec![0f32; (w + 3) * src.height()];
                for y in 0..src.height() {
                    strided[y * (w + 3)..y * (w + 3) + w].copy_from_slice(src.row(y));
                }
                let sub =
                    Plane::from_vec_with_stride(w, src.height(), w + 3, strided).unwrap_or_else(|e| panic!("{e}"));
                for y in 0..src.height() {
                    vertical_taps(y, src.height(), &even, Border::Clamp, &mut rows);
                    let (mut want, mut got) = (vec![0f32; w], vec![f32::NAN; w]);
                    accumulate_rows_generic::<crate::simd::Fused>(&src, &rows, &mut want);
                    let same = want.iter().zip(all256.row(y)).all(|(a, b)| a.to_bits() == b.to_bits());
                    assert!(same, "column pass (256), {taps} taps, width {w}, row {y}");
                    // SAFETY: AVX2 and FMA were checked above.
                    if unsafe { x86::accumulate_rows_avx2(&src, &rows, &mut got) } {
                        assert!(taps <= 64 && w >= 8);
                        let same = want.iter().zip(&got).all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "columns, {taps} taps, width {w}");
                    } else {
                        assert!(taps > 64 || w < 8, "columns refused {taps} taps at width {w}");
                    }
                    if crate::simd::avx512_available() {
                        let same = want.iter().zip(all.row(y)).all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "column pass (512), {taps} taps, width {w}, row {y}");
                        for (name, plane) in [("aligned", &src), ("strided", &sub)] {
                            let mut got = vec![f32::NAN; w];
                            // SAFETY: AVX-512 was checked just above.
                            if unsafe { x86::accumulate_rows_avx512(plane, &rows, &mut got) } {
                                let same = want.iter().zip(&got).all(|(a, b)| a.to_bits() == b.to_bits());
                                assert!(same, "columns (512, {name}), {taps} taps, width {w}");
                            } else {
                                assert!(taps > 64 || w < 8, "512 refused {taps} taps at width {w}");
                            }
                        }
                    }
                }
                let mut p = Vec::new();
                pad_row(src.row(1), h, Border::Clamp, &mut p);
                for (k, is_odd) in [(&even, false), (&odd, true)] {
                    let (mut want, mut got) = (vec![0f32; w], vec![f32::NAN; w]);
                    correlate_folded_generic::<crate::simd::Fused>(&p, k, is_odd, &mut want);
                    // SAFETY: AVX2 and FMA were checked above.
                    if unsafe { x86::correlate_folded_avx2(&p, k, is_odd, &mut got) } {
                        let same = want.iter().zip(&got).all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "rows, {taps} taps (odd: {is_odd}), width {w}");
                    } else {
                        assert!(w < 8, "rows refused {taps} taps at width {w}");
                    }
                    if crate::simd::avx512_available() {
                        // The whole row pass as the AVX-512 build runs it (aligned layout).
                        let mut all = Plane::default();
                        filter_rows(Backend::Avx512, &src, &mut all, k, Border::Clamp, &mut FilterScratch::default())
                            .unwrap_or_else(|e| panic!("{e}"));
                        let same = want.iter().zip(all.row(1)).all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "rows (512), {taps} taps (odd: {is_odd}), width {w}");
                    }
                }
            }
        }
    }
}
