//! The first pyramid level's vertical sums of bytes with `vpmaddubsw`, and the split of
//! their interleaved RGB row into even and odd samples per channel, with AVX-512 and AVX2.
//!
//! Why by hand: the generic loop widens every byte of every tap's row to 16 bits, multiplies
//! and adds it (three instructions per tap and 32 values, the widening on the one shuffle
//! port). Here the bytes of two taps' rows are interleaved (`vpunpck{l,h}bw`) and
//! `vpmaddubsw` multiplies and adds the pair at once, 32 values per instruction, with the
//! weights as signed bytes. The sums are exact integers either way (below 2^16, see
//! `IntegerTaps`), so the results are the generic loop's exactly (tested).

use crate::Plane;
use std::arch::x86_64::*;

/// Most pairs of tap rows the byte kernels take (16 taps, [`super::MAX_TAPS`]).
const MAX_PAIRS: usize = 8;

/// The taps two by two for `vpmaddubsw`: per pair the two rows' bytes and the weight word
/// `(kb << 8) | ka` (little-endian: the low byte of each 16-bit lane, row a's byte, takes
/// ka); an odd one out pairs with itself at weight 0. With the number of pairs; `None` when
/// a weight exceeds 127, a pair's weights 128 (a pair's sum must fit a signed 16-bit lane),
/// a row is outside `src`, there are more than 16 taps, or `n` (the values to sum) is below
/// `min_n` or above the row's.
#[allow(clippy::type_complexity)]
fn row_pairs(
    src: &Plane<[u8; 3]>,
    taps: &[(usize, u16)],
    n: usize,
    min_n: usize,
) -> Option<([(*const u8, *const u8, i16); MAX_PAIRS], usize)> {
    if taps.is_empty() || taps.len() > 2 * MAX_PAIRS || n < min_n || n > src.width() * 3 {
        return None;
    }
    if taps.iter().any(|&(r, k)| k > 127 || r >= src.height()) {
        return None;
    }
    let mut pairs = [(std::ptr::null(), std::ptr::null(), 0i16); MAX_PAIRS];
    let mut np = 0;
    for ch in taps.chunks(2) {
        let (ra, ka) = ch[0];
        let (rb, kb) = ch.get(1).copied().unwrap_or((ra, 0));
        if ka + kb > 128 {
            return None;
        }
        pairs[np] = (src.row(ra).as_flattened().as_ptr(), src.row(rb).as_flattened().as_ptr(), ((kb << 8) | ka) as i16);
        np += 1;
    }
    Some((pairs, np))
}

/// `out[x] = sum_t w_t row_t[x]` over the interleaved bytes of `src`'s rows `taps` (`out` is
/// `3 w` long), as `vertical_bytes_u16`. False (nothing written) when a weight exceeds 127,
/// a pair of weights 128 (a pair's sum must fit a signed 16-bit lane), there are more than
/// 16 taps or fewer than 64 values.
///
/// # Safety
/// The CPU must have AVX-512 F and BW.
#[target_feature(enable = "avx512f,avx512bw,avx2")]
pub(super) unsafe fn vertical_bytes_u16_avx512(src: &Plane<[u8; 3]>, taps: &[(usize, u16)], out: &mut [u16]) -> bool {
    let n = out.len();
    let Some((rows, np)) = row_pairs(src, taps, n, 64) else { return false };
    let pairs: [(*const u8, *const u8, __m512i); MAX_PAIRS] = rows.map(|(a, b, w)| (a, b, _mm512_set1_epi16(w)));
    let pairs = &pairs[..np];
    let ahead = super::rows_ahead(src, taps);
    // unpacklo/hi interleave within 128-bit blocks: the sums of block k of the low half hold
    // values 16k..16k+8 of the 64, the high half's 16k+8..16k+16; these put them in order.
    let first = _mm512_set_epi64(11, 10, 3, 2, 9, 8, 1, 0);
    let second = _mm512_set_epi64(15, 14, 7, 6, 13, 12, 5, 4);
    let o = out.as_mut_ptr();
    let mut x = 0;
    // SAFETY: x + 64 <= n <= 3 w in every call, inside every row and `out`.
    unsafe {
        while x + 64 <= n {
            for r in ahead.iter().flatten() {
                _mm_prefetch::<_MM_HINT_T0>(r.as_ptr().add(x) as *const i8);
            }
            chunk(pairs, o, x, first, second);
            x += 64;
        }
        if x < n {
            // One chunk aligned to the end; recomputes a few values.
            chunk(pairs, o, n - 64, first, second);
        }
    }
    true
}

