//! An active stereo head that keeps a tracked ball in both foveas (SPEC 3.4, 4.3, 7; the
//! lecture's Challenge 1: "track my hand with an active stereo head at 50 Hz ... do the same
//! with the iCub at 60 Hz").
//!
//! The head: a pan-tilt neck and two eyes `baseline_m` apart that verge symmetrically, each
//! an ideal pinhole camera. Frames: the head base is the world frame of [`BallWorld`] (x
//! right, y down, z forward, metres); pan turns about y (positive: right), tilt about x
//! (positive: up); the left eye turns right by half the vergence, the right eye left.
//!
//! Each control step (`1 / control_hz` of simulated time):
//! 1. both eyes render the world at their current pose ([`render_view`]);
//! 2. the ball tracker ([`BallTracker`], boosted) takes the left eye's frame with that eye's
//!    pose and gives the ball's 3D position in the head frame;
//! 3. gaze: when the estimate lies more than `saccade_threshold_deg` from the gaze direction,
//!    a saccade starts towards where the ball will be when it ends; its duration follows the
//!    main sequence `D = 21 ms + 2.2 ms/deg x A` (Carpenter 1988, *Movements of the Eyes*) and
//!    its position the minimum-jerk profile `10 s^3 - 15 s^4 + 6 s^5` (Flash & Hogan 1985), so
//!    the peak velocity is `1.875 A / D` (436 deg/s for 10 deg) and grows with the amplitude.
//!    Between saccades, smooth pursuit: the estimate's angular velocity plus
//!    `pursuit_gain` x the error, at most `max_pursuit_deg_s`;
//! 4. vergence: the disparity at the left fovea against the right image (the log-polar
//!    [`VergenceTracker`], SPEC 4.3) turns the eyes until it is 0; without a good match
//!    (correlation below 0.5) or with the ball lost, the vergence is held.
//!
//! The record of each step: the gaze angles, the angle between each eye's optical axis and the
//! true ball (the foveal error), whether a saccade was under way, the disparity.

use crate::{Result, SimError};
use nalgebra::{Matrix3, Vector3};
use ocellus_fovea::vergence::{VergenceOptions, VergenceTracker};
use ocellus_geometry::camera::{Intrinsics, PinholeCamera};
use ocellus_geometry::distortion::Distortion;
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use ocellus_synth::ball_view::render_view;
use ocellus_synth::ball_world::{BallWorld, GRAVITY};
use ocellus_tracking::colour::{Circle, ColourModel};
use ocellus_tracking::tracker::{BallTracker, TrackerConfig};

/// Parameters of the head and its controller.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadConfig {
    /// Distance between the eyes, metres (the iCub's: 0.068).
    pub baseline_m: f64,
    /// Eye image width, pixels.
    pub eye_width: usize,
    /// Eye image height, pixels.
    pub eye_height: usize,
    /// Eye focal length, pixels.
    pub focal_px: f64,
    /// Control rate, Hz of simulated time (the world is rendered at this rate).
    pub control_hz: f64,
    /// A saccade starts when the ball is further than this from the gaze, degrees.
    pub saccade_threshold_deg: f64,
    /// Pursuit gain on the angular error, 1/s.
    pub pursuit_gain: f64,
    /// Fastest pursuit, degrees per second.
    pub max_pursuit_deg_s: f64,
    /// Share of the measured vergence error corrected per step, in (0, 1].
    pub vergence_gain: f64,
    /// The tracker (its frame rate is set to the control rate).
    pub tracker: TrackerConfig,
}

impl Default for HeadConfig {
    /// iCub-like: 6.8 cm baseline, 320x240 eyes with a 300 px focal length (56 deg across),
    /// 60 Hz, saccades beyond 3 deg, pursuit gain 6/s up to 100 deg/s, vergence gain 0.7.
    fn default() -> Self {
        Self {
            baseline_m: 0.068,
            eye_width: 320,
            eye_height: 240,
            focal_px: 300.0,
            control_hz: 60.0,
            saccade_threshold_deg: 3.0,
            pursuit_gain: 6.0,
            max_pursuit_deg_s: 100.0,
            vergence_gain: 0.7,
            tracker: TrackerConfig { particles: 2000, ..TrackerConfig::at_fps(60.0) },
        }
    }
}

impl HeadConfig {
    fn validate(&self) -> Result<()> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let ok = pos(self.baseline_m)
            && pos(self.focal_px)
            && pos(self.control_hz)
            && self.control_hz <= 10_000.0
            && pos(self.saccade_threshold_deg)
            && pos(self.pursuit_gain)
            && pos(self.max_pursuit_deg_s)
            && pos(self.vergence_gain)
            && self.vergence_gain <= 1.0
            && (16..=4096).contains(&self.eye_width)
            && (16..=4096).contains(&self.eye_height);
        if ok {
            Ok(())
        } else {
            Err(SimError::InvalidConfig(format!("head parameters out of range: {self:?}")))
        }
    }
}

