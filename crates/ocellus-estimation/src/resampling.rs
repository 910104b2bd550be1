//! Resampling of weighted particles (SPEC 7.1): which parents the next generation copies.
//!
//! Each resampler reads normalized weights `w` (finite, >= 0, summing to 1 within 1e-9) and
//! writes `N` parent indices in increasing order; the expected number of copies of particle i
//! is `N w_i` for every scheme. They differ in variance:
//! - [`systematic`]: one uniform offset, `N` equally spaced points on the CDF (the seed's
//!   Algorithm 2, Arulampalam et al. 2002): each particle gets `floor(N w_i)` or
//!   `ceil(N w_i)` copies, the lowest variance and O(N);
//! - [`stratified`]: one uniform per stratum `[j/N, (j+1)/N)`;
//! - [`multinomial`]: `N` independent draws (sorted uniforms, O(N) by order statistics);
//! - [`residual`]: `floor(N w_i)` copies each, the remaining `N - sum floor` drawn
//!   multinomially from the residuals `N w_i - floor(N w_i)`.
//!
//! Every random choice comes from the caller's seeded generator.

use crate::{EstimationError, Result};
use ocellus_image::rng::SplitMix64;

/// Which resampler a filter uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Resampler {
    /// [`systematic`] (default).
    #[default]
    Systematic,
    /// [`stratified`].
    Stratified,
    /// [`multinomial`].
    Multinomial,
    /// [`residual`].
    Residual,
}

impl Resampler {
    /// Parent indices of `w.len()` offspring into `out` (cleared first).
    pub fn resample(self, w: &[f64], rng: &mut SplitMix64, out: &mut Vec<usize>) -> Result<()> {
        match self {
            Resampler::Systematic => systematic(w, rng.unit(), out),
            Resampler::Stratified => stratified(w, rng, out),
            Resampler::Multinomial => multinomial(w, rng, out),
            Resampler::Residual => residual(w, rng, out),
        }
    }
}

/// Checks that `w` is a usable normalized weight vector.
fn check(w: &[f64]) -> Result<()> {
    if w.is_empty() {
        return Err(EstimationError::InvalidInput("no particles to resample".into()));
    }
    let mut sum = 0.0;
    for (i, &v) in w.iter().enumerate() {
        if !(v.is_finite() && v >= 0.0) {
            return Err(EstimationError::InvalidInput(format!("weight {i} is {v}: weights must be finite and >= 0")));
        }
        sum += v;
    }
    if (sum - 1.0).abs() > 1e-9 {
        return Err(EstimationError::InvalidInput(format!("weights sum to {sum}, not 1: normalize them first")));
    }
    Ok(())
}

/// Walks the CDF of `w` at the `m` increasing points `u(j)`, j = 0..m, pushing the index whose
/// CDF interval holds each point: particle i owns (c_{i-1}, c_i], as in the seed's
/// `WHILE u_j > c_i`, so a zero weight owns nothing. The CDF is c_i = w_0 + ... + w_i; the
/// seed prints c_1 = 0, which would never pick particle 1 and end the CDF at 1 - w_1: that is
/// a typo. Round-off can leave the CDF's end a hair below the last point: the walk stops at
/// the last particle with weight instead of running past it.
fn walk(w: &[f64], m: usize, u: impl Fn(usize) -> f64, out: &mut Vec<usize>) {
    // Start at the first particle with weight (a point at exactly 0 must not pick a zero
    // weight before it); stop at the last one.
    let first = w.iter().position(|&v| v > 0.0).unwrap_or(0);
    let last = w.iter().rposition(|&v| v > 0.0).unwrap_or(w.len() - 1);
    out.clear();
    out.reserve(m);
    let (mut i, mut c) = (first, w[first]);
    for j in 0..m {
        let uj = u(j);
        while uj > c && i < last {
            i += 1;
            c += w[i];
        }
        out.push(i);
    }
}

/// Slots each particle of a systematic pass writes unconditionally (one cache line of `usize`).
const FILL: usize = 8;

