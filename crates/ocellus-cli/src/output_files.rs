//! Creating output folders and files with the path in every OS error ("cannot create
//! out/frames: Permission denied"), instead of a bare "Permission denied".

use anyhow::{Context, Result};
use std::path::Path;

/// Creates a folder and its parents.
pub fn create_dir(path: &Path) -> Result<()> {
    std::fs::create_dir_all(path).with_context(|| format!("cannot create folder {}", path.display()))
}

/// A buffered output file whose write errors name it ("out/steps.csv: No space left on
/// device"), so that a full disk halfway through a CSV is reported with the file.
#[derive(Debug)]
pub struct OutputFile {
    path: std::path::PathBuf,
    inner: std::io::BufWriter<std::fs::File>,
}

impl OutputFile {
    fn named(&self, e: std::io::Error) -> std::io::Error {
        std::io::Error::new(e.kind(), format!("{}: {e}", self.path.display()))
    }
}

impl std::io::Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.inner.write(buf).map_err(|e| self.named(e))
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush().map_err(|e| self.named(e))
    }
}

/// Creates (or truncates) a file for buffered writing; call `flush` at the end so that the last
/// write's error is seen.
pub fn create_file(path: &Path) -> Result<OutputFile> {
    let f = std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    Ok(OutputFile { path: path.to_path_buf(), inner: std::io::BufWriter::new(f) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn write_errors_name_the_file() {
        let mut f = create_file(Path::new("/dev/full")).unwrap();
        // Past the buffer, or at the flush: either way the error names the file.
        let e = writeln!(f, "{}", "x".repeat(100_000)).and_then(|()| f.flush()).unwrap_err();
        assert!(e.to_string().starts_with("/dev/full: "), "{e}");
        assert!(create_file(Path::new("/no/such/dir/x.csv")).unwrap_err().to_string().contains("/no/such/dir/x.csv"));
    }
}
