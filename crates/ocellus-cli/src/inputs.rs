//! Turning command-line paths (files and folders) into a list of image files.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

pub use ocellus_io::video::natural_cmp;

/// Files as given, folders expanded to their image files in natural order.
pub fn collect_images(paths: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("cannot list folder {}", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.is_file() && ocellus_io::is_image_path(f))
                .collect();
            files.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
            if files.is_empty() {
                bail!("folder {} contains no PNG, JPEG or PNM image", p.display());
            }
            out.extend(files);
        } else {
            out.push(p.clone());
        }
    }
    if out.is_empty() {
        bail!("no input image given");
    }
    Ok(out)
}

/// File stem for output names ("img" for "dir/img.png").
pub fn stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "image".into())
}
