//! `ocellus eval --tune`: two-fold cross-validated choice of the evaluation-friendly output.
//!
//! Per fold, on the training half: (1) the map alone: skin-channel weight x blur, by mean CC;
//! (2) with that skin weight: blur x prior weight x prior sigma, by mean CC. Both choices are
//! then scored on the other half, so no reported number was tuned on the images it is reported on.

use super::data::{self, Item, Sample};
use super::{density_metrics, mean_se, progress, with_skin, EvalArgs, Model};
use anyhow::{bail, Result};
use ocellus_attention::center_prior::CenterPrior;
use ocellus_image::Plane;
use rayon::prelude::*;
use std::ops::Range;

const SKIN_WEIGHTS: [f32; 4] = [0.0, 1.0, 2.0, 3.0];
const MAP_BLURS: [f32; 7] = [0.0, 0.02, 0.04, 0.06, 0.08, 0.1, 0.12];
const PRIOR_BLURS: [f32; 4] = [0.04, 0.06, 0.08, 0.1];
const PRIOR_WEIGHTS: [f32; 4] = [0.5, 0.6, 0.7, 0.8];
const PRIOR_SIGMAS: [f32; 5] = [0.08, 0.1, 0.12, 0.16, 0.2];

/// `scores[image][combo]` = [CC, SIM, KL] of every combination on every image, for one
/// model's `maps` (one per sample; the samples give the density maps).
fn grid_scores(
    samples: &[Sample],
    maps: &[Option<Plane<f32>>],
    grid: &[CenterPrior],
    what: &str,
) -> Result<Vec<Vec<[f64; 3]>>> {
    let bar = progress(samples.len(), what);
    let r = samples
        .par_iter()
        .zip(maps)
        .map(|(s, map)| {
            let Some(d) = &s.density else { bail!("--tune needs fixation density maps (--fixations)") };
            let r = grid.iter().map(|p| density_metrics(map.as_ref(), d, p)).collect::<Result<Vec<_>>>();
            bar.inc(1);
            r
        })
        .collect::<Result<_>>();
    bar.finish_and_clear();
    r
}

/// Index of the combination with the best mean CC over `train`.
fn best(scores: &[Vec<[f64; 3]>], combos: Range<usize>, train: &Range<usize>) -> usize {
    let mean_cc = |c: usize| train.clone().map(|k| scores[k][c][0]).sum::<f64>();
    combos.max_by(|&i, &j| mean_cc(i).total_cmp(&mean_cc(j))).unwrap_or(0)
}

fn test_means(scores: &[Vec<[f64; 3]>], c: usize, test: &Range<usize>) -> [f64; 3] {
    let m = |k: usize| mean_se(&test.clone().map(|i| scores[i][c][k]).collect::<Vec<_>>()).0;
    [m(0), m(1), m(2)]
}

fn print_mean(what: &str, r: &[[f64; 3]]) -> Result<()> {
    let m = |k: usize| r.iter().map(|x| x[k]).sum::<f64>() / r.len() as f64;
    outln!("{what}, cross-validated mean of both folds: CC {:.4} SIM {:.4} KL {:.4}", m(0), m(1), m(2));
    Ok(())
}

/// Runs the two-fold search and prints the choices and held-out scores.
pub fn run(a: &EvalArgs, model: &Model, items: &[Item]) -> Result<()> {
    if items.len() < 2 {
        bail!("--tune needs at least 2 images");
    }
    // The map-level maps for each skin weight (one set for models without a skin channel).
    let models: Vec<(f32, Model)> = match model {
        Model::Ocellus(cfg) => SKIN_WEIGHTS
            .iter()
            .map(|&w| Ok((w, Model::Ocellus(Box::new(with_skin(cfg, w)?)))))
            .collect::<Result<_>>()?,
        Model::Maps(d) => vec![(0.0, Model::Maps(d.clone()))],
        Model::Centre => bail!("--tune needs a model with maps (ocellus:... or maps:DIR)"),
    };
    // Density maps are loaded once; each skin weight only adds its saliency maps.
    let samples = data::load_samples(items, &models[0].1)?;
    let mut maps: Vec<Vec<Option<Plane<f32>>>> = vec![samples.iter().map(|s| s.map.clone()).collect()];
    for (_, m) in &models[1..] {
        maps.push(data::load_maps(items, m)?);
    }
    outln!("{} images, model {}, two-fold cross-validation by CC", items.len(), a.model);
    let map_grid: Vec<CenterPrior> = MAP_BLURS
        .iter()
        .map(|&b| CenterPrior { blur_sigma_frac_width: b, weight: 0.0, center_sigma_frac: 0.25 })
        .collect();
    let map_scores: Vec<Vec<Vec<[f64; 3]>>> = maps
        .iter()
        .zip(&models)
        .map(|(m, (w, _))| grid_scores(&samples, m, &map_grid, &format!("map alone, skin {w}")))
        .collect::<Result<_>>()?;
    // Flatten (skin, blur) into one combination axis per image.
    let n = items.len();
    let flat: Vec<Vec<[f64; 3]>> =
        (0..n).map(|i| map_scores.iter().flat_map(|per_skin| per_skin[i].iter().copied()).collect()).collect();
    let mut prior_grid = Vec::new();
    for &b in &PRIOR_BLURS {
        for &w in &PRIOR_WEIGHTS {
            for &s in &PRIOR_SIGMAS {
                prior_grid.push(CenterPrior { blur_sigma_frac_width: b, weight: w, center_sigma_frac: s });
            }
        }
    }
    let half = n / 2;
    let folds = [(0..half, half..n), (half..n, 0..half)];
    let mut prior_scores: Vec<Option<Vec<Vec<[f64; 3]>>>> = vec![None; models.len()];
    let (mut map_reported, mut prior_reported) = (Vec::new(), Vec::new());
    for (f, (train, test)) in folds.iter().enumerate() {
        let c = best(&flat, 0..flat[0].len(), train);
        let (skin_idx, blur) = (c / MAP_BLURS.len(), MAP_BLURS[c % MAP_BLURS.len()]);
        let r = test_means(&flat, c, test);
        outln!(
            "fold {}, map alone: chosen on {} images: skin weight {}, blur {:.2}; on the other {}: CC {:.4} SIM {:.4} KL {:.4}",
            f + 1,
            train.len(),
            models[skin_idx].0,
            blur,
            test.len(),
            r[0],
            r[1],
            r[2]
        );
        map_reported.push(r);
        if prior_scores[skin_idx].is_none() {
            let what = format!("prior grid, skin {}", models[skin_idx].0);
            prior_scores[skin_idx] = Some(grid_scores(&samples, &maps[skin_idx], &prior_grid, &what)?);
        }
        let Some(ps) = &prior_scores[skin_idx] else { continue };
        let c = best(ps, 0..prior_grid.len(), train);
        let p = prior_grid[c];
        let r = test_means(ps, c, test);
        outln!(
            "fold {}, centre prior: chosen on {} images: blur {:.2}, weight {:.2}, sigma {:.2}; on the other {}: CC {:.4} SIM {:.4} KL {:.4}",
            f + 1,
            train.len(),
            p.blur_sigma_frac_width,
            p.weight,
            p.center_sigma_frac,
            test.len(),
            r[0],
            r[1],
            r[2]
        );
        prior_reported.push(r);
    }
    print_mean("map alone", &map_reported)?;
    print_mean("with centre prior", &prior_reported)?;
    Ok(())
}
