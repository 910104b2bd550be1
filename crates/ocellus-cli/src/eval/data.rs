//! Finding and loading what `ocellus eval` scores: stimuli, density maps, fixation points.

use super::{model_map, progress, EvalArgs, Model};
use crate::inputs;
use anyhow::{bail, Context, Result};
use ocellus_eval::protocol::Sample;
use ocellus_image::Plane;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// One stimulus and its fixation data.
pub struct Item {
    /// File stem shared by the stimulus and its fixation files.
    pub name: String,
    pub stimulus: PathBuf,
    pub density: Option<PathBuf>,
    pub points: Option<PathBuf>,
}

fn files_with_stem(dir: &Path, stem: &str) -> Vec<PathBuf> {
    let Ok(rd) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut v: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| inputs::stem(p) == stem).collect();
    v.sort();
    v
}

/// The image file in `dir` named `stem.*`.
pub fn find_same_stem(dir: &Path, stem: &str) -> Option<PathBuf> {
    files_with_stem(dir, stem).into_iter().find(|p| ocellus_io::is_image_path(p))
}

fn is_csv(p: &Path) -> bool {
    p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("csv"))
}

/// The points file in `dir` named `stem.csv`, or else a binary fixation map `stem.<image>`.
fn find_points(dir: &Path, stem: &str) -> Option<PathBuf> {
    let files = files_with_stem(dir, stem);
    let csv = files.iter().find(|p| is_csv(p)).cloned();
    csv.or_else(|| files.into_iter().find(|p| ocellus_io::is_image_path(p)))
}

/// An image as grey values in [0, 1] (BT.601 luma, the workspace's grey).
pub fn grey(path: &Path) -> Result<Plane<f32>> {
    Ok(crate::budget::read_image(path)?.to_grey())
}

/// The stimuli of `--stimuli` with their density maps and points files.
pub fn collect_items(a: &EvalArgs) -> Result<Vec<Item>> {
    let stimuli = inputs::collect_images(std::slice::from_ref(&a.stimuli))?;
    let mut items = Vec::new();
    for s in stimuli {
        let name = inputs::stem(&s);
        let density = match &a.fixations {
            Some(dir) => Some(
                find_same_stem(dir, &name)
                    .with_context(|| format!("no fixation map named {name} in {}", dir.display()))?,
            ),
            None => None,
        };
        let points = match &a.points {
            Some(dir) => Some(
                find_points(dir, &name)
                    .with_context(|| format!("no {name}.csv or fixation map {name}.* in {}", dir.display()))?,
            ),
            None => None,
        };
        items.push(Item { name, stimulus: s, density, points });
    }
    if let Some(n) = a.limit {
        items.truncate(n);
    }
    if items.is_empty() {
        bail!("no stimuli found in {}", a.stimuli.display());
    }
    Ok(items)
}

/// Fixation pixels as (column, row).
type Pixels = Vec<(usize, usize)>;

/// Fixation pixels of a binary map: pixels at least half as bright as white (robust to JPEG
/// noise); and the map's size.
fn fixations_of_binary_map(path: &Path) -> Result<(Pixels, (usize, usize))> {
    let g = grey(path)?;
    let size = g.size();
    let b = g.map(|v| if v >= 0.5 { 1.0f64 } else { 0.0 });
    Ok((ocellus_eval::metrics::fixations_from_map(&b), size))
}

fn load_sample(item: &Item, model: &Model, engine: &mut Option<ocellus_attention::SaliencyEngine>) -> Result<Sample> {
    let map = model_map(model, item, engine)?;
    let density = match &item.density {
        Some(p) => Some(grey(p)?.map(|v| v as f64)),
        None => None,
    };
    let (mut fixations, mut size) = (None, density.as_ref().map(|d| d.size()));
    if let Some(p) = &item.points {
        if is_csv(p) {
            let pts = ocellus_io::points::read_points(p)?;
            let (w, h) = match size {
                Some(s) => s,
                None => crate::budget::read_image(&item.stimulus)?.size(),
            };
            size = Some((w, h));
            fixations = Some(ocellus_io::points::to_pixels(&pts, w, h));
        } else {
            let (f, s) = fixations_of_binary_map(p)?;
            if let Some(ds) = size.filter(|&ds| ds != s) {
                bail!("{}: fixation map is {}x{}, density map is {}x{}", p.display(), s.0, s.1, ds.0, ds.1);
            }
            size = Some(s);
            fixations = Some(f);
        }
    }
    // The size every metric works at: the density map's, else the binary fixation map's,
    // else the stimulus's.
    let Some(size) = size else { bail!("{}: no fixation data", item.name) };
    if fixations.as_ref().is_some_and(|f| f.is_empty()) {
        bail!("{}: no fixation inside the image", item.name);
    }
    Ok(Sample { map, density, fixations, size })
}

/// Loads every item (maps computed in parallel, one engine per worker), with a progress bar.
pub fn load_samples(items: &[Item], model: &Model) -> Result<Vec<Sample>> {
    let bar = progress(items.len(), "maps");
    let samples = items
        .par_iter()
        .map_init(
            || None,
            |engine, item| -> Result<Sample> {
                let s = load_sample(item, model, engine).with_context(|| item.name.clone())?;
                bar.inc(1);
                Ok(s)
            },
        )
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    Ok(samples)
}

/// The model's map of every item (in parallel, one engine per worker), without the fixation data.
pub fn load_maps(items: &[Item], model: &Model) -> Result<Vec<Option<Plane<f32>>>> {
    let bar = progress(items.len(), "maps");
    let maps = items
        .par_iter()
        .map_init(
            || None,
            |engine, item| {
                let m = model_map(model, item, engine).with_context(|| item.name.clone());
                bar.inc(1);
                m
            },
        )
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    Ok(maps)
}
