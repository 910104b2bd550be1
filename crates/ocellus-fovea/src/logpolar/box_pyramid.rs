//! The box pyramid the receptive fields read: level l holds the means (f32, general path) or
//! the exact sums (u16, byte fast paths) of 2^l x 2^l pixels, with AVX2/SSSE3 row kernels,
//! and the split of interleaved RGB into channels.

use ocellus_image::Backend;

/// Pixel types the pyramid reads: the sum of two is kept exactly in `Acc`.
pub(super) trait Texel: Copy + Into<f32> {
    /// Pairwise sum type.
    type Acc: Copy + std::ops::Add<Output = Self::Acc> + Into<f32>;
    fn acc(self) -> Self::Acc;
}

impl Texel for u8 {
    type Acc = u16;
    #[inline(always)]
    fn acc(self) -> u16 {
        self as u16
    }
}

impl Texel for f32 {
    type Acc = f32;
    #[inline(always)]
    fn acc(self) -> f32 {
        self
    }
}

/// One box-pyramid level: texels `rect` = [x0, y0, x1, y1) of `dst` (row length `lw`
/// texels) become the means of 2x2 texels of `src` (row length `sw`), C interleaved channels.
/// Row pairs are summed first (contiguous, vectorized), then column pairs.
pub(super) fn halve<T: Texel, const C: usize>(
    src: &[T],
    sw: usize,
    dst: &mut [f32],
    lw: usize,
    rect: [usize; 4],
    row: &mut Vec<f32>,
) {
    let [x0, y0, x1, y1] = rect;
    let n = 2 * (x1 - x0) * C;
    row.resize(n, 0.0);
    for y in y0..y1 {
        let a = &src[(2 * y * sw + 2 * x0) * C..][..n];
        let b = &src[((2 * y + 1) * sw + 2 * x0) * C..][..n];
        for ((r, &p), &q) in row.iter_mut().zip(a).zip(b) {
            *r = (p.acc() + q.acc()).into();
        }
        let d = &mut dst[(y * lw + x0) * C..(y * lw + x1) * C];
        for (o, pair) in d.chunks_exact_mut(C).zip(row.chunks_exact(2 * C)) {
            for ch in 0..C {
                o[ch] = 0.25 * (pair[ch] + pair[C + ch]);
            }
        }
    }
}

/// Sums of 2x2 bytes of rows `a` and `b` into `d`, 16 at a time; returns how many were done.
///
/// # Safety
/// AVX2 must be available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sum4_row_avx2(a: &[u8], b: &[u8], d: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = (d.len().min(a.len() / 2).min(b.len() / 2)) / 16 * 16;
    // SAFETY (whole body): i + 16 <= n outputs, so 2 i + 32 <= 2 n input bytes of each row.
    unsafe {
        let ones = _mm256_set1_epi8(1);
        let mut i = 0;
        while i < n {
            let va = _mm256_loadu_si256(a.as_ptr().add(2 * i) as *const __m256i);
            let vb = _mm256_loadu_si256(b.as_ptr().add(2 * i) as *const __m256i);
            // Pairs of unsigned bytes times 1, summed: 16 words per row, exact.
            let s = _mm256_add_epi16(_mm256_maddubs_epi16(va, ones), _mm256_maddubs_epi16(vb, ones));
            _mm256_storeu_si256(d.as_mut_ptr().add(i) as *mut __m256i, s);
            i += 16;
        }
        n
    }
}

/// Shuffle masks: byte j of channel c's 16 bytes comes from byte 3 j + c of 48 interleaved
/// bytes, which lies in 16-byte block (3 j + c) / 16 (-1: none, the shuffle writes 0).
const RGB_SPLIT: [[[i8; 16]; 3]; 3] = {
    let mut idx = [[[-1i8; 16]; 3]; 3];
    let mut c = 0;
    while c < 3 {
        let mut j = 0;
        while j < 16 {
            let k = 3 * j + c;
            idx[c][k / 16][j] = (k % 16) as i8;
            j += 1;
        }
        c += 1;
    }
    idx
};

