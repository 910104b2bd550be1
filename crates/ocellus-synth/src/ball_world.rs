//! A coloured ball moving in 3D in front of a real photograph, filmed by a known camera with
//! lens distortion: ground truth for the particle-filter tracker (SPEC 7.3, 7.4).
//!
//! The world frame is the camera frame (x right, y down, z forward, metres); gravity points
//! along +y. The ball is ray-traced per pixel with 2x2 samples (lens distortion included:
//! each sample's pixel is undistorted before its ray is cast) and Lambert-shaded by a light
//! from the upper left. Switchable difficulties:
//! - occluders: patches of a second real photo in front of the ball, a narrow pillar that
//!   hides up to half of it (`partial`) and a panel that hides it wholly for
//!   `full_occlusion_frames` frames (`full`); both static, the ball passes behind them;
//! - a distractor: a static second ball of a similar, redder colour;
//! - a lighting change: the frame's gain falls from 1 to 0.65 (blue less) over the middle
//!   fifth of the sequence;
//! - sensor noise: Gaussian, in 8-bit grey levels.
//!
//! Every random choice (the start's jitter, the noise) comes from the seed.

use crate::{Result, SynthError};
use nalgebra::{Matrix3, Vector2, Vector3};
use ocellus_geometry::camera::{Intrinsics, PinholeCamera};
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::sphere::{project_sphere, ray_sphere};
use ocellus_image::resample::{resize, ResampleMethod};
use ocellus_image::rng::SplitMix64;
use ocellus_image::{Backend, Plane};

/// How the ball moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Trajectory {
    /// Thrown from the left in a lob, bouncing on the floor (restitution 0.75).
    Throw,
    /// Dropped, bouncing on the floor (restitution 0.85) while drifting right and away.
    Bounce,
    /// Flying towards the camera and away again (1.3 to 3.1 m) while weaving sideways.
    Approach,
}

/// Which occluders stand in front of the ball.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Occlusion {
    /// None.
    None,
    /// A pillar hiding up to half the ball around a quarter of the sequence.
    Partial,
    /// A panel hiding the ball wholly for `full_occlusion_frames` frames mid-sequence.
    Full,
    /// Both.
    Both,
}

/// Parameters of a ball world.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BallWorldConfig {
    /// Frame width, pixels.
    pub width: usize,
    /// Frame height, pixels.
    pub height: usize,
    /// Frames per second.
    pub fps: f64,
    /// Number of frames.
    pub frames: usize,
    /// The motion.
    pub trajectory: Trajectory,
    /// Ball radius, metres.
    pub radius_m: f64,
    /// Ball colour (lit face), 8-bit RGB.
    pub colour: [u8; 3],
    /// Occluders.
    pub occlusion: Occlusion,
    /// Frames of full occlusion (the panel's size is chosen so), at least 1.
    pub full_occlusion_frames: usize,
    /// A static second ball of similar colour.
    pub distractor: bool,
    /// The lighting change.
    pub lighting_change: bool,
    /// Sensor noise, standard deviation in 8-bit levels.
    pub noise_sigma: f64,
    /// Seed of the start's jitter and the noise.
    pub seed: u64,
    /// The camera's focal length, pixels (principal point at the image centre).
    pub focal_px: f64,
    /// Its lens distortion.
    pub distortion: Distortion,
}

impl BallWorldConfig {
    /// 640x480 at 30 fps, 60 frames, an orange 5 cm ball, focal 600 px with barrel
    /// distortion (k1 -0.12, k2 0.02), noise sigma 3, no occluder, distractor or lighting change.
    pub fn new(trajectory: Trajectory, seed: u64) -> Self {
        Self {
            width: 640,
            height: 480,
            fps: 30.0,
            frames: 60,
            trajectory,
            radius_m: 0.05,
            colour: [245, 120, 25],
            occlusion: Occlusion::None,
            full_occlusion_frames: 10,
            distractor: false,
            lighting_change: false,
            noise_sigma: 3.0,
            seed,
            focal_px: 600.0,
            distortion: Distortion { k1: -0.12, k2: 0.02, k3: 0.0, p1: 0.0005, p2: -0.0003 },
        }
    }

    /// The camera (world = camera frame).
    pub fn camera(&self) -> PinholeCamera {
        let k = Intrinsics::centred(self.focal_px, self.width, self.height);
        PinholeCamera { k, r: Matrix3::identity(), t: Vector3::zeros() }
    }

    fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(SynthError::InvalidConfig(m));
        if !(16..=8192).contains(&self.width) || !(16..=8192).contains(&self.height) {
            return bad(format!("frame size {}x{} is outside 16..=8192 per side", self.width, self.height));
        }
        if !(self.fps.is_finite() && (1.0..=1000.0).contains(&self.fps)) {
            return bad(format!("{} fps is outside 1..=1000", self.fps));
        }
        if !(2..=100_000).contains(&self.frames) {
            return bad(format!("{} frames is outside 2..=100000", self.frames));
        }
        if !(self.radius_m.is_finite() && (0.005..=1.0).contains(&self.radius_m)) {
            return bad(format!("ball radius {} m is outside 0.005..=1", self.radius_m));
        }
        if !(self.noise_sigma.is_finite() && (0.0..=100.0).contains(&self.noise_sigma)) {
            return bad(format!("noise sigma {} is outside 0..=100", self.noise_sigma));
        }
        if !(self.focal_px.is_finite() && self.focal_px > 0.0) {
            return bad(format!("focal length {} px must be positive", self.focal_px));
        }
        let panel = matches!(self.occlusion, Occlusion::Full | Occlusion::Both);
        if self.full_occlusion_frames == 0 || (panel && self.full_occlusion_frames + 4 > self.frames) {
            return bad(format!(
                "{} frames of full occlusion do not fit {} frames (at least 1, and 4 frames to spare)",
                self.full_occlusion_frames, self.frames
            ));
        }
        Ok(())
    }
}

/// The truth of one frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BallTruth {
    /// Frame index from 0.
    pub frame: usize,
    /// Time, seconds.
    pub time_s: f64,
    /// Ball centre, metres.
    pub position: [f64; 3],
    /// Ball velocity, m/s.
    pub velocity: [f64; 3],
    /// Image circle `[x, y, r]`, pixels (`None` when the ball is not wholly in front of the camera).
    pub circle: Option<[f64; 3]>,
    /// Share of the ball's image not hidden by an occluder or the distractor, in [0, 1]
    /// (0 also when it is outside the frame).
    pub visible_fraction: f64,
}

/// An axis-aligned image rectangle `[x0, y0, x1, y1)`, pixels.
type Rect = [f64; 4];

/// A generated ball world.
pub struct BallWorld {
    cfg: BallWorldConfig,
    camera: PinholeCamera,
    background: Plane<[f32; 3]>,
    occluder_texture: Plane<[f32; 3]>,
    states: Vec<([f64; 3], [f64; 3])>,
    occluders: Vec<Rect>,
    distractor: Option<Vector3<f64>>,
}

/// Gravity, m/s^2, along +y.
pub const GRAVITY: f64 = 9.81;

/// The colour of a sphere point `hit` (world), Lambert-shaded by a light from the upper left
/// with an ambient share of 0.3.
pub(crate) fn lambert(centre: &Vector3<f64>, hit: &Vector3<f64>, radius: f64, c: [f32; 3]) -> [f32; 3] {
    let light = Vector3::new(-0.4, -0.6, -0.7).normalize();
    let n = (hit - centre) / radius;
    let l = 0.3 + 0.7 * n.dot(&light).max(0.0) as f32;
    c.map(|v| (v * l).min(255.0))
}

/// The 2x2 sample offsets of a pixel, pixels.
pub(crate) const SUBSAMPLES: [(f64, f64); 4] = [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)];

/// The pixel columns and rows of a `w` x `h` image within `margin` pixels of the circle
/// `[x, y, r]`.
pub(crate) fn circle_box(
    [cx, cy, cr]: [f64; 3],
    margin: f64,
    w: usize,
    h: usize,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let lo = |c: f64| (c - cr - margin).floor().max(0.0) as usize;
    let hi = |c: f64, n: usize| ((c + cr + margin).ceil().max(0.0) as usize).min(n);
    (lo(cx)..hi(cx, w), lo(cy)..hi(cy, h))
}

/// The floor of the thrown ball: its height (camera-frame y, down, metres) and restitution.
const THROW_FLOOR: (f64, f64) = (0.55, 0.75);
/// The floor of the bouncing ball.
const BOUNCE_FLOOR: (f64, f64) = (0.45, 0.85);

