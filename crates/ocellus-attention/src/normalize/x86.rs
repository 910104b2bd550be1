//! AVX-512 forms of N(.)'s per-pixel steps on eight interleaved maps.
//!
//! Why by hand: on `[f32; 8]` pixels LLVM vectorized these loops across pixels, one lane at
//! a time with gathers and scatters (or at 256 bits), so that trivial passes over a 40 x 30
//! map cost as much as a 5-tap filter. (The competition step is fused into the filters:
//! `ocellus_image::preserving::dog_step_lanes`.) Here two pixels (16 floats, lane `i % 8`) are
//! one 512-bit register. Each value is computed with the generic kernel's operations in its
//! order, so the results are the same bit for bit (tested).

use ocellus_image::preserving::Lanes;
use ocellus_image::Plane;
use std::arch::x86_64::*;

/// Per-lane (min, max), as `lanes_min_max_generic`.
///
/// # Safety
/// The CPU must have AVX-512 F and DQ.
#[target_feature(enable = "avx512f,avx512dq,avx2")]
pub(super) unsafe fn lanes_min_max(maps: &Plane<Lanes>) -> (Lanes, Lanes) {
    let (mut mn, mut mx) = (_mm512_set1_ps(f32::INFINITY), _mm512_set1_ps(f32::NEG_INFINITY));
    let (mut mn8, mut mx8) = (_mm256_set1_ps(f32::INFINITY), _mm256_set1_ps(f32::NEG_INFINITY));
    for r in maps.rows() {
        let (pairs, rest) = r.as_chunks::<2>();
        for p in pairs {
            // SAFETY: `p` is 16 contiguous floats.
            let v = unsafe { _mm512_loadu_ps(p.as_ptr() as *const f32) };
            // min_ps(v, m) is `v < m ? v : m`, the generic kernel's select.
            mn = _mm512_min_ps(v, mn);
            mx = _mm512_max_ps(v, mx);
        }
        for p in rest {
            // SAFETY: `p` is 8 contiguous floats.
            let v = unsafe { _mm256_loadu_ps(p.as_ptr()) };
            mn8 = _mm256_min_ps(v, mn8);
            mx8 = _mm256_max_ps(v, mx8);
        }
    }
    let fold = |v: __m512, v8: __m256, min: bool| {
        let (lo, hi) = (_mm512_castps512_ps256(v), _mm512_extractf32x8_ps::<1>(v));
        let mut o = [0f32; 8];
        let r = if min { _mm256_min_ps(_mm256_min_ps(hi, lo), v8) } else { _mm256_max_ps(_mm256_max_ps(hi, lo), v8) };
        // SAFETY: `o` holds 8 floats.
        unsafe { _mm256_storeu_ps(o.as_mut_ptr(), r) };
        o
    };
    (fold(mn, mn8, true), fold(mx, mx8, false))
}

/// `v <- max(0, v) * scale + offset` per lane, as `lanes_affine_generic`.
///
/// # Safety
/// The CPU must have AVX-512 F and DQ, and FMA.
#[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
pub(super) unsafe fn lanes_affine(maps: &mut Plane<Lanes>, scale: &Lanes, offset: &Lanes) {
    // SAFETY: the features were promised by the caller.
    let (s, o, z) = unsafe {
        (
            _mm512_broadcast_f32x8(_mm256_loadu_ps(scale.as_ptr())),
            _mm512_broadcast_f32x8(_mm256_loadu_ps(offset.as_ptr())),
            _mm512_setzero_ps(),
        )
    };
    for y in 0..maps.height() {
        let (pairs, rest) = maps.row_mut(y).as_chunks_mut::<2>();
        for p in pairs {
            let q = p.as_mut_ptr() as *mut f32;
            // SAFETY: `p` is 16 contiguous floats.
            unsafe { _mm512_storeu_ps(q, _mm512_fmadd_ps(_mm512_max_ps(_mm512_loadu_ps(q), z), s, o)) };
        }
        for p in rest {
            for l in 0..8 {
                p[l] = p[l].max(0.0).mul_add(scale[l], offset[l]);
            }
        }
    }
}
