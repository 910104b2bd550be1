//! The ball's motion model p(x_t | x_t-1) (SPEC 7.3): constant velocity with a constant
//! acceleration (gravity, optional) and white acceleration noise, plus a small probability
//! that the ball jumps somewhere the dynamics cannot explain (thrown again, picked up, a
//! tracking loss), so that a detection far from the prediction keeps a finite weight.
//!
//! The noise is the continuous white-noise acceleration model (Bar-Shalom, Li & Kirubarajan
//! 2001, sec. 6.2.2): per axis, position and velocity get the full-rank covariance
//! `q [[dt^3/3, dt^2/2], [dt^2/2, dt]]` with `q = accel_sigma^2 dt` (so the velocity spreads by
//! `accel_sigma dt` per step, as in the discrete model). Full rank matters: the boosted
//! proposal (Okuma et al. 2004) divides by this density, which the discrete white-noise model
//! (position and velocity driven by one acceleration) does not have in 6D.
//!
//! Units: metres, seconds; world frame of the camera extrinsics.

use crate::ball::BallState;
use crate::{Result, TrackingError};
use ocellus_image::rng::SplitMix64;

/// `ln(2 pi)`.
const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// Parameters of the motion model.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionModel {
    /// Time between frames, seconds.
    pub dt_s: f64,
    /// White acceleration noise per axis, m/s^2.
    pub accel_sigma: f64,
    /// Constant acceleration, m/s^2 in world axes (gravity: `[0, 9.81, 0]` for a camera
    /// frame with y down).
    pub gravity: [f64; 3],
    /// Probability per step of a jump the dynamics cannot explain, in [0, 1).
    pub jump_prob: f64,
    /// Spread of a jump's position about the prediction, metres.
    pub jump_sigma_m: f64,
    /// Spread of a jump's velocity about the previous velocity, m/s.
    pub jump_sigma_mps: f64,
}

