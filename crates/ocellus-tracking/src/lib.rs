//! Tracking for ocellus (SPEC 7): the image side of particle-filter tracking. The generic
//! filters and resamplers are in `ocellus-estimation`; this crate says how well a hypothesis
//! explains a frame.
//!
//! - [`binning`]: HSV colour histograms (Pérez et al. 2002) and a frame binned once;
//! - [`colour`]: the seed's likelihood `BC(inner, model) - BC(inner, outer)` of an image circle from sample
//!   points on the disc and on a ring just outside it, skipping a guard band about the edge,
//!   plus a rim term that votes on the edge itself (SPEC 7.2);
//! - [`motion`]: constant velocity with gravity and white acceleration noise, plus rare jumps
//!   and an optional floor the ball bounces on (SPEC 7.3);
//! - [`detection`]: colour-segmentation blobs as 3D ball hypotheses, depth from the blob size
//!   and the known radius (SPEC 7.4);
//! - [`ball`]: the 3D ball projected through a calibrated camera with distortion, as a
//!   particle-filter model with the boosted proposal of Okuma et al. 2004 (SPEC 7.3, 7.4);
//! - [`tracker`]: the tracker over a frame sequence (start from a detection, step, estimate,
//!   lost or not).
//!
//! Image conventions are `ocellus-image`'s: x right, y down, pixel centres at integers.
//!
//! ```
//! use ocellus_image::Plane;
//! use ocellus_tracking::binning::BinnedFrame;
//! use ocellus_tracking::colour::{Circle, ColourModel};
//! // A red disc of radius 12 at (40, 30) on a grey frame.
//! let frame = Plane::from_fn(80, 60, |x, y| {
//!     let d2 = (x as f64 - 40.0).powi(2) + (y as f64 - 30.0).powi(2);
//!     if d2 <= 144.0 { [220u8, 30, 40] } else { [120, 120, 120] }
//! });
//! let model = ColourModel::from_patch(&frame, Circle { x: 40.0, y: 30.0, r: 10.0 })?;
//! let binned = BinnedFrame::new(&frame);
//! let at = model.score(&binned, Circle { x: 40.0, y: 30.0, r: 12.0 });
//! let off = model.score(&binned, Circle { x: 60.0, y: 30.0, r: 12.0 });
//! assert!(at > 0.8 && at > off + 0.5);
//! # Ok::<(), ocellus_tracking::TrackingError>(())
//! ```

pub mod ball;
pub mod binning;
pub mod colour;
pub mod detection;
pub mod motion;
pub mod tracker;

/// Errors of the tracking crate.
#[derive(Debug, thiserror::Error)]
pub enum TrackingError {
    /// An image operation failed (the cause, for matching).
    #[error(transparent)]
    Image(#[from] ocellus_image::ImageError),
    /// The particle filter refused (the cause, for matching).
    #[error(transparent)]
    Estimation(#[from] ocellus_estimation::EstimationError),
    /// A parameter or an input is unusable.
    #[error("invalid tracking input: {0}")]
    Invalid(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, TrackingError>;
