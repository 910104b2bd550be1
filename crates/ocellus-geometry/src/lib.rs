//! Where things are: camera models, calibration, triangulation and stereo (SPEC 5).
//!
//! - [`camera`]: pinhole intrinsics and extrinsics, the 3x4 projection matrix, projection and
//!   back-projection, homogeneous helpers, the thin-lens equation.
//! - [`distortion`]: radial-tangential lens distortion (k1, k2, k3, p1, p2) and its inverse.
//! - [`dlt`]: calibration from 3D-2D correspondences: the seed's linear form (p34 = 1) and the
//!   normalized SVD form (Hartley); reprojection errors; decomposition of P into K, R, t.
//! - [`chessboard`]: chessboard inner-corner detection with sub-pixel refinement.
//! - [`sgm`]: dense disparity by semi-global matching on census costs (4 or 8 paths).
//! - [`homography`]: plane-to-image homographies (normalized DLT).
//! - [`zhang`]: planar-target calibration: Zhang's closed form, then Levenberg-Marquardt over
//!   intrinsics, distortion and poses, with parameter standard deviations.
//! - [`planar`]: planar robot poses (position and heading on the floor).
//! - [`triangulate`]: points from two views (the seed's 4x3 least squares) and from N views (SVD).
//! - [`sphere`]: a sphere's image circle through the lens, and ray-sphere intersection.
//! - [`stereo`]: parallel stereo with explicit units (disparity, depth, pixel sizes).
//! - [`block_matching`]: dense disparity by SAD block matching with uniqueness and
//!   left-right checks; the bad-pixel rate against ground truth.
//!
//! Conventions: world and camera frames are right-handed; the camera looks along its +z axis,
//! x right, y down in the image; pixel centres at integer coordinates, (0, 0) the top-left
//! pixel's centre. A pose maps world to camera: `X_c = R X_w + t`. Lengths are in whatever unit
//! the caller uses (metres or millimetres), consistently; image quantities are in pixels.
//!
//! ```
//! use ocellus_geometry::stereo::{focal_px_from_mm, ParallelStereo};
//! // The seed's exercise: b = 10 cm, f = 6 mm, 1024 pixels over 6 mm, d = 10 px -> 10.24 m.
//! let rig = ParallelStereo { baseline: 0.10, focal_px: focal_px_from_mm(6.0, 6.0 / 1024.0).unwrap() };
//! assert!((rig.depth(10.0).unwrap() - 10.24).abs() < 1e-12);
//! ```

pub mod block_matching;
pub mod camera;
pub mod camera_file;
pub mod chessboard;
pub mod distortion;
pub mod dlt;
pub mod homography;
pub mod planar;
pub mod sgm;
pub mod sphere;
pub mod stereo;
pub mod triangulate;
mod wta;
pub mod zhang;

use thiserror::Error;

/// Errors of the geometry crate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GeometryError {
    /// An image operation failed (the cause, for matching).
    #[error(transparent)]
    Image(#[from] ocellus_image::ImageError),
    /// Too few correspondences.
    #[error("{what} needs at least {need} points, got {got}")]
    TooFewPoints {
        /// What was attempted.
        what: &'static str,
        /// Minimum.
        need: usize,
        /// Given.
        got: usize,
    },
    /// Too few views of a calibration target.
    #[error("{what} needs at least {need} views, got {got}")]
    TooFewViews {
        /// What was attempted.
        what: &'static str,
        /// Minimum.
        need: usize,
        /// Given.
        got: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("{what}: point {index} has a non-finite coordinate")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the point.
        index: usize,
    },
    /// The configuration of points cannot determine the answer.
    #[error("degenerate input: {0}")]
    Degenerate(String),
    /// A point is behind the camera or at its centre, where projection is undefined.
    #[error("point is behind the camera or at its centre (depth {depth})")]
    BehindCamera {
        /// Its depth along the optical axis.
        depth: f64,
    },
    /// Zero disparity: the point is at infinity.
    #[error("zero disparity: the point is at infinite depth")]
    InfiniteDepth,
    /// An iterative method did not converge.
    #[error("{what} did not converge in {iterations} iterations (residual {residual:e})")]
    NoConvergence {
        /// What.
        what: &'static str,
        /// Iterations run.
        iterations: usize,
        /// Last residual.
        residual: f64,
    },
    /// Something looked for in an image is not there.
    #[error("not found: {0}")]
    NotFound(String),
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    Invalid(String),
    /// A camera file that cannot be read or used.
    #[error("{path}: {reason}")]
    CameraFile {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, GeometryError>;

/// Checks that every coordinate of every point is finite.
pub(crate) fn check_finite<const D: usize>(what: &'static str, pts: &[[f64; D]]) -> Result<()> {
    match pts.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        Some(index) => Err(GeometryError::NonFinite { what, index }),
        None => Ok(()),
    }
}