impl MotionModel {
    /// Defaults for a thrown ball filmed at `fps`: 10 m/s^2 noise, no gravity, jumps with
    /// probability 0.02, 1 m and 2 m/s.
    pub fn at_fps(fps: f64) -> Self {
        Self {
            dt_s: 1.0 / fps,
            accel_sigma: 10.0,
            gravity: [0.0; 3],
            jump_prob: 0.02,
            jump_sigma_m: 1.0,
            jump_sigma_mps: 2.0,
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(TrackingError::Invalid(what));
        if !(self.dt_s.is_finite() && self.dt_s > 0.0) {
            return bad(format!("frame interval {} s must be finite and positive", self.dt_s));
        }
        if !(self.accel_sigma.is_finite() && self.accel_sigma > 0.0) {
            return bad(format!("acceleration noise {} m/s^2 must be finite and positive", self.accel_sigma));
        }
        if !self.gravity.iter().all(|g| g.is_finite()) {
            return bad(format!("gravity {:?} m/s^2 is not finite", self.gravity));
        }
        if !(0.0..1.0).contains(&self.jump_prob) {
            return bad(format!("jump probability {} is outside [0, 1)", self.jump_prob));
        }
        for (name, v) in [("jump_sigma_m", self.jump_sigma_m), ("jump_sigma_mps", self.jump_sigma_mps)] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} = {v} must be finite and positive"));
            }
        }
        Ok(())
    }

    /// The noise-free prediction of `prev` one step ahead.
    pub fn predict(&self, prev: &BallState) -> BallState {
        let dt = self.dt_s;
        let mut s = *prev;
        for k in 0..3 {
            s.position[k] += prev.velocity[k] * dt + 0.5 * self.gravity[k] * dt * dt;
            s.velocity[k] += self.gravity[k] * dt;
        }
        s
    }

    /// The Cholesky factor (l11, l21, l22) of one axis' position-velocity noise covariance.
    fn cholesky(&self) -> (f64, f64, f64) {
        let (dt, q) = (self.dt_s, self.accel_sigma * self.accel_sigma * self.dt_s);
        let l11 = (q * dt * dt * dt / 3.0).sqrt();
        let l21 = q.sqrt() * (3.0 * dt).sqrt() / 2.0;
        let l22 = (q * dt).sqrt() / 2.0;
        (l11, l21, l22)
    }

    /// Draws the next state.
    pub fn sample(&self, prev: &BallState, rng: &mut SplitMix64) -> BallState {
        let mut s = self.predict(prev);
        if self.jump_prob > 0.0 && rng.unit() < self.jump_prob {
            for k in 0..3 {
                s.position[k] += self.jump_sigma_m * rng.normal();
                s.velocity[k] = prev.velocity[k] + self.jump_sigma_mps * rng.normal();
            }
            return s;
        }
        let (l11, l21, l22) = self.cholesky();
        for k in 0..3 {
            let (a, b) = rng.normal_pair();
            s.position[k] += l11 * a;
            s.velocity[k] += l21 * a + l22 * b;
        }
        s
    }

    /// `ln p(next | prev)`: the mixture of the white-noise Gaussian and the jump Gaussian.
    pub fn log_density(&self, prev: &BallState, next: &BallState) -> f64 {
        let m = self.predict(prev);
        let (l11, l21, l22) = self.cholesky();
        // Per axis: whiten (dp, dv) with the Cholesky factor; log det = 2 ln(l11 l22).
        let mut quad = 0.0;
        for k in 0..3 {
            let a = (next.position[k] - m.position[k]) / l11;
            let b = (next.velocity[k] - m.velocity[k] - l21 * a) / l22;
            quad += a * a + b * b;
        }
        let smooth = (1.0 - self.jump_prob).ln() - 3.0 * (LN_2PI + (l11 * l22).ln()) - 0.5 * quad;
        if self.jump_prob == 0.0 {
            return smooth;
        }
        let jump = self.jump_prob.ln() + self.log_jump_velocity_density(prev, next) + {
            let mut q = 0.0;
            for k in 0..3 {
                let d = (next.position[k] - m.position[k]) / self.jump_sigma_m;
                q += d * d;
            }
            -1.5 * LN_2PI - 3.0 * self.jump_sigma_m.ln() - 0.5 * q
        };
        log_add(smooth, jump)
    }

    /// Draws a velocity as a jump does: about the previous velocity.
    pub fn sample_jump_velocity(&self, prev: &BallState, rng: &mut SplitMix64) -> [f64; 3] {
        std::array::from_fn(|k| prev.velocity[k] + self.jump_sigma_mps * rng.normal())
    }

    /// `ln` of the jump's velocity density at `next`.
    pub fn log_jump_velocity_density(&self, prev: &BallState, next: &BallState) -> f64 {
        let mut q = 0.0;
        for k in 0..3 {
            let d = (next.velocity[k] - prev.velocity[k]) / self.jump_sigma_mps;
            q += d * d;
        }
        -1.5 * LN_2PI - 3.0 * self.jump_sigma_mps.ln() - 0.5 * q
    }
}

