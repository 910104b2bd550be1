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

/// Output names for the inputs (their file stems), refused when two inputs would write the
/// same files: `a/x.png` and `b/x.png`, or `x.png` and `x.jpg`, would overwrite each other's
/// outputs while the summary still counted both.
pub fn output_stems(files: &[PathBuf]) -> Result<Vec<String>> {
    let stems: Vec<String> = files.iter().map(|f| stem(f)).collect();
    let mut seen: std::collections::HashMap<&str, &Path> = std::collections::HashMap::new();
    for (s, f) in stems.iter().zip(files) {
        if let Some(first) = seen.insert(s.as_str(), f.as_path()) {
            bail!(
                "inputs {} and {} would both write outputs named {s}.*; rename one or run them separately",
                first.display(),
                f.display()
            );
        }
    }
    Ok(stems)
}

/// Refuses an output folder that holds any of the inputs (a file in it, or the folder
/// itself), so that no original is ever overwritten and outputs never mix with inputs.
pub fn check_out_dir(out: &Path, inputs: &[PathBuf]) -> Result<()> {
    let Ok(out_c) = out.canonicalize() else {
        // A folder that does not exist yet holds no input.
        return Ok(());
    };
    for p in inputs {
        let dir = if p.is_dir() {
            Some(p.as_path())
        } else {
            p.parent().map(|d| if d.as_os_str().is_empty() { Path::new(".") } else { d })
        };
        if dir.and_then(|d| d.canonicalize().ok()).is_some_and(|d| d == out_c) {
            if p.is_dir() {
                bail!("output folder {} is the input folder {}: choose another --out", out.display(), p.display());
            }
            bail!(
                "output folder {} holds the input {}: choose another --out so that no original is overwritten",
                out.display(),
                p.display()
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colliding_stems_and_input_folders_are_refused() {
        let dir = std::env::temp_dir().join(format!("ocellus-inputs-{}", std::process::id()));
        let (a, b) = (dir.join("a"), dir.join("b"));
        std::fs::create_dir_all(&a).unwrap();
        std::fs::create_dir_all(&b).unwrap();
        let (xa, xb) = (a.join("x.png"), b.join("x.png"));
        std::fs::write(&xa, b"").unwrap();
        std::fs::write(&xb, b"").unwrap();
        assert_eq!(output_stems(&[xa.clone(), b.join("y.png")]).unwrap(), ["x", "y"]);
        let e = output_stems(&[xa.clone(), xb.clone()]).unwrap_err().to_string();
        assert!(e.contains("x.*"), "{e}");
        assert!(output_stems(&[xa.clone(), a.join("x.jpg")]).is_err());
        // The folder of an input, by any spelling, is refused; a sibling or a new one is not.
        assert!(check_out_dir(&a, std::slice::from_ref(&xa)).is_err());
        assert!(check_out_dir(&dir.join("b/../a"), std::slice::from_ref(&xa)).is_err());
        assert!(check_out_dir(&a, std::slice::from_ref(&a)).is_err());
        assert!(check_out_dir(&b, std::slice::from_ref(&xa)).is_ok());
        assert!(check_out_dir(&dir.join("new"), &[xa]).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
