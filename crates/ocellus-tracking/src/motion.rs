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
    /// A floor the ball bounces on (`None`: no floor).
    #[serde(default)]
    pub floor: Option<Floor>,
}

/// A plane the ball's centre bounces off: a ball thrown or dropped onto the ground.
///
/// The centre may not pass `normal . p = offset_m` while moving along `normal`: when the
/// noise-free flight of a step reaches the plane, the ball bounces at the instant of contact
/// (found in closed form under the constant acceleration) and its velocity along `normal`
/// turns and shrinks by `restitution`; the rest of the step flies on from there. For a floor
/// at camera-frame height `y_floor` (y down) and a ball of radius `R`: `normal = [0, 1, 0]`,
/// `offset_m = y_floor - R`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Floor {
    /// Unit normal pointing into the floor, world axes.
    pub normal: [f64; 3],
    /// Where the centre touches: `normal . p = offset_m`, metres.
    pub offset_m: f64,
    /// Share of the normal speed kept by a bounce, in [0, 1].
    pub restitution: f64,
}

impl Floor {
    /// A horizontal floor for a camera frame with y down: the ball of `radius_m` touches it
    /// when its centre's y is `y_floor_m - radius_m`.
    pub fn below(y_floor_m: f64, radius_m: f64, restitution: f64) -> Self {
        Self { normal: [0.0, 1.0, 0.0], offset_m: y_floor_m - radius_m, restitution }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let n = self.normal.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(n.is_finite() && (n - 1.0).abs() < 1e-6) {
            return Err(TrackingError::Invalid(format!("floor normal {:?} is not a unit vector", self.normal)));
        }
        if !self.offset_m.is_finite() {
            return Err(TrackingError::Invalid(format!("floor offset {} m is not finite", self.offset_m)));
        }
        if !(0.0..=1.0).contains(&self.restitution) {
            return Err(TrackingError::Invalid(format!("restitution {} is outside [0, 1]", self.restitution)));
        }
        Ok(())
    }

