//! Hand-written AVX-512 and AVX2 kernels of the energy-preserving filter on eight
//! interleaved maps.
//!
//! Why by hand: the generic kernel keeps a pixel's eight lanes in an `[f32; 8]`, which LLVM
//! maps onto 256-bit registers even inside the AVX-512 build. On a core with full-width
//! 512-bit units (AMD Zen 5, Intel server cores) one 512-bit register holds two neighbouring
//! pixels of all eight maps (16 floats, one cache line) and does twice the work per
//! instruction. That only pays if the loads do not straddle cache lines: a 64-byte load at
//! an odd pixel splits in two, and with every load split the kernel was no faster than the
//! 256-bit one. So the padded row is kept twice in 64-byte aligned pairs, starting at even
//! and at odd pixels, and the horizontal pass's output in aligned pairs too; every load of
//! the two passes is then one cache line. The AVX2 kernel reads the same buffers one pixel
//! (32 bytes) at a time, so none of its loads straddles a line either.
//!
//! Each output lane is the same chain of fused multiply-adds, in the same tap order, as the
//! generic kernel with [`crate::simd::Fused`], so the results are bit-identical (tested).

use super::{Lanes, Pair, WideScratch};
use crate::Plane;
use std::arch::x86_64::*;

impl WideScratch {
    /// Buffers for `width` x `height` maps and a kernel of half-width `hw`, with the
    /// horizontal pass's border factors `fx` in pairs and the reach of the vertical taps
    /// `rows`.
    pub(super) fn new(width: usize, height: usize, hw: usize, fx: &[f32], rows: &[Vec<(usize, f32)>]) -> Self {
        let off = hw + (hw & 1);
        let wp = width + (width & 1);
        // Pairs read: up to pixel wp - 1 + 2 hw - hw + off, plus its neighbour.
        let pixels = wp + hw + off + 2;
        let n_even = pixels.div_ceil(2) + 1;
        let fx_pairs = (0..wp / 2)
            .map(|q| {
                let (a, b) = (fx.get(2 * q).copied().unwrap_or(0.0), fx.get(2 * q + 1).copied().unwrap_or(0.0));
                Pair(std::array::from_fn(|l| if l < 8 { a } else { b }))
            })
            .collect();
        Self {
            off,
            taps_below: rows.iter().flatten().map(|&(r, _)| r + 1).max().unwrap_or(0),
            even: vec![Pair::default(); n_even],
            odd: vec![Pair::default(); n_even - 1],
            tmp: vec![Pair::default(); height * wp / 2],
            fx_pairs,
        }
    }

    /// `Some((first, npair))` when these buffers fit `src` (`w` x `h`), the kernel `k` and the vertical taps
    /// `rows` (every row below h; `rows` must be those these buffers were built with),
    /// `dst` being `src`'s size (the checks that make the kernels' pointer arithmetic safe):
    /// `first` is the padded pixel that tap 0 of output 0 reads, `npair` the pairs per row
    /// of `tmp`.
    pub(in crate::preserving) fn fits(
        &self,
        k: &[f32],
        rows: &[Vec<(usize, f32)>],
        src: &Plane<Lanes>,
        dst: &Plane<Lanes>,
    ) -> Option<(usize, usize)> {
        let (w, h) = src.size();
        let hw = k.len().saturating_sub(1) / 2;
        let wp = w + (w & 1);
        let fits = w >= 1
            && !k.is_empty()
            && self.off >= hw
            && self.even.len() > (wp + hw + self.off + 2).div_ceil(2)
            && self.tmp.len() >= h * wp / 2
            && self.fx_pairs.len() >= wp / 2
            && rows.len() >= h
            && dst.size() == (w, h)
            // Every tap's row below h: `rows` are the ones `taps_below` was found from (see
            // its field); checking them tap by tap was 1 % of a frame.
            && self.taps_below <= h;
        fits.then(|| (self.off - hw, wp / 2))
    }

    /// Copies one row of the maps into the padded row (`even`), pixel x at `x + off`;
    /// everything else stays zero. Ignores a row longer than the buffer (never, after
    /// [`Self::fits`]).
    pub(in crate::preserving) fn load_row(&mut self, row: &[Lanes]) {
        let n = row.len() * 8;
        if (self.off + row.len()) * 8 > self.even.len() * 16 {
            return;
        }
        // SAFETY: the destination holds `off * 8 + n` floats (checked just above); Pair is
        // plain `[f32; 16]`, so its floats are contiguous.
        unsafe {
            let e = self.even.as_mut_ptr() as *mut f32;
            std::ptr::copy_nonoverlapping(row.as_ptr() as *const f32, e.add(self.off * 8), n);
        }
    }
}