impl Trajectory {
    /// The floor the ball bounces on: its height (camera-frame y, down, metres) and its
    /// restitution (share of the normal speed a bounce keeps). `None` for the approach,
    /// which flies without gravity.
    pub fn floor(self) -> Option<(f64, f64)> {
        match self {
            Trajectory::Throw => Some(THROW_FLOOR),
            Trajectory::Bounce => Some(BOUNCE_FLOOR),
            Trajectory::Approach => None,
        }
    }
}

/// Physics substeps per frame.
const SUBSTEPS: usize = 50;

/// A ballistic flight with bounces on a floor at `floor_y` (the ball's bottom touching it).
fn ballistic(
    p0: [f64; 3],
    v0: [f64; 3],
    floor_y: f64,
    restitution: f64,
    radius: f64,
    dt: f64,
    n: usize,
) -> Vec<([f64; 3], [f64; 3])> {
    let (mut p, mut v) = (p0, v0);
    let h = dt / SUBSTEPS as f64;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        out.push((p, v));
        for _ in 0..SUBSTEPS {
            for k in 0..3 {
                let a = if k == 1 { GRAVITY } else { 0.0 };
                p[k] += v[k] * h + 0.5 * a * h * h;
                v[k] += a * h;
            }
            if p[1] + radius > floor_y && v[1] > 0.0 {
                p[1] = 2.0 * (floor_y - radius) - p[1];
                v[1] *= -restitution;
            }
        }
    }
    out
}

impl BallWorld {
    /// A world over `background` (stretched to the frame), with occluders cut from
    /// `occluder_texture`.
    pub fn new(cfg: BallWorldConfig, background: &Plane<[f32; 3]>, occluder_texture: &Plane<[f32; 3]>) -> Result<Self> {
        cfg.validate()?;
        if background.is_empty() || occluder_texture.is_empty() {
            return Err(SynthError::InvalidConfig("the background and occluder images must not be empty".into()));
        }
        let channels = |p: &Plane<[f32; 3]>| -> [Plane<f32>; 3] { std::array::from_fn(|c| p.map(|v| v[c])) };
        let bg = channels(background);
        let mut planes = Vec::with_capacity(3);
        for c in &bg {
            planes.push(resize(Backend::Auto, c, cfg.width, cfg.height, ResampleMethod::Bilinear)?);
        }
        let bg = Plane::from_fn(cfg.width, cfg.height, |x, y| std::array::from_fn(|c| planes[c].get(x, y)));
        let mut rng = SplitMix64::new(cfg.seed ^ 0x00BA_113D);
        let mut jitter = |s: f64| s * rng.normal();
        let dt = 1.0 / cfg.fps;
        let r = cfg.radius_m;
        let n = cfg.frames;
        let states = match cfg.trajectory {
            Trajectory::Throw => ballistic(
                [-0.7 + jitter(0.05), 0.3 + jitter(0.03), 2.4 + jitter(0.1)],
                [0.9 + jitter(0.05), -3.4 + jitter(0.1), 0.25 + jitter(0.05)],
                THROW_FLOOR.0,
                THROW_FLOOR.1,
                r,
                dt,
                n,
            ),
            Trajectory::Bounce => ballistic(
                [-0.3 + jitter(0.05), -0.5 + jitter(0.03), 1.8 + jitter(0.1)],
                [0.35 + jitter(0.05), jitter(0.1), 0.3 + jitter(0.05)],
                BOUNCE_FLOOR.0,
                BOUNCE_FLOOR.1,
                r,
                dt,
                n,
            ),
            Trajectory::Approach => {
                let (phase, ax) = (jitter(0.3), 0.3 + jitter(0.03));
                (0..n)
                    .map(|k| {
                        let t = k as f64 * dt;
                        let w = [std::f64::consts::TAU / 2.6, std::f64::consts::TAU / 1.7, std::f64::consts::TAU / 2.0];
                        let p = [ax * (w[0] * t + phase).sin(), 0.12 * (w[1] * t).sin(), 2.2 + 0.9 * (w[2] * t).cos()];
                        let v = [
                            ax * w[0] * (w[0] * t + phase).cos(),
                            0.12 * w[1] * (w[1] * t).cos(),
                            -0.9 * w[2] * (w[2] * t).sin(),
                        ];
                        (p, v)
                    })
                    .collect()
            }
        };
        let mut w = Self {
            cfg,
            camera: cfg.camera(),
            background: bg,
            occluder_texture: occluder_texture.clone(),
            states,
            occluders: Vec::new(),
            distractor: None,
        };
        w.place_occluders();
        if cfg.distractor {
            // Off the flight path where possible: the far upper right or left of the view.
            let right = w.states.iter().map(|s| s.0[0]).sum::<f64>() < 0.0;
            w.distractor = Some(Vector3::new(if right { 0.55 } else { -0.55 }, -0.45, 2.0));
        }
        Ok(w)
    }