    /// Time from the start of a step until the centre, at height `h` above the contact plane
    /// (`h = offset - normal . p`, positive above) moving with normal speed `vn` under normal
    /// acceleration `an`, touches it; `None` when not within `dt`.
    fn contact_time(h: f64, vn: f64, an: f64, dt: f64) -> Option<f64> {
        if h <= 0.0 {
            // Already at or past the plane: it bounces now if it is still moving in.
            return (vn > 0.0).then_some(0.0);
        }
        // h - vn t - an t^2 / 2 = 0, the first positive root.
        let t = if an.abs() < 1e-12 {
            (vn > 0.0).then(|| h / vn)?
        } else {
            let disc = vn * vn + 2.0 * an * h;
            if disc < 0.0 {
                return None;
            }
            // The root of the stable form: 2h / (vn + sqrt(disc)).
            let d = vn + disc.sqrt();
            if d <= 0.0 {
                return None;
            }
            2.0 * h / d
        };
        (t <= dt).then_some(t)
    }
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
            floor: None,
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
        self.floor.as_ref().map_or(Ok(()), Floor::validate)
    }

    /// The noise-free prediction of `prev` one step ahead, bouncing off the floor if any.
    pub fn predict(&self, prev: &BallState) -> BallState {
        let dt = self.dt_s;
        let mut s = *prev;
        for k in 0..3 {
            s.position[k] += prev.velocity[k] * dt + 0.5 * self.gravity[k] * dt * dt;
            s.velocity[k] += self.gravity[k] * dt;
        }
        let Some(f) = &self.floor else { return s };
        let dot = |a: &[f64; 3]| f.normal[0] * a[0] + f.normal[1] * a[1] + f.normal[2] * a[2];
        let (h, vn, an) = (f.offset_m - dot(&prev.position), dot(&prev.velocity), dot(&self.gravity));
        let Some(tc) = Floor::contact_time(h, vn, an, dt) else { return s };
        // Along the normal: fly to the contact, turn, fly the rest of the step. Across it the
        // flight is unchanged. One bounce per step (a ball resting on the floor bounces with
        // ever smaller speeds; the step's noise covers the rest).
        let rest = dt - tc;
        let v_out = -f.restitution * (vn + an * tc);
        let h_end = -(v_out * rest + 0.5 * an * rest * rest);
        let (pn, vn_end) = (f.offset_m - h_end.max(0.0), v_out + an * rest);
        let (pn_free, vn_free) = (dot(&s.position), dot(&s.velocity));
        for k in 0..3 {
            s.position[k] += (pn - pn_free) * f.normal[k];
            s.velocity[k] += (vn_end - vn_free) * f.normal[k];
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

    /// The flight of `prev` over `dt` in `substeps` Euler-exact steps with the bounce
    /// applied at each substep's end (the generator's way): the reference for `predict`.
    fn fine_flight(prev: &BallState, g: f64, floor_c: f64, e: f64, dt: f64, substeps: usize) -> BallState {
        let (mut p, mut v) = (prev.position, prev.velocity);
        let h = dt / substeps as f64;
        for _ in 0..substeps {
            for k in 0..3 {
                let a = if k == 1 { g } else { 0.0 };
                p[k] += v[k] * h + 0.5 * a * h * h;
                v[k] += a * h;
            }
            if p[1] > floor_c && v[1] > 0.0 {
                p[1] = 2.0 * floor_c - p[1];
                v[1] *= -e;
            }
        }
        state(p, v)
    }

    #[test]
    fn the_floor_bounces_the_prediction_at_the_instant_of_contact() {
        let floor = Floor::below(0.5, 0.05, 0.8);
        let m = MotionModel { gravity: [0.0, 9.81, 0.0], floor: Some(floor), ..MotionModel::at_fps(30.0) };
        // Falling onto the floor within the step, early, late, and starting on it.
        for (y, vy) in [(0.40, 3.0), (0.44, 0.5), (0.3, 4.0), (0.45, 2.0), (0.2, -1.0)] {
            let prev = state([0.1, y, 2.0], [0.3, vy, -0.2]);
            let got = m.predict(&prev);
            let want = fine_flight(&prev, 9.81, 0.45, 0.8, m.dt_s, 200_000);
            for k in 0..3 {
                assert!((got.position[k] - want.position[k]).abs() < 1e-5, "y {y} vy {vy}: {got:?} vs {want:?}");
                assert!((got.velocity[k] - want.velocity[k]).abs() < 1e-3, "y {y} vy {vy}: {got:?} vs {want:?}");
            }
            assert!(got.position[1] <= 0.45 + 1e-12);
        }
        // Far above the floor, or rising away from it: the free flight.
        let free = MotionModel { floor: None, ..m };
        for prev in [state([0.0, -0.5, 2.0], [0.0, 1.0, 0.0]), state([0.0, 0.44, 2.0], [0.0, -2.0, 0.0])] {
            assert_eq!(m.predict(&prev), free.predict(&prev));
        }
        // A tilted floor bounces along its normal only: the speed along the plane is kept.
        let n = [0.0, 0.6, 0.8];
        let tilted = MotionModel {
            gravity: [0.0; 3],
            floor: Some(Floor { normal: n, offset_m: 1.0, restitution: 1.0 }),
            ..MotionModel::at_fps(30.0)
        };
        let prev = state([0.0, 0.0, 1.2], [0.5, 3.0, 0.0]);
        let s = tilted.predict(&prev);
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        assert!((dot(s.velocity, n) + dot(prev.velocity, n)).abs() < 1e-12, "{s:?}");
        assert!((s.velocity[0] - 0.5).abs() < 1e-12);
        let speed = |v: [f64; 3]| dot(v, v).sqrt();
        assert!((speed(s.velocity) - speed(prev.velocity)).abs() < 1e-12);
        assert!(dot(s.position, n) <= 1.0);
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
            MotionModel { floor: Some(Floor { normal: [0.0, 2.0, 0.0], offset_m: 0.5, restitution: 0.8 }), ..ok },
            MotionModel { floor: Some(Floor { offset_m: f64::NAN, ..Floor::below(0.5, 0.05, 0.8) }), ..ok },
            MotionModel { floor: Some(Floor::below(0.5, 0.05, 1.5)), ..ok },
        ] {
            assert!(m.validate().is_err(), "{m:?}");
        }
        assert_eq!(log_add(f64::NEG_INFINITY, f64::NEG_INFINITY), f64::NEG_INFINITY);
        assert!((log_add(0.0, 0.0) - 2f64.ln()).abs() < 1e-15);
    }
}