/// 64 values from `x` (a function, not a closure, so that it is compiled with the caller's
/// target features).
#[inline(always)]
unsafe fn chunk(pairs: &[(*const u8, *const u8, __m512i)], o: *mut u16, x: usize, first: __m512i, second: __m512i) {
    // SAFETY: the caller keeps x + 64 within every row and `out`.
    unsafe {
        let (mut lo, mut hi) = (_mm512_setzero_si512(), _mm512_setzero_si512());
        for &(a, b, w) in pairs {
            let (va, vb) = (_mm512_loadu_si512(a.add(x) as *const _), _mm512_loadu_si512(b.add(x) as *const _));
            lo = _mm512_add_epi16(lo, _mm512_maddubs_epi16(_mm512_unpacklo_epi8(va, vb), w));
            hi = _mm512_add_epi16(hi, _mm512_maddubs_epi16(_mm512_unpackhi_epi8(va, vb), w));
        }
        _mm512_storeu_si512(o.add(x) as *mut _, _mm512_permutex2var_epi64(lo, first, hi));
        _mm512_storeu_si512(o.add(x + 32) as *mut _, _mm512_permutex2var_epi64(lo, second, hi));
    }
}

/// [`vertical_bytes_u16_avx512`] with 256-bit registers, 32 values at a time: the same
/// pairs of rows through `vpmaddubsw`, which halves the multiplies of the generic loop (on
/// AMD Zen 3 they share one pipe, the loop's bound). The same exact sums; false (nothing
/// written) in the same cases, and for fewer than 32 values.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn vertical_bytes_u16_avx2(src: &Plane<[u8; 3]>, taps: &[(usize, u16)], out: &mut [u16]) -> bool {
    let n = out.len();
    let Some((rows, np)) = row_pairs(src, taps, n, 32) else { return false };
    let pairs: [(*const u8, *const u8, __m256i); MAX_PAIRS] = rows.map(|(a, b, w)| (a, b, _mm256_set1_epi16(w)));
    let pairs = &pairs[..np];
    let ahead = super::rows_ahead(src, taps);
    let o = out.as_mut_ptr();
    let mut x = 0;
    // SAFETY: x + 32 <= n <= 3 w in every call, inside every row and `out`.
    unsafe {
        while x + 32 <= n {
            if x % 64 == 0 {
                for r in ahead.iter().flatten() {
                    _mm_prefetch::<_MM_HINT_T0>(r.as_ptr().add(x) as *const i8);
                }
            }
            chunk_avx2(pairs, o, x);
            x += 32;
        }
        if x < n {
            chunk_avx2(pairs, o, n - 32);
        }
    }
    true
}

