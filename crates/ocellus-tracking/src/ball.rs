//! The 3D ball of the lecture's case study (SPEC 7.3): state (x, y, z, vx, vy, vz) in the
//! world frame (metres, metres per second), constant velocity with an optional gravity,
//! a ball of known radius seen through a calibrated camera, lens distortion included.
//!
//! The particle filter's model ([`BallModel`], an `ocellus_estimation` [`Model`]): each
//! particle moves by [`MotionModel`] or, boosted, is drawn from a bottom-up detection
//! (SPEC 7.4), and is weighed by the colour likelihood of the ball's image circle.

use crate::colour::{BinnedFrame, Circle, ColourModel};
use crate::detection::BallDetection;
use crate::motion::{log_add, MotionModel};
use crate::{Result, TrackingError};
use nalgebra::Vector3;
use ocellus_estimation::particle_filter::{Draw, Model};
use ocellus_geometry::camera::PinholeCamera;
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::sphere::project_sphere;
use ocellus_image::rng::SplitMix64;

/// A ball hypothesis: centre and velocity in the world frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BallState {
    /// Centre, metres.
    pub position: [f64; 3],
    /// Velocity, metres per second.
    pub velocity: [f64; 3],
}

/// The image circle of a ball of `radius_m` centred at `centre` (world, metres), through the
/// lens distortion (`ocellus_geometry::sphere::project_sphere`). `None` when the ball is not
/// fully in front of the camera.
pub fn project_ball(
    camera: &PinholeCamera,
    distortion: &Distortion,
    centre: &Vector3<f64>,
    radius_m: f64,
) -> Option<Circle> {
    project_sphere(camera, distortion, centre, radius_m).map(|[x, y, r]| Circle { x, y, r })
}

/// Spread of the distance of detection draws that keep the parent's predicted distance, as a
/// share of it (see [`BallModel`]).
pub const KEEP_DEPTH_SIGMA_FRAC: f64 = 0.03;

/// What one step of the tracker observes: the binned frame and the bottom-up detections
/// (empty for the plain filter).
#[derive(Clone, Debug, Default)]
pub struct BallFrame {
    /// The frame, binned once.
    pub binned: BinnedFrame,
    /// Colour-blob detections of the ball, 3D.
    pub detections: Vec<BallDetection>,
}

/// The tracking model: motion, camera, colour likelihood and the boosted proposal.
///
/// The proposal is the mixture of Okuma et al. (ECCV 2004), drawn per particle:
/// `q(x | x', z) = alpha q_det(x | z, x') + (1 - alpha) p(x | x')`. `q_det` puts the centre
/// on the line of sight of one of the frame's detections (chosen uniformly): half the draws
/// at the blob's own distance (Gaussian about it, see [`BallDetection`]), half at the
/// parent's predicted distance (spread [`KEEP_DEPTH_SIGMA_FRAC`]), since a blob's size gives
/// the depth only roughly and a bounce or a hit changes the direction, rarely the depth; it
/// draws the velocity as a jump of the motion model does. The
/// importance weight is corrected by `p(x | x') / q(x | x', z)` with both mixtures
/// evaluated exactly; without detections, or with `boost = 0`, it is the bootstrap filter.
#[derive(Clone, Debug)]
pub struct BallModel {
    /// The calibrated camera (world to camera).
    pub camera: PinholeCamera,
    /// Its lens distortion.
    pub distortion: Distortion,
    /// Ball radius, metres.
    pub radius_m: f64,
    /// The motion model p(x_t | x_t-1).
    pub motion: MotionModel,
    /// The colour likelihood.
    pub colour: ColourModel,
    /// Share `alpha` of the proposal drawn from the detections, in [0, 1].
    pub boost: f64,
    /// Spread of a detection draw's velocity about the parent's predicted velocity, across
    /// and along the detection's line of sight, m/s (see `DetectorConfig`).
    pub detection_velocity_sigma_mps: [f64; 2],
}

impl BallModel {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        if !(self.radius_m.is_finite() && self.radius_m > 0.0) {
            return Err(TrackingError::Invalid(format!("ball radius {} m must be finite and positive", self.radius_m)));
        }
        if !(0.0..=1.0).contains(&self.boost) {
            return Err(TrackingError::Invalid(format!("boost alpha {} is outside [0, 1]", self.boost)));
        }
        if !(self.colour.lambda.is_finite() && self.colour.lambda > 0.0) {
            return Err(TrackingError::Invalid(format!(
                "likelihood lambda {} must be finite and positive",
                self.colour.lambda
            )));
        }
        self.motion.validate()
    }

    /// The image circle of a state.
    pub fn circle(&self, s: &BallState) -> Option<Circle> {
        project_ball(&self.camera, &self.distortion, &Vector3::from(s.position), self.radius_m)
    }

    /// `ln q_det(x | z, x')`: the mixture over the detections of, for the centre, their own
    /// Gaussian and the one at the parent's predicted distance (each half), and for the
    /// velocity, the Gaussian about the parent's predicted velocity shaped by that
    /// detection's line of sight. `pred` is the parent's noise-free prediction, `dist` its
    /// distance from the camera centre.
    fn log_detection_density(&self, pred: &BallState, dist: f64, s: &BallState, dets: &[BallDetection]) -> f64 {
        let [across, along] = self.detection_velocity_sigma_mps;
        let mut l = f64::NEG_INFINITY;
        for d in dets {
            let pos = log_add(
                d.log_density(&s.position),
                d.at_distance(dist, KEEP_DEPTH_SIGMA_FRAC).log_density(&s.position),
            );
            l = log_add(l, pos + d.log_velocity_density(&pred.velocity, across, along, &s.velocity));
        }
        l - (2.0 * dets.len() as f64).ln()
    }
}

impl Model for BallModel {
    type State = BallState;
    type Observation = BallFrame;

    fn propose(&self, prev: &BallState, z: &BallFrame, rng: &mut SplitMix64) -> Draw<BallState> {
        let dets = &z.detections;
        if dets.is_empty() || self.boost == 0.0 {
            return Draw { state: self.motion.sample(prev, rng), log_prior_over_proposal: 0.0 };
        }
        let alpha = self.boost;
        let pred = self.motion.predict(prev);
        let dist = (Vector3::from(pred.position) - self.camera.centre()).norm();
        let state = if rng.unit() < alpha {
            let mut d = dets[rng.below(dets.len())];
            if rng.unit() < 0.5 {
                d = d.at_distance(dist, KEEP_DEPTH_SIGMA_FRAC);
            }
            let [across, along] = self.detection_velocity_sigma_mps;
            BallState {
                position: d.sample_position(rng),
                velocity: d.sample_velocity(&pred.velocity, across, along, rng),
            }
        } else {
            self.motion.sample(prev, rng)
        };
        let log_p = self.motion.log_density(prev, &state);
        let log_q =
            log_add(alpha.ln() + self.log_detection_density(&pred, dist, &state, dets), (1.0 - alpha).ln() + log_p);
        let ratio = log_p - log_q;
        // Both are finite for a finite state; a state at infinity is impossible.
        Draw { state, log_prior_over_proposal: if ratio.is_nan() { f64::NEG_INFINITY } else { ratio } }
    }

    fn log_likelihood(&self, s: &BallState, frame: &BallFrame) -> f64 {
        match self.circle(s) {
            Some(c) => self.colour.log_likelihood(&frame.binned, c),
            None => f64::NEG_INFINITY,
        }
    }
}
