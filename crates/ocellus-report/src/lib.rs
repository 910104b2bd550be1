//! One HTML page that shows what ocellus did and how well: a section per capability, each
//! with the command that reproduces it, its key figures beside the seed's or an anchor's,
//! pictures and links to the data files.
//!
//! The page is self-contained: pictures and data are linked by relative paths inside the
//! report's folder, the style is inline, and nothing is fetched from the network (no fonts,
//! no scripts, no styles). It is built from plain data ([`Report`], [`Section`]), which a
//! program writes as `section.json` into each output folder ([`SECTION_FILE`]);
//! [`scan::report_from_dir`] builds a report from whatever folders it finds, with or without
//! those files.
//!
//! ```
//! use ocellus_report::{html::render, Figure, Report, Section};
//! let mut s = Section::new("stereo", "Stereo depth");
//! s.figures.push(Figure::new("bad-2.0", "13.8 %").beside("cv2.StereoSGBM: 18.1 %"));
//! let page = render(&Report { title: "ocellus".into(), intro: String::new(), sections: vec![s] });
//! assert!(page.contains("id=\"stereo\"") && page.contains("13.8 %"));
//! ```

pub mod html;
pub mod scan;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Errors of the report crate.
#[derive(Debug, Error)]
pub enum ReportError {
    /// A file or folder could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A `section.json` is not a section.
    #[error("{path} is not a report section: {why}")]
    BadSection {
        /// The path.
        path: String,
        /// Why.
        why: String,
    },
    /// A path that the page would link to is not inside the report's folder.
    #[error("{0} is not inside the report's folder: a page links only to its own files")]
    OutsideReport(String),
}

/// `Result` of the report crate.
pub type Result<T> = std::result::Result<T, ReportError>;

/// Name of the file in an output folder that describes its section.
pub const SECTION_FILE: &str = "section.json";

/// A whole page.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Page title.
    pub title: String,
    /// A paragraph under the title (plain text).
    pub intro: String,
    /// The sections, in page order.
    pub sections: Vec<Section>,
}

/// What one capability did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Section {
    /// Anchor id: ASCII letters, digits, `-` and `_` (others become `-`).
    pub id: String,
    /// Heading.
    pub title: String,
    /// What it is, one paragraph (plain text).
    pub about: String,
    /// The commands that reproduce it, run in the report's folder.
    pub commands: Vec<String>,
    /// Key figures.
    pub figures: Vec<Figure>,
    /// Pictures, paths relative to the report's folder.
    pub pictures: Vec<Picture>,
    /// Data files, paths relative to the report's folder.
    pub files: Vec<String>,
    /// What the commands printed.
    pub log: String,
    /// Wall time of the commands, seconds (`None`: not measured).
    pub seconds: Option<f64>,
}

impl Section {
    /// An empty section.
    pub fn new(id: &str, title: &str) -> Self {
        Self { id: id.into(), title: title.into(), ..Self::default() }
    }
}

/// One figure: what, its value with unit, and where one exists the seed's or an anchor's
/// figure to compare with.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Figure {
    /// What is measured.
    pub label: String,
    /// The value with its unit, as printed.
    pub value: String,
    /// The figure to compare with, with its source (empty: none).
    pub reference: String,
}

impl Figure {
    /// A figure without a reference.
    pub fn new(label: &str, value: &str) -> Self {
        Self { label: label.into(), value: value.into(), reference: String::new() }
    }

    /// The same with a reference figure.
    pub fn beside(mut self, reference: &str) -> Self {
        self.reference = reference.into();
        self
    }
}

/// A picture and its caption.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Picture {
    /// Path relative to the report's folder (`/` separated).
    pub path: String,
    /// Caption (plain text).
    pub caption: String,
}

impl Picture {
    /// A picture.
    pub fn new(path: &str, caption: &str) -> Self {
        Self { path: path.into(), caption: caption.into() }
    }
}
