//! The seed's visual odometry (SPEC 6.3): a Kalman filter on the camera motion per frame.
//!
//! State `(Tx, Ty, wz)`: the camera's translation over one frame in the image axes (metres)
//! and its rotation (radians), a random walk. Measurement: the 36 group flows, 72 numbers,
//! with the simplified image Jacobian of each point (u, v) (relative to the principal point):
//! `du = (f/z) Tx - v wz`, `dv = (f/z) Ty + u wz` (f focal length in pixels, z camera height).
//! With 72 measurements and 3 states the update is done in information form: the 3x3
//! information matrix gains `sum H^T H / sigma^2`, which is exact and avoids inverting the
//! 72x72 innovation covariance.
//!
//! The floor moving by (du, dv) in the image means the camera moved by `-du` to the right and
//! `+dv` forward (image y points backwards), and turned by `-wz` (clockwise positive); the
//! robot's motion follows with the mount offset ([`crate::kinematics::robot_motion`]).

use crate::kinematics::{moved_by_camera, robot_motion, Mount, Pose2};
use crate::robust::{fit_rigid, lk_rect, window_measurements_smoothed, RobustConfig};
use crate::sad_flow::{group_flows, FlowPoint, SadFlowConfig};
use crate::spline::SmoothedFrame;
use crate::{OdometryError, Result};
use nalgebra::{Matrix3, Vector3};
use ocellus_image::Plane;

/// Which estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// The seed's method: integer SAD, 36 group flows, first-order model and kinematics.
    Seed,
    /// Sub-pixel flow with per-window uncertainty, a robust fit over all windows with the
    /// exact rigid model, exact kinematics ([`crate::robust`]).
    Robust,
}

/// Configuration of [`VisualOdometry`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OdometryConfig {
    /// Camera height above the floor, metres.
    pub height_m: f64,
    /// Focal length, pixels.
    pub focal_px: f64,
    /// Camera position relative to the robot's rotation centre.
    pub mount: Mount,
    /// The flow measurement.
    pub flow: SadFlowConfig,
    /// Random-walk standard deviation per frame of Tx, Ty (metres) and wz (radians).
    pub process_sigma: [f64; 3],
    /// Standard deviation of one flow component, pixels (seed mode).
    pub flow_sigma_px: f64,
    /// Which estimator.
    pub mode: Mode,
    /// Robust-mode parameters.
    pub robust: RobustConfig,
}

impl OdometryConfig {
    /// The seed's method for a camera `height_m` above the floor with focal length
    /// `focal_px`, mounted at `mount`.
    pub fn seed(height_m: f64, focal_px: f64, mount: Mount) -> Self {
        let px_m = height_m / focal_px;
        Self {
            height_m,
            focal_px,
            mount,
            flow: SadFlowConfig::default(),
            // Speed changes of about 0.5 px and 0.1 degree per frame.
            process_sigma: [0.5 * px_m, 0.5 * px_m, 0.1f64.to_radians()],
            flow_sigma_px: 0.5,
            mode: Mode::Seed,
            robust: RobustConfig::default(),
        }
    }

    /// The robust mode for the same camera (see [`crate::robust`]).
    pub fn robust(height_m: f64, focal_px: f64, mount: Mount) -> Self {
        Self { mode: Mode::Robust, ..Self::seed(height_m, focal_px, mount) }
    }

    fn check(&self) -> Result<()> {
        use ocellus_image::check;
        self.robust.check()?;
        (|| {
            check::positive("camera height_m", self.height_m)?;
            check::positive("focal_px", self.focal_px)?;
            check::positive("flow_sigma_px", self.flow_sigma_px)?;
            for (k, s) in self.process_sigma.iter().enumerate() {
                check::positive(&format!("process_sigma[{k}]"), *s)?;
            }
            check::finite("mount right_m", self.mount.right_m)?;
            check::finite("mount forward_m", self.mount.forward_m)
        })()
        .map_err(OdometryError::Invalid)
    }
}

/// What one frame gave.
#[derive(Clone, Debug, PartialEq)]
pub struct OdometryStep {
    /// The robot's pose after this frame.
    pub pose: Pose2,
    /// The filtered camera motion of this frame: right (m), forward (m), turn (rad).
    pub camera_motion: [f64; 3],
    /// Standard deviations of `camera_motion` from the filter's covariance (m, m, rad).
    pub camera_motion_sigma: [f64; 3],
    /// The flow vectors measured (empty for the first frame and on failure).
    pub flows: Vec<FlowPoint>,
    /// Why no measurement was used (the motion was then predicted), if so.
    pub failure: Option<String>,
    /// The camera height at this frame, metres: the calibrated one, or in robust mode the
    /// one followed through the image-scale change (see [`RobustConfig::height_pull`]).
    pub height_m: f64,
}