/// The head's joint angles, radians.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Gaze {
    /// Pan, positive to the right.
    pub pan: f64,
    /// Tilt, positive up.
    pub tilt: f64,
    /// Vergence: the angle between the two optical axes.
    pub vergence: f64,
}

/// `R_y(a)`: turns +z towards +x.
fn rot_y(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// `R_x(a)`: turns +z towards -y (up).
fn rot_x(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

impl Gaze {
    /// The rotation (eye to head frame) and centre of the left (`side = -1`) or right (`+1`) eye.
    pub fn eye(&self, side: f64, baseline_m: f64) -> (Matrix3<f64>, Vector3<f64>) {
        let head = rot_y(self.pan) * rot_x(self.tilt);
        let centre = head * Vector3::new(side * baseline_m / 2.0, 0.0, 0.0);
        (head * rot_y(-side * self.vergence / 2.0), centre)
    }

    /// The gaze angles that fixate `p` (head frame) with both eyes.
    pub fn towards(p: &Vector3<f64>, baseline_m: f64) -> Self {
        let dist = p.norm().max(baseline_m);
        Self {
            pan: p.x.atan2(p.z),
            tilt: (-p.y).atan2(p.x.hypot(p.z)),
            vergence: 2.0 * (baseline_m / 2.0 / dist).atan(),
        }
    }
}

/// A pinhole eye (no distortion) at a pose.
fn eye_camera(k: Intrinsics, rot: &Matrix3<f64>, centre: &Vector3<f64>) -> PinholeCamera {
    let r = rot.transpose();
    PinholeCamera { k, r, t: -(r * centre) }
}

/// The angle between an eye's optical axis and the direction to `p`, degrees.
fn foveal_error_deg(rot: &Matrix3<f64>, centre: &Vector3<f64>, p: &Vector3<f64>) -> f64 {
    let axis = rot * Vector3::z();
    let d = (p - centre).normalize();
    axis.dot(&d).clamp(-1.0, 1.0).acos().to_degrees()
}

/// A saccade under way: from `from` by `delta` (pan, tilt) over `duration_s`.
#[derive(Clone, Copy, Debug)]
struct Saccade {
    from: (f64, f64),
    delta: (f64, f64),
    start_s: f64,
    duration_s: f64,
}

/// The main-sequence duration of a saccade of `amplitude_deg`, seconds (Carpenter 1988).
pub fn saccade_duration_s(amplitude_deg: f64) -> f64 {
    0.021 + 0.0022 * amplitude_deg
}

/// The minimum-jerk share of a movement done at `s` in [0, 1] of its duration.
pub fn min_jerk(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)
}

/// One control step.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct HeadStep {
    /// Simulated time, seconds.
    pub time_s: f64,
    /// The joint angles after the step.
    pub gaze: Gaze,
    /// Whether a saccade was under way.
    pub saccade: bool,
    /// Angle between the left eye's axis and the true ball, degrees.
    pub left_error_deg: f64,
    /// Angle between the right eye's axis and the true ball, degrees.
    pub right_error_deg: f64,
    /// Disparity at the left fovea, pixels (`x_left - x_right`; 0 when fixated).
    pub disparity_px: f64,
    /// Whether the tracker reported the ball lost.
    pub lost: bool,
}

/// A run of the head.
#[derive(Clone, Debug)]
pub struct HeadRun {
    /// Every control step.
    pub steps: Vec<HeadStep>,
    /// Wall time spent rendering the eyes, seconds (the simulation, not the robot).
    pub render_s: f64,
    /// Wall time spent in the robot's loop (tracker, vergence, control), seconds.
    pub control_s: f64,
}

