//! Bilinear quads: each [`super::Fields::Pyramid`] cell is one bilinear read of its level,
//! 8 cells per step with AVX2 gathers where the CPU has them.

use ocellus_image::Backend;

/// Sources of the grey fast path: u8 pixels (level 0) or u16 box sums.
pub(super) trait Quad: Copy + Into<f32> {
    /// Whether 8 quads can be read with AVX2 gathers from a buffer of `len` elements with rows
    /// of `lw`: a gather reads 4 bytes at each quad's two rows.
    fn gather_safe(max_base: usize, lw: usize, len: usize) -> bool;
}

impl Quad for u8 {
    fn gather_safe(max_base: usize, lw: usize, len: usize) -> bool {
        max_base + lw + 4 <= len
    }
}

impl Quad for u16 {
    fn gather_safe(max_base: usize, lw: usize, len: usize) -> bool {
        max_base + lw + 2 <= len
    }
}

/// Bilinear quads `src[b], src[b + 1], src[b + lw], src[b + lw + 1]` with fractions
/// (fx, fy), times `scale`, into `out`, for K sources with the same layout at once (the
/// quads' positions are loaded once); `max_base` is the largest of `bases`.
pub(super) fn quads<T: Quad, const K: usize>(
    backend: Backend,
    src: [&[T]; K],
    lw: usize,
    (bases, max_base): (&[u32], usize),
    fx: &[f32],
    fy: &[f32],
    scale: f32,
    mut out: [&mut [f32]; K],
) {
    let n = out.iter().fold(bases.len().min(fx.len()).min(fy.len()), |n, o| n.min(o.len()));
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if n >= 8
        && src.iter().all(|s| s.len() < i32::MAX as usize && T::gather_safe(max_base, lw, s.len()))
        && backend.has_avx2()
    {
        // SAFETY: a resolved Avx2 means the CPU has AVX2; every gather reads inside its source (checked just above).
        done = unsafe { quads_avx2(src, lw, &bases[..n], &fx[..n], &fy[..n], scale, &mut out) };
    }
    for (s, o) in src.iter().zip(out.iter_mut()) {
        for k in done..n {
            let b = bases[k] as usize;
            let (Some(&p00), Some(&p01), Some(&p10), Some(&p11)) =
                (s.get(b), s.get(b + 1), s.get(b + lw), s.get(b + lw + 1))
            else {
                o[k] = 0.0;
                continue;
            };
            let (p00, p01, p10, p11): (f32, f32, f32, f32) = (p00.into(), p01.into(), p10.into(), p11.into());
            let top = p00 + fx[k] * (p01 - p00);
            let bot = p10 + fx[k] * (p11 - p10);
            o[k] = scale * (top + fy[k] * (bot - top));
        }
    }
}

/// [`quads`] 8 at a time; returns how many were done (a multiple of 8).
///
/// # Safety
/// AVX2 must be available, each source shorter than 2^31 elements, and for every base b the
/// 4 bytes from element b and from element b + lw must lie inside every source; `fx`, `fy`
/// and every output at least as long as `bases`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn quads_avx2<T: Quad, const K: usize>(
    src: [&[T]; K],
    lw: usize,
    bases: &[u32],
    fx: &[f32],
    fy: &[f32],
    scale: f32,
    out: &mut [&mut [f32]; K],
) -> usize {
    use std::arch::x86_64::*;
    let n = bases.len() / 8 * 8;
    let wide = std::mem::size_of::<T>() == 2;
    // SAFETY (whole body): the caller guarantees the feature and the gathers' bounds; the
    // other loads and stores are within the slices (k + 8 <= n).
    unsafe {
        let row = _mm256_set1_epi32(lw as i32);
        let mask = if wide { _mm256_set1_epi32(0xffff) } else { _mm256_set1_epi32(0xff) };
        let sc = _mm256_set1_ps(scale);
        let split = |v: __m256i| {
            let lo = _mm256_cvtepi32_ps(_mm256_and_si256(v, mask));
            let hi = if wide {
                _mm256_cvtepi32_ps(_mm256_srli_epi32::<16>(v))
            } else {
                _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32::<8>(v), mask))
            };
            (lo, hi)
        };
        let mut k = 0;
        while k < n {
            let idx = _mm256_loadu_si256(bases.as_ptr().add(k) as *const __m256i);
            let below = _mm256_add_epi32(idx, row);
            let x = _mm256_loadu_ps(fx.as_ptr().add(k));
            let y = _mm256_loadu_ps(fy.as_ptr().add(k));
            for c in 0..K {
                let p = src[c].as_ptr() as *const i32;
                let (t, b) = if wide {
                    (_mm256_i32gather_epi32::<2>(p, idx), _mm256_i32gather_epi32::<2>(p, below))
                } else {
                    (_mm256_i32gather_epi32::<1>(p, idx), _mm256_i32gather_epi32::<1>(p, below))
                };
                let ((p00, p01), (p10, p11)) = (split(t), split(b));
                let top = _mm256_add_ps(p00, _mm256_mul_ps(x, _mm256_sub_ps(p01, p00)));
                let bot = _mm256_add_ps(p10, _mm256_mul_ps(x, _mm256_sub_ps(p11, p10)));
                let v = _mm256_add_ps(top, _mm256_mul_ps(y, _mm256_sub_ps(bot, top)));
                _mm256_storeu_ps(out[c].as_mut_ptr().add(k), _mm256_mul_ps(v, sc));
            }
            k += 8;
        }
        n
    }
}