impl WideScratch {
    /// [`Self::load_row`], and the pairs from odd pixels (`odd`) from those from even ones,
    /// in one pass: each pair of the row is loaded once, stored in `even` and joined with
    /// the one before into an odd pair. Why one pass: as a copy loop, LLVM turned the first
    /// half into a `memcpy` call (about 1 % of a frame on an AMD EPYC, Zen 4, 630 calls for
    /// 40-pixel rows), and the odd pairs then read `even` back. The pairs of the zero border
    /// are never written, so they stay zero, as their odd pairs do. Does nothing unless `odd`
    /// is one pair shorter than `even` and the row fits.
    ///
    /// # Safety
    /// The CPU must have AVX-512 F.
    #[target_feature(enable = "avx512f,avx2")]
    pub(in crate::preserving) unsafe fn load_pairs_avx512(&mut self, row: &[Lanes]) {
        let w = row.len();
        // Pair `base + q` holds pixels 2q and 2q + 1 of the row (`off` is even); the last one
        // written, `base + (w + 1) / 2 - 1`, must have a pair after it in `even` (zero border).
        let base = self.off / 2;
        let pairs = w.div_ceil(2);
        if pairs == 0
            || self.odd.len() + 1 != self.even.len()
            || !self.off.is_multiple_of(2)
            || base + pairs + 1 > self.even.len()
        {
            return;
        }
        // SAFETY: AVX-512 F was promised by the caller; pairs base - 1 ..= base + pairs of
        // `even` and base - 1 ..= base + pairs - 1 of `odd` exist (checked above, `odd` being
        // one shorter), and the row's loads stay inside its `8 w` floats.
        unsafe {
            let (e, o) = (self.even.as_mut_ptr() as *mut f32, self.odd.as_mut_ptr() as *mut f32);
            let s = row.as_ptr() as *const f32;
            // Odd pair i: the high half of even pair i, the low half of even pair i + 1.
            let join = |a: __m512, b: __m512| _mm512_shuffle_f32x4::<0x4E>(a, b);
            let mut prev = if base > 0 { _mm512_load_ps(e.add(16 * (base - 1))) } else { _mm512_setzero_ps() };
            for q in 0..pairs {
                // A last pixel alone: its pair's second half is the zero border.
                let v = if 2 * q + 1 < w {
                    _mm512_loadu_ps(s.add(16 * q))
                } else {
                    _mm512_maskz_loadu_ps(0x00FF, s.add(16 * q))
                };
                _mm512_store_ps(e.add(16 * (base + q)), v);
                if base + q > 0 {
                    _mm512_store_ps(o.add(16 * (base + q - 1)), join(prev, v));
                }
                prev = v;
            }
            let next = _mm512_load_ps(e.add(16 * (base + pairs)));
            _mm512_store_ps(o.add(16 * (base + pairs - 1)), join(prev, next));
        }
    }
}