/// Runs the head on `world` (its frame rate must be the control rate); `each` sees each step
/// with both eyes' frames.
pub fn run_head(
    world: &BallWorld,
    cfg: &HeadConfig,
    mut each: impl FnMut(&HeadStep, &Plane<[u8; 3]>, &Plane<[u8; 3]>) -> Result<()>,
) -> Result<HeadRun> {
    cfg.validate()?;
    if (world.config().fps - cfg.control_hz).abs() > 1e-9 {
        return Err(SimError::InvalidConfig(format!(
            "the world runs at {} fps, the head at {} Hz: render the world at the control rate",
            world.config().fps,
            cfg.control_hz
        )));
    }
    let dt = 1.0 / cfg.control_hz;
    let k = Intrinsics::centred(cfg.focal_px, cfg.eye_width, cfg.eye_height);
    let (w, h) = (cfg.eye_width, cfg.eye_height);
    let b = cfg.baseline_m;
    // The head starts looking straight ahead at 2 m: its first move is a saccade to the ball.
    let (p0, _) = world.state(0).ok_or_else(|| SimError::InvalidConfig("the world has no frames".into()))?;
    let mut gaze = Gaze::towards(&Vector3::new(0.0, 0.0, 2.0), b);
    let mut tcfg = cfg.tracker;
    tcfg.motion.dt_s = dt;
    tcfg.motion.gravity = [0.0, GRAVITY, 0.0];
    let mut tracker: Option<BallTracker> = None;
    let vopts =
        VergenceOptions { min_disparity: -24, max_disparity: 24, max_radius: 16.0, ..VergenceOptions::default() };
    let mut vergence = VergenceTracker::new(vopts, 4, 0.5)?;
    let mut saccade: Option<Saccade> = None;
    let mut last_target: Option<Gaze> = None;
    let mut steps = Vec::with_capacity(world.len());
    let (mut render_s, mut control_s) = (0.0, 0.0);
    for f in 0..world.len() {
        let t = f as f64 * dt;
        let (truth, _) = world.state(f).ok_or_else(|| SimError::InvalidConfig("frame out of range".into()))?;
        let truth = Vector3::from(truth);
        let (rl, cl) = gaze.eye(-1.0, b);
        let (rr, cr) = gaze.eye(1.0, b);
        let (cam_l, cam_r) = (eye_camera(k, &rl, &cl), eye_camera(k, &rr, &cr));
        let clock = std::time::Instant::now();
        let left = render_view(world, f, &cam_l, w, h, world.config().seed)?;
        let right = render_view(world, f, &cam_r, w, h, world.config().seed ^ 0xE7E)?;
        render_s += clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        // The tracker sees the left eye; its colour model comes from the first frame.
        let tr = match &mut tracker {
            Some(tr) => tr,
            None => {
                let p0 = Vector3::from(p0);
                let [x, y, r] = ocellus_geometry::sphere::project_sphere(
                    &cam_l,
                    &Distortion::default(),
                    &p0,
                    world.config().radius_m,
                )
                .ok_or_else(|| SimError::InvalidConfig("the ball is not in front of the left eye".into()))?;
                let model = ColourModel::from_patch(&left, Circle { x, y, r: 0.8 * r })?;
                tracker.insert(BallTracker::new(tcfg, cam_l, Distortion::default(), world.config().radius_m, model)?)
            }
        };
        tr.set_camera(cam_l);
        let est = tr.process(&left)?;
        // Vergence: the disparity at the left fovea.
        let fovea = [k.cx, k.cy];
        // The workspace's one 8-bit luma (a copy of each 320x240 eye: small next to rendering it).
        let grey = |p: &Plane<[u8; 3]>| RgbImage::U8(p.clone()).to_luma8();
        let v = vergence.update(&grey(&left), &grey(&right), fovea)?;
        let target = est.position.map(|p| Gaze::towards(&Vector3::from(p), b));
        // Gaze.
        let in_saccade = saccade.is_some();
        match (saccade, target) {
            (Some(s), _) => {
                let m = min_jerk((t + dt - s.start_s) / s.duration_s);
                gaze.pan = s.from.0 + m * s.delta.0;
                gaze.tilt = s.from.1 + m * s.delta.1;
                if t + dt >= s.start_s + s.duration_s {
                    saccade = None;
                }
            }
            (None, Some(g)) if !est.lost => {
                let (ep, et) = (g.pan - gaze.pan, g.tilt - gaze.tilt);
                let err_deg = ep.hypot(et).to_degrees();
                let rate = last_target.map_or((0.0, 0.0), |l| ((g.pan - l.pan) / dt, (g.tilt - l.tilt) / dt));
                if err_deg > cfg.saccade_threshold_deg {
                    let a = err_deg;
                    let d = saccade_duration_s(a);
                    // Aim where the ball will be when the saccade ends.
                    let delta = (ep + rate.0 * d, et + rate.1 * d);
                    let d = saccade_duration_s(delta.0.hypot(delta.1).to_degrees());
                    let s = Saccade { from: (gaze.pan, gaze.tilt), delta, start_s: t, duration_s: d };
                    let m = min_jerk(dt / d);
                    gaze.pan = s.from.0 + m * delta.0;
                    gaze.tilt = s.from.1 + m * delta.1;
                    saccade = (dt < d).then_some(s);
                } else {
                    let max = cfg.max_pursuit_deg_s.to_radians();
                    let vp = (rate.0 + cfg.pursuit_gain * ep).clamp(-max, max);
                    let vt = (rate.1 + cfg.pursuit_gain * et).clamp(-max, max);
                    gaze.pan += vp * dt;
                    gaze.tilt += vt * dt;
                }
            }
            _ => {}
        }
        // Vergence from the fovea's disparity; held when the foveal match is poor (the
        // tracker's distance, from a ball a few pixels wide, is too rough to verge on).
        if v.score >= 0.5 && !est.lost {
            gaze.vergence += cfg.vergence_gain * (v.disparity_px / cfg.focal_px).atan();
        }
        gaze.vergence = gaze.vergence.clamp(0.0, 60f64.to_radians());
        last_target = target.filter(|_| !est.lost);
        control_s += clock.elapsed().as_secs_f64();
        let (rl, cl) = gaze.eye(-1.0, b);
        let (rr, cr) = gaze.eye(1.0, b);
        let next_truth = world.state(f + 1).map_or(truth, |s| Vector3::from(s.0));
        let step = HeadStep {
            time_s: t + dt,
            gaze,
            saccade: in_saccade || saccade.is_some(),
            left_error_deg: foveal_error_deg(&rl, &cl, &next_truth),
            right_error_deg: foveal_error_deg(&rr, &cr, &next_truth),
            disparity_px: v.disparity_px,
            lost: est.lost,
        };
        each(&step, &left, &right)?;
        steps.push(step);
    }
    Ok(HeadRun { steps, render_s, control_s })
}

