//! MIT saliency benchmark metrics (Bylinskii et al. 2016), following the definitions of the
//! benchmark's reference code: CC, SIM and KL compare a saliency map with a fixation density
//! map; NSS, AUC-Judd, AUC-Borji, shuffled AUC and information gain use fixation locations.
//!
//! All maps must have the same size (resample saliency maps to the fixation map's size first).
//! Fixations are (x, y) pixel positions; duplicates count once, as in a binary fixation map.

use crate::{EvalError, Result};
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;

/// The benchmark's epsilon (MATLAB's `eps`).
pub const EPS: f64 = 2.2204e-16;

fn values(p: &Plane<f64>) -> Vec<f64> {
    p.to_vec()
}

fn same_size(a: &Plane<f64>, b: &Plane<f64>, what: &'static str) -> Result<()> {
    Ok(ocellus_image::check::same_size(what, b.size(), a.size())?)
}

fn check(metric: &'static str, v: &[f64]) -> Result<()> {
    if v.is_empty() {
        return Err(EvalError::Undefined { metric, why: "the map is empty".into() });
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(EvalError::Undefined { metric, why: "the map has non-finite values".into() });
    }
    Ok(())
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Standard deviation with N - 1 (MATLAB `std`).
fn std_n1(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// Min-max normalization to [0, 1]; a constant map is left unchanged (benchmark rule).
fn min_max_normalize(v: &mut [f64]) {
    let (mn, mx) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    if mx - mn > 0.0 {
        v.iter_mut().for_each(|x| *x = (*x - mn) / (mx - mn));
    }
}

/// Division by the sum when any value is non-zero (benchmark rule).
fn to_distribution(v: &mut [f64]) {
    let s: f64 = v.iter().sum();
    if v.iter().any(|&x| x != 0.0) && s != 0.0 {
        v.iter_mut().for_each(|x| *x /= s);
    }
}

/// Pearson correlation coefficient of the saliency and density maps (z-scored first, which
/// does not change it). Undefined for a constant map.
pub fn cc(saliency: &Plane<f64>, density: &Plane<f64>) -> Result<f64> {
    same_size(saliency, density, "fixation density map")?;
    let (a, b) = (values(saliency), values(density));
    check("CC", &a)?;
    check("CC", &b)?;
    let (ma, mb) = (mean(&a), mean(&b));
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(&b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa == 0.0 || sbb == 0.0 {
        return Err(EvalError::Undefined { metric: "CC", why: "a map is constant".into() });
    }
    Ok(sab / (saa.sqrt() * sbb.sqrt()))
}

/// Similarity (histogram intersection): both maps min-max normalized, divided by their sums,
/// then the sum of the pixelwise minimum. 1 for identical maps, 0 for disjoint ones.
pub fn sim(saliency: &Plane<f64>, density: &Plane<f64>) -> Result<f64> {
    same_size(saliency, density, "fixation density map")?;
    let (mut a, mut b) = (values(saliency), values(density));
    check("SIM", &a)?;
    check("SIM", &b)?;
    for v in [&mut a, &mut b] {
        min_max_normalize(v);
        to_distribution(v);
    }
    Ok(a.iter().zip(&b).map(|(x, y)| x.min(*y)).sum())
}

/// Kullback-Leibler divergence of the density from the saliency map, in nats:
/// `sum f ln(eps + f / (s + eps))` with both maps divided by their sums. 0 is perfect.
pub fn kl(saliency: &Plane<f64>, density: &Plane<f64>) -> Result<f64> {
    same_size(saliency, density, "fixation density map")?;
    let (mut s, mut f) = (values(saliency), values(density));
    check("KL", &s)?;
    check("KL", &f)?;
    if s.iter().chain(&f).any(|&x| x < 0.0) {
        return Err(EvalError::Undefined { metric: "KL", why: "maps must be non-negative".into() });
    }
    to_distribution(&mut s);
    to_distribution(&mut f);
    Ok(s.iter().zip(&f).map(|(s, f)| f * (EPS + f / (s + EPS)).ln()).sum())
}

/// The distinct in-bounds fixation pixels as flat indices (y * width + x).
fn fixation_indices(metric: &'static str, map: &Plane<f64>, fixations: &[(usize, usize)]) -> Result<Vec<usize>> {
    let (w, h) = map.size();
    let mut idx: Vec<usize> = fixations.iter().filter(|&&(x, y)| x < w && y < h).map(|&(x, y)| y * w + x).collect();
    idx.sort_unstable();
    idx.dedup();
    if idx.is_empty() {
        return Err(EvalError::Undefined { metric, why: "no fixation falls inside the map".into() });
    }
    Ok(idx)
}

/// The non-zero pixels of a binary (or any) fixation map, as (x, y).
pub fn fixations_from_map(map: &Plane<f64>) -> Vec<(usize, usize)> {
    let mut v = Vec::new();
    for y in 0..map.height() {
        for (x, &p) in map.row(y).iter().enumerate() {
            if p > 0.0 {
                v.push((x, y));
            }
        }
    }
    v
}

/// Normalized scanpath saliency: the mean of the z-scored saliency map (std with N - 1) at the
/// fixations.
pub fn nss(saliency: &Plane<f64>, fixations: &[(usize, usize)]) -> Result<f64> {
    let v = values(saliency);
    check("NSS", &v)?;
    let idx = fixation_indices("NSS", saliency, fixations)?;
    let (m, s) = (mean(&v), std_n1(&v));
    if s == 0.0 {
        return Err(EvalError::Undefined { metric: "NSS", why: "the saliency map is constant".into() });
    }
    Ok(idx.iter().map(|&i| (v[i] - m) / s).sum::<f64>() / idx.len() as f64)
}

/// Trapezoid area under (fp, tp), points in order.
fn trapezoid(fp: &[f64], tp: &[f64]) -> f64 {
    fp.windows(2).zip(tp.windows(2)).map(|(f, t)| (f[1] - f[0]) * (t[0] + t[1]) / 2.0).sum()
}

/// AUC-Judd: the map is jittered by uniform noise of 1e-7 (seeded, to break ties) and min-max
/// normalized; thresholds are the saliency values at the fixations; TP rate `i / Nf`, FP rate
/// `(pixels above threshold - i) / (Npix - Nf)`; trapezoid area.
pub fn auc_judd(saliency: &Plane<f64>, fixations: &[(usize, usize)], seed: u64) -> Result<f64> {
    let mut s = values(saliency);
    check("AUC-Judd", &s)?;
    let idx = fixation_indices("AUC-Judd", saliency, fixations)?;
    let mut rng = SplitMix64::new(seed);
    s.iter_mut().for_each(|x| *x += rng.unit() / 1e7);
    min_max_normalize(&mut s);
    let (n_fix, n_pix) = (idx.len(), s.len());
    if n_pix <= n_fix {
        return Err(EvalError::Undefined { metric: "AUC-Judd", why: "every pixel is fixated".into() });
    }
    let mut thresholds: Vec<f64> = idx.iter().map(|&i| s[i]).collect();
    thresholds.sort_by(|a, b| b.total_cmp(a));
    let mut sorted = s.clone();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let (mut tp, mut fp) = (vec![0.0], vec![0.0]);
    for (i, &t) in thresholds.iter().enumerate() {
        // pixels with value >= t: a prefix of the descending order
        let above = sorted.partition_point(|&v| v >= t);
        tp.push((i + 1) as f64 / n_fix as f64);
        fp.push((above as f64 - (i + 1) as f64) / (n_pix - n_fix) as f64);
    }
    tp.push(1.0);
    fp.push(1.0);
    Ok(trapezoid(&fp, &tp))
}

/// Area under the curve with thresholds `0:step:max` for positives `pos` and negatives `neg`
/// (the benchmark's Borji and shuffled AUC inner loop).
fn auc_thresholds(pos: &[f64], neg: &[f64], step: f64) -> f64 {
    let mx = pos.iter().chain(neg).fold(0.0f64, |m, &v| m.max(v));
    let n = (mx / step + 1e-9).floor() as usize;
    let (mut tp, mut fp) = (vec![0.0], vec![0.0]);
    for k in (0..=n).rev() {
        let t = k as f64 * step;
        tp.push(pos.iter().filter(|&&v| v >= t).count() as f64 / pos.len() as f64);
        fp.push(neg.iter().filter(|&&v| v >= t).count() as f64 / neg.len() as f64);
    }
    tp.push(1.0);
    fp.push(1.0);
    trapezoid(&fp, &tp)
}

/// Shared set-up of the split AUCs: checks, the min-max normalized map and its values at the
/// fixations.
fn split_auc_setup(
    metric: &'static str,
    saliency: &Plane<f64>,
    fixations: &[(usize, usize)],
    splits: usize,
    step: f64,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut s = values(saliency);
    check(metric, &s)?;
    let idx = fixation_indices(metric, saliency, fixations)?;
    if splits == 0 || !step.is_finite() || step <= 0.0 {
        return Err(EvalError::Undefined { metric, why: "needs splits >= 1 and step > 0".into() });
    }
    min_max_normalize(&mut s);
    let pos = idx.iter().map(|&i| s[i]).collect();
    Ok((s, pos))
}

/// AUC-Borji: min-max normalized map; `splits` times, as many uniformly random pixels (with
/// replacement) as fixations serve as negatives; thresholds `0:step:max` (benchmark: 100
/// splits, step 0.1); mean area.
pub fn auc_borji(
    saliency: &Plane<f64>,
    fixations: &[(usize, usize)],
    splits: usize,
    step: f64,
    seed: u64,
) -> Result<f64> {
    let (s, pos) = split_auc_setup("AUC-Borji", saliency, fixations, splits, step)?;
    let mut rng = SplitMix64::new(seed);
    let total: f64 = (0..splits)
        .map(|_| {
            let neg: Vec<f64> = (0..pos.len()).map(|_| s[rng.below(s.len())]).collect();
            auc_thresholds(&pos, &neg, step)
        })
        .sum();
    Ok(total / splits as f64)
}

/// Shuffled AUC: like [`auc_borji`], but the negatives are fixations of *other* images
/// (`other_fixations`, in this map's pixel coordinates), drawn without replacement,
/// `min(Nf, N_other)` per split. Centre bias in the data then earns no credit.
pub fn auc_shuffled(
    saliency: &Plane<f64>,
    fixations: &[(usize, usize)],
    other_fixations: &[(usize, usize)],
    splits: usize,
    step: f64,
    seed: u64,
) -> Result<f64> {
    let (s, pos) = split_auc_setup("sAUC", saliency, fixations, splits, step)?;
    let mut other = fixation_indices("sAUC", saliency, other_fixations)?;
    let n_neg = pos.len().min(other.len());
    let mut rng = SplitMix64::new(seed);
    let mut total = 0.0;
    for _ in 0..splits {
        // Partial Fisher-Yates shuffle: the first n_neg entries are a uniform sample.
        for i in 0..n_neg {
            let j = i + rng.below(other.len() - i);
            other.swap(i, j);
        }
        let neg: Vec<f64> = other[..n_neg].iter().map(|&i| s[i]).collect();
        total += auc_thresholds(&pos, &neg, step);
    }
    Ok(total / splits as f64)
}

/// Information gain over a baseline map, in bits per fixation: both maps min-max normalized
/// and divided by their sums; mean over fixations of `log2(eps + p) - log2(eps + b)`.
pub fn info_gain(saliency: &Plane<f64>, baseline: &Plane<f64>, fixations: &[(usize, usize)]) -> Result<f64> {
    same_size(saliency, baseline, "baseline map")?;
    let (mut p, mut b) = (values(saliency), values(baseline));
    check("IG", &p)?;
    check("IG", &b)?;
    let idx = fixation_indices("IG", saliency, fixations)?;
    for v in [&mut p, &mut b] {
        min_max_normalize(v);
        to_distribution(v);
    }
    Ok(idx.iter().map(|&i| (EPS + p[i]).log2() - (EPS + b[i]).log2()).sum::<f64>() / idx.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(v: &[f64]) -> Plane<f64> {
        Plane::from_vec(v.len(), 1, v.to_vec()).unwrap()
    }

    #[test]
    fn cc_hand_cases() {
        assert!((cc(&row(&[1., 2., 3., 4.]), &row(&[2., 4., 6., 8.])).unwrap() - 1.0).abs() < 1e-12);
        assert!((cc(&row(&[1., 2., 3., 4.]), &row(&[4., 3., 2., 1.])).unwrap() + 1.0).abs() < 1e-12);
        assert!(cc(&row(&[1., 0., 0., 1.]), &row(&[1., 1., 0., 0.])).unwrap().abs() < 1e-12);
        assert!(cc(&row(&[1., 1.]), &row(&[1., 2.])).is_err(), "constant map");
        assert!(cc(&row(&[1., 2.]), &row(&[1., 2., 3.])).is_err(), "size");
    }

    #[test]
    fn sim_hand_cases() {
        // [0,1,2] -> [0, .5, 1] / 1.5; [1,1,0] -> [1,1,0] / 2; min = [0, 1/3, 0].
        assert!((sim(&row(&[0., 1., 2.]), &row(&[1., 1., 0.])).unwrap() - 1.0 / 3.0).abs() < 1e-12);
        assert!((sim(&row(&[3., 5.]), &row(&[3., 5.])).unwrap() - 1.0).abs() < 1e-12);
        assert!(sim(&row(&[1., 0.]), &row(&[0., 1.])).unwrap().abs() < 1e-12);
    }

    #[test]
    fn kl_hand_cases() {
        // s = [.5, .5], f = [.25, .75]: .25 ln .5 + .75 ln 1.5
        let want = 0.25 * 0.5f64.ln() + 0.75 * 1.5f64.ln();
        assert!((kl(&row(&[1., 1.]), &row(&[1., 3.])).unwrap() - want).abs() < 1e-9);
        assert!(kl(&row(&[2., 6.]), &row(&[1., 3.])).unwrap().abs() < 1e-9);
        // missing mass where people looked costs log(1/eps)
        assert!(kl(&row(&[1., 0.]), &row(&[0., 1.])).unwrap() > 30.0);
    }

    #[test]
    fn nss_hand_case() {
        // mean 2.5, std (N-1) = sqrt(5/3)
        let want = 1.5 / (5.0f64 / 3.0).sqrt();
        assert!((nss(&row(&[1., 2., 3., 4.]), &[(3, 0)]).unwrap() - want).abs() < 1e-12);
        assert!(nss(&row(&[1., 2.]), &[(5, 0)]).is_err(), "no fixation inside");
    }

    #[test]
    fn auc_judd_hand_case() {
        // normalized [0, .4286, .3571, 1]; fixations at 1 and .3571 ->
        // ROC points (0,0) (0,.5) (.5,1) (1,1): area 0.875.
        let s = row(&[0.1, 0.4, 0.35, 0.8]);
        assert!((auc_judd(&s, &[(3, 0), (2, 0)], 1).unwrap() - 0.875).abs() < 1e-6);
        // a perfect map scores 1, its inverse 0
        let m = row(&[0., 0., 1., 0., 1.]);
        assert!((auc_judd(&m, &[(2, 0), (4, 0)], 7).unwrap() - 1.0).abs() < 1e-6);
        // The inverse map: the first threshold already admits all 3 other pixels, so the ROC
        // points are (0,0) (1,.5) (1,1): area 0.25.
        let inv = row(&[1., 1., 0., 1., 0.]);
        assert!((auc_judd(&inv, &[(2, 0), (4, 0)], 7).unwrap() - 0.25).abs() < 1e-6);
    }

    #[test]
    fn borji_and_shuffled_auc_are_seeded_and_ordered() {
        let (w, h) = (32, 24);
        let fix = vec![(20, 5), (21, 6), (22, 5), (5, 18)];
        let good =
            Plane::from_fn(w, h, |x, y| if fix.contains(&(x, y)) { 1.0 } else { 0.05 * ((x * y) % 7) as f64 / 7.0 });
        let bad = Plane::from_fn(w, h, |x, y| ((x * 13 + y * 7) % 11) as f64);
        let a = auc_borji(&good, &fix, 100, 0.1, 3).unwrap();
        assert_eq!(a, auc_borji(&good, &fix, 100, 0.1, 3).unwrap(), "same seed, same value");
        assert!(a > 0.9 && a <= 1.0, "{a}");
        assert!(auc_borji(&bad, &fix, 100, 0.1, 3).unwrap() < a);
        let other = vec![(1, 1), (2, 2), (30, 20), (16, 12), (15, 12)];
        let s = auc_shuffled(&good, &fix, &other, 100, 0.1, 5).unwrap();
        assert!(s > 0.9, "{s}");
        assert!(auc_shuffled(&good, &fix, &[], 10, 0.1, 5).is_err());
    }

    #[test]
    fn info_gain_hand_cases() {
        let b = row(&[1., 1., 2., 4.]);
        assert!(info_gain(&b, &b, &[(1, 0)]).unwrap().abs() < 1e-12);
        // p = [0, 0, 1] (min-max of [1,1,2]), b = [0, .5, 1]/1.5: at x=2: log2(1) - log2(2/3)
        let ig = info_gain(&row(&[1., 1., 2.]), &row(&[0., 1., 2.]), &[(2, 0)]).unwrap();
        assert!((ig - (1.5f64).log2()).abs() < 1e-9, "{ig}");
        assert_eq!(fixations_from_map(&row(&[0., 2., 0., 1.])), vec![(1, 0), (3, 0)]);
    }
}