/// The particle loop of [`systematic`] over `w` (all particles before the last with weight):
/// fills `out` (of length at least `n + FILL`) up to the returned bound and returns the CDF
/// at the end of `w`, that bound, and whether a weight was negative or not finite. The
/// AVX2 build writes a particle's slots in two stores instead of four; the arithmetic is
/// the same (no contraction into FMA), so every backend gives the same parents.
#[allow(clippy::extra_unused_type_parameters)]
#[inline(always)]
fn systematic_fill_generic<M: ocellus_image::simd::Madd>(
    w: &[f64],
    u: f64,
    n: usize,
    out: &mut [usize],
) -> (f64, usize, bool) {
    let (nf, mut c, mut done, mut bad) = (n as f64, 0.0, 0usize, false);
    for (i, &wi) in w.iter().enumerate() {
        bad |= !(0.0..f64::INFINITY).contains(&wi);
        c += wi;
        out[done..done + FILL].fill(i);
        // N c - u >= -1, so truncating N c - u + 1 is the floor plus one (`floor` itself is a
        // libm call on the x86-64 baseline). A zero weight keeps the bound: it owns nothing.
        let upto = ((nf * c - u + 1.0) as usize).min(n);
        if upto > done + FILL {
            out[done + FILL..upto].fill(i);
        }
        done = if wi > 0.0 { upto.max(done) } else { done };
    }
    (c, done, bad)
}

ocellus_image::dispatch_kernel!(
    fn systematic_fill => systematic_fill_generic(w: &[f64], u: f64, n: usize, out: &mut [usize]) -> (f64, usize, bool)
);

/// Systematic resampling, the seed's Algorithm 2: `u_j = (u + j) / N` for j = 0..N with
/// `u` uniform in [0, 1) (the caller's draw, so that the scheme itself is deterministic).
pub fn systematic(w: &[f64], u: f64, out: &mut Vec<usize>) -> Result<()> {
    if w.is_empty() {
        return Err(EstimationError::InvalidInput("no particles to resample".into()));
    }
    if !(0.0..1.0).contains(&u) {
        return Err(EstimationError::InvalidInput(format!("systematic offset {u} must lie in [0, 1)")));
    }
    // The walk of Algorithm 2 branches once per point and once per particle, unpredictably
    // for uneven weights (about 15 ns per particle at 10^6). The same assignment without
    // data-dependent branches: the points u_j <= c_i are j < floor(N c_i - u) + 1, so the
    // range of particle i starts where the previous bound `done` ended. Each particle
    // writes its index into the FILL slots from `done` on, unconditionally (one cache line,
    // no branch); only a range longer than that, rare once N w_i < FILL, takes a loop. What
    // it writes past its range lies at or after the next particle's start, which overwrites
    // it, so out[..done] is final at every step. The output is written once (no zeroing
    // pass, no second pass), and the weights are checked in the same pass rather than in one
    // of their own (`check`, for the others). What remains is the CDF's serial sum, kept
    // serial so that the parents equal those of the seed's walk bit for bit.
    let n = w.len();
    let last = w.iter().rposition(|&v| v > 0.0).unwrap_or(n - 1);
    // FILL slots of slack past the end for the unconditional writes; their old contents
    // are overwritten, so a reused buffer is not cleared.
    if out.len() < n + FILL {
        out.resize(n + FILL, 0);
    } else {
        out.truncate(n + FILL);
    }
    let (c, done, bad) = systematic_fill(ocellus_image::Backend::Auto, &w[..last], u, n, out);
    // The last particle with weight takes the rest: the round-off guard.
    out[done..n].fill(last);
    out.truncate(n);
    let tail = &w[last..];
    let bad = bad || tail.iter().any(|v| !(0.0..f64::INFINITY).contains(v));
    let total = c + tail.iter().sum::<f64>();
    if bad || (total - 1.0).abs() > 1e-9 {
        out.clear();
        return check(w);
    }
    Ok(())
}

/// Stratified resampling: `u_j = (j + U_j) / N`, one uniform per stratum.
pub fn stratified(w: &[f64], rng: &mut SplitMix64, out: &mut Vec<usize>) -> Result<()> {
    check(w)?;
    let inv = 1.0 / w.len() as f64;
    let us: Vec<f64> = (0..w.len()).map(|j| (j as f64 + rng.unit()) * inv).collect();
    walk(w, w.len(), |j| us[j], out);
    Ok(())
}

/// `n` sorted uniforms in [0, 1), by the exponential-spacings construction (the order
/// statistics of `n` uniforms without sorting): O(n).
fn sorted_uniforms(n: usize, rng: &mut SplitMix64) -> Vec<f64> {
    // E_k = -ln(1 - U_k) are exponential; partial sums over the total (with one extra
    // spacing) are distributed as sorted uniforms.
    let e: Vec<f64> = (0..=n).map(|_| -(1.0 - rng.unit()).ln()).collect();
    let total: f64 = e.iter().sum();
    let mut acc = 0.0;
    e[..n]
        .iter()
        .map(|v| {
            acc += v;
            (acc / total).min(1.0 - f64::EPSILON)
        })
        .collect()
}

