//! Packing eight maps into SIMD lanes by 8x8 transposes.
//!
//! Why by hand: written per pixel, the packing is eight scalar loads and stores a pixel
//! (about 4 us for eight 40 x 30 maps, seven times a frame); as blocks of eight pixels of
//! eight maps it is eight vector loads, the classic 24-shuffle transpose and eight stores.
//! It only moves values, so the result is the generic loop's exactly (tested).

use ocellus_image::preserving::Lanes;
use std::arch::x86_64::*;

/// Row `dst` (pixels of eight lanes) from the rows `src` (one per lane, `None` for zeros),
/// all `dst.len()` long.
///
/// # Safety
/// The CPU must have AVX2; every `Some` row holds at least `dst.len()` values.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn interleave_row(src: &[Option<&[f32]>; 8], dst: &mut [Lanes]) {
    let n = dst.len();
    let mut x = 0;
    // SAFETY: x + 8 <= n, inside every row (the caller's promise) and inside `dst`.
    unsafe {
        while x + 8 <= n {
            let r: [__m256; 8] = std::array::from_fn(|l| match src[l] {
                Some(row) => _mm256_loadu_ps(row.as_ptr().add(x)),
                None => _mm256_setzero_ps(),
            });
            let t0 = _mm256_unpacklo_ps(r[0], r[1]);
            let t1 = _mm256_unpackhi_ps(r[0], r[1]);
            let t2 = _mm256_unpacklo_ps(r[2], r[3]);
            let t3 = _mm256_unpackhi_ps(r[2], r[3]);
            let t4 = _mm256_unpacklo_ps(r[4], r[5]);
            let t5 = _mm256_unpackhi_ps(r[4], r[5]);
            let t6 = _mm256_unpacklo_ps(r[6], r[7]);
            let t7 = _mm256_unpackhi_ps(r[6], r[7]);
            let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
            let u1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
            let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
            let u3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
            let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
            let u5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
            let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
            let u7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
            let o = dst.as_mut_ptr().add(x) as *mut f32;
            _mm256_storeu_ps(o, _mm256_permute2f128_ps::<0x20>(u0, u4));
            _mm256_storeu_ps(o.add(8), _mm256_permute2f128_ps::<0x20>(u1, u5));
            _mm256_storeu_ps(o.add(16), _mm256_permute2f128_ps::<0x20>(u2, u6));
            _mm256_storeu_ps(o.add(24), _mm256_permute2f128_ps::<0x20>(u3, u7));
            _mm256_storeu_ps(o.add(32), _mm256_permute2f128_ps::<0x31>(u0, u4));
            _mm256_storeu_ps(o.add(40), _mm256_permute2f128_ps::<0x31>(u1, u5));
            _mm256_storeu_ps(o.add(48), _mm256_permute2f128_ps::<0x31>(u2, u6));
            _mm256_storeu_ps(o.add(56), _mm256_permute2f128_ps::<0x31>(u3, u7));
            x += 8;
        }
    }
    for (xx, px) in dst.iter_mut().enumerate().skip(x) {
        *px = src.map(|r| r.map_or(0.0, |r| r[xx]));
    }
}
