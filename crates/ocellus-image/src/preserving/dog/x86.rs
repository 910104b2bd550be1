//! The fused step of the iterative difference of Gaussians with AVX-512 and AVX2 (see
//! `dog_step_lanes`).

use super::super::x86::{blocks, blocks_up_to, col_sums, col_sums2, pixel_col_sums, pixel_row_block, row_block};
use super::super::{Lanes, WideScratch};
use crate::Plane;
use std::arch::x86_64::*;

/// `max(0, m + e - i - c)`, the operations of `compete_lanes_generic` in its order.
#[inline(always)]
unsafe fn compete_vector(m: __m512, e: __m512, i: __m512, c: __m512, z: __m512) -> __m512 {
    // SAFETY: the caller has AVX-512 F.
    unsafe { _mm512_max_ps(_mm512_sub_ps(_mm512_sub_ps(_mm512_add_ps(m, e), i), c), z) }
}

/// The checks both fused steps need, and where their horizontal passes start: `Some((first_i,
/// first_e, npair))` when both filters' buffers fit `maps` and the excitatory kernel is not
/// the longer (it then reads the inhibitory filter's padded row, pixel x at x + `si.off`,
/// and reaches no further than what `si.fits` checked); `npair` pairs per row of `tmp`.
#[allow(clippy::type_complexity)]
fn fused_fits(
    (ke, re, se): (&[f32], &[Vec<(usize, f32)>], &WideScratch),
    (ki, ri, si): (&[f32], &[Vec<(usize, f32)>], &WideScratch),
    maps: &Plane<Lanes>,
) -> Option<(usize, usize, usize)> {
    let (first_i, npair) = si.fits(ki, ri, maps, maps)?;
    let (_, npair_e) = se.fits(ke, re, maps, maps)?;
    let hw_e = ke.len().checked_sub(1)? / 2;
    let first_e = si.off.checked_sub(hw_e)?;
    (hw_e <= ki.len().saturating_sub(1) / 2 && npair_e == npair).then_some((first_i, first_e, npair))
}

/// One step of the iterative difference of Gaussians on eight interleaved maps, fused:
/// `maps <- max(0, maps + E - I - c)` with `E` and `I` the excitatory and inhibitory
/// energy-preserving filters of `maps` (kernels `ke`, `ki`, vertical taps `re`, `ri`, buffers
/// `se`, `si`), each output as [`preserving_lanes_avx512`] and `compete_lanes` compute
/// it, bit for bit. Why: apart, the two filters each copy every row and build its odd pairs,
/// write their results, and the competition reads them back; fused, the row is prepared once
/// (the excitatory kernel, the shorter, reads the inhibitory one's padded pairs), and the
/// competition takes both sums from registers. False (nothing written) where the buffers do
/// not fit or the excitatory kernel is the longer.
///
/// # Safety
/// The CPU must have AVX-512 F and DQ (and AVX2 + FMA).
#[allow(clippy::type_complexity)]
#[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
pub(in crate::preserving) unsafe fn dog_step_avx512(
    (ke, re, se): (&[f32], &[Vec<(usize, f32)>], &mut WideScratch),
    (ki, ri, si): (&[f32], &[Vec<(usize, f32)>], &mut WideScratch),
    maps: &mut Plane<Lanes>,
    c: &Lanes,
) -> bool {
    let (w, h) = maps.size();
    let Some((first_i, first_e, npair)) = fused_fits((ke, re, se), (ki, ri, si), maps) else { return false };
    if w < 2 || si.odd.len() + 1 != si.even.len() {
        return false;
    }
    let wp = 2 * npair;
    for y in 0..h {
        // SAFETY: AVX-512 F was promised by the caller; `odd` is one pair shorter (checked).
        unsafe { si.load_pairs_avx512(maps.row(y)) };
        let (oi, oe) = (&mut si.tmp[y * npair..(y + 1) * npair], &mut se.tmp[y * npair..(y + 1) * npair]);
        for (x0, p) in blocks_up_to(wp, 10) {
            // SAFETY: as in `preserving_lanes_avx512`, for both kernels.
            unsafe {
                match p {
                    10 => {
                        row_block::<10>(&si.even, &si.odd, first_i, ki, &si.fx_pairs, oi, x0);
                        row_block::<10>(&si.even, &si.odd, first_e, ke, &se.fx_pairs, oe, x0);
                    }
                    8 => {
                        row_block::<8>(&si.even, &si.odd, first_i, ki, &si.fx_pairs, oi, x0);
                        row_block::<8>(&si.even, &si.odd, first_e, ke, &se.fx_pairs, oe, x0);
                    }
                    4 => {
                        row_block::<4>(&si.even, &si.odd, first_i, ki, &si.fx_pairs, oi, x0);
                        row_block::<4>(&si.even, &si.odd, first_e, ke, &se.fx_pairs, oe, x0);
                    }
                    _ => {
                        row_block::<1>(&si.even, &si.odd, first_i, ki, &si.fx_pairs, oi, x0);
                        row_block::<1>(&si.even, &si.odd, first_e, ke, &se.fx_pairs, oe, x0);
                    }
                }
            }
        }
    }
    let (te, ti) = (se.tmp.as_ptr() as *const f32, si.tmp.as_ptr() as *const f32);
    let stride = npair * 16;
    // SAFETY: the features were promised by the caller.
    let (cv, z) = unsafe { (_mm512_broadcast_f32x8(_mm256_loadu_ps(c.as_ptr())), _mm512_setzero_ps()) };
    let mut y = 0;
    while y < h {
        let two = y + 1 < h;
        let rows =
            [maps.row_mut(y).as_mut_ptr() as *mut f32, maps.row_mut((y + 1).min(h - 1)).as_mut_ptr() as *mut f32];
        let (tap_e, tap_i) = ([&re[y][..], &re[(y + 1).min(h - 1)][..]], [&ri[y][..], &ri[(y + 1).min(h - 1)][..]]);
        // Pixels below `from` are done: the last block may start inside the one before it,
        // and a competition must not run twice on a pixel.
        let mut from = 0;
        for (x0, p) in blocks(w) {
            let args = Epilogue { rows, n_rows: if two { 2 } else { 1 }, x0, from, c: cv, z };
            // SAFETY: every tap's row is below h (checked above) and x0 + 2 P <= w.
            unsafe {
                match p {
                    8 => dog_block::<8>(te, ti, stride, tap_e, tap_i, &args),
                    4 => dog_block::<4>(te, ti, stride, tap_e, tap_i, &args),
                    _ => dog_block::<1>(te, ti, stride, tap_e, tap_i, &args),
                }
            }
            from = x0 + 2 * p;
        }
        y += 2;
    }
    true
}