/// The seed's visual odometry over a frame stream.
#[derive(Clone, Debug)]
pub struct VisualOdometry {
    cfg: OdometryConfig,
    prev: Option<Plane<u8>>,
    /// The buffer the next frame is copied into (the frame before the previous one's).
    spare: Plane<u8>,
    /// The previous frame smoothed for Lucas-Kanade (robust mode; each frame is smoothed once),
    /// when it is the previous frame's.
    prev_smooth: SmoothedFrame,
    prev_smooth_valid: bool,
    /// The buffers the current frame is smoothed into (swapped with `prev_smooth`).
    cur_smooth: SmoothedFrame,
    x: Vector3<f64>,
    p: Matrix3<f64>,
    pose: Pose2,
    /// The followed camera height over the calibrated one (robust mode; 1 in seed mode).
    height: crate::height::HeightFollower,
}

impl VisualOdometry {
    /// A filter at rest at the origin.
    pub fn new(cfg: OdometryConfig) -> Result<Self> {
        cfg.check()?;
        let px_m = cfg.height_m / cfg.focal_px;
        // Initially unsure by a few pixels per frame and a degree per frame.
        let p = Matrix3::from_diagonal(&Vector3::new(
            (5.0 * px_m).powi(2),
            (5.0 * px_m).powi(2),
            1f64.to_radians().powi(2),
        ));
        Ok(Self {
            cfg,
            prev: None,
            spare: Plane::default(),
            prev_smooth: SmoothedFrame::default(),
            prev_smooth_valid: false,
            cur_smooth: SmoothedFrame::default(),
            x: Vector3::zeros(),
            p,
            pose: Pose2::default(),
            height: Default::default(),
        })
    }

    /// The current pose.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Standard deviations of the current motion estimate (right m, forward m, turn rad).
    fn sigma(&self) -> [f64; 3] {
        [self.p[(0, 0)].max(0.0).sqrt(), self.p[(1, 1)].max(0.0).sqrt(), self.p[(2, 2)].max(0.0).sqrt()]
    }

    /// Processes the next frame (grey, the same size as the previous ones).
    pub fn step(&mut self, frame: &Plane<u8>) -> Result<OdometryStep> {
        // The frame is copied first, into the buffer of the frame before the previous one:
        // no allocation per step, and the copy reads the frame in one sequential pass, which
        // brings it into the cache for the block search's scattered reads (copied after the
        // step, a seed step on frames fresh from memory took 0.19 instead of 0.12 ms).
        self.spare.clone_from(frame);
        let Some(prev) = self.prev.take() else {
            self.prev = Some(std::mem::take(&mut self.spare));
            return Ok(OdometryStep {
                pose: self.pose,
                camera_motion: [0.0; 3],
                camera_motion_sigma: [0.0; 3],
                flows: Vec::new(),
                failure: None,
                height_m: self.cfg.height_m * self.height.ratio(),
            });
        };
        let frame = std::mem::take(&mut self.spare);
        let step = match self.cfg.mode {
            Mode::Robust => self.step_robust(&prev, &frame),
            Mode::Seed => self.step_seed(&prev, &frame),
        };
        (self.spare, self.prev) = (prev, Some(frame));
        step
    }

    /// The seed's step (SPEC 6.2-6.3) from `prev` to `frame`.
    fn step_seed(&mut self, prev: &Plane<u8>, frame: &Plane<u8>) -> Result<OdometryStep> {
        let (flows, failure) = match group_flows(prev, frame, &self.cfg.flow) {
            Ok(f) => (f, None),
            Err(OdometryError::NoTexture(why)) => (Vec::new(), Some(why)),
            Err(e) => return Err(e),
        };
        // The 72 flow components with the image Jacobian rows of each point.
        let k = self.cfg.focal_px / self.cfg.height_m;
        let w = 1.0 / (self.cfg.flow_sigma_px * self.cfg.flow_sigma_px);
        let (mut info_z, mut b) = (Matrix3::zeros(), Vector3::zeros());
        for f in &flows {
            let h1 = Vector3::new(k, 0.0, -f.v);
            let h2 = Vector3::new(0.0, k, f.u);
            info_z += (h1 * h1.transpose() + h2 * h2.transpose()) * w;
            b += (h1 * f.du + h2 * f.dv) * w;
        }
        self.update(!flows.is_empty(), &info_z, &b)?;
        let (cam_right, cam_forward, turn) = (-self.x[0], self.x[1], -self.x[2]);
        let (r, f, t) = robot_motion(cam_right, cam_forward, turn, &self.cfg.mount);
        self.pose = self.pose.step(r, f, t);
        Ok(self.output(flows, failure))
    }

