//! Creating output folders and files with the path in every OS error ("cannot create
//! out/frames: Permission denied"), instead of a bare "Permission denied".

use anyhow::{Context, Result};
use std::path::Path;

/// Creates a folder and its parents.
pub fn create_dir(path: &Path) -> Result<()> {
    std::fs::create_dir_all(path).with_context(|| format!("cannot create folder {}", path.display()))
}
