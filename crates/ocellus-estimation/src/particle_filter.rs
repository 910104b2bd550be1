//! Generic particle filters (SPEC 7.1): sequential importance sampling with resampling when
//! the effective sample size falls below a share of the particles. With `resample_below = 1`
//! it is the seed's SIR (Algorithm 4, resampling every step); with 0 it is the plain SIS
//! (Algorithm 1).
//!
//! The user supplies the model ([`Model`]): a proposal that draws the new state of one
//! particle and reports the log densities of the draw, and the log likelihood of the
//! observation. One step, for each particle i (the seed; Arulampalam et al. 2002):
//!
//! `log w_i += log p(z | x_i) + log p(x_i | x_i') - log q(x_i | x_i', z)`
//!
//! Weights are kept as logs (no underflow after long runs), and normalized with the
//! log-sum-exp. Particles are updated in parallel (rayon); each particle draws from its own
//! generator seeded by (seed, step, index), so the same seed gives the same particles bit for
//! bit whatever the number of threads.

use crate::resampling::Resampler;
use crate::{EstimationError, Result};
use ocellus_image::rng::SplitMix64;
use rayon::prelude::*;

/// One drawn state with the log densities of the draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Draw<S> {
    /// The new state x_i.
    pub state: S,
    /// `log p(x_i | x_i') - log q(x_i | x_i', z)`: 0 when the proposal is the motion model
    /// itself (the bootstrap filter).
    pub log_prior_over_proposal: f64,
}

/// What a filter needs from a problem: how a particle moves and how well it explains the
/// observation.
pub trait Model: Sync {
    /// A particle's state.
    type State: Clone + Send + Sync;
    /// What one step observes (an image, a measurement vector, ...).
    type Observation: ?Sized + Sync;

    /// Draws the new state of a particle from the proposal q(x | prev, z), with `rng` its own
    /// generator for this step.
    fn propose(&self, prev: &Self::State, z: &Self::Observation, rng: &mut SplitMix64) -> Draw<Self::State>;

    /// `log p(z | x)`; `-inf` for impossible states, never NaN.
    fn log_likelihood(&self, state: &Self::State, z: &Self::Observation) -> f64;
}

/// Parameters of a [`ParticleFilter`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterConfig {
    /// Resample when ESS < `resample_below` x N, in [0, 1] (0.5 by default; 1 resamples
    /// every step, the seed's SIR; 0 never, the plain SIS).
    pub resample_below: f64,
    /// The resampling scheme.
    pub resampler: Resampler,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for FilterConfig {
    fn default() -> Self {
        Self { resample_below: 0.5, resampler: Resampler::Systematic, seed: 1 }
    }
}

/// What one step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// Effective sample size after the weight update (before any resampling), in particles.
    pub ess: f64,
    /// Whether the particles were resampled.
    pub resampled: bool,
    /// `log` of the mean incremental weight: the log marginal likelihood of the observation
    /// under the filter (Doucet & Johansen 2009), `-inf` when every particle is impossible.
    pub log_evidence: f64,
}

/// A particle cloud with log weights.
#[derive(Clone, Debug)]
pub struct ParticleFilter<S> {
    cfg: FilterConfig,
    particles: Vec<S>,
    log_w: Vec<f64>,
    steps: u64,
    // Reused per step: incremental log weights, log likelihoods, normalized weights,
    // parents, and the next generation while resampling.
    increments: Vec<f64>,
    likelihoods: Vec<f64>,
    weights: Vec<f64>,
    parents: Vec<usize>,
    next: Vec<S>,
    /// Whether `propose` ran since the last weighing.
    proposed: bool,
}

/// A generator for (seed, step, stream): SplitMix64 of a mixed key, so streams do not overlap
/// in practice.
/// Particles per chunk of the weight update's parallel passes. Fixed, not set by the thread
/// count, so that the partial sums, added in chunk order, and with them every weight, come out
/// the same bit for bit with one thread or many. The update was the serial part of a step
/// (three passes of `exp` over the cloud): with it serial, 10^4 particles on 2 cores ran
/// 1.78 times as fast as on one.
const WEIGH_CHUNK: usize = 4096;

fn stream(seed: u64, step: u64, index: u64) -> SplitMix64 {
    let mut k = SplitMix64::new(seed ^ step.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let base = k.next_u64();
    SplitMix64::new(base ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03))
}

