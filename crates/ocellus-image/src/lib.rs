//! Typed image planes and the low-level image operations of ocellus.
//!
//! Conventions, used by every crate of ocellus:
//! - x runs right (columns), y runs down (rows); storage is row-major, rows then columns;
//! - pixel (x, y) has its centre at the integer point (x, y) and covers
//!   [x - 0.5, x + 0.5) x [y - 0.5, y + 0.5) (OpenCV's convention, and the camera models');
//!   every reported location (a saliency peak, a fixation, a gaze point) is in these
//!   coordinates, and a coarse map's cell converts to them through [`location`];
//! - grey levels: `u8` planes hold 0..=255; `f32` planes converted from an image hold [0, 1]
//!   (8-bit v becomes v / 255); linear operators (filters, resampling, log-polar sampling)
//!   keep the units of what they are given;
//! - grey from colour is BT.601 luma, 0.299 R + 0.587 G + 0.114 B, made in one place
//!   ([`convert::RgbImage::to_grey`], [`convert::RgbImage::to_luma8`]). The saliency
//!   intensity channel is a feature of its own (SPEC 1.3: the mean of R, G, B, or the
//!   toolbox's weights), not a grey conversion.
//!
//! Hot kernels come in builds chosen by one [`Backend`] that the caller passes down (in an
//! engine's config or as a function's first argument): a portable one (`Scalar`, the
//! reference), hand-written 128-bit integer kernels (`Sse41`) and builds compiled for AVX2 +
//! FMA (`Avx2`); `Auto` picks the fastest this CPU has ([`Backend::detect`]). Each kernel
//! family has a conformance test running every available backend against `Scalar`.
//!
//! ```
//! use ocellus_image::{Backend, Plane, pyramid::{PyramidKernel, pyr_down_alloc}};
//! let img = Plane::from_fn(64, 48, |x, y| (x + y) as f32 / 110.0);
//! let half = pyr_down_alloc(Backend::Auto, &img, &PyramidKernel::itti()).unwrap();
//! assert_eq!((half.width(), half.height()), (32, 24));
//! ```

pub mod check;
pub mod colormap;
pub mod convert;
pub mod draw;
mod error;
pub mod filter;
pub mod location;
mod plane;
pub mod preserving;
pub mod pyramid;
pub mod resample;
pub mod rng;
pub mod simd;

pub use error::{ImageError, Result};
pub use plane::Plane;
pub use simd::Backend;
