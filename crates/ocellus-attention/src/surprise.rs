//! Bayesian surprise (Itti & Baldi 2005; SPEC 2.1) on a saliency map, frame after frame.
//!
//! Each cell of the map holds a Gamma(alpha, beta) belief over the Poisson rate of its saliency
//! value. A new value `lambda'` (the saliency times [`SurpriseConfig::data_scale`]) updates it
//! (seed eq. 8): `alpha' = xi alpha + lambda'`, `beta' = xi beta + 1`, with the forgetting
//! factor `xi` ([`SurpriseConfig::update_factor`]). Surprise is the KL divergence between the
//! posterior and the prior belief, in bits.
//!
//! Beliefs start at the steady state of the update for the first frame's value
//! (`alpha = lambda / (1 - xi)`, `beta = 1 / (1 - xi)`, the iLab prior), so the first frame
//! has zero surprise and a static scene stays unsurprising.
//!
//! Multi-timescale form (iLab Neuromorphic Vision Toolkit): a chain of models; model 0 is fed
//! the data, model k the posterior mean `alpha / beta` of model k - 1, so later models forget
//! more slowly. The surprise of a cell is the sum over the chain (our choice: each model's KL
//! is in bits, and the sum is the information gained at all time scales).

use crate::{AttentionError, Result};
use ocellus_image::Plane;
use serde::{Deserialize, Serialize};

/// Which KL divergence is the surprise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KlDirection {
    /// `KL(posterior || prior)`, the definition of Itti & Baldi (default).
    PosteriorPrior,
    /// `KL(prior || posterior)`, as the seed writes eq. 9.
    PriorPosterior,
}

/// Parameters of [`Surprise`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurpriseConfig {
    /// Forgetting factor `xi` in (0, 1] (iLab: 0.7). Smaller forgets faster.
    pub update_factor: f64,
    /// Number of chained models: 1 is the seed's single model, 5 the iLab chain.
    pub models: usize,
    /// Saliency-to-rate factor: `lambda' = data_scale * saliency` (rates are counts per frame).
    pub data_scale: f64,
    /// Smallest `alpha` a belief may have (keeps the Gamma proper where the saliency is 0).
    pub alpha_floor: f64,
    /// KL direction.
    pub direction: KlDirection,
}

impl Default for SurpriseConfig {
    fn default() -> Self {
        Self {
            update_factor: 0.7,
            models: 1,
            data_scale: 1.0,
            alpha_floor: 1e-2,
            direction: KlDirection::PosteriorPrior,
        }
    }
}

impl SurpriseConfig {
    /// The iLab multi-timescale chain: 5 models, update factor 0.7.
    pub fn chain() -> Self {
        Self { models: 5, ..Self::default() }
    }

    /// Checks the ranges.
    pub fn validate(&self) -> Result<()> {
        use ocellus_image::check;
        (|| {
            check::between("surprise update_factor", self.update_factor, 0.0, 1.0)?;
            check::within("surprise models", self.models, 1, 16)?;
            check::positive("surprise data_scale", self.data_scale)?;
            check::positive("surprise alpha_floor", self.alpha_floor)
        })()
        .map_err(AttentionError::InvalidConfig)
    }
}

/// Surprise over a stream of maps of one size.
#[derive(Debug)]
pub struct Surprise {
    cfg: SurpriseConfig,
    width: usize,
    height: usize,
    /// `alpha` per model, per cell (row-major).
    alpha: Vec<Vec<f64>>,
    /// `(ln Gamma(alpha), psi(alpha))` per model, per cell: this frame's prior is the last
    /// frame's posterior, so each frame needs the special functions once per changed cell.
    special: Vec<Vec<(f64, f64)>>,
    /// `beta` per model (the update does not depend on the data, so it is one number).
    beta: Vec<f64>,
    /// Scratch: the data each model sees.
    data: Vec<f64>,
    map: Plane<f32>,
    started: bool,
}

