//! Bottom-up visual attention: the Itti-Koch-Niebur saliency map (SPEC 1).
//!
//! A frame's path: [`channels`] (intensity, opponency, skin) → Gaussian pyramids
//! (`ocellus_image::pyramid`) → [`gabor`] (orientation) → [`center_surround`] →
//! [`normalize`] (N(.)) → combination in [`saliency::SaliencyEngine`].
//!
//! Conventions: x right, y down; level 0 is the input, level l is `floor(w / 2^l)` x
//! `floor(h / 2^l)`; maps are `f32`. Angles in degrees, 0 = kernel varying along x
//! (responds to vertical edges), counter-clockwise towards +y.
//!
//! ```
//! use ocellus_attention::{SaliencyConfig, SaliencyEngine};
//! use ocellus_image::{convert::RgbImage, Plane};
//! let frame = RgbImage::U8(Plane::from_fn(320, 256, |x, y| {
//!     if (x / 40 + y / 40) % 2 == 0 { [200, 30, 30] } else { [20, 20, 200] }
//! }));
//! let mut engine = SaliencyEngine::new(SaliencyConfig::ace2009(), 320, 256).unwrap();
//! let map = engine.process(&frame).unwrap();
//! assert_eq!((map.width(), map.height()), (20, 16));
//! assert!(map.all_finite());
//! ```

pub mod attention;
pub mod center_surround;
pub mod channels;
pub mod chaos;
pub mod combine;
pub mod config;
pub mod egosphere;
pub mod gabor;
pub mod normalize;
pub mod overrides;
pub mod planning;
pub mod saliency;
pub mod stream;
pub mod surprise;

pub use config::SaliencyConfig;
pub use saliency::SaliencyEngine;

use thiserror::Error;

/// Errors of the attention crate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum AttentionError {
    /// An image operation failed (the cause, for matching; e.g. `ImageError::SizeMismatch`
    /// for a frame or map of the wrong size).
    #[error(transparent)]
    Image(#[from] ocellus_image::ImageError),
    /// A belief update or information measure of the planner failed (the cause).
    #[error(transparent)]
    Estimation(#[from] ocellus_estimation::EstimationError),
    /// A configuration value is out of range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// The frame is too small for the configured pyramid.
    #[error("image is {width}x{height}: the pyramid needs at least {min_side}x{min_side} for {levels} levels (reduce center_levels/deltas for smaller images)")]
    TooSmall {
        /// Frame width.
        width: usize,
        /// Frame height.
        height: usize,
        /// Levels needed (level 0 = input).
        levels: usize,
        /// Minimum side length.
        min_side: usize,
    },
    /// The GPU backend could not be used: no adapter, a configuration it does not do, or a
    /// build without the `gpu` feature (the message says which).
    #[error("GPU backend: {0}")]
    Gpu(String),
    /// Other unusable input (maps, priors).
    #[error("invalid input: {0}")]
    InvalidInput(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, AttentionError>;
