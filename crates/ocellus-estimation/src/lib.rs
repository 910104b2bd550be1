//! State estimation for ocellus: Gaussian beliefs and what observations do to them.
//!
//! - [`gaussian`]: the KL divergence between multivariate normal distributions, in bits.
//! - [`bearing`]: the extended Kalman filter update of a 2D position from bearings to known
//!   landmarks (the self-localization task of view planning, SPEC 2.3).
//! - [`particle_filter`]: generic SIS/SIR particle filters with log weights, the effective
//!   sample size and seeded, thread-count independent randomness (SPEC 7.1);
//! - [`resampling`]: systematic (the seed's Algorithm 2), stratified, multinomial and residual
//!   resampling.
//!
//! Conventions: positions in metres in a right-handed plane frame (x forward along the
//! corridor, y to the left); angles in radians, counter-clockwise from +x.
//!
//! ```
//! use nalgebra::{Matrix2, Vector2};
//! use ocellus_estimation::bearing::{bearing_update_covariance, Landmark};
//! use ocellus_estimation::gaussian::kl_bits;
//! let (mu, prior) = (Vector2::new(0.0, 1.25), Matrix2::new(0.04, 0.0, 0.0, 0.04));
//! let lm = [Landmark { x: 3.0, y: 2.5 }];
//! let post = bearing_update_covariance(&mu, &prior, &lm, 2f64.to_radians()).unwrap();
//! assert!(post.trace() < prior.trace());
//! let gain = kl_bits(&mu, &prior, &mu, &post).unwrap();
//! assert!(gain > 0.0);
//! ```

pub mod bearing;
pub mod gaussian;
pub mod particle_filter;
pub mod resampling;

use thiserror::Error;

/// Errors of the estimation crate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EstimationError {
    /// A covariance is not symmetric positive definite (or not finite).
    #[error("{what} is not a finite positive definite covariance: {detail}")]
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
        /// Its entries.
        detail: String,
    },
    /// An input is not usable.
    #[error("invalid input: {0}")]
    InvalidInput(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, EstimationError>;
