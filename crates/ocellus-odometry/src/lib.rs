//! How the robot moved: visual odometry from a camera looking straight down at the floor
//! (SPEC 6; seed 001, section 5).
//!
//! - [`sad_flow`]: the seed's elaborated SAD block matching: 400 search windows over the
//!   central 400x400 pixels, border windows dropped, 3x3 groups with outlier rejection, 36
//!   flow vectors.
//! - [`kinematics`]: planar poses, and the camera-to-robot motion of seed eq. 20 (a camera
//!   mounted off the rotation centre).
//! - [`robust`]: beyond the seed: sub-pixel Lucas-Kanade refinement with per-window
//!   uncertainty (the aperture problem), then [`rigid_fit`]: a robust fit of the exact rigid
//!   motion over all windows.
//! - [`fusion`]: wheel encoders fused with vision: slips rejected, texture gaps bridged.
//! - [`vo`]: the Kalman filter on the camera motion (Tx, Ty, wz) with the image-Jacobian
//!   measurement model, in information form, and the integration to a robot trajectory.
//!
//! Conventions: image x right, y down, pixel centres at integers; flow positions relative to
//! the principal point. The robot frame is (right, forward); headings turn clockwise seen
//! from above (the image's sense). Lengths at the API are metres (camera height, mount
//! offset, poses), angles radians; flows are pixels.
//!
//! ```
//! use ocellus_odometry::kinematics::Pose2;
//! let p = Pose2::default().step(0.0, 1.0, std::f64::consts::FRAC_PI_2);
//! assert!((p.y + 1.0).abs() < 1e-12); // forward is -y at heading 0
//! ```

pub mod fusion;
mod gain_field;
pub mod height;
pub mod kinematics;
pub mod lucas_kanade;
pub mod rigid_fit;
pub mod robust;
pub mod sad_flow;
pub mod spline;
pub mod vo;

use thiserror::Error;

/// Errors of the odometry crate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum OdometryError {
    /// An image operation failed (the cause, for matching).
    #[error(transparent)]
    Image(#[from] ocellus_image::ImageError),
    /// A parameter is out of range.
    #[error("invalid odometry parameter: {0}")]
    Invalid(String),
    /// Frames too small for the configured windows (frames of different sizes are
    /// `Image(ImageError::SizeMismatch)`).
    #[error("frame is {got_w}x{got_h}: {why}")]
    TooSmall {
        /// Width.
        got_w: usize,
        /// Height.
        got_h: usize,
        /// What was expected.
        why: String,
    },
    /// The image has too little texture to measure motion (e.g. a blank floor).
    #[error("no reliable flow: {0}")]
    NoTexture(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, OdometryError>;