/// 32 values from `x` of [`vertical_bytes_u16_avx2`].
#[inline(always)]
unsafe fn chunk_avx2(pairs: &[(*const u8, *const u8, __m256i)], o: *mut u16, x: usize) {
    // SAFETY: the caller keeps x + 32 within every row and `out`.
    unsafe {
        let (mut lo, mut hi) = (_mm256_setzero_si256(), _mm256_setzero_si256());
        for &(a, b, w) in pairs {
            let (va, vb) = (_mm256_loadu_si256(a.add(x) as *const _), _mm256_loadu_si256(b.add(x) as *const _));
            lo = _mm256_add_epi16(lo, _mm256_maddubs_epi16(_mm256_unpacklo_epi8(va, vb), w));
            hi = _mm256_add_epi16(hi, _mm256_maddubs_epi16(_mm256_unpackhi_epi8(va, vb), w));
        }
        // unpacklo/hi work within 128-bit halves: `lo` holds values 0..8 and 16..24, `hi`
        // 8..16 and 24..32.
        _mm256_storeu_si256(o.add(x) as *mut _, _mm256_permute2x128_si256::<0x20>(lo, hi));
        _mm256_storeu_si256(o.add(x + 16) as *mut _, _mm256_permute2x128_si256::<0x31>(lo, hi));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same sums as the generic loop (AVX-512 and AVX2 kernels), for the seed's interior
    /// and border taps, an odd number of taps and widths around the chunks of 64 and 32;
    /// refused for a weight above 127.
    #[test]
    fn pairs_of_rows_give_the_generic_sums() {
        if !crate::simd::avx2_available() {
            return;
        }
        let mut rng = crate::rng::SplitMix64::new(4);
        for w in [22usize, 23, 30, 64, 100, 213] {
            let src: Plane<[u8; 3]> = Plane::from_fn(w, 9, |_, _| std::array::from_fn(|_| (rng.unit() * 256.0) as u8));
            let sets: [&[(usize, u16)]; 4] = [
                &[(1, 1), (2, 5), (3, 10), (4, 10), (5, 5), (6, 1)],
                &[(0, 10), (1, 10), (2, 5), (3, 1)],
                &[(8, 3), (2, 7), (5, 3)],
                &[(4, 127), (0, 1)],
            ];
            for taps in sets {
                let mut want = vec![0u16; 3 * w];
                crate::pyramid::vertical_bytes_u16(&src, taps, &mut want);
                if crate::simd::avx512_available() {
                    let mut got = vec![0u16; 3 * w];
                    // SAFETY: AVX-512 was checked.
                    let done = unsafe { vertical_bytes_u16_avx512(&src, taps, &mut got) };
                    assert!(done || 3 * w < 64, "width {w}, taps {taps:?}");
                    if done {
                        assert_eq!(want, got, "width {w}, taps {taps:?}");
                    }
                }
                let mut got = vec![0u16; 3 * w];
                // SAFETY: AVX2 was checked above.
                let done = unsafe { vertical_bytes_u16_avx2(&src, taps, &mut got) };
                assert!(done || 3 * w < 32, "width {w}, taps {taps:?}");
                if done {
                    assert_eq!(want, got, "AVX2, width {w}, taps {taps:?}");
                }
            }
            let mut out = vec![0u16; 3 * w];
            // SAFETY: as above.
            assert!(!unsafe { vertical_bytes_u16_avx2(&src, &[(0, 200)], &mut out) });
            if crate::simd::avx512_available() {
                // SAFETY: as above.
                assert!(!unsafe { vertical_bytes_u16_avx512(&src, &[(0, 200)], &mut out) });
            }
        }
    }
}

/// The word permutes of [`split_even_odd_avx512`], fixed for every row and so built at
/// compile time: per half q = (parity, channel c), the word of output j is word
/// `6 j + 3 parity + c` of 192 loaded ones; `idx[q][p]` gives its index within loaded vectors
/// 2p and 2p + 1, `from[q]` the outputs taken from the second and third pair.
struct SplitTables {
    idx: [[[i16; 32]; 3]; 6],
    from: [[u32; 2]; 6],
}

const SPLIT: SplitTables = {
    let mut t = SplitTables { idx: [[[0; 32]; 3]; 6], from: [[0; 2]; 6] };
    let mut q = 0;
    while q < 6 {
        let off = 3 * (q / 3) + q % 3;
        let mut j = 0;
        while j < 32 {
            let i = 6 * j + off;
            t.idx[q][i / 64][j] = (i % 64) as i16;
            if i >= 64 {
                t.from[q][0] |= 1 << j;
            }
            if i >= 128 {
                t.from[q][1] |= 1 << j;
            }
            j += 1;
        }
        q += 1;
    }
    t
};

/// [`super::split_even_odd`] of a row of 16-bit sums: `even[c][k] = row[6 k + c] * scale`,
/// `odd[c][k] = row[6 k + 3 + c] * scale`. Why by hand: LLVM's form of the six-way split
/// was a third of the first level's time. Here 32 outputs of each of the six halves come
/// from six loaded vectors: three two-source word permutes and two blends pick them, then
/// they are widened, converted and scaled (the same product as the generic loop, so the
/// same values; tested). False (nothing written) when the halves are shorter than the row
/// needs.
///
/// # Safety
/// The CPU must have AVX-512 F and BW.
#[target_feature(enable = "avx512f,avx512bw,avx2")]
pub(super) unsafe fn split_even_odd_avx512(
    row: &[u16],
    scale: f32,
    even: [&mut [f32]; 3],
    odd: [&mut [f32]; 3],
) -> bool {
    let w = row.len() / 3;
    let half = w / 2;
    if even.iter().any(|e| e.len() < w.div_ceil(2)) || odd.iter().any(|o| o.len() < half) {
        return false;
    }
    // SAFETY: each table row holds 32 words.
    let idx: [[__m512i; 3]; 6] = std::array::from_fn(|q| {
        std::array::from_fn(|p| unsafe { _mm512_loadu_si512(SPLIT.idx[q][p].as_ptr() as *const _) })
    });
    let from = SPLIT.from;
    let [e0, e1, e2] = even;
    let [o0, o1, o2] = odd;
    let outs: [*mut f32; 6] =
        [e0.as_mut_ptr(), e1.as_mut_ptr(), e2.as_mut_ptr(), o0.as_mut_ptr(), o1.as_mut_ptr(), o2.as_mut_ptr()];
    let sv = _mm512_set1_ps(scale);
    let blocks = half / 32;
    for b in 0..blocks {
        // SAFETY: block b reads row[192 b .. 192 (b + 1)] (192 (b + 1) <= 6 half <= 3 w) and
        // writes outputs [32 b, 32 b + 32) of halves at least `half` long.
        unsafe {
            let p = row.as_ptr().add(192 * b);
            let a: [__m512i; 6] = std::array::from_fn(|i| _mm512_loadu_si512(p.add(32 * i) as *const _));
            for q in 0..6 {
                let r1 = _mm512_permutex2var_epi16(a[0], idx[q][0], a[1]);
                let r2 = _mm512_permutex2var_epi16(a[2], idx[q][1], a[3]);
                let r3 = _mm512_permutex2var_epi16(a[4], idx[q][2], a[5]);
                let r = _mm512_mask_blend_epi16(from[q][1], _mm512_mask_blend_epi16(from[q][0], r1, r2), r3);
                let lo = _mm512_cvtepi32_ps(_mm512_cvtepu16_epi32(_mm512_castsi512_si256(r)));
                let hi = _mm512_cvtepi32_ps(_mm512_cvtepu16_epi32(_mm512_extracti64x4_epi64::<1>(r)));
                _mm512_storeu_ps(outs[q].add(32 * b), _mm512_mul_ps(lo, sv));
                _mm512_storeu_ps(outs[q].add(32 * b + 16), _mm512_mul_ps(hi, sv));
            }
        }
    }
    // SAFETY: the halves were checked above.
    unsafe { split_tail(row, scale, outs, 32 * blocks) };
    true
}

/// The split's outputs from `k0` on, one at a time, and the last pixel of an odd row: the
/// generic loop's products.
///
/// # Safety
/// `outs` are the even halves (at least `ceil(w / 2)` values, w = `row.len() / 3`) then the
/// odd ones (at least `w / 2`).
#[inline(always)]
unsafe fn split_tail(row: &[u16], scale: f32, outs: [*mut f32; 6], k0: usize) {
    let w = row.len() / 3;
    for k in k0..w / 2 {
        let px = &row[6 * k..6 * k + 6];
        for c in 0..3 {
            // SAFETY: k < w / 2 <= every half's length.
            unsafe {
                *outs[c].add(k) = px[c] as f32 * scale;
                *outs[3 + c].add(k) = px[3 + c] as f32 * scale;
            }
        }
    }
    if w % 2 == 1 {
        let last = &row[3 * (w - 1)..3 * w];
        for c in 0..3 {
            // SAFETY: the even halves hold ceil(w / 2) values.
            unsafe { *outs[c].add(w / 2) = last[c] as f32 * scale };
        }
    }
}

/// [`split_even_odd_avx512`] with 256-bit registers: 8 outputs of each of the six halves
/// from 48 words (16 pixels). The words are widened and converted to floats and scaled (the
/// generic loop's product, so the same values; tested); per channel two blends gather its
/// 8 values of 8 pixels, with the 3-periodic masks of the interleaved layout, and a
/// permute orders them evens first; the halves of two such groups are then the even and
/// odd outputs. Why by hand: LLVM's form of the six-way split was a quarter of the first
/// level's time with AVX2 on an AMD EPYC (Zen 3). False (nothing written) as the AVX-512 one.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn split_even_odd_avx2(row: &[u16], scale: f32, even: [&mut [f32]; 3], odd: [&mut [f32]; 3]) -> bool {
    let w = row.len() / 3;
    let half = w / 2;
    if even.iter().any(|e| e.len() < w.div_ceil(2)) || odd.iter().any(|o| o.len() < half) {
        return false;
    }
    // After the blends, lane i of channel c holds pixel [0,3,6,1,4,7,2,5] (R),
    // [5,0,3,6,1,4,7,2] (G), [2,5,0,3,6,1,4,7] (B) of the group of 8; these put pixels
    // 0,2,4,6,1,3,5,7 in order.
    let order = [
        _mm256_setr_epi32(0, 6, 4, 2, 3, 1, 7, 5),
        _mm256_setr_epi32(1, 7, 5, 3, 4, 2, 0, 6),
        _mm256_setr_epi32(2, 0, 6, 4, 5, 3, 1, 7),
    ];
    // Channel c of pixel p is float 3 p + c of the group's three vectors (a, b, d).
    #[inline(always)]
    unsafe fn channel<const MB: i32, const MD: i32>(a: __m256, b: __m256, d: __m256, order: __m256i) -> __m256 {
        // SAFETY: inlined into the AVX2 function.
        unsafe { _mm256_permutevar8x32_ps(_mm256_blend_ps::<MD>(_mm256_blend_ps::<MB>(a, b), d), order) }
    }
    let [e0, e1, e2] = even;
    let [o0, o1, o2] = odd;
    let outs: [*mut f32; 6] =
        [e0.as_mut_ptr(), e1.as_mut_ptr(), e2.as_mut_ptr(), o0.as_mut_ptr(), o1.as_mut_ptr(), o2.as_mut_ptr()];
    let sv = _mm256_set1_ps(scale);
    let blocks = half / 8;
    for b in 0..blocks {
        // SAFETY: block b reads row[48 b .. 48 (b + 1)] (48 (b + 1) <= 6 half <= 3 w) and
        // writes outputs [8 b, 8 b + 8) of halves at least `half` long.
        unsafe {
            let p = row.as_ptr().add(48 * b);
            let f: [__m256; 6] = std::array::from_fn(|i| {
                let v = _mm256_cvtepu16_epi32(_mm_loadu_si128(p.add(8 * i) as *const __m128i));
                _mm256_mul_ps(_mm256_cvtepi32_ps(v), sv)
            });
            let groups: [[__m256; 3]; 2] = std::array::from_fn(|g| {
                let (a, bb, d) = (f[3 * g], f[3 * g + 1], f[3 * g + 2]);
                [
                    channel::<0x92, 0x24>(a, bb, d, order[0]),
                    channel::<0x24, 0x49>(a, bb, d, order[1]),
                    channel::<0x49, 0x92>(a, bb, d, order[2]),
                ]
            });
            for c in 0..3 {
                let (x0, x1) = (groups[0][c], groups[1][c]);
                _mm256_storeu_ps(outs[c].add(8 * b), _mm256_permute2f128_ps::<0x20>(x0, x1));
                _mm256_storeu_ps(outs[3 + c].add(8 * b), _mm256_permute2f128_ps::<0x31>(x0, x1));
            }
        }
    }
    // SAFETY: the halves were checked above.
    unsafe { split_tail(row, scale, outs, 8 * blocks) };
    true
}