/// The energy-preserving filter of eight interleaved maps, as `preserving_lanes_generic`:
/// the horizontal pass of each row (zero border, scaled by `fx`), then the vertical pass
/// through `rows` (weights already scaled) into `dst`. False (nothing written) where the
/// buffers do not fit the maps: `s` must come from [`WideScratch::new`] for this size and
/// kernel.
///
/// # Safety
/// The CPU must have AVX-512 F and DQ (and AVX2 + FMA).
#[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
pub(super) unsafe fn preserving_lanes_avx512(
    k: &[f32],
    rows: &[Vec<(usize, f32)>],
    s: &mut WideScratch,
    src: &Plane<Lanes>,
    dst: &mut Plane<Lanes>,
) -> bool {
    let (w, h) = src.size();
    let Some((first, npair)) = s.fits(k, rows, src, dst) else { return false };
    if w < 2 || s.odd.len() + 1 != s.even.len() {
        return false;
    }
    let wp = 2 * npair;
    for y in 0..h {
        // SAFETY: AVX-512 F was promised by the caller; `odd` is one pair shorter than `even`
        // (checked above).
        unsafe { s.load_pairs_avx512(src.row(y)) };
        let out = &mut s.tmp[y * npair..(y + 1) * npair];
        for (x0, p) in blocks_up_to(wp, 10) {
            // SAFETY: x0 + 2 P <= wp, so the pairs read lie below (wp + hw + off) / 2 + 1
            // (checked above) and those written below npair.
            unsafe {
                match p {
                    10 => row_block::<10>(&s.even, &s.odd, first, k, &s.fx_pairs, out, x0),
                    8 => row_block::<8>(&s.even, &s.odd, first, k, &s.fx_pairs, out, x0),
                    4 => row_block::<4>(&s.even, &s.odd, first, k, &s.fx_pairs, out, x0),
                    _ => row_block::<1>(&s.even, &s.odd, first, k, &s.fx_pairs, out, x0),
                }
            }
        }
    }
    // Vertical pass two output rows at a time (one row last when h is odd): the horizontal
    // pass's output (40 x 30 maps: 38 KB) stays in L1.
    let tmp = s.tmp.as_ptr() as *const f32;
    let mut y = 0;
    while y < h {
        let out = dst.row_mut(y).as_mut_ptr() as *mut f32;
        // Rows y and y + 1 together, when y + 1 exists.
        let pair =
            (y + 1 < h).then(|| ([&rows[y][..], &rows[y + 1][..]], [out, dst.row_mut(y + 1).as_mut_ptr() as *mut f32]));
        for (x0, p) in blocks(w) {
            // SAFETY: every tap's row is below h (checked above) and x0 + 2 P <= w <= wp.
            unsafe {
                match (pair, p) {
                    (Some((t, o)), 8) => col_block2::<8>(tmp, npair * 16, t, o, x0),
                    (Some((t, o)), 4) => col_block2::<4>(tmp, npair * 16, t, o, x0),
                    (Some((t, o)), _) => col_block2::<1>(tmp, npair * 16, t, o, x0),
                    (None, 8) => col_block::<8>(tmp, npair * 16, &rows[y], out, x0),
                    (None, 4) => col_block::<4>(tmp, npair * 16, &rows[y], out, x0),
                    (None, _) => col_block::<1>(tmp, npair * 16, &rows[y], out, x0),
                }
            }
        }
        y += 2;
    }
    true
}

/// The blocks `(x0, pairs)` covering [0, w) (w >= 2): 8 pairs of pixels while they fit, then
/// 4, then single pairs, the last aligned to the end (a pixel may be computed twice, with the
/// same result). A plain iterator, not a callback: a closure would not be compiled with the
/// kernel's target features.
#[inline(always)]
pub(in crate::preserving) fn blocks(w: usize) -> impl Iterator<Item = (usize, usize)> {
    blocks_up_to(w, 8)
}

/// [`blocks`] with blocks of 10 pairs first where `widest` is 10: the horizontal pass's
/// chains of multiply-adds need 8 in flight to hide their latency, so a 40-pixel row as
/// 10 + 10 pairs runs at full rate where 8 + 8 + 4 ran its last block at half. (The vertical
/// pass computes two rows per block, so its 4-pair blocks have 8 chains already.)
#[inline(always)]
pub(in crate::preserving) fn blocks_up_to(w: usize, widest: usize) -> impl Iterator<Item = (usize, usize)> {
    let mut x = 0;
    std::iter::from_fn(move || {
        if x >= w {
            return None;
        }
        let p = if widest >= 10 && x + 20 <= w {
            10
        } else if x + 16 <= w {
            8
        } else if x + 8 <= w {
            4
        } else {
            1
        };
        let x0 = x.min(w - 2);
        x = x0 + 2 * p;
        Some((x0, p))
    })
}

/// `2 P` outputs of the horizontal pass from the even pixel `x0`: `fx[x] sum_t k[t] p[x + t]`
/// with `p[i]` padded pixel `i + first` (`first = off - hw`), read as aligned pairs from
/// `even` or `odd` by the parity of the pixel.
#[inline(always)]
pub(in crate::preserving) unsafe fn row_block<const P: usize>(
    even: &[Pair],
    odd: &[Pair],
    first: usize,
    k: &[f32],
    fx: &[Pair],
    out: &mut [Pair],
    x0: usize,
) {
    // SAFETY: the caller keeps every pair read and written inside the buffers.
    unsafe {
        let mut a = [_mm512_setzero_ps(); P];
        for (t, &kt) in k.iter().enumerate() {
            let wv = _mm512_set1_ps(kt);
            let i = x0 + t + first;
            let base = if i & 1 == 0 { even.as_ptr().add(i / 2) } else { odd.as_ptr().add(i / 2) };
            for (j, a) in a.iter_mut().enumerate() {
                *a = _mm512_fmadd_ps(wv, _mm512_load_ps(base.add(j) as *const f32), *a);
            }
        }
        let (f, o) = (fx.as_ptr().add(x0 / 2), out.as_mut_ptr().add(x0 / 2));
        for (j, a) in a.iter().enumerate() {
            _mm512_store_ps(o.add(j) as *mut f32, _mm512_mul_ps(*a, _mm512_load_ps(f.add(j) as *const f32)));
        }
    }
}

