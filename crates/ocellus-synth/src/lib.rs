//! Generators of ground-truth scenes and image sequences built from real images.
//!
//! - [`attention_scenes`]: sequences for surprise, context and attention (a static scene with
//!   sensor noise, an object that appears suddenly, a steady camera pan), with per-frame truth.
//! - [`ball_world`]: a shaded coloured ball flying, bouncing, approaching in 3D in front of a
//!   real photo, with occluders, a distractor, a lighting change and noise (tracking truth).
//! - [`ball_view`]: the ball world seen by any moving pinhole camera (the eyes of a stereo head).
//! - [`chessboard`]: views of a chessboard through a known distorted camera (calibration
//!   ground truth).
//! - [`ground`]: a camera looking down at a tiled real-texture floor with known planar motion
//!   (visual odometry ground truth), and simulated wheel encoders.
//! - [`corridor`]: a corridor with textured walls, poster landmarks and a person, rendered by
//!   a pinhole camera with a pan angle (view-planning experiments).
//!
//! Conventions: x right, y down, pixel centres at integer coordinates; grey levels of noise in
//! 8-bit units; every random choice comes from a seed, so the same configuration gives the
//! same frames bit for bit.
//!
//! ```
//! use ocellus_image::{convert::RgbImage, Plane};
//! use ocellus_synth::attention_scenes::{Scenario, SceneConfig, SceneGenerator};
//! let world = RgbImage::U8(Plane::from_fn(300, 120, |x, y| [(x % 256) as u8, (y * 2) as u8, 90]));
//! let object = RgbImage::U8(Plane::from_fn(64, 64, |x, _| [255, (x * 4) as u8, 0]));
//! let cfg = SceneConfig { width: 160, height: 120, frames: 6, event_frame: 3, object_size: (32, 32),
//!     object_at: (80, 40), ..SceneConfig::new(Scenario::SuddenObject) };
//! let generator = SceneGenerator::new(cfg, &[world], &object).unwrap();
//! let (frame, truth) = generator.frame(4).unwrap();
//! assert_eq!(frame.size(), (160, 120));
//! assert_eq!(truth.object.unwrap().x, 80);
//! ```

pub mod attention_scenes;
pub mod ball_view;
pub mod ball_world;
pub mod chessboard;
pub mod corridor;
pub mod floors;
pub mod ground;
pub mod texture;

use thiserror::Error;

/// Errors of the generators.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SynthError {
    /// An image operation failed (the cause, for matching).
    #[error(transparent)]
    Image(#[from] ocellus_image::ImageError),
    /// A parameter is out of range.
    #[error("invalid scene configuration: {0}")]
    InvalidConfig(String),
    /// A frame index past the end.
    #[error("frame {index} asked, the sequence has {len}")]
    NoSuchFrame {
        /// Index asked.
        index: usize,
        /// Number of frames.
        len: usize,
    },
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, SynthError>;