impl<S: Clone + Send + Sync> ParticleFilter<S> {
    /// A filter over `particles`, equally weighted.
    pub fn new(cfg: FilterConfig, particles: Vec<S>) -> Result<Self> {
        if particles.is_empty() {
            return Err(EstimationError::InvalidInput("a particle filter needs at least one particle".into()));
        }
        if !(0.0..=1.0).contains(&cfg.resample_below) {
            return Err(EstimationError::InvalidInput(format!(
                "resample_below = {} is outside [0, 1]",
                cfg.resample_below
            )));
        }
        let n = particles.len();
        Ok(Self {
            cfg,
            particles,
            log_w: vec![-(n as f64).ln(); n],
            steps: 0,
            increments: Vec::new(),
            likelihoods: Vec::new(),
            weights: Vec::new(),
            parents: Vec::new(),
            next: Vec::new(),
            proposed: false,
        })
    }

    /// Starts over from `particles`, equally weighted (the step count, and so the random
    /// streams, continue).
    pub fn reset(&mut self, particles: Vec<S>) -> Result<()> {
        if particles.is_empty() {
            return Err(EstimationError::InvalidInput("a particle filter needs at least one particle".into()));
        }
        let n = particles.len();
        self.particles = particles;
        self.log_w = vec![-(n as f64).ln(); n];
        Ok(())
    }

    /// The particles.
    pub fn particles(&self) -> &[S] {
        &self.particles
    }

    /// The normalized log weights (log-sum-exp 0).
    pub fn log_weights(&self) -> &[f64] {
        &self.log_w
    }

    /// The normalized weights.
    pub fn weights(&self) -> Vec<f64> {
        self.log_w.iter().map(|l| l.exp()).collect()
    }

