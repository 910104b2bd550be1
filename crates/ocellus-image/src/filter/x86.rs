//! Hand-written AVX2 kernels for the two passes of a separable filter. Why by hand: the
//! generic kernels keep their sums in `[f32; 32]` arrays, which LLVM maps well onto 256-bit
//! registers but, inside the AVX-512 build, into 512-bit registers patched together with
//! masked inserts and permutes for the odd tap; with only two dependent chains per chunk the
//! column pass of an 11-tap Gaussian was slower with AVX-512 than with AVX2. Here each
//! output lane is the same chain of fused multiply-adds, in the same tap order, as in the
//! generic kernel with [`crate::simd::Fused`] (so the results are bit-identical), and 64
//! outputs at a time give eight independent chains, enough to hide the multiply-add latency.

use crate::Plane;
use std::arch::x86_64::*;

/// Most taps these kernels take (the row pointers live on the stack); longer kernels
/// use the generic code.
pub(super) const MAX_TAPS: usize = 64;

/// The rows' first pixels and the weights of `accumulate_rows` for `n` outputs; None where
/// the hand-written kernels do not apply: more than [`MAX_TAPS`] rows, fewer than 8 outputs,
/// or rows shorter than `n`.
#[allow(clippy::type_complexity)]
fn row_pointers(
    src: &Plane<f32>,
    rows: &[(usize, f32)],
    n: usize,
) -> Option<([*const f32; MAX_TAPS], [f32; MAX_TAPS])> {
    if rows.len() > MAX_TAPS || n < 8 || src.width() < n {
        return None;
    }
    let mut ptrs = [std::ptr::null::<f32>(); MAX_TAPS];
    let mut wts = [0f32; MAX_TAPS];
    for (i, &(r, w)) in rows.iter().enumerate() {
        ptrs[i] = src.row(r).as_ptr();
        wts[i] = w;
    }
    Some((ptrs, wts))
}

/// `out[x] = sum_i w_i * src.row(r_i)[x]`, as `accumulate_rows_generic`; false (nothing
/// written) where this kernel does not apply: more than [`MAX_TAPS`] rows, or fewer than
/// 8 outputs.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn accumulate_rows_avx2(src: &Plane<f32>, rows: &[(usize, f32)], out: &mut [f32]) -> bool {
    let n = out.len();
    let Some((ptrs, wts)) = row_pointers(src, rows, n) else { return false };
    let (ptrs, wts) = (&ptrs[..rows.len()], &wts[..rows.len()]);
    let o = out.as_mut_ptr();
    let mut x = 0;
    // `L` output vectors of 8 from `x`, one chain each.
    #[inline(always)]
    unsafe fn chunk<const L: usize>(ptrs: &[*const f32], wts: &[f32], o: *mut f32, x: usize) {
        // SAFETY: the caller keeps x + 8 L within every row and the output.
        unsafe {
            let mut a = [_mm256_setzero_ps(); L];
            for (&p, &w) in ptrs.iter().zip(wts) {
                let w = _mm256_set1_ps(w);
                for (k, a) in a.iter_mut().enumerate() {
                    *a = _mm256_fmadd_ps(w, _mm256_loadu_ps(p.add(x + 8 * k)), *a);
                }
            }
            for (k, a) in a.iter().enumerate() {
                _mm256_storeu_ps(o.add(x + 8 * k), *a);
            }
        }
    }
    // SAFETY (all loads and stores below): every row holds at least n values (checked
    // above) and every access covers [x, x + 8 * k) with x + 8 * k <= n.
    unsafe {
        while x + 64 <= n {
            chunk::<8>(ptrs, wts, o, x);
            x += 64;
        }
        while x + 32 <= n {
            chunk::<4>(ptrs, wts, o, x);
            x += 32;
        }
        tail_quads(ptrs, wts, o, x, n);
    }
    true
}

