//! Foveal vision (SPEC 4; seed 000, "log-polar foveal vision"): sample densely at the gaze
//! point and sparsely in the periphery, so that rotation and scaling about the gaze point
//! become shifts.
//!
//! - [`logpolar`]: the retino-cortical map. R log-spaced rings between the fovea radius
//!   rho_0 and rho_max, S sectors, a linear fovea inside rho_0; every cell is a receptive field
//!   that averages the image over its area (no point sampling, so the periphery does not
//!   alias), from a precomputed sparse weight table over a box pyramid. Grey and RGB, and the
//!   inverse map for display.
//! - [`phase_correlation`]: sub-pixel shift between two equal-size arrays, cyclic.
//! - [`register`]: rotation and scale between two images by phase correlation in log-polar
//!   space (directly about the centres, or on the magnitude spectra for translation
//!   invariance: Fourier-Mellin).
//! - [`vergence`]: the horizontal disparity at the gaze point of a stereo pair, from the
//!   log-polar images; [`vergence::VergenceTracker`] follows it over a stereo stream for
//!   binocular tracking.
//!
//! Conventions: image x right, y down; pixel (x, y) has its centre at (x, y) (the
//! convention of [`ocellus_image::resample::sample_bilinear`]). Angles are measured from +x
//! towards +y (clockwise on the screen), in radians at the API unless a name says degrees.
//!
//! ```
//! use ocellus_fovea::logpolar::{LogPolarConfig, LogPolarMap};
//! use ocellus_image::Plane;
//! let img = Plane::from_fn(64, 48, |x, y| ((x * 7 + y * 3) % 256) as u8);
//! let map = LogPolarMap::new(&LogPolarConfig::for_image(64, 48), 64, 48).unwrap();
//! let cortex = map.sample_grey(&img).unwrap();
//! assert_eq!(cortex.size(), (map.sectors(), map.rows()));
//! ```

pub mod logpolar;
pub mod phase_correlation;
pub mod register;
pub mod vergence;

use thiserror::Error;

/// Errors of the fovea crate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FoveaError {
    /// An image operation failed (the cause, for matching).
    #[error(transparent)]
    Image(#[from] ocellus_image::ImageError),
    /// A parameter is out of range.
    #[error("invalid log-polar parameter: {0}")]
    Invalid(String),
    /// The images do not determine an answer (flat, or no overlap).
    #[error("no estimate: {0}")]
    NoEstimate(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, FoveaError>;
