//! File formats for ocellus: image files in, maps out.
//!
//! - [`read_image`]: PNG, JPEG and PNM (PBM/PGM/PPM/PAM) into an [`RgbImage`], with a clear
//!   error for a missing, unreadable, empty, corrupt or unsupported file.
//! - [`npy`]: NumPy `.npy` arrays (read f32/f64 in C or Fortran order; write f32, C order).
//! - [`pfm`]: Portable Float Map, single channel, as Middlebury writes it (rows bottom-up).
//! - [`csv`]: numeric CSV rows; [`points`]: CSV files of 2D points (fixations), in pixels.
//! - [`ply`]: coloured point clouds.
//! - [`video`]: frame sources (image folders, Y4M, any video through the ffmpeg program) and
//!   [`y4m`] reading and writing; [`video_writer`]: MP4 output through ffmpeg.
//!
//! ```
//! use ocellus_image::Plane;
//! let map = Plane::from_fn(4, 3, |x, y| (x + 10 * y) as f32);
//! let bytes = ocellus_io::npy::encode_f32(&[3, 4], &map.to_vec());
//! let back = ocellus_io::npy::parse(&bytes, std::path::Path::new("map.npy")).unwrap();
//! assert_eq!(back.shape, vec![3, 4]);
//! assert_eq!(back.data[5], 11.0); // row 1, column 1
//! let err = ocellus_io::read_image("/no/such/file.png").unwrap_err();
//! assert!(err.to_string().contains("no such file"));
//! ```

pub mod csv;
pub mod npy;
pub mod pfm;
pub mod ply;
pub mod points;
pub mod tum;
pub mod video;
pub mod video_writer;
pub mod y4m;

use ocellus_image::convert::{from_dynamic, RgbImage};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors of file input and output.
#[derive(Debug, Error)]
pub enum IoError {
    /// The file does not exist.
    #[error("{path}: no such file")]
    NotFound {
        /// The path asked for.
        path: PathBuf,
    },
    /// The file exists but could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is empty.
    #[error("{path}: file is empty")]
    EmptyFile {
        /// The path.
        path: PathBuf,
    },
    /// The file's format is not one ocellus reads.
    #[error("{path}: unsupported image format (ocellus reads PNG, JPEG and PNM)")]
    Unsupported {
        /// The path.
        path: PathBuf,
    },
    /// The file claims a supported format but its content is broken.
    #[error("{path}: cannot decode: {reason}")]
    Corrupt {
        /// The path.
        path: PathBuf,
        /// What the decoder said.
        reason: String,
    },
    /// A video or frame sequence failed at a frame (the frames before it were delivered).
    #[error("{path}: frame {frame}: {reason}")]
    Video {
        /// The video or folder.
        path: PathBuf,
        /// Index of the frame that failed (0-based).
        frame: usize,
        /// What went wrong.
        reason: String,
    },
    /// The ffmpeg program is missing or failed to start.
    #[error("{0}")]
    Ffmpeg(String),
    /// The content is valid but unusable (zero size, wrong shape, ...).
    #[error("{path}: {reason}")]
    Invalid {
        /// The path.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

impl IoError {
    /// The frame a video error happened at, if it is one.
    pub fn frame(&self) -> Option<usize> {
        match self {
            IoError::Video { frame, .. } => Some(*frame),
            _ => None,
        }
    }
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, IoError>;

pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    match std::fs::read(path) {
        Ok(b) => Ok(b),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(IoError::NotFound { path: path.into() }),
        Err(e) => Err(IoError::Io { path: path.into(), source: e }),
    }
}

pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(|e| IoError::Io { path: path.into(), source: e })
}

/// Extensions that [`read_image`] accepts (lower case), for folder scans.
pub const IMAGE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "pnm", "pbm", "pgm", "ppm", "pam"];

/// True when the path's extension is one of [`IMAGE_EXTENSIONS`].
pub fn is_image_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// Reads an image file (format from its content, not its name) as RGB.
pub fn read_image(path: impl AsRef<Path>) -> Result<RgbImage> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    decode_image(&bytes, path)
}

/// Decodes image bytes; `path` is only used in error messages.
pub fn decode_image(bytes: &[u8], path: &Path) -> Result<RgbImage> {
    if bytes.is_empty() {
        return Err(IoError::EmptyFile { path: path.into() });
    }
    let format = image::guess_format(bytes).map_err(|_| IoError::Unsupported { path: path.into() })?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg | image::ImageFormat::Pnm) {
        return Err(IoError::Unsupported { path: path.into() });
    }
    let img = image::load_from_memory_with_format(bytes, format)
        .map_err(|e| IoError::Corrupt { path: path.into(), reason: e.to_string() })?;
    from_dynamic(&img).map_err(|e| IoError::Invalid { path: path.into(), reason: e.to_string() })
}

/// Writes an `image` buffer as PNG.
pub fn write_png<P, C>(path: impl AsRef<Path>, img: &image::ImageBuffer<P, C>) -> Result<()>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    let path = path.as_ref();
    img.save_with_format(path, image::ImageFormat::Png).map_err(|e| match e {
        image::ImageError::IoError(source) => IoError::Io { path: path.into(), source },
        other => IoError::Invalid { path: path.into(), reason: other.to_string() },
    })
}