/// Outputs `[x, n)` of `accumulate_rows` (n >= 8) 8 at a time, the last 8 aligned to the
/// end (recomputing a few outputs, as the generic kernel does); taps dealt to four running
/// sums in turn, the taps past the last whole four to the first, as `dot8` does.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn tail_quads(ptrs: &[*const f32], wts: &[f32], o: *mut f32, mut x: usize, n: usize) {
    /// `a + w * p[x .. x + 8]` (a function, not a closure, to be compiled with AVX2 and FMA).
    #[inline(always)]
    unsafe fn fma8(w: f32, p: *const f32, x: usize, a: __m256) -> __m256 {
        // SAFETY: the caller keeps [x, x + 8) within the row.
        unsafe { _mm256_fmadd_ps(_mm256_set1_ps(w), _mm256_loadu_ps(p.add(x)), a) }
    }
    let taps = ptrs.len().min(wts.len());
    let quads = taps / 4 * 4;
    // SAFETY: the caller's rows and output hold n >= 8 values; every access covers
    // [x0, x0 + 8) with x0 + 8 <= n.
    unsafe {
        while x < n {
            let x0 = if x + 8 <= n { x } else { n - 8 };
            // Four named sums, not an array indexed by `t % 4`: a computed index kept the
            // sums on the stack, each multiply-add waiting on a store and a reload (the
            // Gabor bank's column passes on a 20x15 level spent 60 % of their time here).
            let [mut a0, mut a1, mut a2, mut a3] = [_mm256_setzero_ps(); 4];
            let mut t = 0;
            while t < quads {
                a0 = fma8(wts[t], ptrs[t], x0, a0);
                a1 = fma8(wts[t + 1], ptrs[t + 1], x0, a1);
                a2 = fma8(wts[t + 2], ptrs[t + 2], x0, a2);
                a3 = fma8(wts[t + 3], ptrs[t + 3], x0, a3);
                t += 4;
            }
            while t < taps {
                a0 = fma8(wts[t], ptrs[t], x0, a0);
                t += 1;
            }
            _mm256_storeu_ps(o.add(x0), _mm256_add_ps(_mm256_add_ps(a0, a1), _mm256_add_ps(a2, a3)));
            x = x0 + 8;
        }
    }
}

/// `accumulate_rows_avx2` with 512-bit registers (16 outputs each) where the generic kernel
/// keeps one chain per output (the first `32 floor(n / 32)` outputs), then the same tail.
/// When every row starts at the same offset within a cache line, a masked first vector
/// brings the rest of the loads onto cache-line boundaries: a 64-byte load that straddles
/// two lines costs two, and with every load split the 512-bit kernel would gain nothing.
#[target_feature(enable = "avx512f,avx2,fma")]
pub(super) unsafe fn accumulate_rows_avx512(src: &Plane<f32>, rows: &[(usize, f32)], out: &mut [f32]) -> bool {
    let n = out.len();
    let Some((ptrs, wts)) = row_pointers(src, rows, n) else { return false };
    let (ptrs, wts) = (&ptrs[..rows.len()], &wts[..rows.len()]);
    let o = out.as_mut_ptr();
    let n32 = n / 32 * 32;
    let line = |p: *const f32| (p as usize) % 64;
    let head = match ptrs.first() {
        Some(&p0) if ptrs.iter().all(|&p| line(p) == line(p0)) => ((64 - line(p0)) % 64 / 4).min(n32),
        _ => 0,
    };
    // `L` output vectors of 16 from `x`, one chain each; `mask` limits the last vector.
    #[inline(always)]
    unsafe fn chunk<const L: usize>(ptrs: &[*const f32], wts: &[f32], o: *mut f32, x: usize, mask: __mmask16) {
        // SAFETY: the caller keeps the unmasked elements within every row and the output.
        unsafe {
            let mut a = [_mm512_setzero_ps(); L];
            for (&p, &w) in ptrs.iter().zip(wts) {
                let w = _mm512_set1_ps(w);
                for (k, a) in a.iter_mut().enumerate() {
                    let v = if k + 1 == L {
                        _mm512_maskz_loadu_ps(mask, p.add(x + 16 * k))
                    } else {
                        _mm512_loadu_ps(p.add(x + 16 * k))
                    };
                    *a = _mm512_fmadd_ps(w, v, *a);
                }
            }
            for (k, a) in a.iter().enumerate() {
                if k + 1 == L {
                    _mm512_mask_storeu_ps(o.add(x + 16 * k), mask, *a);
                } else {
                    _mm512_storeu_ps(o.add(x + 16 * k), *a);
                }
            }
        }
    }
    // SAFETY (all loads and stores below): every row holds at least n values (checked
    // above) and every unmasked access lies in [x, n32) with n32 <= n.
    unsafe {
        let mut x = 0;
        if head > 0 {
            chunk::<1>(ptrs, wts, o, 0, (1u16 << head) - 1);
            x = head;
        }
        while x + 128 <= n32 {
            chunk::<8>(ptrs, wts, o, x, !0);
            x += 128;
        }
        if x + 64 <= n32 {
            chunk::<4>(ptrs, wts, o, x, !0);
            x += 64;
        }
        if x + 32 <= n32 {
            chunk::<2>(ptrs, wts, o, x, !0);
            x += 32;
        }
        while x < n32 {
            let left = n32 - x;
            let mask = if left >= 16 { !0 } else { (1u16 << left) - 1 };
            chunk::<1>(ptrs, wts, o, x, mask);
            x += 16.min(left);
        }
        tail_quads(ptrs, wts, o, n32, n);
    }
    true
}

