//! `ocellus eval`: saliency maps against human fixations, with the MIT benchmark metrics.
//!
//! Density metrics (CC, SIM, KL) need fixation density maps (`--fixations`); location metrics
//! (NSS, AUC-Judd, AUC-Borji, shuffled AUC, IG) need fixation points (`--points`: binary
//! fixation maps or CSV files). Either or both may be given.

mod data;
mod tune;

use crate::config_file;
use anyhow::{bail, Context, Result};
use clap::Args;
use data::{Item, Sample};
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_attention::center_prior::{center_gaussian, CenterPrior};
use ocellus_attention::config::{ChannelConfig, ChannelKind};
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_eval::metrics;
use ocellus_image::Plane;
use rayon::prelude::*;
use serde_json::json;
use std::path::PathBuf;

/// Blur and prior shipped as the `--center-prior` defaults: what two-fold cross-validated grid
/// search (`ocellus eval --tune`) chose on the 100-image MIT1003 subset (Judd et al. 2009) the project was tuned on: both folds
/// chose skin weight 3, prior weight 0.60 and sigma 0.12, and blur 0.06 and 0.04 (we ship
/// their mean).
pub const DEFAULT_PRIOR: CenterPrior =
    CenterPrior { blur_sigma_frac_width: 0.05, weight: 0.6, center_sigma_frac: 0.12 };

/// Skin-channel weight of the `--center-prior` mode (both folds of `--tune` chose it).
pub const DEFAULT_PRIOR_SKIN_WEIGHT: f32 = 3.0;

/// The centre prior used as the IG baseline and as the `centre` model: sigma 0.25 of the larger side.
const BASELINE_SIGMA_FRAC: f32 = 0.25;

/// Seeded splits of the AUC-Borji and shuffled AUC (benchmark: 100 splits, thresholds step 0.1).
const AUC_SPLITS: usize = 100;
const AUC_STEP: f64 = 0.1;

/// Arguments of `ocellus eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Folder of stimulus images.
    #[arg(long)]
    pub stimuli: PathBuf,
    /// Folder of fixation density maps (grey images named like the stimuli): CC, SIM, KL.
    #[arg(long, required_unless_present = "points")]
    pub fixations: Option<PathBuf>,
    /// Folder of fixation points named like the stimuli: binary fixation maps (images whose
    /// non-zero pixels are fixations) or CSV files of `x,y` pixel positions (x right, y down,
    /// pixel centres at integers): NSS, AUC-Judd, AUC-Borji, shuffled AUC and IG.
    #[arg(long)]
    pub points: Option<PathBuf>,
    /// `ocellus:ace2009`, `ocellus:stb`, `maps:DIR` (precomputed maps named like the stimuli,
    /// any size, resized bilinearly) or `centre` (the centre prior alone, sigma 0.25).
    #[arg(long, default_value = "ocellus:ace2009")]
    pub model: String,
    /// TOML file overriding fields of the `ocellus:` preset (as `ocellus saliency --config`).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Adds the skin-colour channel to an `ocellus:` model with this weight (default 0: none;
    /// 3 with --center-prior). Range: 0..=100.
    #[arg(long, value_parser = crate::ranges::within(0.0f32, 100.0))]
    pub skin_weight: Option<f32>,
    /// The evaluation-friendly output: skin weight 3, blur 0.05 of the width, centre prior
    /// weight 0.6 with sigma 0.12 of the larger side (chosen by --tune), unless
    /// --skin-weight/--blur/--prior-weight/--prior-sigma say otherwise.
    #[arg(long)]
    pub center_prior: bool,
    /// Gaussian blur of the map, sigma as a fraction of the image width (default 0, or 0.05
    /// with --center-prior). Range: 0..=0.5.
    #[arg(long, value_parser = crate::ranges::within(0.0f32, 0.5))]
    pub blur: Option<f32>,
    /// Weight of the centre prior. Range: 0..=1.
    #[arg(long, value_parser = crate::ranges::within(0.0f32, 1.0))]
    pub prior_weight: Option<f32>,
    /// Sigma of the centre prior as a fraction of the larger side. Range: above 0, at most 2.
    #[arg(long, value_parser = crate::ranges::above(0.0f32, 2.0))]
    pub prior_sigma: Option<f32>,
    /// Choose, by grid search on half of the images and report on the other half, then swap
    /// (two-fold cross-validation): the skin weight and blur of the map alone, then blur,
    /// weight and sigma of the centre prior. Needs --fixations (selection by CC).
    #[arg(long)]
    pub tune: bool,
    /// Use only the first N images (natural order). Range: 1..=1000000.
    #[arg(long, value_parser = crate::ranges::within(1usize, 1_000_000))]
    pub limit: Option<usize>,
    /// Write per-image metric values to this JSON file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// What produces the maps.
pub(crate) enum Model {
    /// The saliency engine with this configuration.
    Ocellus(Box<SaliencyConfig>),
    /// Precomputed maps in a folder.
    Maps(PathBuf),
    /// The centre prior alone.
    Centre,
}

