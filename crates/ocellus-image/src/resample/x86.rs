//! The horizontal step of resampling with vector gathers.
//!
//! Why by hand: each output reads two table-chosen samples of the row, which the compiler
//! leaves as scalar loads (about a nanosecond per output on the saliency engine's 42 maps
//! a frame, 6 % of it). Each output is the generic kernel's `fma(w, b - a, a)`, so the
//! results are the same bit for bit (tested).
//!
//! With AVX-512 the samples of 16 outputs usually lie within 64 of the row (every
//! upsampling, and downsampling by up to 4: all of the saliency engine's rescaling), so
//! four loads and two-source permutes pick them ([`columns_permute_avx512`]); with AVX2 those
//! of 8 within 16 ([`columns_avx2`], up to a factor of 2). Other blocks take gathers, which
//! are slow (a 512-bit one was slower than two 256-bit ones on both cores measured: the
//! rescaling stage of `bench saliency` 0.068 -> 0.055 ms a frame on an AMD EPYC, Zen 4).

use super::Columns;
use std::arch::x86_64::*;

/// The column step one output at a time (rows shorter than a vector).
#[inline(always)]
fn scalar_columns(cols: &Columns, row: &[f32], out: &mut [f32]) {
    for o in 0..out.len() {
        let (a, b) = (row[cols.i0[o] as usize], row[cols.i1[o] as usize]);
        out[o] = cols.w[o].mul_add(b - a, a);
    }
}

/// [`columns_avx2`] with 512-bit registers: per 16 outputs, when their samples lie within 64 of the
/// row (from the block's first `i0`), the four vectors there (masked at the row's end) and
/// two-source permutes give both samples of each output; a wider block takes two 256-bit
/// gathers (every block, for tables that are not monotonic). The same `fma(w, b - a, a)`, so
/// the same bits (tested). False (nothing written) for fewer than 16 outputs.
///
/// # Safety
/// The CPU must have AVX-512 F and DQ (and AVX2, FMA); `cols.max_index < row.len()` and the
/// tables at least `out.len()` long (the caller checks both).
#[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
pub(super) unsafe fn columns_permute_avx512(cols: &Columns, row: &[f32], out: &mut [f32]) -> bool {
    let n = out.len();
    if n < 16 {
        return false;
    }
    let len = row.len();
    // The row's floats from `start`, 16 of them, those past its end as zeros (a masked load
    // reads nothing there).
    #[inline(always)]
    unsafe fn window(row: &[f32], start: usize) -> __m512 {
        let left = row.len().saturating_sub(start);
        let mask: __mmask16 = if left >= 16 { 0xFFFF } else { ((1u32 << left) - 1) as __mmask16 };
        // SAFETY: the lanes read are the mask's, all inside the row.
        unsafe { _mm512_maskz_loadu_ps(mask, row.as_ptr().wrapping_add(start)) }
    }
    /// The samples at offsets `r` (0..64) of the window `v`: index bits 0-4 choose within a
    /// pair of vectors, bit 5 the pair. (Functions, not closures, so that they are compiled
    /// with the caller's target features.)
    #[inline(always)]
    unsafe fn pick(v: &[__m512; 4], r: __m512i) -> __m512 {
        // SAFETY: register operations only; the caller has AVX-512 F.
        unsafe {
            let lo = _mm512_permutex2var_ps(v[0], r, v[1]);
            let hi = _mm512_permutex2var_ps(v[2], r, v[3]);
            _mm512_mask_blend_ps(_mm512_cmpge_epi32_mask(r, _mm512_set1_epi32(32)), lo, hi)
        }
    }
    /// The samples at indices `i` of the row, by two 256-bit gathers.
    #[inline(always)]
    unsafe fn gather(row: &[f32], i: __m512i) -> __m512 {
        // SAFETY: the caller keeps every index inside the row; it has AVX-512 F and DQ.
        unsafe {
            let lo = _mm256_i32gather_ps::<4>(row.as_ptr(), _mm512_castsi512_si256(i));
            let hi = _mm256_i32gather_ps::<4>(row.as_ptr(), _mm512_extracti64x4_epi64::<1>(i));
            _mm512_insertf32x8::<1>(_mm512_castps256_ps512(lo), hi)
        }
    }
    let mut o = 0;
    // SAFETY: o0 + 16 <= n <= table lengths; every index is at most `max_index < len`, and
    // the window's loads are masked to the row.
    unsafe {
        while o < n {
            let o0 = o.min(n - 16);
            let base = cols.i0[o0] as usize;
            let top = cols.i1[o0 + 15] as usize;
            let w = _mm512_loadu_ps(cols.w.as_ptr().add(o0));
            let i0 = _mm512_loadu_si512(cols.i0.as_ptr().add(o0) as *const _);
            let i1 = _mm512_loadu_si512(cols.i1.as_ptr().add(o0) as *const _);
            let (a, b) = if cols.monotonic && top < base + 64 && top < len {
                let v = [window(row, base), window(row, base + 16), window(row, base + 32), window(row, base + 48)];
                let start = _mm512_set1_epi32(base as i32);
                (pick(&v, _mm512_sub_epi32(i0, start)), pick(&v, _mm512_sub_epi32(i1, start)))
            } else {
                (gather(row, i0), gather(row, i1))
            };
            _mm512_storeu_ps(out.as_mut_ptr().add(o0), _mm512_fmadd_ps(w, _mm512_sub_ps(b, a), a));
            o = o0 + 16;
        }
    }
    true
}