/// The folded correlation of a padded row, as `correlate_folded_generic`: `out[x] =
/// k[h] p[x + h] + sum_t k[h + t] (p[x + h + t] ± p[x + h - t])` (the centre term left
/// out for an odd kernel). False (nothing written) for fewer than 8 outputs or a `p`
/// shorter than `out.len() + k.len() - 1`.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn correlate_folded_avx2(p: &[f32], k: &[f32], odd: bool, out: &mut [f32]) -> bool {
    let n = out.len();
    let h = k.len() / 2;
    if n < 8 || k.is_empty() || p.len() < n + 2 * h {
        return false;
    }
    let (c, o) = (p.as_ptr().wrapping_add(h), out.as_mut_ptr());
    let kc = _mm256_set1_ps(k[h]);
    // `L` output vectors of 8 from `x` (`c` points at the centre tap of output 0).
    #[inline(always)]
    unsafe fn chunk<const L: usize>(c: *const f32, o: *mut f32, x: usize, k: &[f32], kc: __m256, odd: bool) {
        let h = k.len() / 2;
        // SAFETY: the caller keeps x + 8 L <= n, so every load lies in p[x, x + 8 L + 2 h).
        unsafe {
            let mut a = [_mm256_setzero_ps(); L];
            if !odd {
                for (j, a) in a.iter_mut().enumerate() {
                    *a = _mm256_mul_ps(kc, _mm256_loadu_ps(c.add(x + 8 * j)));
                }
            }
            for t in 1..=h {
                let w = _mm256_set1_ps(k[h + t]);
                for (j, a) in a.iter_mut().enumerate() {
                    let (sp, sm) = (_mm256_loadu_ps(c.add(x + 8 * j + t)), _mm256_loadu_ps(c.add(x + 8 * j).sub(t)));
                    let s = if odd { _mm256_sub_ps(sp, sm) } else { _mm256_add_ps(sp, sm) };
                    *a = _mm256_fmadd_ps(w, s, *a);
                }
            }
            for (j, a) in a.iter().enumerate() {
                _mm256_storeu_ps(o.add(x + 8 * j), *a);
            }
        }
    }
    let mut x = 0;
    // SAFETY: x + 8 L <= n in every call, and p holds n + 2 h values (checked above).
    unsafe {
        while x + 32 <= n {
            chunk::<4>(c, o, x, k, kc, odd);
            x += 32;
        }
        while x < n {
            let x0 = if x + 8 <= n { x } else { n - 8 };
            chunk::<1>(c, o, x0, k, kc, odd);
            x = x0 + 8;
        }
    }
    true
}

/// `$m!(t)` for the tap offsets 1 to 15: `valignd` takes its shift as an immediate, so each
/// offset is written out (the tap macros skip those beyond the kernel's half-width).
macro_rules! each_tap_1_to_15 {
    ($m:ident) => {
        $m!(1);
        $m!(2);
        $m!(3);
        $m!(4);
        $m!(5);
        $m!(6);
        $m!(7);
        $m!(8);
        $m!(9);
        $m!(10);
        $m!(11);
        $m!(12);
        $m!(13);
        $m!(14);
        $m!(15);
    };
}