/// Channel `c` of the 16 pixels at `p` (48 bytes).
///
/// # Safety
/// SSSE3 must be available and 48 bytes readable at `p`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3")]
#[inline]
unsafe fn split_channel(p: *const u8, m: &[std::arch::x86_64::__m128i; 3]) -> std::arch::x86_64::__m128i {
    use std::arch::x86_64::*;
    // SAFETY: the caller guarantees the feature and the 48 bytes.
    unsafe {
        let (x, y, z) = (
            _mm_loadu_si128(p as *const __m128i),
            _mm_loadu_si128(p.add(16) as *const __m128i),
            _mm_loadu_si128(p.add(32) as *const __m128i),
        );
        _mm_or_si128(_mm_or_si128(_mm_shuffle_epi8(x, m[0]), _mm_shuffle_epi8(y, m[1])), _mm_shuffle_epi8(z, m[2]))
    }
}

/// [`deinterleave`] 16 pixels per step; returns how many were done.
///
/// # Safety
/// SSSE3 must be available; `rgb` holds 3 bytes per element of `r`, `g`, `b`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3")]
unsafe fn deinterleave_ssse3(rgb: &[u8], r: &mut [u8], g: &mut [u8], b: &mut [u8]) -> usize {
    use std::arch::x86_64::*;
    let n = r.len().min(g.len()).min(b.len()).min(rgb.len() / 3) / 16 * 16;
    // SAFETY (whole body): 3 (i + 16) <= 3 n bytes read, i + 16 <= n written per channel.
    unsafe {
        let m: [[__m128i; 3]; 3] = RGB_SPLIT.map(|per| per.map(|v| _mm_loadu_si128(v.as_ptr() as *const __m128i)));
        let mut i = 0;
        while i < n {
            let p = rgb.as_ptr().add(3 * i);
            for (c, dst) in [r.as_mut_ptr(), g.as_mut_ptr(), b.as_mut_ptr()].into_iter().enumerate() {
                _mm_storeu_si128(dst.add(i) as *mut __m128i, split_channel(p, &m[c]));
            }
            i += 16;
        }
        n
    }
}

/// Level-1 sums of the three channels: `r[i]` is the sum of the red bytes of pixels 2i and
/// 2i + 1 of rows `a` and `b` (interleaved RGB), and so on; AVX2 or SSSE3 kernels for the
/// resolved `backend` of those.
pub(super) fn sum4_rgb_row(backend: Backend, a: &[u8], b: &[u8], r: &mut [u16], g: &mut [u16], bl: &mut [u16]) {
    let n = r.len().min(g.len()).min(bl.len()).min(a.len() / 6).min(b.len() / 6);
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if backend.has_avx2() {
        // SAFETY: a resolved Avx2 means the CPU has AVX2; the kernel stays inside the slices.
        done = unsafe { sum4_rgb_row_avx2(&a[..6 * n], &b[..6 * n], &mut r[..n], &mut g[..n], &mut bl[..n]) };
    } else if backend == Backend::Sse41 {
        // SAFETY: a resolved Sse41 means the CPU has SSSE3; the kernel stays inside the slices.
        done = unsafe { sum4_rgb_row_ssse3(&a[..6 * n], &b[..6 * n], &mut r[..n], &mut g[..n], &mut bl[..n]) };
    }
    for i in done..n {
        let s =
            |c: usize| a[6 * i + c] as u16 + a[6 * i + 3 + c] as u16 + b[6 * i + c] as u16 + b[6 * i + 3 + c] as u16;
        (r[i], g[i], bl[i]) = (s(0), s(1), s(2));
    }
}