impl Model {
    fn parse(a: &EvalArgs) -> Result<Model> {
        if a.model == "centre" {
            return Ok(Model::Centre);
        }
        if let Some(dir) = a.model.strip_prefix("maps:") {
            return Ok(Model::Maps(dir.into()));
        }
        let Some(preset) = a.model.strip_prefix("ocellus:") else {
            bail!("unknown model '{}' (ocellus:ace2009, ocellus:stb, maps:DIR, centre)", a.model);
        };
        let cfg = config_file::load(preset, a.config.as_deref())?;
        Ok(Model::Ocellus(Box::new(with_skin(&cfg, skin_weight(a))?)))
    }
}

/// The skin weight asked for, or the mode's default.
fn skin_weight(a: &EvalArgs) -> f32 {
    a.skin_weight.unwrap_or(if a.center_prior { DEFAULT_PRIOR_SKIN_WEIGHT } else { 0.0 })
}

/// `cfg` with its skin channel set to `weight` (added if missing, removed for 0).
pub(crate) fn with_skin(cfg: &SaliencyConfig, weight: f32) -> Result<SaliencyConfig> {
    if !weight.is_finite() || weight < 0.0 {
        bail!("--skin-weight must be >= 0, got {weight}");
    }
    let mut c = cfg.clone();
    c.channels.retain(|ch| ch.kind != ChannelKind::Skin);
    if weight > 0.0 {
        c.channels.push(ChannelConfig { kind: ChannelKind::Skin, weight });
    }
    c.validate()?;
    Ok(c)
}

/// The model's map for one image (map level, or any size for `maps:`); None for `centre`.
pub(crate) fn model_map(model: &Model, item: &Item, engine: &mut Option<SaliencyEngine>) -> Result<Option<Plane<f32>>> {
    match model {
        Model::Centre => Ok(None),
        Model::Maps(dir) => {
            let p = data::find_same_stem(dir, &item.name)
                .with_context(|| format!("no map named {} in {}", item.name, dir.display()))?;
            Ok(Some(data::grey(&p)?))
        }
        Model::Ocellus(cfg) => {
            let img = crate::budget::read_image(&item.stimulus)?;
            let (w, h) = img.size();
            if engine.as_ref().map(|e| e.frame_size()) != Some((w, h)) {
                *engine = Some(SaliencyEngine::new((**cfg).clone(), w, h)?);
            }
            let Some(e) = engine.as_mut() else { bail!("engine missing") };
            Ok(Some(e.process(&img)?.clone()))
        }
    }
}

/// The evaluated map at `w` x `h`: the model's map with blur and prior, or the centre prior.
pub(crate) fn final_map(map: Option<&Plane<f32>>, w: usize, h: usize, prior: &CenterPrior) -> Result<Plane<f64>> {
    let full = match map {
        Some(m) => prior.apply(m, w, h)?,
        None => center_gaussian(w, h, prior.center_sigma_frac * w.max(h) as f32),
    };
    Ok(full.map(|v| v as f64))
}

/// CC, SIM, KL of `map` (prior applied) against the density map.
pub(crate) fn density_metrics(map: Option<&Plane<f32>>, density: &Plane<f64>, prior: &CenterPrior) -> Result<[f64; 3]> {
    let s = final_map(map, density.width(), density.height(), prior)?;
    Ok([metrics::cc(&s, density)?, metrics::sim(&s, density)?, metrics::kl(&s, density)?])
}

/// NSS, AUC-Judd, AUC-Borji, sAUC, IG of `saliency` at the fixations; `others` are the other
/// images' fixations in this image's pixels (sAUC negatives). Seeded by the image's index.
fn location_metrics(
    saliency: &Plane<f64>,
    fixations: &[(usize, usize)],
    others: &[(usize, usize)],
    index: usize,
) -> Result<[f64; 5]> {
    let (w, h) = saliency.size();
    let seed = 0x5eed_0000 + index as u64;
    let baseline = center_gaussian(w, h, BASELINE_SIGMA_FRAC * w.max(h) as f32).map(|v| v as f64);
    Ok([
        metrics::nss(saliency, fixations)?,
        metrics::auc_judd(saliency, fixations, seed)?,
        metrics::auc_borji(saliency, fixations, AUC_SPLITS, AUC_STEP, seed)?,
        // One image alone has no other images' fixations: no shuffled AUC.
        if others.is_empty() {
            f64::NAN
        } else {
            metrics::auc_shuffled(saliency, fixations, others, AUC_SPLITS, AUC_STEP, seed)?
        },
        metrics::info_gain(saliency, &baseline, fixations)?,
    ])
}

pub(crate) fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 { v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    (m, (var / n).sqrt())
}

pub(crate) fn progress(n: usize, what: &str) -> ProgressBar {
    let b = ProgressBar::new(n as u64);
    b.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}").unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    b.set_message(what.to_string());
    b
}