/// Longest half-width `h` that [`correlate_folded_avx512`] takes (kernels of up to 33 taps):
/// every tap then reads from the aligned vectors just before, at and after an output's.
pub(super) const FOLDED_512_MAX_HALF: usize = 16;

/// The folded correlation of a padded row, as `correlate_folded_generic`, with 512-bit
/// registers and every load on a cache-line boundary. Why: with a row shifted by every tap
/// offset in turn, a 64-byte load straddles two cache lines 15 times out of 16 and costs two;
/// here each output vector loads the aligned vectors before, at and after it once, and the
/// shifted ones are cut from them (`valignd`). The padded row is `buf[start..]` (`p` of the
/// generic kernel, `out.len() + 2 h` values); the caller places it so that
/// `buf[start + h]` (output 0's centre) is 64-byte aligned, with 16 values of room before
/// it and 48 after `buf[start + h + out.len()]`. False (nothing written) otherwise, and for
/// fewer than 8 outputs.
#[target_feature(enable = "avx512f,avx2,fma")]
pub(super) unsafe fn correlate_folded_avx512(buf: &[f32], start: usize, k: &[f32], odd: bool, out: &mut [f32]) -> bool {
    let n = out.len();
    let h = k.len() / 2;
    let c = buf.as_ptr().wrapping_add(start + h);
    // Below 8 outputs the generic kernel sums in another order; it keeps them.
    if n < 8
        || k.len().is_multiple_of(2)
        || h > FOLDED_512_MAX_HALF
        || start + h < 16
        || !(c as usize).is_multiple_of(64)
    {
        return false;
    }
    if buf.len() < start + h + n.div_ceil(16) * 16 + 32 {
        return false;
    }
    // Taps as broadcast registers, the centre first.
    let mut w = [_mm512_setzero_ps(); FOLDED_512_MAX_HALF + 1];
    for (t, w) in w.iter_mut().enumerate().take(h + 1) {
        *w = _mm512_set1_ps(k[h + t]);
    }
    let o = out.as_mut_ptr();
    let nv = n.div_ceil(16);
    // SAFETY: vector v reads buf[start + h + 16 (v - 1) .. start + h + 16 (v + 2)], inside
    // buf for v < nv (checked above); stores write out[16 v ..] masked to n.
    unsafe {
        let mut v = 0;
        while v + 4 <= nv {
            folded_vectors::<4>(c, o, v, n, &w, h, odd);
            v += 4;
        }
        if v + 2 <= nv {
            folded_vectors::<2>(c, o, v, n, &w, h, odd);
            v += 2;
        }
        while v < nv {
            folded_vectors::<1>(c, o, v, n, &w, h, odd);
            v += 1;
        }
    }
    true
}

/// Output vectors `v0 .. v0 + L` of [`correlate_folded_avx512`]: for each, `w[0] c + sum_t
/// w[t] (c[+t] ± c[-t])` (the centre term left out for an odd kernel), the shifted vectors
/// cut from the aligned ones before (`m`), at (`a`) and after (`b`) it.
#[inline(always)]
unsafe fn folded_vectors<const L: usize>(
    c: *const f32,
    o: *mut f32,
    v0: usize,
    n: usize,
    w: &[__m512; FOLDED_512_MAX_HALF + 1],
    h: usize,
    odd: bool,
) {
    // SAFETY: the caller keeps the three aligned vectors of each output inside the buffer.
    unsafe {
        let mut m = [_mm512_setzero_ps(); L];
        let mut a = [_mm512_setzero_ps(); L];
        let mut b = [_mm512_setzero_ps(); L];
        let mut acc = [_mm512_setzero_ps(); L];
        for j in 0..L {
            let x = 16 * (v0 + j);
            m[j] = _mm512_load_ps(c.add(x).sub(16));
            a[j] = _mm512_load_ps(c.add(x));
            b[j] = _mm512_load_ps(c.add(x + 16));
            if !odd {
                acc[j] = _mm512_mul_ps(w[0], a[j]);
            }
        }
        // One tap: its two shifted vectors from `valignd` with immediate offsets, so each
        // tap is written out once per offset.
        macro_rules! tap {
            ($t:literal) => {
                if $t <= h {
                    for j in 0..L {
                        let sp = _mm512_castsi512_ps(_mm512_alignr_epi32::<$t>(
                            _mm512_castps_si512(b[j]),
                            _mm512_castps_si512(a[j]),
                        ));
                        let sm = _mm512_castsi512_ps(_mm512_alignr_epi32::<{ 16 - $t }>(
                            _mm512_castps_si512(a[j]),
                            _mm512_castps_si512(m[j]),
                        ));
                        let s = if odd { _mm512_sub_ps(sp, sm) } else { _mm512_add_ps(sp, sm) };
                        acc[j] = _mm512_fmadd_ps(w[$t], s, acc[j]);
                    }
                }
            };
        }
        each_tap_1_to_15!(tap);
        if h >= 16 {
            for j in 0..L {
                let s = if odd { _mm512_sub_ps(b[j], m[j]) } else { _mm512_add_ps(b[j], m[j]) };
                acc[j] = _mm512_fmadd_ps(w[16], s, acc[j]);
            }
        }
        for j in 0..L {
            let x = 16 * (v0 + j);
            let left = n - x;
            let mask = if left >= 16 { !0u16 } else { (1u16 << left) - 1 };
            _mm512_mask_storeu_ps(o.add(x), mask, acc[j]);
        }
    }
}

