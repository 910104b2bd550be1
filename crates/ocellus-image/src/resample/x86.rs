//! The horizontal step of resampling with vector gathers.
//!
//! Why by hand: each output reads two table-chosen samples of the row, which the compiler
//! leaves as scalar loads (about a nanosecond per output on the saliency engine's 42 maps
//! a frame, 6 % of it). Each output is the generic kernel's `fma(w, b - a, a)`, so the
//! results are the same bit for bit (tested).
//!
//! 256-bit gathers in every build: a 512-bit form was slower on both cores measured (the
//! rescaling stage of `bench saliency` 0.068 -> 0.055 ms a frame with the 256-bit one in the
//! AVX-512 build on an AMD EPYC, Zen 4; an Intel Xeon's AVX2 build rescaled in 0.05 ms
//! against its AVX-512 build's 0.07).

use super::Columns;
use std::arch::x86_64::*;

/// Outputs `from..` of the column step, one at a time (rows shorter than a vector).
#[inline(always)]
fn scalar_columns(cols: &Columns, row: &[f32], out: &mut [f32], from: usize) {
    for o in from..out.len() {
        let (a, b) = (row[cols.i0[o] as usize], row[cols.i1[o] as usize]);
        out[o] = cols.w[o].mul_add(b - a, a);
    }
}

/// `out[o] = fma(w[o], row[i1[o]] - row[i0[o]], row[i0[o]])` for every output, 8 at a time.
///
/// # Safety
/// The CPU must have AVX2 and FMA; `cols.max_index < row.len()` and the tables at least
/// `out.len()` long (the caller checks both).
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn columns_avx2(cols: &Columns, row: &[f32], out: &mut [f32]) {
    let n = out.len();
    let mut o = 0;
    // SAFETY: every index is at most `max_index < row.len()`, and o0 + 8 <= n <= table lengths.
    unsafe {
        // 8 at a time, the last 8 aligned to the end (recomputing a few outputs, with the
        // same values).
        while o < n && n >= 8 {
            let o0 = o.min(n - 8);
            let i0 = _mm256_loadu_si256(cols.i0.as_ptr().add(o0) as *const __m256i);
            let i1 = _mm256_loadu_si256(cols.i1.as_ptr().add(o0) as *const __m256i);
            let w = _mm256_loadu_ps(cols.w.as_ptr().add(o0));
            let a = _mm256_i32gather_ps::<4>(row.as_ptr(), i0);
            let b = _mm256_i32gather_ps::<4>(row.as_ptr(), i1);
            _mm256_storeu_ps(out.as_mut_ptr().add(o0), _mm256_fmadd_ps(w, _mm256_sub_ps(b, a), a));
            o = o0 + 8;
        }
    }
    scalar_columns(cols, row, out, o);
}