    /// The ball's image circles over frames `range` (those wholly in front of the camera).
    fn circles(&self, range: std::ops::Range<usize>) -> Vec<[f64; 3]> {
        range.filter_map(|k| self.circle(k)).collect()
    }

    fn circle(&self, k: usize) -> Option<[f64; 3]> {
        let p = Vector3::from(self.states.get(k)?.0);
        project_sphere(&self.camera, &self.cfg.distortion, &p, self.cfg.radius_m)
    }

    /// Occluders from the truth: the panel covers every circle of the full-occlusion frames,
    /// the pillar is half a diameter wide on the path a quarter into the sequence.
    fn place_occluders(&mut self) {
        let n = self.cfg.frames;
        let occ = self.cfg.occlusion;
        if matches!(occ, Occlusion::Partial | Occlusion::Both) {
            let k = n / 4;
            if let Some([x, y, r]) = self.circle(k) {
                let around = self.circles(k.saturating_sub(4)..(k + 5).min(n));
                let (y0, y1) = around.iter().fold((y - r, y + r), |(a, b), c| (a.min(c[1] - c[2]), b.max(c[1] + c[2])));
                self.occluders.push([x - 0.5 * r, y0 - 2.0, x + 0.5 * r, y1 + 2.0]);
            }
        }
        if matches!(occ, Occlusion::Full | Occlusion::Both) {
            let m = self.cfg.full_occlusion_frames;
            let k0 = (n - m) / 2 + n / 8;
            let k0 = k0.min(n - m - 2);
            let cs = self.circles(k0..k0 + m);
            if let Some(first) = cs.first() {
                let init = [first[0] - first[2], first[1] - first[2], first[0] + first[2], first[1] + first[2]];
                let b = cs.iter().fold(init, |b, c| {
                    [b[0].min(c[0] - c[2]), b[1].min(c[1] - c[2]), b[2].max(c[0] + c[2]), b[3].max(c[1] + c[2])]
                });
                self.occluders.push([b[0] - 1.5, b[1] - 1.5, b[2] + 1.5, b[3] + 1.5]);
            }
        }
    }

    /// The configuration.
    pub fn config(&self) -> &BallWorldConfig {
        &self.cfg
    }

