//! A report from a folder of outputs ([`report_from_dir`]), as `ocellus report DIR` builds it.
//!
//! Each subfolder of the report's folder becomes a section. A subfolder with a
//! [`SECTION_FILE`] is shown as that file says (the demo writes one per part); any other
//! subfolder gets a section of what it holds: its pictures (at most [`MAX_PICTURES`], evenly
//! spread over a long run of frames) and links to its data files. An optional
//! [`LAYOUT_FILE`] in the report's folder gives the title, the introduction and the order of
//! the sections. Pictures and files that do not exist are left out, so the page never shows
//! a broken picture.

use crate::{Picture, Report, ReportError, Result, Section, SECTION_FILE};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Name of the optional file in the report's folder with its title, introduction and
/// section order.
pub const LAYOUT_FILE: &str = "report.json";
/// Most pictures of a section found by scanning.
pub const MAX_PICTURES: usize = 8;
/// Most data files listed for a section found by scanning.
pub const MAX_FILES: usize = 40;
/// How deep the scan looks into a subfolder (1: its own files only).
pub const MAX_DEPTH: usize = 3;

/// The optional layout of a report's folder ([`LAYOUT_FILE`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Layout {
    /// Page title.
    pub title: String,
    /// Paragraph under the title.
    pub intro: String,
    /// Subfolder names in page order; the others follow by name.
    pub order: Vec<String>,
}

/// Extensions shown as pictures.
const PICTURE_EXT: &[&str] = &["png", "jpg", "jpeg", "gif", "svg", "webp"];
/// Extensions listed as data files.
const DATA_EXT: &[&str] =
    &["csv", "json", "tum", "toml", "txt", "npy", "pfm", "ply", "mp4", "y4m", "rrd", "parquet", "pgm", "ppm"];

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io { path: path.display().to_string(), source }
}

/// `path` relative to `base`, `/` separated.
fn relative(path: &Path, base: &Path) -> Result<String> {
    let rel = path.strip_prefix(base).map_err(|_| ReportError::OutsideReport(path.display().to_string()))?;
    let parts: Vec<String> = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    Ok(parts.join("/"))
}

fn extension(p: &Path) -> String {
    p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default()
}

/// The files under `dir` up to `depth` levels, sorted by path.
fn files_under(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).map_err(io(dir))?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            if depth > 1 {
                files_under(&p, depth - 1, out)?;
            }
        } else if p.is_file() {
            out.push(p);
        }
    }
    Ok(())
}

/// At most `n` of `v`, evenly spread (the first and the last kept).
fn spread<T: Clone>(v: &[T], n: usize) -> Vec<T> {
    if v.len() <= n {
        return v.to_vec();
    }
    if n < 2 {
        return v.iter().take(n).cloned().collect();
    }
    (0..n).map(|i| v[i * (v.len() - 1) / (n - 1)].clone()).collect()
}

/// The section of a subfolder without a [`SECTION_FILE`]: its pictures and data files
/// (paths relative to `base`); `None` when it holds neither.
pub fn scan_section(dir: &Path, base: &Path) -> Result<Option<Section>> {
    let mut files = Vec::new();
    files_under(dir, MAX_DEPTH, &mut files)?;
    let name = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut s = Section::new(&name, &name);
    let pictures: Vec<&PathBuf> = files.iter().filter(|p| PICTURE_EXT.contains(&extension(p).as_str())).collect();
    let data: Vec<&PathBuf> = files.iter().filter(|p| DATA_EXT.contains(&extension(p).as_str())).collect();
    if pictures.is_empty() && data.is_empty() {
        return Ok(None);
    }
    for p in spread(&pictures, MAX_PICTURES) {
        let rel = relative(p, base)?;
        let caption = relative(p, dir)?;
        s.pictures.push(Picture { path: rel, caption });
    }
    for p in data.iter().take(MAX_FILES) {
        s.files.push(relative(p, base)?);
    }
    let mut notes = Vec::new();
    if pictures.len() > MAX_PICTURES {
        notes.push(format!("{} of {} pictures shown", MAX_PICTURES, pictures.len()));
    }
    if data.len() > MAX_FILES {
        notes.push(format!("{} of {} data files listed", MAX_FILES, data.len()));
    }
    s.about = format!(
        "What {name}/ holds{}.",
        if notes.is_empty() { String::new() } else { format!(" ({})", notes.join("; ")) }
    );
    Ok(Some(s))
}

