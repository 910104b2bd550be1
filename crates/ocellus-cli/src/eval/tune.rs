//! `ocellus eval --tune`: two-fold cross-validated choice of the evaluation-friendly output.
//!
//! Per fold, on the training half: (1) the map alone: skin-channel weight x blur, by mean CC;
//! (2) with that skin weight: blur x prior weight x prior sigma, by mean CC. Both choices are
//! then scored on the other half, so no reported number was tuned on the images it is reported on.

use super::data::{self, Item};
use super::{progress, with_skin, EvalArgs, Model};
use anyhow::{bail, Result};
use ocellus_eval::center_prior::CenterPrior;
use ocellus_eval::protocol::Sample;
use ocellus_eval::tuning::{best, folds, grid_scores, map_grid, prior_grid, test_means, MAP_BLURS, SKIN_WEIGHTS};
use ocellus_image::{Backend, Plane};

/// [`grid_scores`] with a progress bar.
fn scores_with_bar(
    samples: &[Sample],
    maps: &[Option<Plane<f32>>],
    grid: &[CenterPrior],
    what: &str,
) -> Result<Vec<Vec<[f64; 3]>>> {
    let bar = progress(samples.len(), what);
    let r = grid_scores(Backend::Auto, samples, maps, grid, &|| bar.inc(1));
    bar.finish_and_clear();
    Ok(r?)
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
    let map_grid = map_grid();
    let map_scores: Vec<Vec<Vec<[f64; 3]>>> = maps
        .iter()
        .zip(&models)
        .map(|(m, (w, _))| scores_with_bar(&samples, m, &map_grid, &format!("map alone, skin {w}")))
        .collect::<Result<_>>()?;
    // Flatten (skin, blur) into one combination axis per image.
    let n = items.len();
    let flat: Vec<Vec<[f64; 3]>> =
        (0..n).map(|i| map_scores.iter().flat_map(|per_skin| per_skin[i].iter().copied()).collect()).collect();
    let prior_grid = prior_grid();
    let folds = folds(n);
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
            prior_scores[skin_idx] = Some(scores_with_bar(&samples, &maps[skin_idx], &prior_grid, &what)?);
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