/// `2 P` outputs of the vertical pass from pixel `x0`: `sum_i w_i tmp[r_i][x]`, rows of
/// `tmp` `stride` floats apart.
#[inline(always)]
unsafe fn col_block<const P: usize>(tmp: *const f32, stride: usize, taps: &[(usize, f32)], out: *mut f32, x0: usize) {
    // SAFETY: the caller keeps [x0, x0 + 2 P) within the rows and every r_i < height.
    unsafe {
        let a = col_sums::<P>(tmp, stride, taps, x0);
        for (j, a) in a.iter().enumerate() {
            _mm512_storeu_ps(out.add((x0 + 2 * j) * 8), *a);
        }
    }
}

/// The sums of [`col_block`], in registers.
#[inline(always)]
pub(in crate::preserving) unsafe fn col_sums<const P: usize>(
    tmp: *const f32,
    stride: usize,
    taps: &[(usize, f32)],
    x0: usize,
) -> [__m512; P] {
    // SAFETY: the caller keeps [x0, x0 + 2 P) within the rows and every r_i < height.
    unsafe {
        let mut a = [_mm512_setzero_ps(); P];
        for &(r, wt) in taps {
            let s = tmp.add(r * stride + x0 * 8);
            let wv = _mm512_set1_ps(wt);
            for (j, a) in a.iter_mut().enumerate() {
                *a = _mm512_fmadd_ps(wv, _mm512_loadu_ps(s.add(16 * j)), *a);
            }
        }
        a
    }
}

/// `2 P` outputs of the vertical pass from pixel `x0` in two output rows at once: each row of
/// `tmp` that both rows' taps read is loaded once for both sums (the taps of rows y and y + 1
/// are runs of consecutive rows, one apart), instead of once per output row. Each sum takes
/// its taps in their order, so the chains are those of [`col_block`].
#[inline(always)]
unsafe fn col_block2<const P: usize>(
    tmp: *const f32,
    stride: usize,
    taps: [&[(usize, f32)]; 2],
    out: [*mut f32; 2],
    x0: usize,
) {
    // SAFETY: the caller keeps [x0, x0 + 2 P) within the rows and every r_i < height.
    unsafe {
        let a = col_sums2::<P>(tmp, stride, taps, x0);
        for (o, a) in out.iter().zip(&a) {
            for (k, a) in a.iter().enumerate() {
                _mm512_storeu_ps(o.add((x0 + 2 * k) * 8), *a);
            }
        }
    }
}

/// The sums of [`col_block2`], in registers.
#[inline(always)]
pub(in crate::preserving) unsafe fn col_sums2<const P: usize>(
    tmp: *const f32,
    stride: usize,
    taps: [&[(usize, f32)]; 2],
    x0: usize,
) -> [[__m512; P]; 2] {
    // SAFETY: the caller keeps [x0, x0 + 2 P) within the rows and every r_i < height.
    unsafe {
        let mut a = [[_mm512_setzero_ps(); P]; 2];
        let (mut i, mut j) = (0, 0);
        loop {
            // The next row of either list, the lower first (both lists ascend).
            let (ri, rj) = (taps[0].get(i).map(|t| t.0), taps[1].get(j).map(|t| t.0));
            let r = match (ri, rj) {
                (Some(p), Some(q)) => p.min(q),
                (Some(p), None) => p,
                (None, Some(q)) => q,
                (None, None) => break,
            };
            let s = tmp.add(r * stride + x0 * 8);
            let mut v = [_mm512_setzero_ps(); P];
            for (k, v) in v.iter_mut().enumerate() {
                *v = _mm512_loadu_ps(s.add(16 * k));
            }
            if ri == Some(r) {
                let wv = _mm512_set1_ps(taps[0][i].1);
                for k in 0..P {
                    a[0][k] = _mm512_fmadd_ps(wv, v[k], a[0][k]);
                }
                i += 1;
            }
            if rj == Some(r) {
                let wv = _mm512_set1_ps(taps[1][j].1);
                for k in 0..P {
                    a[1][k] = _mm512_fmadd_ps(wv, v[k], a[1][k]);
                }
                j += 1;
            }
        }
        a
    }
}

