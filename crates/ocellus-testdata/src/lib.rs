//! Finds test data for ocellus tests, benchmarks and examples, from any working directory.
//!
//! Everything a test reads lives inside the repository, so a fresh clone runs the whole suite:
//! - [`data_file`]: a file in the repository's `testdata/` (real images, the stereo pair with
//!   its ground truth, reference saliency maps, a few MIT1003 stimuli; see `testdata/LICENSES.md`);
//! - [`asset`]: a file in `assets/`, the CC0 / public-domain images the binary embeds.
//!
//! [`external_file`] may add an optional folder named by the `OCELLUS_DATA` environment
//! variable for larger data sets (profiling examples, full evaluations); no test depends on it.
//!
//! ```
//! let astronaut = ocellus_testdata::asset("astronaut.png");
//! assert!(astronaut.is_file());
//! let pair = ocellus_testdata::data_file("motorcycle_left.png");
//! assert!(pair.is_file());
//! ```

use std::path::{Path, PathBuf};

/// The repository root, from this crate's manifest directory (crates/ocellus-testdata).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("..")
}

/// The repository's `testdata/` folder.
pub fn data_dir() -> PathBuf {
    repo_root().join("testdata")
}

/// A file or folder in `testdata/`, or a panic that names the missing path (tests only: a
/// missing file of the repository is a broken checkout, not user input).
pub fn data_file(rel: &str) -> PathBuf {
    let p = data_dir().join(rel);
    assert!(p.exists(), "test data file {} is missing from the repository", p.display());
    p
}

/// A file in the optional external data folder named by `OCELLUS_DATA`, if that variable is
/// set and the file exists there. For examples and evaluations on larger sets than the
/// repository ships; tests must not depend on it.
pub fn external_file(rel: &str) -> Option<PathBuf> {
    let dir = PathBuf::from(std::env::var_os("OCELLUS_DATA")?);
    let p = dir.join(rel);
    p.exists().then_some(p)
}

/// The repository's `assets/` folder.
pub fn assets_dir() -> PathBuf {
    repo_root().join("assets")
}

/// A file in `assets/`.
pub fn asset(rel: &str) -> PathBuf {
    assets_dir().join(rel)
}