/// Most kernels [`bank_rows_avx512`] filters a row with at once.
pub(super) const BANK_MAX: usize = 8;

/// The taps of a bank's even and odd kernels (centre first), after the checks both bank
/// kernels need: `E` even and `O` odd indices, each kernel once, all of one odd length of
/// half-width `h` at most [`FOLDED_512_MAX_HALF`], the outputs `src`'s size, `src` at least
/// 8 wide.
struct BankTaps<const E: usize, const O: usize> {
    h: usize,
    we: [[f32; FOLDED_512_MAX_HALF + 1]; E],
    wo: [[f32; FOLDED_512_MAX_HALF + 1]; O],
}

impl<const E: usize, const O: usize> BankTaps<E, O> {
    fn new(src: &Plane<f32>, ks: &[&[f32]], (even, odd): (&[usize], &[usize]), dsts: &[Plane<f32>]) -> Option<Self> {
        let (w, h_img) = src.size();
        let len = ks.first()?.len();
        let h = len / 2;
        let n = ks.len();
        let fits = even.len() == E
            && odd.len() == O
            && dsts.len() == n
            && even.iter().chain(odd).all(|&i| i < n)
            && (0..n).all(|i| even.iter().chain(odd).filter(|&&j| j == i).count() == 1)
            && w >= 8
            && !len.is_multiple_of(2)
            && h <= FOLDED_512_MAX_HALF
            && ks.iter().all(|k| k.len() == len)
            && dsts.iter().all(|d| d.size() == (w, h_img));
        if !fits {
            return None;
        }
        let table = |k: &[f32]| {
            let mut t = [0f32; FOLDED_512_MAX_HALF + 1];
            t[..=h].copy_from_slice(&k[h..]);
            t
        };
        Some(Self {
            h,
            we: std::array::from_fn(|i| table(ks[even[i]])),
            wo: std::array::from_fn(|i| table(ks[odd[i]])),
        })
    }
}