/// [`preserving_lanes_avx512`] with 256-bit registers, one pixel of eight maps each: the
/// same aligned buffers, so that no load of either pass straddles a cache line (with the
/// generic kernel's buffers every other one did). Bit-identical to the generic kernel with
/// [`crate::simd::Fused`] (tested).
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn preserving_lanes_avx2(
    k: &[f32],
    rows: &[Vec<(usize, f32)>],
    s: &mut WideScratch,
    src: &Plane<Lanes>,
    dst: &mut Plane<Lanes>,
) -> bool {
    let (w, h) = src.size();
    let Some((first, npair)) = s.fits(k, rows, src, dst) else { return false };
    let (step, wide) = if w >= 8 { (8, true) } else { (1, false) };
    for y in 0..h {
        s.load_row(src.row(y));
        let e = s.even.as_ptr() as *const f32;
        let fx = s.fx_pairs.as_ptr() as *const f32;
        let out = s.tmp[y * npair..].as_mut_ptr() as *mut f32;
        let mut x = 0;
        while x < w {
            let x0 = if x + step <= w { x } else { w - step };
            // SAFETY: pixels x0 .. x0 + step lie within the row, the padded pixels they read
            // within `even` and the outputs within the row's pairs of `tmp`.
            unsafe {
                if wide {
                    pixel_row_block::<8>(e, first, k, fx, out, x0)
                } else {
                    pixel_row_block::<1>(e, first, k, fx, out, x0)
                }
            }
            x = x0 + step;
        }
    }
    let tmp = s.tmp.as_ptr() as *const f32;
    for (y, r) in rows.iter().enumerate().take(h) {
        let out = dst.row_mut(y).as_mut_ptr() as *mut f32;
        let mut x = 0;
        while x < w {
            let x0 = if x + step <= w { x } else { w - step };
            // SAFETY: every tap's row is below h (checked above) and x0 + step <= w.
            unsafe {
                if wide {
                    pixel_col_block::<8>(tmp, npair * 16, r, out, x0)
                } else {
                    pixel_col_block::<1>(tmp, npair * 16, r, out, x0)
                }
            }
            x = x0 + step;
        }
    }
    true
}

/// `P` pixels of the horizontal pass from pixel `x0` with 256-bit registers:
/// `fx[x] sum_t k[t] p[x + t]`, padded pixel `i` at `e + 8 (i + first)`; the factor of
/// pixel x is float `8 x` of the factor pairs (see [`WideScratch::new`]).
#[inline(always)]
pub(in crate::preserving) unsafe fn pixel_row_block<const P: usize>(
    e: *const f32,
    first: usize,
    k: &[f32],
    fx: *const f32,
    out: *mut f32,
    x0: usize,
) {
    // SAFETY: the caller keeps every pixel read and written inside the buffers.
    unsafe {
        let mut a = [_mm256_setzero_ps(); P];
        for (t, &kt) in k.iter().enumerate() {
            let wv = _mm256_set1_ps(kt);
            let base = e.add((x0 + t + first) * 8);
            for (j, a) in a.iter_mut().enumerate() {
                *a = _mm256_fmadd_ps(wv, _mm256_load_ps(base.add(8 * j)), *a);
            }
        }
        for (j, a) in a.iter().enumerate() {
            let x = x0 + j;
            _mm256_store_ps(out.add(8 * x), _mm256_mul_ps(*a, _mm256_load_ps(fx.add(8 * x))));
        }
    }
}

/// `P` pixels of the vertical pass from pixel `x0` with 256-bit registers:
/// `sum_i w_i tmp[r_i][x]`, rows of `tmp` `stride` floats apart.
#[inline(always)]
unsafe fn pixel_col_block<const P: usize>(
    tmp: *const f32,
    stride: usize,
    taps: &[(usize, f32)],
    out: *mut f32,
    x0: usize,
) {
    // SAFETY: the caller keeps [x0, x0 + P) within the rows and every r_i < height.
    unsafe {
        let a = pixel_col_sums::<P>(tmp, stride, taps, x0);
        for (j, a) in a.iter().enumerate() {
            _mm256_storeu_ps(out.add((x0 + j) * 8), *a);
        }
    }
}

/// The vertical sums of `P` pixels from `x0` (as the AVX2 filter's column pass takes them).
#[inline(always)]
pub(in crate::preserving) unsafe fn pixel_col_sums<const P: usize>(
    tmp: *const f32,
    stride: usize,
    taps: &[(usize, f32)],
    x0: usize,
) -> [__m256; P] {
    // SAFETY: the caller keeps [x0, x0 + P) within the rows and every r_i < height.
    unsafe {
        let mut a = [_mm256_setzero_ps(); P];
        for &(r, wt) in taps {
            let s = tmp.add(r * stride + x0 * 8);
            let wv = _mm256_set1_ps(wt);
            for (j, a) in a.iter_mut().enumerate() {
                *a = _mm256_fmadd_ps(wv, _mm256_load_ps(s.add(8 * j)), *a);
            }
        }
        a
    }
}
