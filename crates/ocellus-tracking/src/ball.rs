//! The 3D ball of the lecture's case study (SPEC 7.3): state (x, y, z, vx, vy, vz) in the
//! world frame (metres, metres per second), constant velocity with an optional gravity,
//! a ball of known radius seen through a calibrated camera, lens distortion included.
//!
//! The particle filter's model ([`BallModel`], an `ocellus_estimation` [`Model`]): each
//! particle moves with its velocity over `dt` plus white acceleration noise (the discrete
//! white-noise acceleration model, Bar-Shalom et al. 2001, ch. 6), and is weighed by the
//! colour likelihood of the ball's image circle in the frame.

use crate::colour::{BinnedFrame, Circle, ColourModel};
use crate::{Result, TrackingError};
use nalgebra::Vector3;
use ocellus_estimation::particle_filter::{Draw, Model};
use ocellus_geometry::camera::PinholeCamera;
use ocellus_geometry::distortion::Distortion;
use ocellus_image::rng::SplitMix64;

/// A ball hypothesis: centre and velocity in the world frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BallState {
    /// Centre, metres.
    pub position: [f64; 3],
    /// Velocity, metres per second.
    pub velocity: [f64; 3],
}

/// The image circle of a ball of `radius_m` centred at `centre` (world, metres): the centre's
/// pixel and the radius `f R / sqrt(d^2 - R^2)` (the sphere's angular radius, d its distance
/// from the camera), both through the lens distortion. `None` when the ball is not fully in
/// front of the camera.
pub fn project_ball(
    camera: &PinholeCamera,
    distortion: &Distortion,
    centre: &Vector3<f64>,
    radius_m: f64,
) -> Option<Circle> {
    let xc = camera.r * centre + camera.t;
    let d2 = xc.norm_squared();
    if !(xc.z > radius_m && d2 > radius_m * radius_m && radius_m > 0.0) {
        return None;
    }
    let (px, _) = camera.project(centre).ok()?;
    let r_px = camera.k.fx * radius_m / (d2 - radius_m * radius_m).sqrt();
    let (cx, cy) = distortion.distort_pixel(&camera.k, px.x, px.y);
    let (ex, ey) = distortion.distort_pixel(&camera.k, px.x + r_px, px.y);
    let r = (ex - cx).hypot(ey - cy);
    (cx.is_finite() && cy.is_finite() && r.is_finite()).then_some(Circle { x: cx, y: cy, r })
}

/// The tracking model: motion, camera and colour likelihood.
#[derive(Clone, Debug)]
pub struct BallModel {
    /// The calibrated camera (world to camera).
    pub camera: PinholeCamera,
    /// Its lens distortion.
    pub distortion: Distortion,
    /// Ball radius, metres.
    pub radius_m: f64,
    /// Time between frames, seconds.
    pub dt_s: f64,
    /// Standard deviation of the white acceleration noise per axis, m/s^2.
    pub accel_sigma: f64,
    /// Constant acceleration (e.g. gravity, [0, 9.81, 0] for y down), m/s^2.
    pub gravity: [f64; 3],
    /// The colour likelihood.
    pub colour: ColourModel,
}

impl BallModel {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(self.radius_m) && ok(self.dt_s) && self.accel_sigma.is_finite() && self.accel_sigma >= 0.0) {
            return Err(TrackingError::Invalid(format!(
                "ball radius {} m, frame interval {} s and acceleration noise {} m/s^2 must be finite (and positive)",
                self.radius_m, self.dt_s, self.accel_sigma
            )));
        }
        if !self.gravity.iter().all(|g| g.is_finite()) {
            return Err(TrackingError::Invalid(format!("gravity {:?} is not finite", self.gravity)));
        }
        Ok(())
    }

    /// The image circle of a state.
    pub fn circle(&self, s: &BallState) -> Option<Circle> {
        project_ball(&self.camera, &self.distortion, &Vector3::from(s.position), self.radius_m)
    }
}

impl Model for BallModel {
    type State = BallState;
    type Observation = BinnedFrame;

    /// Constant velocity with white acceleration noise a ~ N(0, sigma^2) per axis over the
    /// interval: p += v dt + (g + a) dt^2 / 2, v += (g + a) dt. The proposal is the motion
    /// model (the bootstrap filter), so the prior/proposal ratio is 1.
    fn propose(&self, prev: &BallState, _: &BinnedFrame, rng: &mut SplitMix64) -> Draw<BallState> {
        let dt = self.dt_s;
        let mut s = *prev;
        for k in 0..3 {
            let a = self.gravity[k] + self.accel_sigma * rng.normal();
            s.position[k] += prev.velocity[k] * dt + 0.5 * a * dt * dt;
            s.velocity[k] += a * dt;
        }
        Draw { state: s, log_prior_over_proposal: 0.0 }
    }

    fn log_likelihood(&self, s: &BallState, frame: &BinnedFrame) -> f64 {
        match self.circle(s) {
            Some(c) => self.colour.log_likelihood(frame, c),
            None => f64::NEG_INFINITY,
        }
    }
}
