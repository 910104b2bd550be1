//! The benchmark protocol behind `ocellus eval`: how a model's map becomes the evaluated map
//! (blur and centre prior at the image's size), which metrics are computed on it and with
//! which settings, and how the per-image values are summarized. The CLI only finds the files
//! and prints; tests and the Python package run the same protocol.
//!
//! Settings: the MIT benchmark's (Bylinskii et al. 2016): AUC-Borji and shuffled AUC with 100
//! splits and thresholds every 0.1; information gain against a centre Gaussian of sigma 0.25
//! of the larger side; shuffled-AUC negatives are the other images' fixations. Every random
//! choice is seeded by the image's index, so a run is reproducible.

use crate::center_prior::{center_gaussian, CenterPrior};
use crate::{metrics, EvalError, Result};
use ocellus_image::location::cell_to_pixel;
use ocellus_image::{Backend, Plane};
use rayon::prelude::*;

/// The blur and centre prior of `--center-prior` (chosen by two-fold cross-validation on
/// MIT1003 with [`crate::tuning`]).
pub const DEFAULT_PRIOR: CenterPrior =
    CenterPrior { blur_sigma_frac_width: 0.05, weight: 0.6, center_sigma_frac: 0.12 };
/// The skin channel weight that goes with [`DEFAULT_PRIOR`] (people look at faces).
pub const DEFAULT_PRIOR_SKIN_WEIGHT: f32 = 3.0;
/// Sigma of the information-gain baseline, fraction of the larger side.
pub const BASELINE_SIGMA_FRAC: f32 = 0.25;
/// Random splits of AUC-Borji and shuffled AUC.
pub const AUC_SPLITS: usize = 100;
/// Threshold step of AUC-Borji and shuffled AUC.
pub const AUC_STEP: f64 = 0.1;
/// Names of the density metrics, in the order of [`Scores::density`].
pub const DENSITY_NAMES: [&str; 3] = ["CC", "SIM", "KL"];
/// Names of the location metrics, in the order of [`Scores::location`].
pub const LOCATION_NAMES: [&str; 5] = ["NSS", "AUC-Judd", "AUC-Borji", "sAUC", "IG"];

/// The map evaluated as it is: no blur, no centre prior.
pub fn no_prior() -> CenterPrior {
    CenterPrior { blur_sigma_frac_width: 0.0, weight: 0.0, center_sigma_frac: BASELINE_SIGMA_FRAC }
}

/// One image ready to score.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sample {
    /// The model's map (any size: it is resampled to `size`); `None` scores the centre prior
    /// alone.
    pub map: Option<Plane<f32>>,
    /// Fixation density map, `size`.
    pub density: Option<Plane<f64>>,
    /// Fixated pixels (x, y) in `size`'s pixels.
    pub fixations: Option<Vec<(usize, usize)>>,
    /// The size every metric works at (width, height).
    pub size: (usize, usize),
}

/// Per-image values: the density metrics and the location metrics, where the inputs exist.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scores {
    /// CC, SIM, KL ([`DENSITY_NAMES`]).
    pub density: Option<[f64; 3]>,
    /// NSS, AUC-Judd, AUC-Borji, sAUC, IG ([`LOCATION_NAMES`]); sAUC is NaN when no other
    /// image has fixations.
    pub location: Option<[f64; 5]>,
}

/// The evaluated map at `w` x `h`: the model's map with blur and prior, or the centre prior
/// alone.
pub fn final_map(
    backend: Backend,
    map: Option<&Plane<f32>>,
    w: usize,
    h: usize,
    prior: &CenterPrior,
) -> Result<Plane<f64>> {
    let full = match map {
        Some(m) => prior.apply(backend, m, w, h)?,
        None => center_gaussian(w, h, prior.center_sigma_frac * w.max(h) as f32),
    };
    Ok(full.map(|v| v as f64))
}

/// CC, SIM, KL of `map` (prior applied) against the density map.
pub fn density_metrics(
    backend: Backend,
    map: Option<&Plane<f32>>,
    density: &Plane<f64>,
    prior: &CenterPrior,
) -> Result<[f64; 3]> {
    let s = final_map(backend, map, density.width(), density.height(), prior)?;
    Ok([metrics::cc(&s, density)?, metrics::sim(&s, density)?, metrics::kl(&s, density)?])
}