/// [`sum4_rgb_row`] 8 texels (16 pixels, 48 bytes of each row) per step: each channel's 16
/// bytes are gathered with three byte shuffles, then `maddubs` adds the pixel pairs.
/// Returns how many texels were done.
///
/// # Safety
/// SSSE3 must be available; `a` and `b` hold at least 6 bytes per texel of `r`, `g`, `bl`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3")]
unsafe fn sum4_rgb_row_ssse3(a: &[u8], b: &[u8], r: &mut [u16], g: &mut [u16], bl: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = r.len().min(g.len()).min(bl.len()).min(a.len() / 6).min(b.len() / 6) / 8 * 8;
    // SAFETY (whole body): 6 (i + 8) <= 6 n bytes are read from each row, i + 8 <= n
    // texels written to each channel.
    unsafe {
        let m: [[__m128i; 3]; 3] = RGB_SPLIT.map(|per| per.map(|v| _mm_loadu_si128(v.as_ptr() as *const __m128i)));
        let ones = _mm_set1_epi8(1);
        let mut i = 0;
        while i < n {
            let (pa, pb) = (a.as_ptr().add(6 * i), b.as_ptr().add(6 * i));
            for (c, dst) in [r.as_mut_ptr(), g.as_mut_ptr(), bl.as_mut_ptr()].into_iter().enumerate() {
                let s = _mm_add_epi16(
                    _mm_maddubs_epi16(split_channel(pa, &m[c]), ones),
                    _mm_maddubs_epi16(split_channel(pb, &m[c]), ones),
                );
                _mm_storeu_si128(dst.add(i) as *mut __m128i, s);
            }
            i += 8;
        }
        n
    }
}

/// [`sum4_rgb_row`] 16 texels (32 pixels) per step: the low lane takes pixels 0-15, the high
/// lane 16-31, each 48-byte block is loaded once for the three channels. Returns how many
/// texels were done.
///
/// # Safety
/// AVX2 must be available; `a` and `b` hold at least 6 bytes per texel of `r`, `g`, `bl`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sum4_rgb_row_avx2(a: &[u8], b: &[u8], r: &mut [u16], g: &mut [u16], bl: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = r.len().min(g.len()).min(bl.len()).min(a.len() / 6).min(b.len() / 6) / 16 * 16;
    // SAFETY (whole body): 6 (i + 16) <= 6 n bytes are read from each row, i + 16 <= n
    // texels written to each channel.
    unsafe {
        let m: [[__m256i; 3]; 3] = RGB_SPLIT
            .map(|per| per.map(|v| _mm256_broadcastsi128_si256(_mm_loadu_si128(v.as_ptr() as *const __m128i))));
        let ones = _mm256_set1_epi8(1);
        // Blocks k = 0, 1, 2 of pixels 0-15 (low lane) and 16-31 (high lane).
        let blocks = |p: *const u8| -> [__m256i; 3] {
            std::array::from_fn(|k| {
                let lo = _mm_loadu_si128(p.add(16 * k) as *const __m128i);
                let hi = _mm_loadu_si128(p.add(48 + 16 * k) as *const __m128i);
                _mm256_inserti128_si256::<1>(_mm256_castsi128_si256(lo), hi)
            })
        };
        let channel = |v: &[__m256i; 3], m: &[__m256i; 3]| {
            _mm256_or_si256(
                _mm256_or_si256(_mm256_shuffle_epi8(v[0], m[0]), _mm256_shuffle_epi8(v[1], m[1])),
                _mm256_shuffle_epi8(v[2], m[2]),
            )
        };
        let mut i = 0;
        while i < n {
            let (va, vb) = (blocks(a.as_ptr().add(6 * i)), blocks(b.as_ptr().add(6 * i)));
            for (c, dst) in [r.as_mut_ptr(), g.as_mut_ptr(), bl.as_mut_ptr()].into_iter().enumerate() {
                let s = _mm256_add_epi16(
                    _mm256_maddubs_epi16(channel(&va, &m[c]), ones),
                    _mm256_maddubs_epi16(channel(&vb, &m[c]), ones),
                );
                _mm256_storeu_si256(dst.add(i) as *mut __m256i, s);
            }
            i += 16;
        }
        n
    }
}

/// Splits interleaved RGB bytes into three channel rows (SSSE3 for a resolved `Sse41` or
/// `Avx2` backend).
pub(super) fn deinterleave(backend: Backend, rgb: &[u8], r: &mut [u8], g: &mut [u8], b: &mut [u8]) {
    let n = r.len().min(g.len()).min(b.len()).min(rgb.len() / 3);
    let (rgb, r, g, b) = (&rgb[..3 * n], &mut r[..n], &mut g[..n], &mut b[..n]);
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if backend != Backend::Scalar {
        // SAFETY: resolved Sse41 and Avx2 imply SSSE3; the kernel stays inside the slices.
        done = unsafe { deinterleave_ssse3(rgb, r, g, b) };
    }
    for i in done..n {
        r[i] = rgb[3 * i];
        g[i] = rgb[3 * i + 1];
        b[i] = rgb[3 * i + 2];
    }
}

