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
//! - [`pipeline`]: the ordered frame pipeline (decode, parallel workers, in-order sink).
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
pub mod pipeline;
pub mod ply;
pub mod points;
pub mod tum;
pub mod video;
pub mod video_writer;
pub mod y4m;

use ocellus_image::convert::{from_dynamic, RgbImage};
use ocellus_image::Plane;
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
    /// The image is larger than the caller's pixel limit (checked from the header, before
    /// any pixel is decoded).
    #[error("{path}: {width}x{height} is {:.1} megapixels, over the limit of {:.1} megapixels", (*width * *height) as f64 / 1e6, *max_pixels as f64 / 1e6)]
    TooLarge {
        /// The path.
        path: PathBuf,
        /// Width in pixels.
        width: u64,
        /// Height in pixels.
        height: u64,
        /// The limit, pixels.
        max_pixels: u64,
    },
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

/// Largest image [`read_image`] decodes, pixels (width x height): 100 megapixels. Callers
/// with a memory budget pass their own limit to [`read_image_within`].
pub const DEFAULT_MAX_PIXELS: u64 = 100_000_000;

/// Reads an image file (format from its content, not its name) as RGB, up to
/// [`DEFAULT_MAX_PIXELS`].
pub fn read_image(path: impl AsRef<Path>) -> Result<RgbImage> {
    read_image_within(path, DEFAULT_MAX_PIXELS)
}

/// Reads an image file of at most `max_pixels` pixels; a larger one is refused from its
/// header, before anything is allocated for it ([`IoError::TooLarge`]).
pub fn read_image_within(path: impl AsRef<Path>, max_pixels: u64) -> Result<RgbImage> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    decode_image_within(&bytes, path, max_pixels)
}

/// Decodes image bytes, up to [`DEFAULT_MAX_PIXELS`]; `path` is only used in error messages.
pub fn decode_image(bytes: &[u8], path: &Path) -> Result<RgbImage> {
    decode_image_within(bytes, path, DEFAULT_MAX_PIXELS)
}

/// Decodes image bytes of at most `max_pixels` pixels.
///
/// A JPEG without its end-of-image marker is refused as truncated: the decoder would fill the
/// missing rows with grey and say nothing.
pub fn decode_image_within(bytes: &[u8], path: &Path, max_pixels: u64) -> Result<RgbImage> {
    if bytes.is_empty() {
        return Err(IoError::EmptyFile { path: path.into() });
    }
    let format = image::guess_format(bytes).map_err(|_| IoError::Unsupported { path: path.into() })?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg | image::ImageFormat::Pnm) {
        return Err(IoError::Unsupported { path: path.into() });
    }
    let corrupt = |reason: String| IoError::Corrupt { path: path.into(), reason };
    if format == image::ImageFormat::Jpeg && !has_jpeg_end(bytes) {
        return Err(corrupt("truncated JPEG: the end-of-image marker is missing".into()));
    }
    let reader = || image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let (w, h) = reader().into_dimensions().map_err(|e| corrupt(e.to_string()))?;
    if w as u64 * h as u64 > max_pixels {
        return Err(IoError::TooLarge { path: path.into(), width: w.into(), height: h.into(), max_pixels });
    }
    let mut limits = image::Limits::default();
    // The size is checked above; the decoder may use up to 16-bit RGBA for it.
    limits.max_alloc = Some((w as u64 * h as u64).saturating_mul(8).max(1 << 26));
    let mut r = reader();
    r.limits(limits);
    let img = r.decode().map_err(|e| corrupt(e.to_string()))?;
    from_dynamic(&img).map_err(|e| IoError::Invalid { path: path.into(), reason: e.to_string() })
}

/// Whether JPEG data ends with its EOI marker (0xFFD9), allowing the zero or 0xFF padding
/// some encoders append.
fn has_jpeg_end(bytes: &[u8]) -> bool {
    let end = bytes.iter().rposition(|&b| b != 0 && b != 0xff).map_or(0, |i| i + 1);
    end >= 2 && bytes[end - 1] == 0xd9 && bytes[end - 2] == 0xff
        || bytes[..end].windows(2).rev().take(64).any(|w| w == [0xff, 0xd9])
}

/// The pixels [`write_png`] stores: `u8` as 8-bit grey, `[u8; 3]` as 8-bit RGB.
pub trait PngPixel: Copy + Default {
    /// The PNG colour type.
    const COLOR: image::ExtendedColorType;
    /// Appends the pixel's bytes.
    fn extend(self, out: &mut Vec<u8>);
}

impl PngPixel for u8 {
    const COLOR: image::ExtendedColorType = image::ExtendedColorType::L8;
    fn extend(self, out: &mut Vec<u8>) {
        out.push(self);
    }
}

impl PngPixel for [u8; 3] {
    const COLOR: image::ExtendedColorType = image::ExtendedColorType::Rgb8;
    fn extend(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self);
    }
}

/// Writes a plane of grey (`u8`) or RGB (`[u8; 3]`) pixels as PNG, rows top to bottom.
/// (`ocellus_image::convert::to_grey8` makes 8-bit grey of a float map.)
pub fn write_png<P: PngPixel>(path: impl AsRef<Path>, img: &Plane<P>) -> Result<()> {
    let path = path.as_ref();
    let (w, h) = img.size();
    if w == 0 || h == 0 || w > u32::MAX as usize || h > u32::MAX as usize {
        return Err(IoError::Invalid { path: path.into(), reason: format!("cannot write a {w}x{h} image") });
    }
    let mut bytes = Vec::with_capacity(w * h * std::mem::size_of::<P>());
    for y in 0..h {
        img.row(y).iter().for_each(|p| p.extend(&mut bytes));
    }
    image::save_buffer_with_format(path, &bytes, w as u32, h as u32, P::COLOR, image::ImageFormat::Png).map_err(|e| {
        match e {
            image::ImageError::IoError(source) => IoError::Io { path: path.into(), source },
            other => IoError::Invalid { path: path.into(), reason: other.to_string() },
        }
    })
}