impl Surprise {
    /// A surprise engine for `width` x `height` maps.
    pub fn new(cfg: SurpriseConfig, width: usize, height: usize) -> Result<Self> {
        cfg.validate()?;
        if width == 0 || height == 0 {
            return Err(AttentionError::InvalidInput(format!("surprise map of {width}x{height}")));
        }
        let n = width * height;
        Ok(Self {
            alpha: vec![vec![0.0; n]; cfg.models],
            special: vec![vec![(0.0, 0.0); n]; cfg.models],
            beta: vec![0.0; cfg.models],
            data: vec![0.0; n],
            map: Plane::new(width, height),
            started: false,
            width,
            height,
            cfg,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SurpriseConfig {
        &self.cfg
    }

    /// The last surprise map, in bits per cell.
    pub fn map(&self) -> &Plane<f32> {
        &self.map
    }

    /// Forgets all beliefs (the next frame starts them again).
    pub fn reset(&mut self) {
        self.started = false;
    }

    /// Updates the beliefs with `saliency` (same size as the engine, finite, >= 0) and returns
    /// the surprise map in bits.
    pub fn update(&mut self, saliency: &Plane<f32>) -> Result<&Plane<f32>> {
        ocellus_image::check::same_size("saliency map given to surprise", saliency.size(), (self.width, self.height))?;
        if !saliency.all_finite() || saliency.min_max().0 < 0.0 {
            return Err(AttentionError::InvalidInput("saliency for surprise must be finite and >= 0".into()));
        }
        let s = self.cfg.data_scale;
        for (y, row) in saliency.rows().enumerate() {
            for (x, &v) in row.iter().enumerate() {
                self.data[y * self.width + x] = v as f64 * s;
            }
        }
        let (xi, floor) = (self.cfg.update_factor, self.cfg.alpha_floor);
        self.map.fill(0.0);
        let w = self.width;
        for m in 0..self.cfg.models {
            let (alpha, special) = (&mut self.alpha[m], &mut self.special[m]);
            if !self.started {
                for ((a, sp), &d) in alpha.iter_mut().zip(special.iter_mut()).zip(&self.data) {
                    *a = (d / (1.0 - xi)).max(floor);
                    *sp = ln_gamma_digamma(*a);
                }
                self.beta[m] = 1.0 / (1.0 - xi);
            } else {
                let b0 = self.beta[m];
                let mut b1 = xi * b0 + 1.0;
                // At the steady state b1 = b0 up to rounding: keep it exact, so that an
                // unchanged alpha gives exactly zero surprise without any special function.
                if (b1 - b0).abs() <= 1e-12 * b0 {
                    b1 = b0;
                }
                let (ln_b, db) = ((b1 / b0).ln(), b0 - b1);
                for (y, row) in self.data.chunks_exact_mut(w).enumerate() {
                    let out = self.map.row_mut(y);
                    let i0 = y * w;
                    for (x, d) in row.iter_mut().enumerate() {
                        let (a, sp) = (&mut alpha[i0 + x], &mut special[i0 + x]);
                        let a1 = (xi * *a + *d).max(floor);
                        // The next model of the chain sees this model's posterior mean.
                        *d = a1 / b1;
                        if a1 == *a && db == 0.0 {
                            continue;
                        }
                        let (lg0, psi0) = *sp;
                        let (lg1, psi1) = ln_gamma_digamma(a1);
                        // Closed forms of kl_gamma with the cached prior terms.
                        let kl = match self.cfg.direction {
                            KlDirection::PosteriorPrior => (a1 - *a) * psi1 - lg1 + lg0 + *a * ln_b + a1 * db / b1,
                            KlDirection::PriorPosterior => (*a - a1) * psi0 - lg0 + lg1 - a1 * ln_b - *a * db / b0,
                        };
                        out[x] += (kl.max(0.0) / std::f64::consts::LN_2) as f32;
                        (*a, *sp) = (a1, (lg1, psi1));
                    }
                }
                self.beta[m] = b1;
            }
            if !self.started {
                for (d, a) in self.data.iter_mut().zip(alpha.iter()) {
                    *d = a / self.beta[m];
                }
            }
        }
        self.started = true;
        Ok(&self.map)
    }
}

/// `KL(Gamma(a1, b1) || Gamma(a2, b2))` in nats, shapes `a` and rates `b` (all > 0):
/// `(a1 - a2) psi(a1) - lnG(a1) + lnG(a2) + a2 (ln b1 - ln b2) + a1 (b2 - b1) / b1`.
pub fn kl_gamma(a1: f64, b1: f64, a2: f64, b2: f64) -> f64 {
    let kl = (a1 - a2) * digamma(a1) - ln_gamma(a1) + ln_gamma(a2) + a2 * (b1 / b2).ln() + a1 * (b2 - b1) / b1;
    // Rounding can make a zero divergence slightly negative.
    kl.max(0.0)
}

/// `(ln Gamma(x), psi(x))` for `x > 0` in one pass: the shift to x >= 8 keeps the product
/// `P = x (x + 1) ...` and its derivative `P'`, so `sum 1 / (x + i) = P' / P` costs one division.
pub fn ln_gamma_digamma(x: f64) -> (f64, f64) {
    let (mut z, mut p, mut dp) = (x, 1.0, 0.0);
    while z < 8.0 {
        dp = dp * z + p;
        p *= z;
        z += 1.0;
    }
    let inv = 1.0 / z;
    let inv2 = inv * inv;
    let ln_z = z.ln();
    let lg_series = inv
        * (1.0 / 12.0
            - inv2
                * (1.0 / 360.0
                    - inv2
                        * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 * (1.0 / 1188.0 - inv2 * 691.0 / 360_360.0)))));
    let psi_series = inv2
        * (1.0 / 12.0
            - inv2
                * (1.0 / 120.0
                    - inv2 * (1.0 / 252.0 - inv2 * (1.0 / 240.0 - inv2 * (1.0 / 132.0 - inv2 * 691.0 / 32_760.0)))));
    let lg = (z - 0.5) * ln_z - z + 0.5 * (2.0 * std::f64::consts::PI).ln() + lg_series - p.ln();
    let psi = ln_z - 0.5 * inv - psi_series - dp / p;
    (lg, psi)
}

/// `ln Gamma(x)` for `x > 0`: recurrence up to x >= 8, then Stirling's series (error < 1e-14).
pub fn ln_gamma(x: f64) -> f64 {
    let (mut x, mut prod) = (x, 1.0);
    while x < 8.0 {
        prod *= x;
        x += 1.0;
    }
    let inv = 1.0 / x;
    let inv2 = inv * inv;
    let series = inv
        * (1.0 / 12.0
            - inv2
                * (1.0 / 360.0
                    - inv2
                        * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 * (1.0 / 1188.0 - inv2 * 691.0 / 360_360.0)))));
    (x - 0.5) * x.ln() - x + 0.5 * (2.0 * std::f64::consts::PI).ln() + series - prod.ln()
}