/// Where [`dog_block`] writes: the map rows (one or two), the block's first pixel, the
/// first pixel not yet done, and the constant and zero vectors.
struct Epilogue {
    rows: [*mut f32; 2],
    n_rows: usize,
    x0: usize,
    from: usize,
    c: __m512,
    z: __m512,
}

/// `2 P` pixels from `x0` of one or two map rows: both vertical sums ([`col_sums2`] or
/// [`col_sums`], as the separate filter takes them), then the competition in place on the
/// pixels from `from` on.
#[inline(always)]
unsafe fn dog_block<const P: usize>(
    te: *const f32,
    ti: *const f32,
    stride: usize,
    tap_e: [&[(usize, f32)]; 2],
    tap_i: [&[(usize, f32)]; 2],
    g: &Epilogue,
) {
    // SAFETY: the caller keeps [x0, x0 + 2 P) within the rows and every tap row below h.
    unsafe {
        let (e, i) = if g.n_rows == 2 {
            (col_sums2::<P>(te, stride, tap_e, g.x0), col_sums2::<P>(ti, stride, tap_i, g.x0))
        } else {
            let (e, i) = (col_sums::<P>(te, stride, tap_e[0], g.x0), col_sums::<P>(ti, stride, tap_i[0], g.x0));
            ([e, e], [i, i])
        };
        for r in 0..g.n_rows {
            for k in 0..P {
                let px = g.x0 + 2 * k;
                let mask = (if px >= g.from { 0x00FFu16 } else { 0 }) | (if px + 1 >= g.from { 0xFF00 } else { 0 });
                let q = g.rows[r].add(px * 8);
                let m = _mm512_maskz_loadu_ps(mask, q);
                _mm512_mask_storeu_ps(q, mask, compete_vector(m, e[r][k], i[r][k], g.c, g.z));
            }
        }
    }
}

