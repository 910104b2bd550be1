//! Run-time choice between the portable, AVX2 + FMA and AVX-512 builds of the hot kernels.
//!
//! Each hot kernel is written once as an `#[inline(always)]` function generic over [`Madd`]
//! (how `a * b + c` is computed) and instantiated three times: a portable build (separate
//! multiply and add), a build inside `#[target_feature(enable = "avx2,fma")]` that uses fused
//! multiply-adds and lets the compiler vectorize with 256-bit registers, and the same inside
//! `avx512f,avx512bw,avx512vl,avx512dq` for 512-bit registers (and masked loop tails). They
//! agree to within float rounding (tests check 1e-5). One source per kernel, compiled per
//! width: the loops are plain slices the compiler vectorizes, and a new width costs one line
//! here. Where the compiler's code is not good enough (a few kernels of the filters, the
//! normalization and odometry), a generic kernel hands over to intrinsics written for one
//! width, reached through [`Madd::AVX2`] and [`Madd::AVX512`], that give its results bit for
//! bit (each has a test that compares the bits).

use serde::{Deserialize, Serialize};

/// Which build of the hot kernels to run: the caller chooses one (in an engine's config or as
/// a function's first argument) and it is passed down to every kernel the call reaches, so
/// that `Scalar` runs no SIMD code anywhere. Conformance tests run every entry of
/// [`Backend::available`] against `Scalar`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// The fastest one this CPU supports (decided once per call of [`Backend::resolve`]).
    #[default]
    Auto,
    /// Portable code, no CPU feature assumed: the reference every other backend is tested
    /// against.
    Scalar,
    /// SSE4.1 + SSSE3 (x86-64): the 128-bit integer kernels (log-polar box pyramid, SAD block
    /// search); the float kernels run their portable build.
    Sse41,
    /// AVX2 + FMA (x86-64), which implies SSE4.1: every float kernel's 256-bit build and the
    /// hand-written AVX2 integer kernels.
    Avx2,
    /// AVX-512 F + BW + VL + DQ (x86-64), which implies AVX2 + FMA: every float kernel
    /// compiled for 512-bit registers; the hand-written integer kernels run their AVX2 form.
    Avx512,
    /// The GPU, through wgpu, where a pipeline has a GPU path: the saliency engine's whole
    /// pipeline, with the `gpu` feature of `ocellus-attention`. Everything that runs on the
    /// CPU meanwhile (a spatial prior, every other pipeline) uses the best CPU backend, as
    /// `Auto`.
    Gpu,
}

impl Backend {
    /// The fastest backend available on this CPU.
    pub fn detect() -> Backend {
        if avx512_available() {
            Backend::Avx512
        } else if avx2_available() {
            Backend::Avx2
        } else if sse41_available() {
            Backend::Sse41
        } else {
            Backend::Scalar
        }
    }

    /// Turns `Auto` (and `Gpu`, for the CPU's kernels) into a concrete CPU backend; an
    /// unavailable one falls back to the best available below it (`Avx512` to `Avx2` to
    /// `Sse41` to `Scalar`).
    pub fn resolve(self) -> Backend {
        match self {
            Backend::Auto | Backend::Gpu => Backend::detect(),
            Backend::Avx512 if !avx512_available() => Backend::Avx2.resolve(),
            Backend::Avx2 if !avx2_available() => Backend::Sse41.resolve(),
            Backend::Sse41 if !sse41_available() => Backend::Scalar,
            b => b,
        }
    }

    /// Every concrete backend this CPU can run, `Scalar` first (for conformance tests).
    pub fn available() -> Vec<Backend> {
        let mut v = vec![Backend::Scalar];
        if sse41_available() {
            v.push(Backend::Sse41);
        }
        if avx2_available() {
            v.push(Backend::Avx2);
        }
        if avx512_available() {
            v.push(Backend::Avx512);
        }
        v
    }

    /// True when this backend resolves to one whose CPU has AVX2 + FMA (`Avx2` or `Avx512`):
    /// the hand-written AVX2 kernels may run.
    pub fn has_avx2(self) -> bool {
        matches!(self.resolve(), Backend::Avx2 | Backend::Avx512)
    }