/// Digamma `psi(x) = d/dx ln Gamma(x)` for `x > 0`: recurrence up to x >= 8, then the
/// asymptotic series (error < 1e-14).
pub fn digamma(x: f64) -> f64 {
    let (mut x, mut acc) = (x, 0.0);
    while x < 8.0 {
        acc -= 1.0 / x;
        x += 1.0;
    }
    let inv = 1.0 / x;
    let inv2 = inv * inv;
    let series = inv2
        * (1.0 / 12.0
            - inv2
                * (1.0 / 120.0
                    - inv2 * (1.0 / 252.0 - inv2 * (1.0 / 240.0 - inv2 * (1.0 / 132.0 - inv2 * 691.0 / 32_760.0)))));
    acc + x.ln() - 0.5 * inv - series
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_special_functions_match_the_separate_ones() {
        for &x in &[0.01, 0.3, 1.0, 2.5, 7.9, 8.0, 13.0, 250.0] {
            let (lg, psi) = ln_gamma_digamma(x);
            assert!((lg - ln_gamma(x)).abs() < 1e-12 * (1.0 + lg.abs()), "lnG({x})");
            assert!((psi - digamma(x)).abs() < 1e-12 * (1.0 + psi.abs()), "psi({x})");
        }
    }

    #[test]
    fn cached_update_equals_the_direct_formula() {
        // Surprise of one cell over a few frames, against kl_gamma on the same beliefs.
        for dir in [KlDirection::PosteriorPrior, KlDirection::PriorPosterior] {
            let cfg = SurpriseConfig { direction: dir, ..Default::default() };
            let mut s = Surprise::new(cfg, 1, 1).unwrap();
            let (xi, b) = (0.7, 1.0 / 0.3);
            let mut a = 2.0 / 0.3;
            s.update(&Plane::from_fn(1, 1, |_, _| 2.0)).unwrap();
            for &v in &[2.0f32, 5.0, 0.0, 0.0, 3.5] {
                let a1 = (xi * a + v as f64).max(1e-2);
                let want = match dir {
                    KlDirection::PosteriorPrior => kl_gamma(a1, b, a, b),
                    KlDirection::PriorPosterior => kl_gamma(a, b, a1, b),
                } / std::f64::consts::LN_2;
                let got = s.update(&Plane::from_fn(1, 1, |_, _| v)).unwrap().get(0, 0) as f64;
                assert!((got - want).abs() < 1e-5 * (1.0 + want), "{dir:?} {v}: {got} vs {want}");
                a = a1;
            }
        }
    }

    #[test]
    fn special_functions_match_known_values() {
        // Gamma(1/2) = sqrt(pi); Gamma(n) = (n-1)!; psi(1) = -Euler-Mascheroni; psi(1/2).
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-13);
        assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-12);
        assert!((ln_gamma(100.0) - 359.134_205_369_575_4).abs() < 1e-9);
        assert!((digamma(1.0) + 0.577_215_664_901_532_9).abs() < 1e-13);
        assert!((digamma(0.5) + 0.577_215_664_901_532_9 + 2.0 * 2f64.ln()).abs() < 1e-13);
        // psi(30) = H_29 - gamma.
        assert!((digamma(30.0) - 3.384_438_132_685_525).abs() < 1e-12);
    }

    /// KL by numerical integration of p ln(p / q) over the rate (Simpson on x = t^2, which
    /// smooths the x^(a-1) behaviour at 0).
    fn kl_numeric(a1: f64, b1: f64, a2: f64, b2: f64) -> f64 {
        let ln_pdf = |a: f64, b: f64, x: f64| a * b.ln() + (a - 1.0) * x.ln() - b * x - ln_gamma(a);
        let hi = ((a1 / b1) + 40.0 * a1.sqrt() / b1 + 40.0 / b1).sqrt();
        let n = 400_000;
        let h = hi / n as f64;
        let mut sum = 0.0;
        for i in 1..n {
            let t = i as f64 * h;
            let x = t * t;
            let (lp, lq) = (ln_pdf(a1, b1, x), ln_pdf(a2, b2, x));
            let f = lp.exp() * (lp - lq) * 2.0 * t;
            sum += f * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum * h / 3.0
    }

    #[test]
    fn gamma_kl_matches_numerical_integration() {
        for &(a1, b1, a2, b2) in
            &[(2.0, 1.0, 3.0, 1.5), (5.5, 3.333, 4.0, 3.333), (20.0, 2.0, 14.0, 2.0), (1.5, 0.5, 2.5, 0.8)]
        {
            let (c, n) = (kl_gamma(a1, b1, a2, b2), kl_numeric(a1, b1, a2, b2));
            assert!((c - n).abs() < 1e-6 * (1.0 + n), "KL({a1},{b1} || {a2},{b2}): closed {c}, numeric {n}");
        }
        assert_eq!(kl_gamma(3.0, 2.0, 3.0, 2.0), 0.0);
    }

    #[test]
    fn constant_input_is_unsurprising_and_a_change_is_surprising() {
        let mut s = Surprise::new(SurpriseConfig::default(), 4, 3).unwrap();
        let calm = Plane::from_fn(4, 3, |x, y| (x + y) as f32 * 0.5);
        for _ in 0..5 {
            assert!(s.update(&calm).unwrap().min_max().1 < 1e-9);
        }
        let mut event = calm.clone();
        event.set(2, 1, 8.0);
        let m = s.update(&event).unwrap().clone();
        let (x, y) =
            (0..12).map(|i| (i % 4, i / 4)).max_by(|a, b| m.get(a.0, a.1).total_cmp(&m.get(b.0, b.1))).unwrap();
        assert_eq!((x, y), (2, 1));
        assert!(m.get(2, 1) > 1.0, "{} bits", m.get(2, 1));
        // Repeating the event: the belief adapts, surprise falls.
        let again = s.update(&event).unwrap().get(2, 1);
        assert!(again < m.get(2, 1));
        // The chain: every model adds surprise.
        let mut c = Surprise::new(SurpriseConfig::chain(), 4, 3).unwrap();
        c.update(&calm).unwrap();
        assert!(c.update(&event).unwrap().get(2, 1) > m.get(2, 1));
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut s = Surprise::new(SurpriseConfig::default(), 4, 3).unwrap();
        assert!(s.update(&Plane::new(3, 3)).is_err());
        assert!(s.update(&Plane::from_fn(4, 3, |_, _| -1.0)).is_err());
        assert!(s.update(&Plane::from_fn(4, 3, |_, _| f32::NAN)).is_err());
        assert!(Surprise::new(SurpriseConfig { update_factor: 1.0, ..Default::default() }, 4, 3).is_err());
        assert!(Surprise::new(SurpriseConfig::default(), 0, 3).is_err());
    }
}
