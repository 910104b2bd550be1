//! `ocellus report DIR`: the HTML page of whatever outputs are in a folder.

use anyhow::{bail, Result};
use clap::Args;
use ocellus_report::scan::{report_from_dir, write_report};
use std::path::PathBuf;

/// Arguments of `ocellus report`.
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Folder of outputs (e.g. the `--out` folders of other subcommands); the page is written
    /// as DIR/index.html, one section per subfolder (as its section.json says, or what it
    /// holds: pictures and data files).
    pub dir: PathBuf,
    /// Page title (unless DIR/report.json gives one).
    #[arg(long, default_value = "ocellus report")]
    pub title: String,
}

/// Writes DIR/index.html.
pub fn run(a: ReportArgs) -> Result<()> {
    if !a.dir.is_dir() {
        bail!("{} is not a folder", a.dir.display());
    }
    let report = report_from_dir(&a.dir, &a.title)?;
    if report.sections.is_empty() {
        bail!("{} holds no subfolder with pictures or data files: nothing to report", a.dir.display());
    }
    let page = write_report(&a.dir, &report)?;
    let pictures: usize = report.sections.iter().map(|s| s.pictures.len()).sum();
    outln!("{} sections, {pictures} pictures: wrote {}", report.sections.len(), page.display());
    Ok(())
}