/// Every row of `src` through each of the kernels `ks` (all of one odd length, half-width at
/// most [`FOLDED_512_MAX_HALF`]; those at the indices `even` even-symmetric, those at `odd`
/// odd-symmetric) into the plane of `dsts` at the same index (already `src`'s size), padded
/// by `border`: what [`correlate_folded_avx512`] gives for each kernel alone, bit for bit,
/// from one pass over the row. Why: the shifted vectors (two `valignd` per tap) and the pair
/// sums and differences are the same for every kernel of a bank that filters one input, so
/// they are cut once for all of them instead of once per kernel; the Gabor bank's six row
/// passes become one. The parities are type parameters so that each tap's multiply-add
/// takes its sum or difference without a run-time choice. False (nothing written) when the
/// sizes or kernels do not fit.
///
/// # Safety
/// The CPU must have AVX-512 F (and AVX2, FMA).
#[target_feature(enable = "avx512f,avx2,fma")]
pub(super) unsafe fn bank_rows_avx512<const E: usize, const O: usize>(
    src: &Plane<f32>,
    ks: &[&[f32]],
    (even, odd): (&[usize], &[usize]),
    dsts: &mut [Plane<f32>],
    border: super::Border,
    padded: &mut Vec<f32>,
) -> bool {
    let (w, h_img) = src.size();
    let Some(BankTaps { h, we, wo }) = BankTaps::<E, O>::new(src, ks, (even, odd), dsts) else { return false };
    // The padded row placed as `rows_pass` places it: output 0's centre on a cache line.
    let start = super::aligned_padding(padded, w, h);
    let nv = w.div_ceil(16);
    if padded.len() < start + h + nv * 16 + 32 {
        return false;
    }
    for y in 0..h_img {
        super::pad_into(src.row(y), h, border, &mut padded[start..start + w + 2 * h]);
        let c = padded.as_ptr().wrapping_add(start + h);
        // Distinct planes (each index once, checked above), so the rows do not alias.
        let oe: [*mut f32; E] = std::array::from_fn(|i| dsts[even[i]].row_mut(y).as_mut_ptr());
        let oo: [*mut f32; O] = std::array::from_fn(|i| dsts[odd[i]].row_mut(y).as_mut_ptr());
        for v in 0..nv {
            // SAFETY: vector v reads padded[start + h + 16 (v - 1) .. start + h + 16 (v + 2)],
            // inside the buffer (checked above); stores write the rows' [16 v, w) masked.
            unsafe { bank_vector::<E, O>(c, (&oe, &oo), v, w, (&we, &wo), h) };
        }
    }
    true
}

/// Output vector `v` of every kernel of [`bank_rows_avx512`], each as
/// [`folded_vectors`] computes it: `w[0] c + sum_t w[t] (c[+t] ± c[-t])` (the centre term
/// left out for an odd kernel), taps in the same order.
#[allow(clippy::type_complexity)]
#[inline(always)]
unsafe fn bank_vector<const E: usize, const O: usize>(
    c: *const f32,
    (oe, oo): (&[*mut f32; E], &[*mut f32; O]),
    v: usize,
    n: usize,
    (we, wo): (&[[f32; FOLDED_512_MAX_HALF + 1]; E], &[[f32; FOLDED_512_MAX_HALF + 1]; O]),
    h: usize,
) {
    // SAFETY: the caller keeps the three aligned vectors inside the buffer and the stores
    // inside the rows.
    unsafe {
        let x = 16 * v;
        let m = _mm512_load_ps(c.add(x).sub(16));
        let a = _mm512_load_ps(c.add(x));
        let b = _mm512_load_ps(c.add(x + 16));
        let mut ae: [__m512; E] = std::array::from_fn(|k| _mm512_mul_ps(_mm512_set1_ps(we[k][0]), a));
        let mut ao = [_mm512_setzero_ps(); O];
        macro_rules! tap {
            ($t:literal) => {
                if $t <= h {
                    let sp =
                        _mm512_castsi512_ps(_mm512_alignr_epi32::<$t>(_mm512_castps_si512(b), _mm512_castps_si512(a)));
                    let sm = _mm512_castsi512_ps(_mm512_alignr_epi32::<{ 16 - $t }>(
                        _mm512_castps_si512(a),
                        _mm512_castps_si512(m),
                    ));
                    if E > 0 {
                        let s = _mm512_add_ps(sp, sm);
                        for k in 0..E {
                            ae[k] = _mm512_fmadd_ps(_mm512_set1_ps(we[k][$t]), s, ae[k]);
                        }
                    }
                    if O > 0 {
                        let d = _mm512_sub_ps(sp, sm);
                        for k in 0..O {
                            ao[k] = _mm512_fmadd_ps(_mm512_set1_ps(wo[k][$t]), d, ao[k]);
                        }
                    }
                }
            };
        }
        each_tap_1_to_15!(tap);
        if h >= 16 {
            let (s, d) = (_mm512_add_ps(b, m), _mm512_sub_ps(b, m));
            for k in 0..E {
                ae[k] = _mm512_fmadd_ps(_mm512_set1_ps(we[k][16]), s, ae[k]);
            }
            for k in 0..O {
                ao[k] = _mm512_fmadd_ps(_mm512_set1_ps(wo[k][16]), d, ao[k]);
            }
        }
        let left = n - x;
        let mask = if left >= 16 { !0u16 } else { (1u16 << left) - 1 };
        for k in 0..E {
            _mm512_mask_storeu_ps(oe[k].add(x), mask, ae[k]);
        }
        for k in 0..O {
            _mm512_mask_storeu_ps(oo[k].add(x), mask, ao[k]);
        }
    }
}

