use thiserror::Error;

/// Errors of the image operations. Messages carry the offending values.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ImageError {
    /// The image has no pixels.
    #[error("image is {width}x{height}: it has no pixels")]
    Empty {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// A buffer does not hold the pixels its size promises.
    #[error("buffer of {len} values cannot hold a {width}x{height} image with row stride {stride}")]
    BufferSize {
        /// Values in the buffer.
        len: usize,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Row stride in values.
        stride: usize,
    },
    /// Two images that must have the same size do not.
    #[error("size mismatch: {what} is {got_w}x{got_h}, expected {want_w}x{want_h}")]
    SizeMismatch {
        /// Which image.
        what: &'static str,
        /// Actual width.
        got_w: usize,
        /// Actual height.
        got_h: usize,
        /// Expected width.
        want_w: usize,
        /// Expected height.
        want_h: usize,
    },
    /// A parameter is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, ImageError>;
