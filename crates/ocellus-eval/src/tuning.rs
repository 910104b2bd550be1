//! Choosing blur, centre prior and skin weight without fitting the test images: two-fold
//! cross-validation by CC over fixed grids (`ocellus eval --tune`). Each fold picks the grid
//! point with the best mean CC on one half of the images and reports the metrics on the other.

use crate::center_prior::CenterPrior;
use crate::protocol::{density_metrics, mean_se, Sample, BASELINE_SIGMA_FRAC};
use crate::{EvalError, Result};
use ocellus_image::{Backend, Plane};
use rayon::prelude::*;
use std::ops::Range;

/// Skin channel weights tried.
pub const SKIN_WEIGHTS: [f32; 4] = [0.0, 1.0, 2.0, 3.0];
/// Map blurs (fraction of the width) tried for the map alone.
pub const MAP_BLURS: [f32; 7] = [0.0, 0.02, 0.04, 0.06, 0.08, 0.1, 0.12];
/// Blurs tried with the centre prior.
pub const PRIOR_BLURS: [f32; 4] = [0.04, 0.06, 0.08, 0.1];
/// Centre prior weights tried.
pub const PRIOR_WEIGHTS: [f32; 4] = [0.5, 0.6, 0.7, 0.8];
/// Centre prior sigmas (fraction of the larger side) tried.
pub const PRIOR_SIGMAS: [f32; 5] = [0.08, 0.1, 0.12, 0.16, 0.2];

/// The map-alone grid: each of [`MAP_BLURS`], no prior.
pub fn map_grid() -> Vec<CenterPrior> {
    MAP_BLURS
        .iter()
        .map(|&b| CenterPrior { blur_sigma_frac_width: b, weight: 0.0, center_sigma_frac: BASELINE_SIGMA_FRAC })
        .collect()
}

/// The centre-prior grid: every (blur, weight, sigma) of [`PRIOR_BLURS`] x [`PRIOR_WEIGHTS`]
/// x [`PRIOR_SIGMAS`], sigma fastest.
pub fn prior_grid() -> Vec<CenterPrior> {
    let mut g = Vec::new();
    for &b in &PRIOR_BLURS {
        for &w in &PRIOR_WEIGHTS {
            for &s in &PRIOR_SIGMAS {
                g.push(CenterPrior { blur_sigma_frac_width: b, weight: w, center_sigma_frac: s });
            }
        }
    }
    g
}

/// `scores[image][combo]` = [CC, SIM, KL] of every grid point on every image, for one
/// model's `maps` (one per sample; the samples give the density maps). `tick` is called once
/// per image done.
pub fn grid_scores(
    backend: Backend,
    samples: &[Sample],
    maps: &[Option<Plane<f32>>],
    grid: &[CenterPrior],
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<Vec<[f64; 3]>>> {
    if maps.len() != samples.len() {
        return Err(EvalError::InvalidConfig(format!("{} maps for {} images", maps.len(), samples.len())));
    }
    samples
        .par_iter()
        .zip(maps)
        .map(|(s, map)| {
            let Some(d) = &s.density else {
                return Err(EvalError::Undefined { metric: "tuning", why: "it needs fixation density maps".into() });
            };
            let r = grid.iter().map(|p| density_metrics(backend, map.as_ref(), d, p)).collect::<Result<Vec<_>>>();
            tick();
            r
        })
        .collect()
}

/// The two folds of `n` images: (train, test) = (first half, second half) and the reverse.
pub fn folds(n: usize) -> [(Range<usize>, Range<usize>); 2] {
    let half = n / 2;
    [(0..half, half..n), (half..n, 0..half)]
}

/// Index of the combination in `combos` with the best mean CC over the images `train`
/// (the first on ties).
pub fn best(scores: &[Vec<[f64; 3]>], combos: Range<usize>, train: &Range<usize>) -> usize {
    let cc = |c: usize| train.clone().filter_map(|k| scores.get(k).and_then(|s| s.get(c))).map(|v| v[0]).sum::<f64>();
    let mut best = combos.start;
    for c in combos {
        if cc(c) > cc(best) {
            best = c;
        }
    }
    best
}

/// Mean CC, SIM, KL of combination `c` over the images `test`.
pub fn test_means(scores: &[Vec<[f64; 3]>], c: usize, test: &Range<usize>) -> [f64; 3] {
    let m = |k: usize| {
        let v: Vec<f64> = test.clone().filter_map(|i| scores.get(i).and_then(|s| s.get(c))).map(|v| v[k]).collect();
        mean_se(&v).0
    };
    [m(0), m(1), m(2)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_and_choices() {
        assert_eq!(map_grid().len(), MAP_BLURS.len());
        assert_eq!(prior_grid().len(), 80);
        assert_eq!(prior_grid()[1].center_sigma_frac, PRIOR_SIGMAS[1]);
        let [(a, b), (c, d)] = folds(5);
        assert_eq!((a, b, c, d), (0..2, 2..5, 2..5, 0..2));
        // Image 0 prefers combo 1, image 1 combo 0; trained on image 0 the choice is 1.
        let s = vec![vec![[0.1, 0.0, 0.0], [0.9, 0.0, 0.0]], vec![[0.8, 1.0, 2.0], [0.2, 3.0, 4.0]]];
        assert_eq!(best(&s, 0..2, &(0..1)), 1);
        assert_eq!(best(&s, 0..2, &(1..2)), 0);
        assert_eq!(test_means(&s, 1, &(1..2)), [0.2, 3.0, 4.0]);
    }
}
