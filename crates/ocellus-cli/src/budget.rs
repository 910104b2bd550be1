//! The working-memory budget: what a command may allocate, refused before it is allocated.
//!
//! The budget is 4096 MiB unless the environment variable `OCELLUS_MAX_MEMORY_MB` says
//! otherwise (16..=16777216). The heaviest per-pixel pipeline (saliency with conspicuity
//! maps, log-polar registration of two images by their spectra) needs about
//! [`BYTES_PER_PIXEL`] bytes per input pixel, so an input image or frame may have at most
//! budget / [`BYTES_PER_PIXEL`] pixels (67 megapixels with the default, e.g. 8192 x 8192);
//! commands whose need grows with another parameter (the stereo cost volume with the disparity
//! range) check that need with [`check`].

use anyhow::{bail, Result};
use ocellus_image::convert::RgbImage;
use ocellus_io::video::Frames;
use std::path::Path;

/// The variable that raises or lowers the budget, MiB.
pub const ENV: &str = "OCELLUS_MAX_MEMORY_MB";

/// The budget when [`ENV`] is not set, MiB.
pub const DEFAULT_MB: u64 = 4096;

/// Working memory per input pixel of the heaviest image pipeline, bytes, with a margin. Peak
/// resident memory over pixels, measured on a 4000x3000 image: `saliency` 31, `logpolar` 23,
/// `logpolar register --mode spectrum` 47 (both images together).
pub const BYTES_PER_PIXEL: u64 = 64;

/// The budget in bytes; a malformed [`ENV`] is an error rather than silently the default.
pub fn bytes() -> Result<u64> {
    match std::env::var(ENV) {
        Err(std::env::VarError::NotPresent) => Ok(DEFAULT_MB << 20),
        Err(e) => bail!("{ENV}: {e}"),
        Ok(v) => match v.trim().parse::<u64>() {
            Ok(mb) if (16..=1 << 24).contains(&mb) => Ok(mb << 20),
            _ => bail!("{ENV}={v} is not a number of MiB in the range 16..=16777216"),
        },
    }
}

/// The largest image or frame a command reads, pixels.
pub fn max_pixels() -> Result<u64> {
    Ok(bytes()? / BYTES_PER_PIXEL)
}

/// Refuses `need_bytes` for `what` if it exceeds the budget, with the limit and how to raise it.
pub fn check(what: &str, need_bytes: u64) -> Result<()> {
    let budget = bytes()?;
    if need_bytes > budget {
        bail!(
            "{what} needs about {} MiB of working memory, over the budget of {} MiB; set {ENV} to raise it",
            need_bytes >> 20,
            budget >> 20
        );
    }
    Ok(())
}

fn explain(e: ocellus_io::IoError) -> anyhow::Error {
    match e {
        ocellus_io::IoError::TooLarge { .. } => anyhow::anyhow!(
            "{e}: the working-memory budget of {} MiB allows {BYTES_PER_PIXEL} bytes per pixel; set {ENV} to raise it",
            bytes().unwrap_or(DEFAULT_MB << 20) >> 20
        ),
        e => e.into(),
    }
}

/// Reads an image within the budget.
pub fn read_image(path: impl AsRef<Path>) -> Result<RgbImage> {
    ocellus_io::read_image_within(path, max_pixels()?).map_err(explain)
}

/// Opens a frame source whose frames fit the budget.
pub fn open_frames(path: &Path) -> Result<Frames> {
    Frames::open_within(path, max_pixels()?).map_err(explain)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_names_the_limit_and_the_variable() {
        // The default applies in tests (the variable is not set by the test harness).
        if std::env::var_os(ENV).is_some() {
            return;
        }
        assert_eq!(bytes().unwrap(), 4096 << 20);
        assert!(check("a small thing", 1 << 20).is_ok());
        let e = check("the cost volume", 5 << 30).unwrap_err().to_string();
        assert!(e.contains("5120 MiB") && e.contains("4096 MiB") && e.contains(ENV), "{e}");
    }
}