/// `ln(e^a + e^b)` without overflow; `-inf` when both are.
pub fn log_add(a: f64, b: f64) -> f64 {
    let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
    if hi == f64::NEG_INFINITY {
        return hi;
    }
    hi + (lo - hi).exp().ln_1p()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(p: [f64; 3], v: [f64; 3]) -> BallState {
        BallState { position: p, velocity: v }
    }

    #[test]
    fn samples_have_the_stated_moments() {
        let m = MotionModel { jump_prob: 0.0, gravity: [0.0, 9.81, 0.0], ..MotionModel::at_fps(30.0) };
        let prev = state([0.1, -0.2, 2.0], [1.0, -2.0, 0.5]);
        let pred = m.predict(&prev);
        let (n, dt, q) = (200_000, m.dt_s, m.accel_sigma.powi(2) * m.dt_s);
        let mut rng = SplitMix64::new(4);
        let (mut sp, mut sv, mut spp, mut svv, mut spv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let s = m.sample(&prev, &mut rng);
            let (dp, dv) = (s.position[1] - pred.position[1], s.velocity[1] - pred.velocity[1]);
            sp += dp;
            sv += dv;
            spp += dp * dp;
            svv += dv * dv;
            spv += dp * dv;
        }
        let nf = n as f64;
        // Closed form: q dt^3/3, q dt, q dt^2/2; the sample moments within 2 %.
        for (got, want) in [(spp / nf, q * dt.powi(3) / 3.0), (svv / nf, q * dt), (spv / nf, q * dt * dt / 2.0)] {
            assert!((got / want - 1.0).abs() < 0.02, "{got} vs {want}");
        }
        assert!((sp / nf).abs() < 3.0 * (q * dt.powi(3) / 3.0 / nf).sqrt());
        assert!((sv / nf).abs() < 3.0 * (q * dt / nf).sqrt());
        // Gravity moved the mean: y + vy dt + g dt^2 / 2.
        assert!((pred.position[1] - (-0.2 - 2.0 * dt + 0.5 * 9.81 * dt * dt)).abs() < 1e-15);
    }

    #[test]
    fn the_density_integrates_to_one_along_a_line() {
        // Along a line through the mean in the 6D space, integrate the density numerically and
        // compare with the closed-form 1D marginal: a Gaussian with variance u^T Sigma u.
        let m = MotionModel { jump_prob: 0.0, ..MotionModel::at_fps(30.0) };
        let prev = state([0.0, 0.0, 2.0], [0.3, 0.0, -0.1]);
        let pred = m.predict(&prev);
        let (dt, q) = (m.dt_s, m.accel_sigma.powi(2) * m.dt_s);
        // The density at the mean: (2 pi)^-3 det(Sigma)^-1/2, det per axis q^2 dt^4 / 12.
        let want = -3.0 * LN_2PI - 1.5 * (q * q * dt.powi(4) / 12.0).ln();
        assert!((m.log_density(&prev, &pred) - want).abs() < 1e-9);
        // A point one position sigma away on x only: the conditional quadratic form is
        // dp^2 / (q dt^3 / 3) / (1 - rho^2) with rho^2 = 3/4.
        let s11 = q * dt.powi(3) / 3.0;
        let mut off = pred;
        off.position[0] += s11.sqrt();
        let drop = m.log_density(&prev, &pred) - m.log_density(&prev, &off);
        assert!((drop - 0.5 / (1.0 - 0.75)).abs() < 1e-9, "{drop}");
    }

    #[test]
    fn jumps_keep_far_states_possible() {
        let smooth = MotionModel { jump_prob: 0.0, ..MotionModel::at_fps(30.0) };
        let jumpy = MotionModel::at_fps(30.0);
        let prev = state([0.0, 0.0, 2.0], [0.0; 3]);
        let far = state([0.4, 0.0, 2.3], [1.0, 0.0, 0.0]);
        assert!(smooth.log_density(&prev, &far) < -1e4);
        let l = jumpy.log_density(&prev, &far);
        // The jump term alone, by hand.
        let pos = -1.5 * LN_2PI - 0.5 * (0.16 + 0.09);
        let vel = -1.5 * LN_2PI - 3.0 * 2f64.ln() - 0.5 * 1.0 / 4.0;
        assert!((l - (0.02f64.ln() + pos + vel)).abs() < 1e-9, "{l}");
        // Near the prediction the smooth part dominates and the jump barely changes it.
        let p = jumpy.predict(&prev);
        assert!((jumpy.log_density(&prev, &p) - smooth.log_density(&prev, &p) - 0.98f64.ln()).abs() < 1e-6);
    }

    #[test]
    fn bad_parameters_are_refused() {
        let ok = MotionModel::at_fps(60.0);
        assert!(ok.validate().is_ok());
        for m in [
            MotionModel { dt_s: 0.0, ..ok },
            MotionModel { accel_sigma: f64::NAN, ..ok },
            MotionModel { gravity: [0.0, f64::INFINITY, 0.0], ..ok },
            MotionModel { jump_prob: 1.0, ..ok },
            MotionModel { jump_sigma_m: -1.0, ..ok },
        ] {
            assert!(m.validate().is_err(), "{m:?}");
        }
        assert_eq!(log_add(f64::NEG_INFINITY, f64::NEG_INFINITY), f64::NEG_INFINITY);
        assert!((log_add(0.0, 0.0) - 2f64.ln()).abs() < 1e-15);
    }
}
