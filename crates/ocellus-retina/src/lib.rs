//! The self-organizing retina (SPEC 8; seed 000 after Ruesch, Ferreira & Bernardino, Adaptive
//! Behavior 21(6) 2013 and IEEE TAMD 4(4) 2012): an agent learns its receptive fields, its
//! motor fields and the predictors that link them only by predicting what its own actions do
//! to its image. With rotation and dilation actions a fovea emerges; with translations the
//! layout stays uniform.
//!
//! - [`disc`]: the sensor's pixels, a disc of integer offsets about the gaze point;
//! - [`action`]: actions (shift, rotate, dilate), action sets and their motor codes q;
//! - [`experience`]: triplets (i0, i1, q) rendered from real images;
//! - [`model`]: `o = S i`, `a = M q`, `P^q = sum_k a_k P_k`, the prediction
//!   `i1_hat = S^T P^q S i0`, its cost and the analytic gradient, batched and parallel over
//!   triplets;
//! - [`solver`]: projected gradient descent (spectral step sizes and a line search) and Adam
//!   with projection, seeded and deterministic;
//! - [`layout`]: receptive-field sizes against eccentricity, the fovea index, densities;
//! - [`experiment`]: the seed's two experiments at their sizes, and reduced ones;
//! - [`picture`]: receptive fields, motor fields and predictors as images.
//!
//! Conventions: a patch is a vector over the disc's pixels in the order of [`disc::Disc`];
//! grey levels in [0, 1] (`ocellus_image`'s convention); matrices are row-major `Vec`s
//! (S: fields x pixels, M: motor fields x motor cells, P: motor fields x fields x fields).
//!
//! ```
//! use ocellus_retina::disc::Disc;
//! let d = Disc::with_pixels(481).unwrap();
//! assert_eq!(d.len(), 481);
//! assert!((d.radius() - 12.2).abs() < 0.1);
//! ```

pub mod action;
pub mod disc;
pub mod experience;
pub mod experiment;
mod gemm;
pub mod layout;
pub mod model;
pub mod picture;
pub mod solver;

pub use gemm::Real;

use thiserror::Error;

/// Errors of the retina crate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RetinaError {
    /// A parameter or an input is out of range.
    #[error("invalid retina parameter: {0}")]
    Invalid(String),
    /// The images cannot hold the patch and its actions.
    #[error("images too small: {0}")]
    TooSmall(String),
    /// A checkpoint does not fit the experiment.
    #[error("checkpoint does not match: {0}")]
    Checkpoint(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, RetinaError>;