/// `out[o] = fma(w[o], row[i1[o]] - row[i0[o]], row[i0[o]])` for every output, 8 at a time
/// (the last 8 aligned to the end, recomputing a few outputs with the same values; shorter
/// rows one at a time): when the samples of 8 outputs lie within 16 of the row (every
/// upsampling and downsampling by up to 2), two loads (masked at the row's end) and in-lane
/// permutes give both samples of each output; other blocks, and every block of tables that
/// are not monotonic, take two gathers. The generic kernel's results bit for bit (tested).
///
/// # Safety
/// The CPU must have AVX2 and FMA; `cols.max_index < row.len()` and the tables at least
/// `out.len()` long (the caller checks both).
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn columns_avx2(cols: &Columns, row: &[f32], out: &mut [f32]) {
    let n = out.len();
    if n < 8 {
        scalar_columns(cols, row, out);
        return;
    }
    /// The row's floats from `start`, 8 of them, those past its end as zeros (a masked load
    /// reads nothing there).
    #[inline(always)]
    unsafe fn window(row: &[f32], start: usize) -> __m256 {
        let left = row.len().saturating_sub(start).min(8) as i32;
        // SAFETY: the lanes read are the mask's, all inside the row.
        unsafe {
            let mask = _mm256_cmpgt_epi32(_mm256_set1_epi32(left), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
            _mm256_maskload_ps(row.as_ptr().wrapping_add(start), mask)
        }
    }
    /// The samples at offsets `r` (0..16) of the window `v`: index bits 0-2 choose within a
    /// vector, bit 3 the vector.
    #[inline(always)]
    unsafe fn pick(v: [__m256; 2], r: __m256i) -> __m256 {
        // SAFETY: register operations only; the caller has AVX2.
        unsafe {
            let (lo, hi) = (_mm256_permutevar8x32_ps(v[0], r), _mm256_permutevar8x32_ps(v[1], r));
            _mm256_blendv_ps(lo, hi, _mm256_castsi256_ps(_mm256_cmpgt_epi32(r, _mm256_set1_epi32(7))))
        }
    }
    let len = row.len();
    let mut o = 0;
    // SAFETY: o0 + 8 <= n <= table lengths; every index is at most `max_index < len`, and
    // the window's loads are masked to the row.
    unsafe {
        while o < n {
            let o0 = o.min(n - 8);
            let base = cols.i0[o0] as usize;
            let top = cols.i1[o0 + 7] as usize;
            let w = _mm256_loadu_ps(cols.w.as_ptr().add(o0));
            let i0 = _mm256_loadu_si256(cols.i0.as_ptr().add(o0) as *const __m256i);
            let i1 = _mm256_loadu_si256(cols.i1.as_ptr().add(o0) as *const __m256i);
            let (a, b) = if cols.monotonic && top < base + 16 && top < len {
                let v = [window(row, base), window(row, base + 8)];
                let start = _mm256_set1_epi32(base as i32);
                (pick(v, _mm256_sub_epi32(i0, start)), pick(v, _mm256_sub_epi32(i1, start)))
            } else {
                (_mm256_i32gather_ps::<4>(row.as_ptr(), i0), _mm256_i32gather_ps::<4>(row.as_ptr(), i1))
            };
            _mm256_storeu_ps(out.as_mut_ptr().add(o0), _mm256_fmadd_ps(w, _mm256_sub_ps(b, a), a));
            o = o0 + 8;
        }
    }
}
