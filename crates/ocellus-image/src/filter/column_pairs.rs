//! The column pass of a separable filter with a clamped border, two output rows at a time,
//! hand-written for AVX2 and for AVX-512 from one body.
//!
//! Why: rows `y` and `y + 1` read the same input rows but one, so each loaded vector feeds
//! both rows' sums (half the loads per multiply-add), and the per-row set-up (the tap list,
//! the row pointers) is paid once per pair; the one-row kernels spent about as long on
//! loads and set-up as on arithmetic. Each output keeps the chain of fused multiply-adds of
//! `accumulate_rows_generic` with [`crate::simd::Fused`] (one chain in tap order over the
//! first `32 floor(w / 32)` outputs, then the same 8-wide tail), so the results are
//! bit-identical (tested).

use super::x86::{tail_quads, MAX_TAPS};
use crate::Plane;
use std::arch::x86_64::*;

/// Defines `$name(src, dst, k) -> bool`: the whole clamped column pass with `$v` registers
/// of `$lanes` floats, `$big` registers per row in the wide chunks.
macro_rules! column_pairs {
    ($(#[$m:meta])* $name:ident, $features:literal, $v:ty, $lanes:literal, $big:literal,
     $zero:ident, $set1:ident, $loadu:ident, $storeu:ident, $fmadd:ident) => {
        $(#[$m])*
        #[target_feature(enable = $features)]
        pub(super) unsafe fn $name(src: &Plane<f32>, dst: &mut Plane<f32>, k: &[f32]) -> bool {
            let (w, h) = src.size();
            let n = k.len();
            if w < 8 || n == 0 || n + 1 > MAX_TAPS || dst.size() != (w, h) || h == 0 {
                return false;
            }
            let hw = (n - 1) / 2;
            let n32 = w / 32 * 32;
            // Row pointers from the base and the stride: `src.row()` in a closure was a call
            // and a bounds check per tap and output row, a third of the pass on a 20x15 map.
            let (base, stride) = (src.as_slice().as_ptr(), src.stride());
            let mut ptrs = [std::ptr::null::<f32>(); MAX_TAPS];
            let mut y = 0;
            while y < h {
                let pair = y + 1 < h;
                for (t, p) in ptrs.iter_mut().enumerate().take(n + 1) {
                    let yy = (y as isize + t as isize - hw as isize).clamp(0, h as isize - 1) as usize;
                    *p = base.wrapping_add(yy * stride);
                }
                let o0 = dst.row_mut(y).as_mut_ptr();
                let o1 = if pair { dst.row_mut(y + 1).as_mut_ptr() } else { o0 };
                // SAFETY: every row holds w >= n32 values and the outputs too; each chunk
                // covers [x, x + L lanes) within n32; the tail keeps within w.
                unsafe {
                    let mut x = 0;
                    if pair {
                        while x + $big * $lanes <= n32 {
                            pair_chunk::<$big>(&ptrs[..n + 1], k, o0, o1, x);
                            x += $big * $lanes;
                        }
                        // What is left in as few chunks as possible: one register per
                        // row is only two chains, too few to hide the latency.
                        if x + 4 * $lanes <= n32 {
                            pair_chunk::<4>(&ptrs[..n + 1], k, o0, o1, x);
                            x += 4 * $lanes;
                        }
                        if x + 2 * $lanes <= n32 {
                            pair_chunk::<2>(&ptrs[..n + 1], k, o0, o1, x);
                            x += 2 * $lanes;
                        }
                        while x + $lanes <= n32 {
                            pair_chunk::<1>(&ptrs[..n + 1], k, o0, o1, x);
                            x += $lanes;
                        }
                        tail_quads(&ptrs[1..n + 1], k, o1, n32, w);
                    } else {
                        while x + $lanes <= n32 {
                            one_chunk(&ptrs[..n], k, o0, x);
                            x += $lanes;
                        }
                    }
                    tail_quads(&ptrs[..n], k, o0, n32, w);
                }
                y += if pair { 2 } else { 1 };
            }
            return true;

            /// `L` vectors of outputs of two consecutive rows: `a` sums `k[t] r[t]` for
            /// t < n, `b` sums `k[t - 1] r[t]` for 1 <= t <= n (`ptrs` holds n + 1 rows).
            #[inline(always)]
            unsafe fn pair_chunk<const L: usize>(ptrs: &[*const f32], k: &[f32], o0: *mut f32, o1: *mut f32, x: usize) {
                let n = k.len();
                // SAFETY: the caller keeps x + L lanes within every row and both outputs.
                unsafe {
                    let mut a: [$v; L] = [$zero(); L];
                    let mut b: [$v; L] = [$zero(); L];
                    let first = $set1(k[0]);
                    for (j, a) in a.iter_mut().enumerate() {
                        *a = $fmadd(first, $loadu(ptrs[0].add(x + $lanes * j)), *a);
                    }
                    for t in 1..n {
                        let (wa, wb) = ($set1(k[t]), $set1(k[t - 1]));
                        let p = ptrs[t];
                        for j in 0..L {
                            let v = $loadu(p.add(x + $lanes * j));
                            a[j] = $fmadd(wa, v, a[j]);
                            b[j] = $fmadd(wb, v, b[j]);
                        }
                    }
                    let last = $set1(k[n - 1]);
                    for (j, b) in b.iter_mut().enumerate() {
                        *b = $fmadd(last, $loadu(ptrs[n].add(x + $lanes * j)), *b);
                    }
                    for j in 0..L {
                        $storeu(o0.add(x + $lanes * j), a[j]);
                        $storeu(o1.add(x + $lanes * j), b[j]);
                    }
                }
            }

            /// One vector of outputs of one row: `sum_t k[t] r[t]`, one chain.
            #[inline(always)]
            unsafe fn one_chunk(ptrs: &[*const f32], k: &[f32], o: *mut f32, x: usize) {
                // SAFETY: the caller keeps x + lanes within every row and the output.
                unsafe {
                    let mut a: $v = $zero();
                    for (&p, &w) in ptrs.iter().zip(k) {
                        a = $fmadd($set1(w), $loadu(p.add(x)), a);
                    }
                    $storeu(o.add(x), a);
                }
            }
        }
    };
}

column_pairs!(
    /// The clamped column pass with 256-bit registers, four per row in the wide chunks (eight
    /// chains). False (nothing written) for fewer than 8 columns or more than `MAX_TAPS - 1`
    /// taps.
    cols_clamp_avx2, "avx2,fma", __m256, 8, 4,
    _mm256_setzero_ps, _mm256_set1_ps, _mm256_loadu_ps, _mm256_storeu_ps, _mm256_fmadd_ps
);

column_pairs!(
    /// The clamped column pass with 512-bit registers, five per row in the wide chunks (ten
    /// chains). False (nothing written) for fewer than 8 columns or more than `MAX_TAPS - 1`
    /// taps.
    cols_clamp_avx512, "avx512f,avx2,fma", __m512, 16, 5,
    _mm512_setzero_ps, _mm512_set1_ps, _mm512_loadu_ps, _mm512_storeu_ps, _mm512_fmadd_ps
);
