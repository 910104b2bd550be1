//! The 3D ball of the lecture's case study (SPEC 7.3): state (x, y, z, vx, vy, vz) in the
//! world frame (metres, metres per second), constant velocity with an optional gravity,
//! a ball of known radius seen through a calibrated camera, lens distortion included.
//!
//! The particle filter's model ([`BallModel`], an `ocellus_estimation` [`Model`]): each
//! particle moves by [`MotionModel`] or, boosted, is drawn from a bottom-up detection
//! (SPEC 7.4), and is weighed by the colour likelihood of the ball's image circle.

use crate::binning::{union_rect, BinnedFrame};
use crate::colour::{Circle, ColourModel};
use crate::detection::BallDetection;
use crate::motion::{log_add, MotionModel};
use crate::{Result, TrackingError};
use nalgebra::Vector3;
use ocellus_estimation::particle_filter::{Draw, Model, ParticleFilter, StepReport};
use ocellus_geometry::camera::PinholeCamera;
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::sphere::project_sphere;
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;
use rayon::prelude::*;

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

/// Where the cut-blob term of [`BallModel::log_cut_blob`] stops growing, in its standard
/// deviations.
pub const CUT_BLOB_CAP_SIGMAS: f64 = 3.0;

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
    /// A frame where no particle's circle reaches this, in [-1, 1], carries no evidence: the
    /// ball is hidden, and [`Self::weigh`] leaves the weights as they are (`-1` weighs every
    /// frame). Compared with the likelihood's exponent over lambda: the colour score plus
    /// the weighted rim term (`ColourModel::log_likelihood`).
    pub evidence_score: f64,
    /// Spread of a cut blob's circle as an observation of the ball's image circle, pixels
    /// (centre and radius), in [0, inf); 0 leaves cut blobs out of the likelihood (see
    /// [`Self::log_cut_blob`]).
    pub cut_sigma_px: f64,
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
        if !(self.cut_sigma_px.is_finite() && self.cut_sigma_px >= 0.0) {
            return Err(TrackingError::Invalid(format!(
                "cut-blob spread {} px must be finite and at least 0",
                self.cut_sigma_px
            )));
        }
        if !(self.colour.rim_weight.is_finite() && self.colour.rim_weight >= 0.0) {
            return Err(TrackingError::Invalid(format!(
                "rim weight {} must be finite and at least 0",
                self.colour.rim_weight
            )));
        }
        self.motion.validate()
    }

    /// The log likelihood of image circle `c` under the frame's cut blobs: where the
    /// detector saw the ball cut by an occluder, its circle (from the blob's longer side and
    /// round side, see [`crate::detection`]) observes the ball's image circle, with spread
    /// [`Self::cut_sigma_px`] on the centre and the radius. There the colour likelihood
    /// cannot: a ball half hidden behind a panel scores higher on a circle 9 % too small
    /// inside its visible part than on its own circle, half occluder (generated bounce 1,
    /// frame 48: `exp(2.6)` times more likely), and the boosted filter's depth ran 9-11 % too
    /// far for two frames after the ball came out. The term is a truncated quadratic,
    /// `-0.5 min(d^2 / sigma^2, 9)` with d the distance in (x, y, r) to the nearest cut
    /// blob's circle, pixels: circles nowhere near a cut blob (a distractor's) all pay the
    /// same 4.5, so they are not pulled. 0 when the frame has no cut blob or the term is off.
    pub fn log_cut_blob(&self, c: &Circle, dets: &[BallDetection]) -> f64 {
        if self.cut_sigma_px <= 0.0 {
            return 0.0;
        }
        let cap = CUT_BLOB_CAP_SIGMAS * CUT_BLOB_CAP_SIGMAS;
        let mut best: Option<f64> = None;
        for d in dets.iter().filter(|d| d.cut) {
            let q = (c.x - d.circle.x).powi(2) + (c.y - d.circle.y).powi(2) + (c.r - d.circle.r).powi(2);
            let q = (q / (self.cut_sigma_px * self.cut_sigma_px)).min(cap);
            best = Some(best.map_or(q, |b: f64| b.min(q)));
        }
        best.map_or(0.0, |q| -0.5 * q)
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

impl BallModel {
    /// The pixel rectangle [x0, y0, x1, y1) that holds every likelihood sample of every
    /// state's image circle in a `w` x `h` frame: binning only it
    /// ([`BinnedFrame::update_region`]) gives the same scores as binning the frame. Empty
    /// when no state is in view.
    pub fn samples_region(&self, states: &[BallState], w: usize, h: usize) -> [usize; 4] {
        let circles: Vec<Option<Circle>> = states.par_iter().map(|s| self.circle(s)).collect();
        circles_region(&circles, w, h)
    }

    /// One step of a filter without detections (the plain SIR/SIS, `boost = 0`): moves the
    /// particles, bins only the region their circles read into `obs`
    /// ([`Self::samples_region`]; the scores are those of the whole frame binned), then weighs
    /// and resamples. `obs.detections` is cleared.
    pub fn step_in_region(
        &self,
        filter: &mut ParticleFilter<BallState>,
        frame: &Plane<[u8; 3]>,
        obs: &mut BallFrame,
    ) -> Result<StepReport> {
        obs.detections.clear();
        filter.propose(self, obs);
        let (w, h) = frame.size();
        // Each circle is projected once, for the region and for the likelihood.
        let circles: Vec<Option<Circle>> = filter.particles().par_iter().map(|s| self.circle(s)).collect();
        obs.binned.update_region(frame, circles_region(&circles, w, h));
        self.weigh_circles(filter, obs, &circles)
    }

    /// The weight update of a step, after `filter.propose`: the colour likelihood of every
    /// particle, unless no particle's circle reaches [`Self::evidence_score`]. Then the ball
    /// is taken to be hidden (a full occlusion) and the frame carries no evidence: the
    /// particles keep their weights and coast on the motion model. Weighing such a frame
    /// would hand the cloud to whichever wrong circles happen to score best, typically
    /// tiny, far ones, and it would climb away from the ball while it is hidden.
    pub fn weigh(&self, filter: &mut ParticleFilter<BallState>, obs: &BallFrame) -> Result<StepReport> {
        let circles: Vec<Option<Circle>> = filter.particles().par_iter().map(|s| self.circle(s)).collect();
        self.weigh_circles(filter, obs, &circles)
    }

    /// The weight update of a frame taken to carry no evidence, after `filter.propose`: the
    /// particles keep their weights (times the proposal's importance ratio) and coast on the
    /// motion model; states out of view (behind the camera) stay impossible.
    pub fn coast(&self, filter: &mut ParticleFilter<BallState>) -> Result<StepReport> {
        let circles: Vec<Option<Circle>> = filter.particles().par_iter().map(|s| self.circle(s)).collect();
        Ok(filter.weigh_proposed_with(|_, out| carry_no_evidence(&circles, out))?)
    }

    /// [`Self::weigh`] with the particles' image circles already projected (`circles[i]` of
    /// particle `i`; `None` out of view).
    fn weigh_circles(
        &self,
        filter: &mut ParticleFilter<BallState>,
        obs: &BallFrame,
        circles: &[Option<Circle>],
    ) -> Result<StepReport> {
        let lambda = self.colour.lambda;
        let least = lambda * self.evidence_score;
        let binned = &obs.binned;
        Ok(filter.weigh_proposed_with(|_, out| {
            out.par_iter_mut().zip(circles.par_iter()).for_each(|(l, c)| {
                *l = c.map_or(f64::NEG_INFINITY, |c| self.colour.log_likelihood(binned, c));
            });
            if out.iter().all(|&l| l < least) {
                carry_no_evidence(circles, out);
            } else if self.cut_sigma_px > 0.0 && obs.detections.iter().any(|d| d.cut) {
                out.par_iter_mut().zip(circles.par_iter()).for_each(|(l, c)| {
                    if let Some(c) = c {
                        *l += self.log_cut_blob(c, &obs.detections);
                    }
                });
            }
        })?)
    }
}

/// The log likelihoods of a frame without evidence: 0 for every state in view, so the
/// weights are kept; states out of view (behind the camera) stay impossible.
fn carry_no_evidence(circles: &[Option<Circle>], out: &mut [f64]) {
    out.iter_mut().zip(circles).for_each(|(l, c)| *l = if c.is_some() { 0.0 } else { f64::NEG_INFINITY });
}

/// The rectangle holding every sample of every circle in a `w` x `h` frame (`None`: out of
/// view); empty when none is in view.
fn circles_region(circles: &[Option<Circle>], w: usize, h: usize) -> [usize; 4] {
    circles.par_iter().map(|c| c.map_or([0; 4], |c| c.samples_rect(w, h))).reduce(|| [0; 4], union_rect)
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
            Some(c) => self.colour.log_likelihood(&frame.binned, c) + self.log_cut_blob(&c, &frame.detections),
            None => f64::NEG_INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::MotionModel;
    use nalgebra::Matrix3;
    use ocellus_geometry::camera::Intrinsics;

    /// The cat photo, the same with an orange ball of 5 cm at `ball` seen through a camera of
    /// focal 500 px with `distortion`, and the plain filter's model of it.
    fn ball_on_photo(
        distortion: Distortion,
        ball: &Vector3<f64>,
        evidence_score: f64,
    ) -> (Plane<[u8; 3]>, Plane<[u8; 3]>, BallModel) {
        let photo = ocellus_io::read_image(ocellus_testdata::asset("chelsea.png")).unwrap().to_u8();
        let (w, h) = photo.size();
        let k = Intrinsics { fx: 500.0, fy: 500.0, cx: w as f64 / 2.0, cy: h as f64 / 2.0, skew: 0.0 };
        let camera = PinholeCamera { k, r: Matrix3::identity(), t: Vector3::zeros() };
        let c = project_ball(&camera, &distortion, ball, 0.05).unwrap();
        let frame = Plane::from_fn(w, h, |x, y| {
            if (x as f64 - c.x).powi(2) + (y as f64 - c.y).powi(2) <= c.r * c.r {
                [240, 110, 30]
            } else {
                photo.get(x, y)
            }
        });
        let model = BallModel {
            camera,
            distortion,
            radius_m: 0.05,
            motion: MotionModel::at_fps(30.0),
            colour: ColourModel::from_colour([240, 110, 30]),
            boost: 0.0,
            detection_velocity_sigma_mps: [3.0, 0.5],
            evidence_score,
            cut_sigma_px: 0.0,
        };
        (photo, frame, model)
    }

    #[test]
    fn binning_only_the_particles_region_gives_the_scores_of_the_whole_frame() {
        let distortion = Distortion { k1: -0.1, k2: 0.01, k3: 0.0, p1: 0.0, p2: 0.0 };
        let ball = Vector3::new(0.1, 0.05, 1.5);
        let (_, frame, model) = ball_on_photo(distortion, &ball, -1.0);
        let (w, h) = frame.size();
        let mut rng = SplitMix64::new(3);
        // A cloud about the ball, some of it reaching past the frame's edges.
        let states: Vec<BallState> = (0..500)
            .map(|i| {
                let s = if i % 50 == 0 { 0.8 } else { 0.05 };
                BallState {
                    position: [ball.x + s * rng.normal(), ball.y + s * rng.normal(), ball.z + 0.2 * rng.normal()],
                    velocity: [0.0; 3],
                }
            })
            .collect();
        let full = BallFrame { binned: BinnedFrame::new(&frame), detections: Vec::new() };
        let region = model.samples_region(&states, w, h);
        assert!((region[2] - region[0]) * (region[3] - region[1]) < w * h, "{region:?}");
        let mut part = BallFrame::default();
        part.binned.update_region(&frame, region);
        for s in &states {
            let (a, b) = (model.log_likelihood(s, &full), model.log_likelihood(s, &part));
            assert_eq!(a.to_bits(), b.to_bits(), "{s:?}");
        }
        assert_eq!(model.samples_region(&[], w, h), [0; 4]);
    }

    #[test]
    fn a_frame_where_no_particle_sees_the_ball_carries_no_evidence() {
        let (photo, with_ball, model) = ball_on_photo(Distortion::default(), &Vector3::new(0.0, 0.0, 1.5), 0.2);
        let mut rng = SplitMix64::new(8);
        let cloud: Vec<BallState> = (0..300)
            .map(|_| BallState {
                position: [0.02 * rng.normal(), 0.02 * rng.normal(), 1.5 + 0.1 * rng.normal()],
                velocity: [0.0; 3],
            })
            .collect();
        let cfg = ocellus_estimation::particle_filter::FilterConfig { resample_below: 0.0, ..Default::default() };
        let weigh = |m: &BallModel, frame: &Plane<[u8; 3]>| {
            let mut f = ParticleFilter::new(cfg, cloud.clone()).unwrap();
            let obs = BallFrame { binned: BinnedFrame::new(frame), detections: Vec::new() };
            f.propose(m, &obs);
            let best =
                f.particles().iter().map(|p| m.colour.score(&obs.binned, m.circle(p).unwrap())).fold(-1.0, f64::max);
            (m.weigh(&mut f, &obs).unwrap().ess, best)
        };
        // The ball hidden (the photo alone): no circle scores 0.2, the weights stay equal.
        let (ess, best) = weigh(&model, &photo);
        assert!(best < 0.2, "{best}");
        assert!((ess - 300.0).abs() < 1e-9, "{ess}");
        // Weighed anyway, the cloud would follow the best wrong circles.
        let always = BallModel { evidence_score: -1.0, ..model.clone() };
        assert!(weigh(&always, &photo).0 < 250.0);
        // The ball in view: the frame is weighed.
        let (ess, best) = weigh(&model, &with_ball);
        assert!(best > 0.5 && ess < 100.0, "best {best}, ess {ess}");
    }

    #[test]
    fn a_cut_blob_pulls_circles_near_it_and_no_others() {
        let (_, _, model) = ball_on_photo(Distortion::default(), &Vector3::new(0.0, 0.0, 1.5), 0.2);
        let det = |x: f64, r: f64, cut: bool| BallDetection {
            circle: Circle { x, y: 100.0, r },
            position: [0.0, 0.0, 1.5],
            direction: [0.0, 0.0, 1.0],
            distance_m: 1.5,
            sigma_lateral_m: 0.01,
            sigma_depth_m: 0.1,
            cut,
        };
        let on = BallModel { cut_sigma_px: 0.5, ..model.clone() };
        let c = |x: f64, r: f64| Circle { x, y: 100.0, r };
        let dets = [det(100.0, 12.0, true), det(200.0, 20.0, true), det(300.0, 12.0, false)];
        // 0 on a cut blob's circle; a Gaussian of 0.5 px in (x, y, r) near it.
        assert_eq!(on.log_cut_blob(&c(100.0, 12.0), &dets), 0.0);
        assert!((on.log_cut_blob(&c(100.3, 12.4), &dets) - -0.5 * 0.25 / 0.25).abs() < 1e-12);
        // The nearest cut blob counts, past 3 sigma all alike; an uncut blob does not count.
        assert!((on.log_cut_blob(&c(199.0, 20.0), &dets) - -0.5 * 4.0).abs() < 1e-12);
        assert_eq!(on.log_cut_blob(&c(100.0, 14.0), &dets), -4.5);
        assert_eq!(on.log_cut_blob(&c(300.0, 12.0), &dets), -4.5);
        // No cut blob, or the term off: nothing.
        assert_eq!(on.log_cut_blob(&c(100.0, 14.0), &dets[2..]), 0.0);
        assert_eq!(model.log_cut_blob(&c(100.0, 14.0), &dets), 0.0);
        assert!(BallModel { cut_sigma_px: f64::NAN, ..model.clone() }.validate().is_err());
        assert!(BallModel { cut_sigma_px: -1.0, ..model }.validate().is_err());
    }
}