/// The blur and prior asked for on the command line.
fn prior_from_args(a: &EvalArgs) -> Result<CenterPrior> {
    let base = if a.center_prior {
        DEFAULT_PRIOR
    } else {
        CenterPrior { blur_sigma_frac_width: 0.0, weight: 0.0, center_sigma_frac: BASELINE_SIGMA_FRAC }
    };
    let prior = CenterPrior {
        blur_sigma_frac_width: a.blur.unwrap_or(base.blur_sigma_frac_width),
        weight: a.prior_weight.unwrap_or(base.weight),
        center_sigma_frac: a.prior_sigma.unwrap_or(base.center_sigma_frac),
    };
    prior.validate()?;
    Ok(prior)
}

/// Per-image values: the density metrics and the location metrics, where the inputs exist.
struct Scores {
    density: Option<[f64; 3]>,
    location: Option<[f64; 5]>,
}

const DENSITY_NAMES: [&str; 3] = ["CC", "SIM", "KL"];
const LOCATION_NAMES: [&str; 5] = ["NSS", "AUC-Judd", "AUC-Borji", "sAUC", "IG"];

fn score_all(samples: &[Sample], prior: &CenterPrior) -> Result<Vec<Scores>> {
    let bar = progress(samples.len(), "metrics");
    let scores = samples
        .par_iter()
        .enumerate()
        .map(|(i, s)| -> Result<Scores> {
            let (w, h) = s.size;
            let map = final_map(s.map.as_ref(), w, h, prior)?;
            let density = match &s.density {
                Some(d) => Some([metrics::cc(&map, d)?, metrics::sim(&map, d)?, metrics::kl(&map, d)?]),
                None => None,
            };
            let location = match &s.fixations {
                Some(f) => Some(location_metrics(&map, f, &data::other_fixations(samples, i), i)?),
                None => None,
            };
            bar.inc(1);
            Ok(Scores { density, location })
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    Ok(scores)
}

fn print_table(scores: &[Scores]) -> Result<()> {
    outln!("{:<10} {:>8} {:>8}", "metric", "mean", "s.e.");
    let row = |name: &str, v: Vec<f64>| -> Result<()> {
        if v.iter().any(|x| x.is_nan()) {
            outln!("{name:<10} {:>8} (needs fixations of at least 2 images)", "n/a");
            return Ok(());
        }
        let (m, se) = mean_se(&v);
        outln!("{name:<10} {m:>8.4} {se:>8.4}");
        Ok(())
    };
    if scores.iter().all(|s| s.density.is_some()) {
        for (k, name) in DENSITY_NAMES.iter().enumerate() {
            row(name, scores.iter().filter_map(|s| s.density.map(|d| d[k])).collect())?;
        }
    } else {
        outln!("CC, SIM and KL need fixation density maps (--fixations).");
    }
    if scores.iter().all(|s| s.location.is_some()) {
        for (k, name) in LOCATION_NAMES.iter().enumerate() {
            row(name, scores.iter().filter_map(|s| s.location.map(|d| d[k])).collect())?;
        }
    } else {
        outln!("NSS, AUC-Judd, AUC-Borji, shuffled AUC and IG need fixation points (--points: binary maps or CSV).");
    }
    Ok(())
}

fn write_json(
    path: &std::path::Path,
    a: &EvalArgs,
    prior: &CenterPrior,
    items: &[Item],
    scores: &[Scores],
) -> Result<()> {
    let rows: Vec<_> = items
        .iter()
        .zip(scores)
        .map(|(i, s)| {
            let mut o = serde_json::Map::new();
            o.insert("image".into(), json!(i.name));
            for (names, vals) in [
                (&DENSITY_NAMES[..], s.density.map(|d| d.to_vec())),
                (&LOCATION_NAMES[..], s.location.map(|d| d.to_vec())),
            ] {
                for (n, v) in names.iter().zip(vals.unwrap_or_default()) {
                    o.insert((*n).into(), json!(v));
                }
            }
            serde_json::Value::Object(o)
        })
        .collect();
    let doc = json!({"model": a.model, "skin_weight": skin_weight(a), "prior": prior, "images": rows});
    std::fs::write(path, serde_json::to_string_pretty(&doc)?)
        .with_context(|| format!("cannot write {}", path.display()))?;
    outln!("per-image values written to {}", path.display());
    Ok(())
}

/// Runs the subcommand.
pub fn run(a: EvalArgs) -> Result<()> {
    let items = data::collect_items(&a)?;
    let prior = prior_from_args(&a)?;
    let model = Model::parse(&a)?;
    if a.tune {
        return tune::run(&a, &model, &items);
    }
    let samples = data::load_samples(&items, &model)?;
    outln!("{} images, model {}", items.len(), a.model);
    let scores = score_all(&samples, &prior)?;
    outln!(
        "blur {:.3} of width, centre prior weight {:.2}, sigma {:.2} of the larger side",
        prior.blur_sigma_frac_width,
        prior.weight,
        prior.center_sigma_frac
    );
    print_table(&scores)?;
    if let Some(path) = &a.json {
        write_json(path, &a, &prior, &items, &scores)?;
    }
    Ok(())
}
