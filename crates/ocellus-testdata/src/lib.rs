//! Finds test data for ocellus tests and benchmarks, from any working directory.
//!
//! - [`data_dir`]: the shared data folder (`../shared/data` beside the repository), or the
//!   folder named by the `OCELLUS_DATA` environment variable.
//! - [`assets_dir`]: the repository's own `assets/` (CC0 / public-domain images).
//!
//! ```
//! let astronaut = ocellus_testdata::asset("astronaut.png");
//! assert!(astronaut.is_file());
//! ```

use std::path::{Path, PathBuf};

/// The repository root, from this crate's manifest directory (crates/ocellus-testdata).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("..")
}

/// The shared data folder, if it exists: `$OCELLUS_DATA`, else `<repo>/../shared/data`.
pub fn data_dir() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("OCELLUS_DATA") {
        let p = PathBuf::from(p);
        return p.is_dir().then_some(p);
    }
    let p = repo_root().join("..").join("shared").join("data");
    p.is_dir().then_some(p)
}

/// A file in the shared data folder, or a panic that says where it was looked for
/// (tests only: a missing data folder is a broken test set-up, not user input).
pub fn data_file(rel: &str) -> PathBuf {
    match data_dir() {
        Some(d) => {
            let p = d.join(rel);
            assert!(p.exists(), "test data file {} is missing", p.display());
            p
        }
        None => panic!("shared data folder not found: set OCELLUS_DATA or place it at <repo>/../shared/data"),
    }
}

/// The repository's `assets/` folder.
pub fn assets_dir() -> PathBuf {
    repo_root().join("assets")
}

/// A file in `assets/`.
pub fn asset(rel: &str) -> PathBuf {
    assets_dir().join(rel)
}