    /// The camera (world = camera frame).
    pub fn camera(&self) -> &PinholeCamera {
        &self.camera
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// The occluders' image rectangles `[x0, y0, x1, y1)`, pixels.
    pub fn occluders(&self) -> &[[f64; 4]] {
        &self.occluders
    }

    fn occluded(&self, x: f64, y: f64) -> Option<usize> {
        self.occluders.iter().position(|o| x >= o[0] && x < o[2] && y >= o[1] && y < o[3])
    }

    /// The ball's centre and velocity at frame `k` (metres, m/s; world = reference camera
    /// frame).
    pub fn state(&self, k: usize) -> Option<([f64; 3], [f64; 3])> {
        self.states.get(k).copied()
    }

    /// The background photo as the reference camera sees it (frame size, 0..255 RGB).
    pub(crate) fn background(&self) -> &Plane<[f32; 3]> {
        &self.background
    }

    /// The gain per channel at frame `k` (the lighting change).
    pub(crate) fn gain(&self, k: usize) -> [f32; 3] {
        if !self.cfg.lighting_change {
            return [1.0; 3];
        }
        let n = self.cfg.frames as f64;
        let t = ((k as f64 - 0.4 * n) / (0.2 * n)).clamp(0.0, 1.0) as f32;
        [1.0 - 0.35 * t, 1.0 - 0.35 * t, 1.0 - 0.45 * t]
    }

    /// Frame `k` and its truth.
    pub fn frame(&self, k: usize) -> Result<(Plane<[u8; 3]>, BallTruth)> {
        let len = self.len();
        let &(pos, vel) = self.states.get(k).ok_or(SynthError::NoSuchFrame { index: k, len })?;
        let mut img = self.background.clone();
        let (w, h) = (self.cfg.width, self.cfg.height);
        let ball = Vector3::from(pos);
        let r = self.cfg.radius_m;
        let base = self.cfg.colour.map(|c| c as f32);
        let redder = [base[0].min(255.0) * 0.97, base[1] * 0.8, base[2] * 1.3 + 10.0];
        let shade = |centre: &Vector3<f64>, hit: &Vector3<f64>, rad: f64, c: [f32; 3]| lambert(centre, hit, rad, c);
        let spheres: Vec<(Vector3<f64>, [f32; 3], bool)> =
            std::iter::once((ball, base, true)).chain(self.distractor.map(|d| (d, redder, false))).collect();
        let (mut ball_samples, mut ball_visible) = (0usize, 0usize);
        for (centre, _, _) in &spheres {
            let Some([cx, cy, cr]) = project_sphere(&self.camera, &self.cfg.distortion, centre, r) else { continue };
            let (xs, ys) = circle_box([cx, cy, cr], 3.0, w, h);
            for y in ys {
                for x in xs.clone() {
                    let mut acc = [0.0f32; 3];
                    let mut hits = 0;
                    for (sx, sy) in SUBSAMPLES {
                        let (px, py) = (x as f64 + sx, y as f64 + sy);
                        let Ok((ux, uy)) = self.cfg.distortion.undistort_pixel(&self.camera.k, px, py) else {
                            continue;
                        };
                        let (o, d) = self.camera.back_project(&Vector2::new(ux, uy));
                        // The nearest sphere along this ray.
                        let nearest = spheres
                            .iter()
                            .filter_map(|s| ray_sphere(&o, &d, &s.0, r).map(|t| (t, s)))
                            .min_by(|a, b| a.0.total_cmp(&b.0));
                        let Some((t, s)) = nearest else { continue };
                        if s.0 != *centre {
                            continue;
                        }
                        if s.2 {
                            ball_samples += 1;
                        }
                        if self.occluded(px, py).is_some() {
                            continue;
                        }
                        if s.2 {
                            ball_visible += 1;
                        }
                        let c = shade(&s.0, &(o + t * d), r, s.1);
                        for i in 0..3 {
                            acc[i] += c[i];
                        }
                        hits += 1;
                    }
                    if hits > 0 {
                        let bg = img.get(x, y);
                        let a = hits as f32 / 4.0;
                        let v: [f32; 3] = std::array::from_fn(|i| acc[i] / 4.0 + (1.0 - a) * bg[i]);
                        img.set(x, y, v);
                    }
                }
            }
        }
        // Occluders in front: the texture stretched over each rectangle.
        let (tw, th) = self.occluder_texture.size();
        for o in &self.occluders {
            let (x0, x1) = (o[0].ceil().max(0.0) as usize, (o[2].ceil().max(0.0) as usize).min(w));
            let (y0, y1) = (o[1].ceil().max(0.0) as usize, (o[3].ceil().max(0.0) as usize).min(h));
            for y in y0..y1 {
                for x in x0..x1 {
                    let u = ((x - x0) * tw / (x1 - x0).max(1)).min(tw - 1);
                    let v = ((y - y0) * th / (y1 - y0).max(1)).min(th - 1);
                    img.set(x, y, self.occluder_texture.get(u, v));
                }
            }
        }
        let gain = self.gain(k);
        let mut noise = SplitMix64::new(self.cfg.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k as u64);
        let sigma = self.cfg.noise_sigma;
        let out = Plane::from_fn(w, h, |x, y| {
            let p = img.get(x, y);
            std::array::from_fn(|i| {
                let n = if sigma > 0.0 { sigma * noise.normal() } else { 0.0 };
                (p[i] as f64 * gain[i] as f64 + n).round().clamp(0.0, 255.0) as u8
            })
        });
        let circle = self.circle(k);
        let in_view = circle.is_some_and(|[x, y, _]| x >= 0.0 && y >= 0.0 && x < w as f64 && y < h as f64);
        let visible_fraction =
            if ball_samples > 0 && in_view { ball_visible as f64 / ball_samples as f64 } else { 0.0 };
        let truth = BallTruth {
            frame: k,
            time_s: k as f64 / self.cfg.fps,
            position: pos,
            velocity: vel,
            circle,
            visible_fraction,
        };
        Ok((out, truth))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn textures() -> (Plane<[f32; 3]>, Plane<[f32; 3]>) {
        let load =
            |n: &str| ocellus_io::read_image(ocellus_testdata::data_file(n)).unwrap().to_u8().map(|p| p.map(f32::from));
        (load("astronaut.png"), load("rocket.jpg"))
    }

    #[test]
    fn the_ball_is_where_the_truth_says_and_occlusions_happen() {
        let (bg, occ) = textures();
        let cfg = BallWorldConfig {
            occlusion: Occlusion::Both,
            noise_sigma: 0.0,
            ..BallWorldConfig::new(Trajectory::Throw, 2)
        };
        let world = BallWorld::new(cfg, &bg, &occ).unwrap();
        let mut hidden = 0;
        let mut partial = 0;
        for k in 0..world.len() {
            let (f, t) = world.frame(k).unwrap();
            assert_eq!(f.size(), (640, 480));
            if t.visible_fraction == 0.0 {
                hidden += 1;
            } else if t.visible_fraction < 0.9 {
                partial += 1;
            }
            if t.visible_fraction == 1.0 {
                // The centre pixel has the ball's hue: red high, blue low.
                let [x, y, r] = t.circle.unwrap();
                assert!(r > 5.0);
                let p = f.get(x.round() as usize, y.round() as usize);
                assert!(p[0] > 100 && p[0] as i32 > p[2] as i32 + 60, "frame {k}: {p:?} at ({x}, {y})");
            }
        }
        // The panel hides the ball wholly for about the asked 10 frames (the edges partly).
        assert!((9..=13).contains(&hidden), "{hidden} hidden frames");
        assert!(partial >= 2, "{partial} partly hidden frames");
    }

    #[test]
    fn the_flight_obeys_gravity_between_bounces() {
        let (bg, occ) = textures();
        let world = BallWorld::new(BallWorldConfig::new(Trajectory::Bounce, 5), &bg, &occ).unwrap();
        let dt = 1.0 / 30.0;
        let mut checked = 0;
        for k in 1..world.len() - 1 {
            let (a, b, c) = (world.states[k - 1], world.states[k], world.states[k + 1]);
            // No bounce in between: vy grows by g dt each frame.
            if a.1[1] > 0.0 && c.1[1] > a.1[1] {
                assert!((b.1[1] - a.1[1] - GRAVITY * dt).abs() < 1e-9);
                let second = c.0[1] - 2.0 * b.0[1] + a.0[1];
                assert!((second - GRAVITY * dt * dt).abs() < 1e-9);
                checked += 1;
            }
            // Never through the floor.
            assert!(b.0[1] + 0.05 <= 0.45 + 1e-9);
        }
        assert!(checked > 10);
    }

    #[test]
    fn same_seed_same_frames() {
        let (bg, occ) = textures();
        let cfg = BallWorldConfig {
            distractor: true,
            lighting_change: true,
            ..BallWorldConfig::new(Trajectory::Approach, 9)
        };
        let a = BallWorld::new(cfg, &bg, &occ).unwrap().frame(30).unwrap();
        let b = BallWorld::new(cfg, &bg, &occ).unwrap().frame(30).unwrap();
        assert_eq!(a, b);
        let other = BallWorld::new(BallWorldConfig { seed: 10, ..cfg }, &bg, &occ).unwrap().frame(30).unwrap();
        assert_ne!(a.0, other.0);
    }

    #[test]
    fn bad_configurations_are_refused() {
        let (bg, occ) = textures();
        let ok = BallWorldConfig::new(Trajectory::Throw, 1);
        for cfg in [
            BallWorldConfig { frames: 1, ..ok },
            BallWorldConfig { fps: f64::NAN, ..ok },
            BallWorldConfig { radius_m: 0.0, ..ok },
            BallWorldConfig { noise_sigma: -1.0, ..ok },
            BallWorldConfig { occlusion: Occlusion::Full, full_occlusion_frames: 58, ..ok },
            BallWorldConfig { occlusion: Occlusion::Both, frames: 13, ..ok },
            BallWorldConfig { full_occlusion_frames: 0, ..ok },
        ] {
            assert!(BallWorld::new(cfg, &bg, &occ).is_err(), "{cfg:?}");
        }
        // Without the panel a sequence may be shorter than its occlusion would be.
        assert!(BallWorld::new(BallWorldConfig { frames: 8, ..ok }, &bg, &occ).is_ok());
        assert!(matches!(BallWorld::new(ok, &bg, &occ).unwrap().frame(60), Err(SynthError::NoSuchFrame { .. })));
    }
}