    /// The filter's predict and (when `measured`) information-form update with the
    /// measurement's information `info_z` and information vector `b` (`H^T R^-1 z`).
    fn update(&mut self, measured: bool, info_z: &Matrix3<f64>, b: &Vector3<f64>) -> Result<()> {
        let s = self.cfg.process_sigma;
        let p_pred = self.p + Matrix3::from_diagonal(&Vector3::new(s[0] * s[0], s[1] * s[1], s[2] * s[2]));
        if !measured {
            self.p = p_pred;
            return Ok(());
        }
        let info_prior = p_pred.try_inverse().unwrap_or_else(Matrix3::zeros);
        let cov = (info_prior + info_z)
            .try_inverse()
            .ok_or_else(|| OdometryError::NoTexture("the flow does not determine the motion".into()))?;
        self.x = cov * (info_prior * self.x + b);
        self.p = cov;
        Ok(())
    }

    /// The step's report from the current state.
    fn output(&self, flows: Vec<FlowPoint>, failure: Option<String>) -> OdometryStep {
        OdometryStep {
            pose: self.pose,
            camera_motion: [-self.x[0], self.x[1], -self.x[2]],
            camera_motion_sigma: self.sigma(),
            flows,
            failure,
            height_m: self.cfg.height_m * self.height.ratio(),
        }
    }

    fn step_robust(&mut self, prev: &Plane<u8>, frame: &Plane<u8>) -> Result<OdometryStep> {
        // The translation is measured in frame n-1's pixels, at frame n-1's height.
        let scale = self.cfg.height_m * self.height.ratio() / self.cfg.focal_px;
        let sigma = self.cfg.robust.smooth_sigma_px;
        let backend = self.cfg.robust.flow.backend;
        // Valid again only once this frame's smoothing is in place (an error below leaves it so).
        let prev_valid = std::mem::replace(&mut self.prev_smooth_valid, false);
        ocellus_image::check::same_size("frame (against the previous one)", frame.size(), prev.size())?;
        let rect = lk_rect(frame.width(), frame.height(), &self.cfg.robust)?;
        self.cur_smooth.update(backend, frame, sigma, rect)?;
        if !prev_valid {
            self.prev_smooth.update(backend, prev, sigma, rect)?;
        }
        let fit = window_measurements_smoothed(prev, frame, &self.prev_smooth, &self.cur_smooth, &self.cfg.robust)
            .and_then(|m| fit_rigid(&m, &self.cfg.robust).map(|f| (f, m)));
        std::mem::swap(&mut self.prev_smooth, &mut self.cur_smooth);
        self.prev_smooth_valid = true;
        let (flows, failure, info_z, b) = match fit {
            Ok((f, m)) => {
                // Frame n is frame n-1 magnified by 1 + k: the camera came down by 1 / (1 + k).
                // A change beyond 20 % in one frame is not a height change the floor allows.
                if f.scale_change.is_finite() && f.scale_change.abs() < 0.2 {
                    let r = &self.cfg.robust;
                    self.height.update(f.scale_change, r.height_pull, r.height_noise_frames);
                }
                // State (Tx, Ty, wz) = M (right_px, forward_px, turn), M = diag(-s, s, -1).
                let z = Vector3::new(-scale * f.right_px, scale * f.forward_px, -f.turn_rad);
                let m_inv = Matrix3::from_diagonal(&Vector3::new(-1.0 / scale, 1.0 / scale, -1.0));
                let info_z = m_inv.transpose() * f.info * m_inv;
                let flows = m.iter().map(|w| FlowPoint { u: w.u, v: w.v, du: w.du, dv: w.dv, inliers: 1 }).collect();
                (flows, None, info_z, info_z * z)
            }
            Err(OdometryError::NoTexture(why)) => (Vec::new(), Some(why), Matrix3::zeros(), Vector3::zeros()),
            Err(e) => return Err(e),
        };
        self.update(failure.is_none(), &info_z, &b)?;
        let (cam_right, cam_forward, turn) = (-self.x[0], self.x[1], -self.x[2]);
        self.pose = moved_by_camera(&self.pose, cam_right, cam_forward, turn, &self.cfg.mount);
        Ok(self.output(flows, failure))
    }
}