/// Sums of 2x2 words of rows `a` and `b` into `d`, 16 at a time (the column sums below 2^15,
/// as signed words for `madd`); returns how many were done.
///
/// # Safety
/// AVX2 must be available.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sum4_u16_row_avx2(a: &[u16], b: &[u16], d: &mut [u16]) -> usize {
    use std::arch::x86_64::*;
    let n = (d.len().min(a.len() / 2).min(b.len() / 2)) / 16 * 16;
    // SAFETY (whole body): i + 16 <= n outputs, so 2 i + 32 <= 2 n input words per row.
    unsafe {
        let ones = _mm256_set1_epi16(1);
        let mut i = 0;
        while i < n {
            let (pa, pb) = (a.as_ptr().add(2 * i) as *const __m256i, b.as_ptr().add(2 * i) as *const __m256i);
            let v0 = _mm256_add_epi16(_mm256_loadu_si256(pa), _mm256_loadu_si256(pb));
            let v1 = _mm256_add_epi16(_mm256_loadu_si256(pa.add(1)), _mm256_loadu_si256(pb.add(1)));
            let (s0, s1) = (_mm256_madd_epi16(v0, ones), _mm256_madd_epi16(v1, ones));
            // packus works per 128-bit lane: put the quarters back in order.
            let packed = _mm256_permute4x64_epi64::<0b11_01_10_00>(_mm256_packus_epi32(s0, s1));
            _mm256_storeu_si256(d.as_mut_ptr().add(i) as *mut __m256i, packed);
            i += 16;
        }
        n
    }
}

/// What the u16 box-sum pyramid is summed from: u8 pixels or u16 sums of 4^(l-1) pixels
/// (l <= 4, so every column sum stays below 2^15 until the last pair).
pub(super) trait SumTexel: Copy + Into<u16> {
    /// A kernel for the leading texels of a row (it returns how many it did), for a resolved
    /// `backend` that has one.
    fn row_kernel(backend: Backend) -> Option<RowKernel<Self>>;
}

/// Sums of 2x2 elements of rows `a` and `b` into `d`; returns how many were done.
type RowKernel<T> = unsafe fn(&[T], &[T], &mut [u16]) -> usize;

impl SumTexel for u8 {
    fn row_kernel(backend: Backend) -> Option<RowKernel<u8>> {
        #[cfg(target_arch = "x86_64")]
        if backend.has_avx2() {
            return Some(sum4_row_avx2 as RowKernel<u8>);
        }
        None
    }
}

impl SumTexel for u16 {
    fn row_kernel(backend: Backend) -> Option<RowKernel<u16>> {
        #[cfg(target_arch = "x86_64")]
        if backend.has_avx2() {
            return Some(sum4_u16_row_avx2 as RowKernel<u16>);
        }
        None
    }
}

/// One level of the u16 box-sum pyramid: texels `rect` of `dst` (rows of `lw`) are the sums
/// of 2x2 elements of `src` (rows of `sw`); 16 texels per step for a resolved `Avx2`.
pub(super) fn sum4<T: SumTexel>(backend: Backend, src: &[T], sw: usize, dst: &mut [u16], lw: usize, rect: [usize; 4]) {
    let [x0, y0, x1, y1] = rect;
    let n = x1 - x0;
    let kernel = T::row_kernel(backend);
    for y in y0..y1 {
        let a = &src[2 * y * sw + 2 * x0..][..2 * n];
        let b = &src[(2 * y + 1) * sw + 2 * x0..][..2 * n];
        let d = &mut dst[y * lw + x0..y * lw + x1];
        // SAFETY: a kernel is only given for a resolved backend, whose features the CPU has; it stays inside the
        // three slices.
        let done = kernel.map_or(0, |k| unsafe { k(a, b, d) });
        for i in done..n {
            d[i] = a[2 * i].into() + a[2 * i + 1].into() + b[2 * i].into() + b[2 * i + 1].into();
        }
    }
}
