//! Typed image planes and the low-level image operations of ocellus.
//!
//! Conventions, used by every crate of ocellus:
//! - x runs right (columns), y runs down (rows); storage is row-major, rows then columns;
//! - pixel (x, y) covers the square [x, x+1) x [y, y+1); its centre is (x + 0.5, y + 0.5);
//! - intensities are `f32` in [0, 1] once converted from the input's integer range.
//!
//! Hot kernels come in two builds from one source: a portable one and one compiled for
//! AVX2 + FMA, chosen at run time ([`Backend::detect`]). They agree to within 1e-5.
//!
//! ```
//! use ocellus_image::{Plane, pyramid::{PyramidKernel, pyr_down_alloc}};
//! let img = Plane::from_fn(64, 48, |x, y| (x + y) as f32 / 110.0);
//! let half = pyr_down_alloc(&img, &PyramidKernel::itti()).unwrap();
//! assert_eq!((half.width(), half.height()), (32, 24));
//! ```

pub mod check;
pub mod convert;
mod error;
pub mod filter;
mod plane;
pub mod preserving;
pub mod pyramid;
pub mod resample;
pub mod rng;
pub mod simd;

pub use error::{ImageError, Result};
pub use plane::Plane;
pub use simd::Backend;
