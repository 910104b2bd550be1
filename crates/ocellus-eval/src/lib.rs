//! How well a saliency map predicts where people look: the metrics of the MIT saliency
//! benchmark (Bylinskii, Judd, Oliva, Torralba & Durand 2016, "What do different evaluation
//! metrics tell us about saliency models?"), written from its definitions.
//!
//! Maps are `f64` planes of one size (x right, y down). A *density* map is a continuous
//! fixation map (CC, SIM, KL need only that); *fixations* are pixel locations (NSS, the AUCs
//! and IG need them). Every random choice takes a seed.
//!
//! ```
//! use ocellus_eval::metrics::{cc, sim};
//! use ocellus_image::Plane;
//! let a = Plane::from_fn(4, 3, |x, y| (x + y) as f64);
//! assert!((cc(&a, &a).unwrap() - 1.0).abs() < 1e-12);
//! assert!((sim(&a, &a).unwrap() - 1.0).abs() < 1e-12);
//! ```

pub mod center_prior;
pub mod metrics;
pub mod protocol;
pub mod tracking;
pub mod trajectory;
pub mod tuning;

use thiserror::Error;

/// Errors of the evaluation crate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EvalError {
    /// An image operation failed (the cause, for matching).
    #[error(transparent)]
    Image(#[from] ocellus_image::ImageError),
    /// The metric is undefined for this input (empty map, no fixations, non-finite values...).
    #[error("{metric} is undefined here: {why}")]
    Undefined {
        /// Metric name.
        metric: &'static str,
        /// Why.
        why: String,
    },
    /// A parameter of the protocol (blur, centre prior, grid) is out of range.
    #[error("invalid evaluation parameter: {0}")]
    InvalidConfig(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, EvalError>;