/// [`bank_rows_avx512`] with 256-bit registers and unaligned loads, as
/// [`correlate_folded_avx2`] computes each kernel alone (bit for bit): the two shifted
/// vectors of each tap, and their sum and difference, are loaded and formed once for every
/// kernel of the bank. False (nothing written) when the sizes or kernels do not fit.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn bank_rows_avx2<const E: usize, const O: usize>(
    src: &Plane<f32>,
    ks: &[&[f32]],
    (even, odd): (&[usize], &[usize]),
    dsts: &mut [Plane<f32>],
    border: super::Border,
    padded: &mut Vec<f32>,
) -> bool {
    let (w, h_img) = src.size();
    let Some(BankTaps { h, we, wo }) = BankTaps::<E, O>::new(src, ks, (even, odd), dsts) else { return false };
    padded.resize(w + 2 * h, 0.0);
    for y in 0..h_img {
        super::pad_into(src.row(y), h, border, &mut padded[..w + 2 * h]);
        let c = padded.as_ptr().wrapping_add(h);
        // Distinct planes (each index once, checked above), so the rows do not alias.
        let oe: [*mut f32; E] = std::array::from_fn(|i| dsts[even[i]].row_mut(y).as_mut_ptr());
        let oo: [*mut f32; O] = std::array::from_fn(|i| dsts[odd[i]].row_mut(y).as_mut_ptr());
        let mut x = 0;
        while x < w {
            // Eight outputs at a time, the last eight aligned to the end (a few recomputed,
            // with the same values).
            let x0 = if x + 8 <= w { x } else { w - 8 };
            // SAFETY: the loads read padded[x0 .. x0 + 8 + 2 h], inside the padded row.
            unsafe { bank_pixels8::<E, O>(c, (&oe, &oo), x0, (&we, &wo), h) };
            x = x0 + 8;
        }
    }
    true
}

/// Eight outputs from `x0` of every kernel of [`bank_rows_avx2`], each as
/// [`correlate_folded_avx2`] computes it.
#[allow(clippy::type_complexity)]
#[inline(always)]
unsafe fn bank_pixels8<const E: usize, const O: usize>(
    c: *const f32,
    (oe, oo): (&[*mut f32; E], &[*mut f32; O]),
    x0: usize,
    (we, wo): (&[[f32; FOLDED_512_MAX_HALF + 1]; E], &[[f32; FOLDED_512_MAX_HALF + 1]; O]),
    h: usize,
) {
    // SAFETY: the caller keeps every load inside the padded row and the stores in the rows.
    unsafe {
        let a = _mm256_loadu_ps(c.add(x0));
        let mut ae: [__m256; E] = std::array::from_fn(|k| _mm256_mul_ps(_mm256_set1_ps(we[k][0]), a));
        let mut ao = [_mm256_setzero_ps(); O];
        for t in 1..=h {
            let (sp, sm) = (_mm256_loadu_ps(c.add(x0 + t)), _mm256_loadu_ps(c.add(x0).sub(t)));
            if E > 0 {
                let s = _mm256_add_ps(sp, sm);
                for k in 0..E {
                    ae[k] = _mm256_fmadd_ps(_mm256_set1_ps(we[k][t]), s, ae[k]);
                }
            }
            if O > 0 {
                let d = _mm256_sub_ps(sp, sm);
                for k in 0..O {
                    ao[k] = _mm256_fmadd_ps(_mm256_set1_ps(wo[k][t]), d, ao[k]);
                }
            }
        }
        for k in 0..E {
            _mm256_storeu_ps(oe[k].add(x0), ae[k]);
        }
        for k in 0..O {
            _mm256_storeu_ps(oo[k].add(x0), ao[k]);
        }
    }
}