/// Multinomial resampling: `N` independent draws from the weights.
pub fn multinomial(w: &[f64], rng: &mut SplitMix64, out: &mut Vec<usize>) -> Result<()> {
    check(w)?;
    let us = sorted_uniforms(w.len(), rng);
    walk(w, w.len(), |j| us[j], out);
    Ok(())
}

/// Residual resampling: `floor(N w_i)` copies of each particle, then the remaining
/// `R = N - sum floor(N w_i)` drawn multinomially from the residual weights
/// `(N w_i - floor(N w_i)) / R`.
pub fn residual(w: &[f64], rng: &mut SplitMix64, out: &mut Vec<usize>) -> Result<()> {
    check(w)?;
    let n = w.len();
    let mut counts = vec![0usize; n];
    let mut residuals = vec![0.0; n];
    let mut copied = 0usize;
    for i in 0..n {
        let nw = n as f64 * w[i];
        let f = (nw.floor() as usize).min(n - copied);
        counts[i] = f;
        copied += f;
        residuals[i] = (nw - f as f64).max(0.0);
    }
    let rest = n - copied;
    if rest > 0 {
        let s: f64 = residuals.iter().sum();
        if s > 0.0 {
            residuals.iter_mut().for_each(|r| *r /= s);
            let us = sorted_uniforms(rest, rng);
            let mut extra = Vec::with_capacity(rest);
            walk(&residuals, rest, |j| us[j], &mut extra);
            for i in extra {
                counts[i] += 1;
            }
        } else {
            // Only round-off remains: give the leftover to the heaviest particle.
            let heaviest = (0..n).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
            counts[heaviest] += rest;
        }
    }
    out.clear();
    out.reserve(n);
    for (i, &c) in counts.iter().enumerate() {
        out.extend(std::iter::repeat_n(i, c));
    }
    Ok(())
}