#[cfg(test)]
mod split_tests {
    use super::*;

    /// The same halves as the generic split, on widths with and without a last block of 32
    /// and an odd last pixel.
    #[test]
    fn split_equals_the_generic_split() {
        if !crate::simd::avx2_available() {
            return;
        }
        let mut rng = crate::rng::SplitMix64::new(8);
        for w in [1usize, 2, 5, 15, 16, 17, 31, 63, 64, 65, 127, 640, 641] {
            let row: Vec<u16> = (0..3 * w).map(|_| (rng.unit() * 8160.0) as u16).collect();
            let scale = 1.0 / (32.0 * 255.0);
            let mk = || -> ([Vec<f32>; 3], [Vec<f32>; 3]) {
                (std::array::from_fn(|_| vec![f32::NAN; w.div_ceil(2)]), std::array::from_fn(|_| vec![f32::NAN; w / 2]))
            };
            let (mut we, mut wo) = mk();
            {
                let [a, b, c] = &mut we;
                let [d, e, f] = &mut wo;
                crate::pyramid::split_even_odd(&row, scale, [a, b, c], [d, e, f]);
            }
            let bits = |v: &[Vec<f32>; 3]| -> Vec<u32> { v.iter().flatten().map(|x| x.to_bits()).collect() };
            for wide in [false, true] {
                if wide && !crate::simd::avx512_available() {
                    continue;
                }
                let (mut ge, mut go) = mk();
                let done = {
                    let [a, b, c] = &mut ge;
                    let [d, e, f] = &mut go;
                    // SAFETY: AVX2 was checked above, AVX-512 where it is used.
                    unsafe {
                        if wide {
                            split_even_odd_avx512(&row, scale, [a, b, c], [d, e, f])
                        } else {
                            split_even_odd_avx2(&row, scale, [a, b, c], [d, e, f])
                        }
                    }
                };
                assert!(done, "width {w}");
                assert_eq!(bits(&we), bits(&ge), "even halves, width {w}, AVX-512 {wide}");
                assert_eq!(bits(&wo), bits(&go), "odd halves, width {w}, AVX-512 {wide}");
            }
        }
    }
}