    /// The effective sample size `1 / sum w_i^2`, in particles (N for equal weights, 1 when
    /// one particle holds all the weight).
    pub fn ess(&self) -> f64 {
        let s: f64 = self.log_w.iter().map(|l| (2.0 * l).exp()).sum();
        if s > 0.0 {
            1.0 / s
        } else {
            0.0
        }
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The weighted mean of `f` over the particles (e.g. the position part of the state).
    pub fn mean<const D: usize>(&self, f: impl Fn(&S) -> [f64; D]) -> [f64; D] {
        let mut m = [0.0; D];
        for (p, l) in self.particles.iter().zip(&self.log_w) {
            let (v, w) = (f(p), l.exp());
            for k in 0..D {
                m[k] += w * v[k];
            }
        }
        m
    }

    /// The first half of [`Self::step`]: moves every particle by the proposal and keeps its
    /// prior-over-proposal weight, without reading a likelihood. Between this and
    /// [`Self::weigh_proposed`] the caller may prepare the observation from where the
    /// particles now are (a tracker bins only the part of the frame they can see); `step`
    /// is the two in a row. A proposal that reads the observation sees `z` as it is now.
    /// Particles are moved in place: no allocation per step.
    pub fn propose<M: Model<State = S>>(&mut self, model: &M, z: &M::Observation) {
        let (seed, step) = (self.cfg.seed, self.steps);
        let n = self.particles.len();
        self.increments.resize(n, 0.0);
        self.particles.par_iter_mut().zip(self.increments.par_iter_mut()).enumerate().for_each(|(i, (p, inc))| {
            let mut rng = stream(seed, step, i as u64);
            let d = model.propose(p, z, &mut rng);
            *inc = d.log_prior_over_proposal;
            *p = d.state;
        });
        self.proposed = true;
    }

    /// [`Self::propose`] with the proposal applied by the caller, to the whole cloud at once:
    /// `proposal(particles, increments)` moves the particles in place and writes each one's
    /// `ln p(x | x') - ln q(x | x', z)` into `increments` (zeroed: 0 for the bootstrap
    /// filter). For proposals written over arrays (numpy, a GPU); then
    /// [`Self::weigh_proposed_with`] completes the step.
    pub fn propose_with(&mut self, proposal: impl FnOnce(&mut [S], &mut [f64])) {
        self.increments.clear();
        self.increments.resize(self.particles.len(), 0.0);
        proposal(&mut self.particles, &mut self.increments);
        self.proposed = true;
    }

    /// The second half of [`Self::step`]: weighs the particles moved by [`Self::propose`]
    /// by the observation `z`, normalizes and resamples. An error when nothing was proposed
    /// since the last step.
    pub fn weigh_proposed<M: Model<State = S>>(&mut self, model: &M, z: &M::Observation) -> Result<StepReport> {
        self.weigh_proposed_with(|particles, out| {
            particles.par_iter().zip(out.par_iter_mut()).for_each(|(p, l)| *l = model.log_likelihood(p, z));
        })
    }

    /// [`Self::weigh_proposed`] with the log likelihoods written by the caller:
    /// `log_likelihoods(particles, out)` fills `out[i]` with `log p(z | particles[i])` (`out`
    /// comes zeroed, one entry per particle). For likelihoods that look at the whole cloud
    /// before they commit, e.g. a tracker that treats a frame where no particle sees its
    /// target as carrying no evidence. An error when nothing was proposed since the last
    /// step, or when an entry is NaN.
    pub fn weigh_proposed_with(&mut self, log_likelihoods: impl FnOnce(&[S], &mut [f64])) -> Result<StepReport> {
        if !self.proposed || self.increments.len() != self.particles.len() {
            return Err(EstimationError::InvalidInput("weigh_proposed without propose".into()));
        }
        self.proposed = false;
        self.likelihoods.clear();
        self.likelihoods.resize(self.particles.len(), 0.0);
        log_likelihoods(&self.particles, &mut self.likelihoods);
        self.increments.par_iter_mut().zip(self.likelihoods.par_iter()).for_each(|(inc, l)| *inc += l);
        self.steps += 1;
        self.weigh()
    }

    /// One step: propose every particle, weight it by the observation `z`, normalize, and
    /// resample when the ESS falls below the configured share. When every particle is
    /// impossible (all log likelihoods `-inf`), the weights are left equal and the report's
    /// `log_evidence` is `-inf`: the cloud follows the motion model until it finds the
    /// target again.
    pub fn step<M: Model<State = S>>(&mut self, model: &M, z: &M::Observation) -> Result<StepReport> {
        self.propose(model, z);
        self.weigh_proposed(model, z)
    }

    /// Multiplies the weights by `exp(log_increments)` without moving the particles (e.g. to
    /// weigh a starting cloud by a first observation), normalizes, and resamples when the
    /// ESS falls below the configured share; as a step's weight update.
    pub fn reweight(&mut self, log_increments: &[f64]) -> Result<StepReport> {
        if log_increments.len() != self.particles.len() {
            return Err(EstimationError::InvalidInput(format!(
                "{} weight increments for {} particles",
                log_increments.len(),
                self.particles.len()
            )));
        }
        self.increments.clear();
        self.increments.extend_from_slice(log_increments);
        self.weigh()
    }

    /// Applies `self.increments` to the log weights, normalizes, resamples if due. One pass
    /// of `exp` gives the log evidence, the normalized weights and the ESS, in parallel
    /// over fixed chunks ([`WEIGH_CHUNK`]).
    fn weigh(&mut self) -> Result<StepReport> {
        let n = self.particles.len();
        if self.increments.par_iter().any(|v| v.is_nan()) {
            return Err(EstimationError::InvalidInput("the model gave a NaN log weight".into()));
        }
        self.log_w.par_iter_mut().zip(self.increments.par_iter()).for_each(|(w, inc)| *w += inc);
        // The log evidence: log sum_i w_i' exp(inc_i), the previous weights being normalized;
        // computed as m + log sum_i exp(l_i - m) with m the largest log weight.
        let m = self.log_w.par_iter().copied().reduce(|| f64::NEG_INFINITY, f64::max);
        self.weights.resize(n, 0.0);
        let sums: Vec<f64> = if m.is_finite() {
            self.weights
                .par_chunks_mut(WEIGH_CHUNK)
                .zip(self.log_w.par_chunks(WEIGH_CHUNK))
                .map(|(e, l)| {
                    let mut s = 0.0;
                    for (e, l) in e.iter_mut().zip(l) {
                        *e = (l - m).exp();
                        s += *e;
                    }
                    s
                })
                .collect()
        } else {
            Vec::new()
        };
        let sum: f64 = sums.iter().sum();
        let total = m + sum.ln();
        if !total.is_finite() {
            let lw = -(n as f64).ln();
            self.log_w.par_iter_mut().for_each(|l| *l = lw);
            return Ok(StepReport { ess: n as f64, resampled: false, log_evidence: f64::NEG_INFINITY });
        }
        let inv = 1.0 / sum;
        let squares: Vec<f64> = self
            .weights
            .par_chunks_mut(WEIGH_CHUNK)
            .zip(self.log_w.par_chunks_mut(WEIGH_CHUNK))
            .map(|(w, l)| {
                let mut q = 0.0;
                for (w, l) in w.iter_mut().zip(l.iter_mut()) {
                    *l -= total;
                    *w *= inv;
                    q += *w * *w;
                }
                q
            })
            .collect();
        let q: f64 = squares.iter().sum();
        let ess = if q > 0.0 { 1.0 / q } else { 0.0 };
        let resampled = ess < self.cfg.resample_below * n as f64;
        if resampled {
            self.resample_by_weights()?;
        }
        Ok(StepReport { ess, resampled, log_evidence: total })
    }

    /// Resamples now with the configured scheme; the weights become equal.
    pub fn resample(&mut self) -> Result<()> {
        self.weights.clear();
        self.weights.par_extend(self.log_w.par_iter().map(|l| l.exp()));
        // exp of normalized logs sums to 1 within round-off; renormalize for the check.
        let s: f64 = self.weights.iter().sum();
        self.weights.par_iter_mut().for_each(|w| *w /= s);
        self.resample_by_weights()
    }

    /// Resamples by `self.weights` (normalized, one per particle); the weights become equal.
    fn resample_by_weights(&mut self) -> Result<()> {
        let n = self.particles.len();
        let mut rng = stream(self.cfg.seed, self.steps, u64::MAX);
        self.cfg.resampler.resample(&self.weights, &mut rng, &mut self.parents)?;
        self.next.clear();
        let particles = &self.particles;
        self.next.par_extend(self.parents.par_iter().map(|&p| particles[p].clone()));
        std::mem::swap(&mut self.particles, &mut self.next);
        let lw = -(n as f64).ln();
        self.log_w.par_iter_mut().for_each(|l| *l = lw);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1-D random walk observed with Gaussian noise; the proposal is the motion model,
    /// optionally shifted towards the observation (then the prior/proposal ratio is not 0).
    struct Walk {
        step_sigma: f64,
        obs_sigma: f64,
        pull: f64,
    }

    fn log_normal(x: f64, mu: f64, s: f64) -> f64 {
        -0.5 * ((x - mu) / s).powi(2) - (s * (2.0 * std::f64::consts::PI).sqrt()).ln()
    }

    impl Model for Walk {
        type State = f64;
        type Observation = f64;
        fn propose(&self, prev: &f64, z: &f64, rng: &mut SplitMix64) -> Draw<f64> {
            let centre = prev + self.pull * (z - prev);
            let x = centre + self.step_sigma * rng.normal();
            let ratio = log_normal(x, *prev, self.step_sigma) - log_normal(x, centre, self.step_sigma);
            Draw { state: x, log_prior_over_proposal: ratio }
        }
        fn log_likelihood(&self, x: &f64, z: &f64) -> f64 {
            log_normal(*z, *x, self.obs_sigma)
        }
    }

    #[test]
    fn propose_then_weigh_is_step_bit_for_bit() {
        let model = Walk { step_sigma: 0.3, obs_sigma: 0.2, pull: 0.4 };
        let start: Vec<f64> = (0..257).map(|i| i as f64 * 0.01).collect();
        let cfg = FilterConfig { resample_below: 0.7, ..FilterConfig::default() };
        let mut a = ParticleFilter::new(cfg, start.clone()).unwrap();
        let mut b = ParticleFilter::new(cfg, start).unwrap();
        for (t, z) in [0.5, 0.8, 1.7, 1.2, 0.9].iter().enumerate() {
            let ra = a.step(&model, z).unwrap();
            b.propose(&model, z);
            let rb = b.weigh_proposed(&model, z).unwrap();
            assert_eq!(ra, rb, "step {t}");
            assert_eq!(a.particles(), b.particles());
            assert_eq!(a.log_weights(), b.log_weights());
        }
        assert!(b.weigh_proposed(&model, &0.0).is_err(), "weighing twice");
    }

    #[test]
    fn caller_written_likelihoods_add_to_the_proposal_weights() {
        let model = Walk { step_sigma: 0.3, obs_sigma: 0.2, pull: 0.4 };
        let cfg = FilterConfig { resample_below: 0.0, ..FilterConfig::default() };
        let start: Vec<f64> = (0..64).map(|i| i as f64 * 0.05).collect();
        let (mut a, mut b) =
            (ParticleFilter::new(cfg, start.clone()).unwrap(), ParticleFilter::new(cfg, start).unwrap());
        let z = 1.1;
        // The same likelihoods written by the caller give the model's step bit for bit.
        a.step(&model, &z).unwrap();
        b.propose(&model, &z);
        b.weigh_proposed_with(|ps, out| {
            assert!(out.iter().all(|&l| l == 0.0), "out comes zeroed");
            for (p, l) in ps.iter().zip(out.iter_mut()) {
                *l = model.log_likelihood(p, &z);
            }
        })
        .unwrap();
        assert_eq!(a.log_weights(), b.log_weights());
        // Leaving them at 0 keeps only the prior/proposal ratios: an uninformative frame.
        let mut c = ParticleFilter::new(cfg, vec![0.0, 1.0]).unwrap();
        c.propose(&model, &z);
        c.weigh_proposed_with(|_, _| {}).unwrap();
        let mut want = Vec::new();
        for (i, prev) in [0.0f64, 1.0].iter().enumerate() {
            let mut rng = stream(cfg.seed, 0, i as u64);
            let centre = prev + 0.4 * (z - prev);
            let x = centre + 0.3 * rng.normal();
            want.push(log_normal(x, *prev, 0.3) - log_normal(x, centre, 0.3));
        }
        let total = (want[0].exp() + want[1].exp()).ln();
        for (got, w) in c.log_weights().iter().zip(&want) {
            assert!((got - (w - total)).abs() < 1e-12, "{got} vs {}", w - total);
        }
        c.propose(&model, &z);
        assert!(c.weigh_proposed_with(|_, out| out[1] = f64::NAN).is_err(), "NaN is refused");
    }

    #[test]
    fn sis_weight_update_matches_a_hand_computation() {
        // Two particles, no resampling: w_i ∝ w_i' p(z | x_i) p(x_i | x_i') / q(x_i | x_i', z).
        let m = Walk { step_sigma: 0.5, obs_sigma: 0.3, pull: 0.4 };
        let cfg = FilterConfig { resample_below: 0.0, ..Default::default() };
        let mut f = ParticleFilter::new(cfg, vec![0.0, 1.0]).unwrap();
        let z = 0.8;
        f.step(&m, &z).unwrap();
        // The same draws by hand, from the same per-particle streams.
        let mut want = Vec::new();
        for (i, prev) in [0.0f64, 1.0].iter().enumerate() {
            let mut rng = stream(cfg.seed, 0, i as u64);
            let centre = prev + 0.4 * (z - prev);
            let x = centre + 0.5 * rng.normal();
            let p_z = (-0.5 * ((z - x) / 0.3f64).powi(2)).exp() / (0.3 * (2.0 * std::f64::consts::PI).sqrt());
            let prior = (-0.5 * ((x - prev) / 0.5f64).powi(2)).exp();
            let q = (-0.5 * ((x - centre) / 0.5f64).powi(2)).exp();
            want.push((x, 0.5 * p_z * prior / q));
            assert_eq!(f.particles()[i], x);
        }
        let total = want[0].1 + want[1].1;
        for (i, w) in f.weights().iter().enumerate() {
            assert!((w - want[i].1 / total).abs() < 1e-12, "{w} vs {}", want[i].1 / total);
        }
    }

    #[test]
    fn tracks_a_random_walk_and_resamples_below_the_threshold() {
        let m = Walk { step_sigma: 0.2, obs_sigma: 0.1, pull: 0.0 };
        let mut truth = SplitMix64::new(77);
        let mut f = ParticleFilter::new(FilterConfig::default(), vec![0.0; 2000]).unwrap();
        let (mut x, mut err2, mut resamples) = (0.0, 0.0, 0);
        for _ in 0..100 {
            x += 0.2 * truth.normal();
            let z = x + 0.1 * truth.normal();
            let r = f.step(&m, &z).unwrap();
            assert!(r.ess >= 1.0 && r.ess <= 2000.0 + 1e-6);
            resamples += usize::from(r.resampled);
            if r.resampled {
                assert!(r.ess < 1000.0);
                assert!((f.ess() - 2000.0).abs() < 1e-6);
            }
            let [m] = f.mean(|p| [*p]);
            err2 += (m - x).powi(2);
        }
        // The posterior of this linear-Gaussian model has sd ~0.08: the filter is close to it.
        let rmse = (err2 / 100.0).sqrt();
        assert!(rmse < 0.12, "rmse {rmse}");
        assert!(resamples > 10, "{resamples} resamplings");
    }

    #[test]
    fn same_seed_same_particles_with_one_thread_or_many() {
        let m = Walk { step_sigma: 0.3, obs_sigma: 0.2, pull: 0.2 };
        // 5000 particles: the weight update's sums run over two chunks. Resampling every
        // step, and only below half the ESS (the log weights then carry over).
        let run = |threads: usize, resample_below: f64| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let cfg = FilterConfig { resample_below, resampler: Resampler::Residual, seed: 9 };
                let mut f = ParticleFilter::new(cfg, (0..5000).map(|i| i as f64 * 1e-3).collect()).unwrap();
                let ess: Vec<f64> = (0..20).map(|k| f.step(&m, &(k as f64 * 0.1)).unwrap().ess).collect();
                (f.particles().to_vec(), f.log_weights().to_vec(), ess)
            })
        };
        for r in [1.0, 0.5] {
            let one = run(1, r);
            assert_eq!(one, run(4, r));
            assert_eq!(one, run(3, r));
            assert_eq!(one, run(1, r));
        }
    }

    #[test]
    fn impossible_observations_keep_the_cloud_and_bad_setups_are_errors() {
        struct Never;
        impl Model for Never {
            type State = f64;
            type Observation = ();
            fn propose(&self, prev: &f64, _: &(), rng: &mut SplitMix64) -> Draw<f64> {
                Draw { state: prev + rng.normal(), log_prior_over_proposal: 0.0 }
            }
            fn log_likelihood(&self, _: &f64, _: &()) -> f64 {
                f64::NEG_INFINITY
            }
        }
        let mut f = ParticleFilter::new(FilterConfig::default(), vec![0.0; 10]).unwrap();
        let r = f.step(&Never, &()).unwrap();
        assert_eq!((r.log_evidence, r.resampled), (f64::NEG_INFINITY, false));
        assert!((f.ess() - 10.0).abs() < 1e-9 && f.particles().iter().any(|p| *p != 0.0));
        assert!(ParticleFilter::<f64>::new(FilterConfig::default(), vec![]).is_err());
        assert!(ParticleFilter::new(FilterConfig { resample_below: 1.5, ..Default::default() }, vec![0.0]).is_err());
        assert!(
            ParticleFilter::new(FilterConfig { resample_below: f64::NAN, ..Default::default() }, vec![0.0]).is_err()
        );
    }

    #[test]
    fn a_proposal_written_over_the_cloud_weighs_as_the_hand_computation() {
        let cfg = FilterConfig { resample_below: 0.0, ..FilterConfig::default() };
        let mut f = ParticleFilter::new(cfg, vec![0.0f64, 1.0, 2.0, 3.0]).unwrap();
        f.propose_with(|p, inc| {
            p.iter_mut().for_each(|x| *x += 0.5);
            inc[3] = -1.0;
        });
        // Observation 2 with unit Gaussian noise.
        f.weigh_proposed_with(|p, out| {
            p.iter().zip(out.iter_mut()).for_each(|(x, l)| *l = -0.5 * (x - 2.0) * (x - 2.0))
        })
        .unwrap();
        assert_eq!(f.particles(), &[0.5, 1.5, 2.5, 3.5]);
        let raw: Vec<f64> = [0.5f64, 1.5, 2.5, 3.5]
            .iter()
            .enumerate()
            .map(|(i, x)| (-0.5 * (x - 2.0) * (x - 2.0) - if i == 3 { 1.0 } else { 0.0 }).exp())
            .collect();
        let s: f64 = raw.iter().sum();
        for (w, r) in f.weights().iter().zip(&raw) {
            assert!((w - r / s).abs() < 1e-12, "{w} vs {}", r / s);
        }
    }
}
