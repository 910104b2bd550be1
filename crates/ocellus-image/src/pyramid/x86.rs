//! The first pyramid level's vertical sums of bytes with `vpmaddubsw`.
//!
//! Why by hand: the generic loop widens every byte of every tap's row to 16 bits, multiplies
//! and adds it (three instructions per tap and 32 values, the widening on the one shuffle
//! port). Here the bytes of two taps' rows are interleaved (`vpunpck{l,h}bw`) and
//! `vpmaddubsw` multiplies and adds the pair at once, 32 values per instruction, with the
//! weights as signed bytes. The sums are exact integers either way (below 2^16, see
//! `IntegerTaps`), so the results are the generic loop's exactly (tested).

use crate::Plane;
use std::arch::x86_64::*;

/// `out[x] = sum_t w_t row_t[x]` over the interleaved bytes of `src`'s rows `taps` (`out` is
/// `3 w` long), as `vertical_bytes_u16`. False (nothing written) when a weight exceeds 127,
/// a pair of weights 128 (a pair's sum must fit a signed 16-bit lane), there are more than
/// 16 taps or fewer than 64 values.
///
/// # Safety
/// The CPU must have AVX-512 F and BW.
#[target_feature(enable = "avx512f,avx512bw,avx2")]
pub(super) unsafe fn vertical_bytes_u16_avx512(src: &Plane<[u8; 3]>, taps: &[(usize, u16)], out: &mut [u16]) -> bool {
    const MAX_PAIRS: usize = 8;
    let n = out.len();
    if taps.is_empty() || taps.len() > 2 * MAX_PAIRS || n < 64 || n > src.width() * 3 {
        return false;
    }
    if taps.iter().any(|&(r, k)| k > 127 || r >= src.height()) {
        return false;
    }
    // Taps two by two; an odd one out pairs with itself at weight 0.
    let mut pairs: [(*const u8, *const u8, __m512i); MAX_PAIRS] =
        [(std::ptr::null(), std::ptr::null(), _mm512_setzero_si512()); MAX_PAIRS];
    let mut np = 0;
    for ch in taps.chunks(2) {
        let (ra, ka) = ch[0];
        let (rb, kb) = ch.get(1).copied().unwrap_or((ra, 0));
        if ka + kb > 128 {
            return false;
        }
        // Little-endian: the low byte of each 16-bit lane (row a's byte) takes ka.
        let w = _mm512_set1_epi16(((kb << 8) | ka) as i16);
        pairs[np] = (src.row(ra).as_flattened().as_ptr(), src.row(rb).as_flattened().as_ptr(), w);
        np += 1;
    }
    let pairs = &pairs[..np];
    // unpacklo/hi interleave within 128-bit blocks: the sums of block k of the low half hold
    // values 16k..16k+8 of the 64, the high half's 16k+8..16k+16; these put them in order.
    let first = _mm512_set_epi64(11, 10, 3, 2, 9, 8, 1, 0);
    let second = _mm512_set_epi64(15, 14, 7, 6, 13, 12, 5, 4);
    let o = out.as_mut_ptr();
    let mut x = 0;
    // SAFETY: x + 64 <= n <= 3 w in every call, inside every row and `out`.
    unsafe {
        while x + 64 <= n {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The same sums as the generic loop, for the seed's interior and border taps, an odd
    /// number of taps and widths around the chunk of 64; refused for a weight above 127.
    #[test]
    fn pairs_of_rows_give_the_generic_sums() {
        if !crate::simd::avx512_available() {
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
                let mut got = vec![0u16; 3 * w];
                // SAFETY: AVX-512 was checked above.
                let done = unsafe { vertical_bytes_u16_avx512(&src, taps, &mut got) };
                assert!(done || 3 * w < 64, "width {w}, taps {taps:?}");
                if done {
                    assert_eq!(want, got, "width {w}, taps {taps:?}");
                }
            }
            let mut out = vec![0u16; 3 * w];
            // SAFETY: as above.
            assert!(!unsafe { vertical_bytes_u16_avx512(&src, &[(0, 200)], &mut out) });
        }
    }
}