/// Reads a [`SECTION_FILE`], keeping only the pictures and files that exist under `base`.
pub fn read_section(file: &Path, base: &Path) -> Result<Section> {
    let text = std::fs::read_to_string(file).map_err(io(file))?;
    let mut s: Section = serde_json::from_str(&text)
        .map_err(|e| ReportError::BadSection { path: file.display().to_string(), why: e.to_string() })?;
    let exists = |p: &str| crate::html::href(p).is_some() && base.join(p).is_file();
    s.pictures.retain(|p| exists(&p.path));
    s.files.retain(|f| exists(f));
    Ok(s)
}

/// The report of a folder of outputs (see the module doc); `title` unless [`LAYOUT_FILE`]
/// gives one.
pub fn report_from_dir(dir: &Path, title: &str) -> Result<Report> {
    let layout_path = dir.join(LAYOUT_FILE);
    let layout: Layout = if layout_path.is_file() {
        let text = std::fs::read_to_string(&layout_path).map_err(io(&layout_path))?;
        serde_json::from_str(&text)
            .map_err(|e| ReportError::BadSection { path: layout_path.display().to_string(), why: e.to_string() })?
    } else {
        Layout::default()
    };
    let mut subdirs: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io(dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    let rank = |p: &PathBuf| {
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        (layout.order.iter().position(|o| *o == name).unwrap_or(usize::MAX), name)
    };
    subdirs.sort_by_key(rank);
    let mut sections = Vec::new();
    for d in &subdirs {
        let f = d.join(SECTION_FILE);
        if f.is_file() {
            sections.push(read_section(&f, dir)?);
        } else if let Some(s) = scan_section(d, dir)? {
            sections.push(s);
        }
    }
    Ok(Report {
        title: if layout.title.is_empty() { title.into() } else { layout.title },
        intro: layout.intro,
        sections,
    })
}

/// Writes `report` as `dir/index.html`; returns its path.
pub fn write_report(dir: &Path, report: &Report) -> Result<PathBuf> {
    let path = dir.join("index.html");
    std::fs::write(&path, crate::html::render(report)).map_err(io(&path))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // tests abort on broken set-up
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("ocellus-report-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_folder_of_outputs_becomes_sections_in_the_layouts_order() {
        let d = temp("scan");
        std::fs::create_dir_all(d.join("odo/flow")).unwrap();
        for k in 0..20 {
            std::fs::write(d.join(format!("odo/flow/flow_{k:02}.png")), b"png").unwrap();
        }
        std::fs::write(d.join("odo/trajectory.tum"), b"0 0 0 0 0 0 0 1\n").unwrap();
        std::fs::create_dir_all(d.join("empty")).unwrap();
        std::fs::create_dir_all(d.join("stereo")).unwrap();
        std::fs::write(d.join("stereo/disparity.png"), b"png").unwrap();
        let mut s = Section::new("stereo", "Stereo depth");
        s.pictures = vec![Picture::new("stereo/disparity.png", "d"), Picture::new("stereo/missing.png", "m")];
        s.files = vec!["../outside.csv".into()];
        std::fs::write(d.join("stereo").join(SECTION_FILE), serde_json::to_string(&s).unwrap()).unwrap();
        let layout = Layout { title: "T".into(), intro: "I".into(), order: vec!["stereo".into()] };
        std::fs::write(d.join(LAYOUT_FILE), serde_json::to_string(&layout).unwrap()).unwrap();

        let r = report_from_dir(&d, "fallback").unwrap();
        assert_eq!(r.title, "T");
        let ids: Vec<&str> = r.sections.iter().map(|s| s.id.as_str()).collect();
        assert_eq!(ids, ["stereo", "odo"]);
        // The missing picture and the path outside are left out.
        assert_eq!(r.sections[0].pictures.len(), 1);
        assert!(r.sections[0].files.is_empty());
        // 20 frames: 8 shown, evenly, the first and the last among them.
        let odo = &r.sections[1];
        assert_eq!(odo.pictures.len(), MAX_PICTURES);
        assert_eq!(odo.pictures[0].path, "odo/flow/flow_00.png");
        assert_eq!(odo.pictures[MAX_PICTURES - 1].path, "odo/flow/flow_19.png");
        assert_eq!(odo.files, ["odo/trajectory.tum"]);
        assert!(odo.about.contains("8 of 20 pictures"));
        let page = write_report(&d, &r).unwrap();
        assert!(std::fs::read_to_string(page).unwrap().contains("odo/flow/flow_19.png"));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_broken_section_file_is_a_clear_error() {
        let d = temp("bad");
        std::fs::create_dir_all(d.join("x")).unwrap();
        std::fs::write(d.join("x").join(SECTION_FILE), b"{ not json").unwrap();
        let e = report_from_dir(&d, "t").unwrap_err().to_string();
        assert!(e.contains("section.json") && e.contains("is not a report section"), "{e}");
        assert!(report_from_dir(&d.join("nowhere"), "t").is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