/// NSS, AUC-Judd, AUC-Borji, sAUC, IG of `saliency` at the fixations; `others` are the other
/// images' fixations in this image's pixels (sAUC negatives). Seeded by the image's `index`.
pub fn location_metrics(
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

/// The fixations of every sample but `i`, rescaled to sample `i`'s pixels (pixel centres
/// map to pixel centres, rounded to the nearest pixel): the negatives of the shuffled AUC.
pub fn other_fixations(samples: &[Sample], i: usize) -> Vec<(usize, usize)> {
    let Some(target) = samples.get(i) else { return Vec::new() };
    let (w, h) = target.size;
    let mut out = Vec::new();
    for (j, s) in samples.iter().enumerate() {
        let (Some(f), true) = (&s.fixations, j != i) else { continue };
        out.extend(f.iter().map(|&(x, y)| {
            let [tx, ty] = cell_to_pixel((x, y), s.size, (w, h));
            (
                tx.round().clamp(0.0, w.saturating_sub(1) as f64) as usize,
                ty.round().clamp(0.0, h.saturating_sub(1) as f64) as usize,
            )
        }));
    }
    out
}

/// Every sample's scores under `prior`, in parallel over images; `tick` is called once per
/// image done (for a progress bar).
pub fn score_all(
    backend: Backend,
    samples: &[Sample],
    prior: &CenterPrior,
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<Scores>> {
    prior.validate()?;
    samples
        .par_iter()
        .enumerate()
        .map(|(i, s)| -> Result<Scores> {
            check_sample(s)?;
            let (w, h) = s.size;
            let map = final_map(backend, s.map.as_ref(), w, h, prior)?;
            let density = match &s.density {
                Some(d) => Some([metrics::cc(&map, d)?, metrics::sim(&map, d)?, metrics::kl(&map, d)?]),
                None => None,
            };
            let location = match &s.fixations {
                Some(f) => Some(location_metrics(&map, f, &other_fixations(samples, i), i)?),
                None => None,
            };
            tick();
            Ok(Scores { density, location })
        })
        .collect()
}

/// Mean and standard error of the mean (sample standard deviation / sqrt(n)); NaN mean for
/// no values.
pub fn mean_se(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 { v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    (m, (var / n).sqrt())
}

/// Checks that a sample's maps have the size it claims (a caller's assembly error).
pub fn check_sample(s: &Sample) -> Result<()> {
    let (w, h) = s.size;
    if let Some(d) = &s.density {
        ocellus_image::check::same_size("density map", d.size(), s.size)?;
    }
    if let Some(f) = &s.fixations {
        if f.iter().any(|&(x, y)| x >= w || y >= h) {
            return Err(EvalError::Undefined { metric: "fixations", why: format!("a fixation lies outside {w}x{h}") });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_centre_prior_scores_a_centred_density_well() {
        let (w, h) = (40, 30);
        let density = center_gaussian(w, h, 5.0).map(|v| v as f64);
        let fix = vec![(20, 15), (19, 14), (21, 15)];
        let centre = Sample { map: None, density: Some(density.clone()), fixations: Some(fix.clone()), size: (w, h) };
        // A map peaked in a corner is a worse model of the same data.
        let corner = Plane::from_fn(w, h, |x, y| if x < 4 && y < 4 { 1.0 } else { 0.0 });
        let off = Sample { map: Some(corner), ..centre.clone() };
        let prior = CenterPrior { blur_sigma_frac_width: 0.0, weight: 1.0, center_sigma_frac: 5.0 / 40.0 };
        let s = score_all(Backend::Scalar, &[centre, off], &prior, &|| ()).unwrap();
        let d = s[0].density.unwrap();
        assert!((d[0] - 1.0).abs() < 1e-6 && (d[1] - 1.0).abs() < 1e-6 && d[2].abs() < 1e-6, "{d:?}");
        let raw = score_all(
            Backend::Scalar,
            &[Sample {
                map: Some(Plane::from_fn(w, h, |x, y| if x < 4 && y < 4 { 1.0 } else { 0.0 })),
                density: Some(density),
                fixations: Some(fix),
                size: (w, h),
            }],
            &no_prior(),
            &|| (),
        )
        .unwrap();
        assert!(raw[0].density.unwrap()[0] < 0.5);
        assert!(raw[0].location.unwrap()[3].is_nan(), "one image: no shuffled AUC");
        assert_eq!(mean_se(&[1.0, 3.0]), (2.0, 1.0));
    }

    #[test]
    fn other_fixations_map_pixel_centres_to_pixel_centres() {
        let a = Sample { fixations: Some(vec![(0, 0), (9, 4)]), size: (10, 5), ..Default::default() };
        let b = Sample { fixations: Some(vec![(1, 1)]), size: (20, 10), ..Default::default() };
        assert_eq!(other_fixations(&[a.clone(), b.clone()], 1), vec![(1, 1), (19, 9)]);
        assert_eq!(other_fixations(&[a, b], 0), vec![(0, 0)]);
        assert!(other_fixations(&[], 3).is_empty());
    }
}