/// Offspring counts of each particle from parent indices (`counts[i]` = copies of i).
pub fn offspring_counts(parents: &[usize], n: usize) -> Vec<usize> {
    let mut c = vec![0usize; n];
    for &p in parents {
        if p < n {
            c[p] += 1;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_weights(n: usize, rng: &mut SplitMix64, spiky: bool) -> Vec<f64> {
        let raw: Vec<f64> = (0..n).map(|_| if spiky { rng.unit().powi(8) } else { rng.unit() }).collect();
        let s: f64 = raw.iter().sum();
        raw.iter().map(|v| v / s).collect()
    }

    const ALL: [Resampler; 4] =
        [Resampler::Systematic, Resampler::Stratified, Resampler::Multinomial, Resampler::Residual];

    #[test]
    fn counts_sum_to_n_and_indices_increase() {
        let mut rng = SplitMix64::new(1);
        let mut out = Vec::new();
        for case in 0..200 {
            let n = 1 + case % 37;
            let w = random_weights(n, &mut rng, case % 2 == 0);
            for r in ALL {
                r.resample(&w, &mut rng, &mut out).unwrap();
                assert_eq!(out.len(), n, "{r:?}");
                assert!(out.windows(2).all(|p| p[0] <= p[1]) && out.iter().all(|&i| i < n), "{r:?}");
                assert!(out.iter().all(|&i| w[i] > 0.0), "{r:?} copied a zero-weight particle");
            }
        }
    }

    #[test]
    fn systematic_offspring_is_floor_or_ceil_of_n_w() {
        let mut rng = SplitMix64::new(2);
        let mut out = Vec::new();
        for case in 0..500 {
            let n = 2 + case % 50;
            let w = random_weights(n, &mut rng, case % 3 == 0);
            systematic(&w, rng.unit(), &mut out).unwrap();
            for (i, c) in offspring_counts(&out, n).into_iter().enumerate() {
                let nw = n as f64 * w[i];
                // 1e-9 of slack for the CDF's round-off.
                assert!(
                    c as f64 >= (nw - 1e-9).floor() && c as f64 <= (nw + 1e-9).ceil(),
                    "case {case}: {c} copies of N w = {nw}"
                );
            }
        }
    }

    #[test]
    fn expected_offspring_is_n_w_for_every_scheme() {
        // Fixed weights, many seeds: the mean count of each particle is N w_i within 5
        // standard errors (the per-draw variance is at most N w (1 - w) for every scheme).
        let w = [0.02, 0.3, 0.005, 0.175, 0.1, 0.4];
        let n = w.len();
        let trials = 20_000;
        for r in ALL {
            let mut rng = SplitMix64::new(3);
            let mut sums = vec![0.0; n];
            let mut out = Vec::new();
            for _ in 0..trials {
                r.resample(&w, &mut rng, &mut out).unwrap();
                for (s, c) in sums.iter_mut().zip(offspring_counts(&out, n)) {
                    *s += c as f64;
                }
            }
            for i in 0..n {
                let mean = sums[i] / trials as f64;
                let se = (n as f64 * w[i] * (1.0 - w[i]) / trials as f64).sqrt();
                assert!(
                    (mean - n as f64 * w[i]).abs() < 5.0 * se + 1e-12,
                    "{r:?}: particle {i} mean {mean}, want {}",
                    n as f64 * w[i]
                );
            }
        }
    }

    #[test]
    fn systematic_equals_the_walk_of_algorithm_2() {
        // The closed form against the seed's loop (WHILE u_j > c_i: i = i + 1), point by point.
        let mut rng = SplitMix64::new(6);
        let (mut fast, mut slow) = (Vec::new(), Vec::new());
        for case in 0..2000 {
            let n = 1 + case % 64;
            let mut w = random_weights(n, &mut rng, case % 2 == 0);
            if case % 5 == 0 {
                // Zero weights first, last and between.
                w[0] = 0.0;
                w[n - 1] = 0.0;
                let s: f64 = w.iter().sum();
                if s == 0.0 {
                    continue;
                }
                w.iter_mut().for_each(|v| *v /= s);
            }
            let u = rng.unit();
            systematic(&w, u, &mut fast).unwrap();
            walk(&w, n, |j| (u + j as f64) / n as f64, &mut slow);
            assert_eq!(fast, slow, "case {case}");
        }
    }

    #[test]
    fn every_backend_gives_the_same_systematic_parents() {
        let mut rng = SplitMix64::new(7);
        for case in 0..300 {
            let n = 1 + case * 7 % 500;
            let w = random_weights(n, &mut rng, case % 2 == 0);
            let u = rng.unit();
            let runs: Vec<_> = ocellus_image::Backend::available()
                .into_iter()
                .map(|b| {
                    let mut out = vec![usize::MAX; n + FILL];
                    let r = systematic_fill(b, &w[..n - 1], u, n, &mut out);
                    (r, out[..r.1].to_vec())
                })
                .collect();
            assert!(runs.windows(2).all(|p| p[0] == p[1]), "case {case}");
        }
    }

    #[test]
    fn seed_algorithm_2_on_a_hand_example() {
        // w = (0.1, 0.4, 0.5), u = 0.5: points 1/6, 1/2, 5/6 against the CDF 0.1, 0.5, 1.0.
        let mut out = Vec::new();
        systematic(&[0.1, 0.4, 0.5], 0.5, &mut out).unwrap();
        assert_eq!(out, vec![1, 1, 2]);
        // A last weight that round-off puts a hair short still ends inside the particles.
        systematic(&[0.5, 0.5 - 1e-12], 0.999_999_999_999, &mut out).unwrap();
        assert_eq!(out, vec![0, 1]);
    }

    #[test]
    fn bad_weights_are_errors() {
        let mut out = Vec::new();
        let mut rng = SplitMix64::new(4);
        for w in [vec![], vec![0.5, 0.6], vec![f64::NAN, 1.0], vec![-0.1, 1.1], vec![0.0, 0.0]] {
            for r in ALL {
                assert!(r.resample(&w, &mut rng, &mut out).is_err(), "{r:?} {w:?}");
            }
        }
        assert!(systematic(&[1.0], 1.0, &mut out).is_err());
    }
}

#[cfg(test)]
mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any non-negative weights with a positive sum, normalized: every scheme gives N valid,
        /// increasing parents. Raw input (NaN, negative, unnormalized) is an error, never a panic.
        #[test]
        fn any_weights(raw in proptest::collection::vec(0.0f64..1e6, 1..200), seed in any::<u64>(), scale in -2.0f64..2.0) {
            let s: f64 = raw.iter().sum();
            let mut rng = SplitMix64::new(seed);
            let mut out = Vec::new();
            for r in [Resampler::Systematic, Resampler::Stratified, Resampler::Multinomial, Resampler::Residual] {
                if s > 0.0 {
                    let w: Vec<f64> = raw.iter().map(|v| v / s).collect();
                    // Renormalized weights can miss 1 by round-off only.
                    r.resample(&w, &mut rng, &mut out).unwrap();
                    prop_assert_eq!(out.len(), w.len());
                    prop_assert!(out.windows(2).all(|p| p[0] <= p[1]) && out.iter().all(|&i| w[i] > 0.0));
                }
                let scaled: Vec<f64> = raw.iter().map(|v| v * scale).collect();
                let _ = r.resample(&scaled, &mut rng, &mut out);
            }
        }
    }
}