/// The figures of a run.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct HeadSummary {
    /// Steps.
    pub steps: usize,
    /// Share of steps with the ball within 2 degrees of both foveas.
    pub within_2deg: f64,
    /// Share within 5 degrees.
    pub within_5deg: f64,
    /// Median of the larger of the two foveal errors, degrees.
    pub median_error_deg: f64,
    /// Saccades made.
    pub saccades: usize,
    /// Control steps per second of wall time (tracker, vergence, control; rendering
    /// excluded).
    pub control_hz: f64,
}

impl HeadRun {
    /// The run's figures.
    pub fn summary(&self) -> HeadSummary {
        let n = self.steps.len().max(1) as f64;
        let mut worst: Vec<f64> = self.steps.iter().map(|s| s.left_error_deg.max(s.right_error_deg)).collect();
        worst.sort_by(f64::total_cmp);
        let within = |deg: f64| worst.iter().filter(|&&e| e <= deg).count() as f64 / n;
        HeadSummary {
            steps: self.steps.len(),
            within_2deg: within(2.0),
            within_5deg: within(5.0),
            median_error_deg: worst.get(worst.len() / 2).copied().unwrap_or(0.0),
            saccades: saccade_count(&self.steps),
            control_hz: self.steps.len() as f64 / self.control_s.max(1e-12),
        }
    }
}

/// Saccades in a run: steps with a saccade under way whose previous step had none.
pub fn saccade_count(steps: &[HeadStep]) -> usize {
    steps.iter().enumerate().filter(|(i, s)| s.saccade && (*i == 0 || !steps[i - 1].saccade)).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_main_sequence_grows_with_amplitude() {
        // Peak velocity of a minimum-jerk movement: 1.875 A / D.
        let peak = |a: f64| 1.875 * a / saccade_duration_s(a);
        assert!((saccade_duration_s(10.0) - 0.043).abs() < 1e-12);
        assert!((peak(10.0) - 436.0).abs() < 1.0);
        assert!(peak(5.0) < peak(10.0) && peak(10.0) < peak(20.0) && peak(20.0) < peak(40.0));
        // The profile: 0 to 1, half way at half time, peak slope 1.875.
        assert_eq!(min_jerk(0.0), 0.0);
        assert_eq!(min_jerk(1.0), 1.0);
        assert!((min_jerk(0.5) - 0.5).abs() < 1e-12);
        let slope = (min_jerk(0.5 + 1e-6) - min_jerk(0.5 - 1e-6)) / 2e-6;
        assert!((slope - 1.875).abs() < 1e-6);
    }

    #[test]
    fn fixating_a_point_puts_it_on_both_axes() {
        let p = Vector3::new(0.3, -0.2, 1.5);
        let g = Gaze::towards(&p, 0.068);
        for side in [-1.0, 1.0] {
            let (r, c) = g.eye(side, 0.068);
            let e = foveal_error_deg(&r, &c, &p);
            // Symmetric vergence fixates exactly only straight ahead; off-axis the error is
            // a fraction of a degree.
            assert!(e < 0.3, "side {side}: {e} deg");
        }
        let ahead = Vector3::new(0.0, 0.0, 1.0);
        let g = Gaze::towards(&ahead, 0.068);
        for side in [-1.0, 1.0] {
            let (r, c) = g.eye(side, 0.068);
            assert!(foveal_error_deg(&r, &c, &ahead) < 1e-5, "acos near 1 keeps about 1e-6 deg");
        }
    }
}