    /// Short name, for reports.
    pub fn name(self) -> &'static str {
        if self == Backend::Gpu {
            return "gpu";
        }
        match self.resolve() {
            Backend::Avx512 => "avx512",
            Backend::Avx2 => "avx2+fma",
            Backend::Sse41 => "sse4.1",
            _ => "scalar",
        }
    }
}

/// True when the CPU has AVX2 and FMA (std caches the detection).
#[inline]
pub fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") && sse41_available()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// True when the CPU has AVX-512 F, BW, VL and DQ besides AVX2 and FMA.
#[inline]
pub fn avx512_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        avx2_available()
            && is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512bw")
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("avx512dq")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// True when the CPU has SSE4.1 and SSSE3.
#[inline]
pub fn sse41_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        is_x86_feature_detected!("sse4.1") && is_x86_feature_detected!("ssse3")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// How a kernel computes `a * b + c`.
pub trait Madd {
    /// True for the flavour that [`dispatch_kernel!`] instantiates only inside functions
    /// compiled with AVX2 and FMA (or AVX-512, which implies them): kernels may then call
    /// `#[target_feature(enable = "avx2")]` helpers (explicit intrinsics) without a further
    /// check.
    const AVX2: bool;
    /// True for the flavour that [`dispatch_kernel!`] instantiates only inside functions
    /// compiled with AVX-512 F/BW/VL/DQ (besides AVX2 and FMA): kernels may then call
    /// `#[target_feature(enable = "avx512f")]` helpers without a further check.
    const AVX512: bool = false;
    /// `a * b + c`, fused or not.
    fn madd(a: f32, b: f32, c: f32) -> f32;
}

/// Separate multiply and add: portable, no FMA instruction needed.
pub struct Plain;
impl Madd for Plain {
    const AVX2: bool = false;
    #[inline(always)]
    fn madd(a: f32, b: f32, c: f32) -> f32 {
        a * b + c
    }
}

/// Fused multiply-add; only used inside functions compiled with the `fma` feature.
pub struct Fused;
impl Madd for Fused {
    const AVX2: bool = true;
    #[inline(always)]
    fn madd(a: f32, b: f32, c: f32) -> f32 {
        a.mul_add(b, c)
    }
}

/// Fused multiply-add inside functions compiled for AVX-512 (which implies AVX2 and FMA):
/// the same arithmetic as [`Fused`], so the generic kernels give the same results; it only
/// lets them reach the hand-written 512-bit kernels.
pub struct Fused512;
impl Madd for Fused512 {
    const AVX2: bool = true;
    const AVX512: bool = true;
    #[inline(always)]
    fn madd(a: f32, b: f32, c: f32) -> f32 {
        a.mul_add(b, c)
    }
}

/// Defines `$name(backend, args..) -> ret` that runs `$generic::<Plain>` or, on AVX2 + FMA
/// (AVX-512) CPUs, `$generic::<Fused>` compiled with those features enabled. Dispatch once
/// per plane, not per row, so the whole loop nest is compiled for the chosen features.
#[macro_export]
macro_rules! dispatch_kernel {
    ($(#[$m:meta])* $vis:vis fn $name:ident => $generic:ident ( $($arg:ident : $ty:ty),* $(,)? ) $(-> $ret:ty)?) => {
        $(#[$m])*
        #[inline]
        $vis fn $name(backend: $crate::Backend, $($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2,fma")]
                unsafe fn avx2($($arg: $ty),*) $(-> $ret)? {
                    $generic::<$crate::simd::Fused>($($arg),*)
                }
                #[target_feature(enable = "avx2,fma,avx512f,avx512bw,avx512vl,avx512dq")]
                unsafe fn avx512($($arg: $ty),*) $(-> $ret)? {
                    $generic::<$crate::simd::Fused512>($($arg),*)
                }
                match backend.resolve() {
                    // SAFETY: resolve() returns Avx512 only when the CPU has AVX-512 F/BW/VL/DQ, AVX2 and FMA.
                    $crate::Backend::Avx512 => return unsafe { avx512($($arg),*) },
                    // SAFETY: resolve() returns Avx2 only when the CPU supports AVX2 and FMA.
                    $crate::Backend::Avx2 => return unsafe { avx2($($arg),*) },
                    _ => {}
                }
            }
            let _ = backend;
            $generic::<$crate::simd::Plain>($($arg),*)
        }
    };
}
