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
use data::Item;
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_attention::config::ChannelKind;
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_eval::center_prior::CenterPrior;
use ocellus_eval::protocol::{
    mean_se, no_prior, score_all, Scores, DEFAULT_PRIOR, DEFAULT_PRIOR_SKIN_WEIGHT, DENSITY_NAMES, LOCATION_NAMES,
};
use ocellus_image::{Backend, Plane};
use serde_json::json;
use std::path::PathBuf;

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
    Ok(cfg.with_channel_weight(ChannelKind::Skin, weight)?)
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
    let base = if a.center_prior { DEFAULT_PRIOR } else { no_prior() };
    let prior = CenterPrior {
        blur_sigma_frac_width: a.blur.unwrap_or(base.blur_sigma_frac_width),
        weight: a.prior_weight.unwrap_or(base.weight),
        center_sigma_frac: a.prior_sigma.unwrap_or(base.center_sigma_frac),
    };
    prior.validate()?;
    Ok(prior)
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
    let bar = progress(samples.len(), "metrics");
    let scores = score_all(Backend::Auto, &samples, &prior, &|| bar.inc(1))?;
    bar.finish_and_clear();
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