/// [`dog_step_avx512`] with 256-bit registers, one pixel of eight maps each, on the AVX2
/// kernel's buffers: the row copied once for both filters' horizontal passes, both vertical
/// sums in registers for the competition. Each output as the separate AVX2 filters and the
/// competition compute it, bit for bit (tested). False (nothing written) where the buffers
/// do not fit or the excitatory kernel is the longer.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[allow(clippy::type_complexity)]
#[target_feature(enable = "avx2,fma")]
pub(in crate::preserving) unsafe fn dog_step_avx2(
    (ke, re, se): (&[f32], &[Vec<(usize, f32)>], &mut WideScratch),
    (ki, ri, si): (&[f32], &[Vec<(usize, f32)>], &mut WideScratch),
    maps: &mut Plane<Lanes>,
    c: &Lanes,
) -> bool {
    let (w, h) = maps.size();
    let Some((first_i, first_e, npair)) = fused_fits((ke, re, se), (ki, ri, si), maps) else { return false };
    // Both passes in blocks of 10 pixels where the row has them: 10 chains of multiply-adds
    // in flight instead of 8 (whose 4-cycle latency two pipes just cover), which on a
    // 40-pixel map is 4 blocks instead of 5: the step about 2 % faster for the horizontal
    // pass and 1 % more for the vertical one on an AMD EPYC (Zen 3; as the AVX-512 kernel's
    // blocks of 10 pairs). Two map rows at a time in the vertical pass, as the AVX-512
    // kernel does, was no faster here.
    let block = if w >= 10 {
        10
    } else if w >= 8 {
        8
    } else {
        1
    };
    for y in 0..h {
        si.load_row(maps.row(y));
        let e = si.even.as_ptr() as *const f32;
        let (fi, fe) = (si.fx_pairs.as_ptr() as *const f32, se.fx_pairs.as_ptr() as *const f32);
        let (oi, oe) = (si.tmp[y * npair..].as_mut_ptr() as *mut f32, se.tmp[y * npair..].as_mut_ptr() as *mut f32);
        let mut x = 0;
        while x < w {
            let x0 = if x + block <= w { x } else { w - block };
            // SAFETY: as in `preserving_lanes_avx2`, for both kernels (the excitatory one
            // reaches less far into the padded row).
            unsafe {
                match block {
                    10 => {
                        pixel_row_block::<10>(e, first_i, ki, fi, oi, x0);
                        pixel_row_block::<10>(e, first_e, ke, fe, oe, x0);
                    }
                    8 => {
                        pixel_row_block::<8>(e, first_i, ki, fi, oi, x0);
                        pixel_row_block::<8>(e, first_e, ke, fe, oe, x0);
                    }
                    _ => {
                        pixel_row_block::<1>(e, first_i, ki, fi, oi, x0);
                        pixel_row_block::<1>(e, first_e, ke, fe, oe, x0);
                    }
                }
            }
            x = x0 + block;
        }
    }
    let (te, ti) = (se.tmp.as_ptr() as *const f32, si.tmp.as_ptr() as *const f32);
    let stride = npair * 16;
    // SAFETY: `c` holds 8 floats.
    let (cv, z) = (unsafe { _mm256_loadu_ps(c.as_ptr()) }, _mm256_setzero_ps());
    for y in 0..h {
        let row = maps.row_mut(y).as_mut_ptr() as *mut f32;
        let mut x = 0;
        while x < w {
            let x0 = if x + block <= w { x } else { w - block };
            // SAFETY: every tap's row is below h (checked above) and x0 + block <= w; the
            // pixels below `x` are done and not competed again.
            unsafe {
                match block {
                    10 => dog_pixels::<10>((te, ti), stride, (&re[y], &ri[y]), row, x0, x, (cv, z)),
                    8 => dog_pixels::<8>((te, ti), stride, (&re[y], &ri[y]), row, x0, x, (cv, z)),
                    _ => dog_pixels::<1>((te, ti), stride, (&re[y], &ri[y]), row, x0, x, (cv, z)),
                }
            }
            x = x0 + block;
        }
    }
    true
}

/// `P` pixels from `x0` of one map row in the AVX2 fused step: both vertical sums, then the
/// competition in place on the pixels from `from` on.
#[allow(clippy::type_complexity)]
#[inline(always)]
unsafe fn dog_pixels<const P: usize>(
    (te, ti): (*const f32, *const f32),
    stride: usize,
    (tap_e, tap_i): (&[(usize, f32)], &[(usize, f32)]),
    row: *mut f32,
    x0: usize,
    from: usize,
    (c, z): (__m256, __m256),
) {
    // SAFETY: the caller keeps [x0, x0 + P) within the rows and every tap row below h.
    unsafe {
        let (e, i) = (pixel_col_sums::<P>(te, stride, tap_e, x0), pixel_col_sums::<P>(ti, stride, tap_i, x0));
        for j in 0..P {
            if x0 + j >= from {
                let q = row.add((x0 + j) * 8);
                let v = _mm256_sub_ps(_mm256_sub_ps(_mm256_add_ps(_mm256_loadu_ps(q), e[j]), i[j]), c);
                _mm256_storeu_ps(q, _mm256_max_ps(v, z));
            }
        }
    }
}
