//! The seed's corridor experiment as a simulation (SPEC 2.6): a robot drives down a corridor
//! and, every 0.5 m, chooses where to point its camera with the information-based planner.
//!
//! Each step: the position belief is predicted with odometry noise (its covariance grows);
//! the camera, at the pan chosen last step, captures a burst of three frames from the true
//! pose (rendered from real imagery); saliency (with flicker) → surprise → chaos degree are
//! computed on the burst; the landmarks in view are observed as noisy bearings (EKF update,
//! the covariance shrinks); then the planner chooses the next pan from the belief, the
//! surprise map and the chaos degree. In the event scenario a person appears in the middle of
//! the burst of step `event_step`. Nothing in the loop knows where the person or the
//! landmarks should be looked at: the choice comes from the gains.

use crate::{Result, SimError};
use nalgebra::{Matrix2, Vector2};
use ocellus_attention::planning::{Decision, PlannerConfig, ViewPlanner};
use ocellus_attention::stream::{StreamConfig, StreamEngine};
use ocellus_estimation::bearing::{bearing, bearing_update, Landmark};
use ocellus_image::convert::RgbImage;
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;
use ocellus_synth::corridor::{Corridor, CorridorConfig, CorridorTextures};

/// Parameters of a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// Number of planning steps.
    pub steps: usize,
    /// Distance driven between plans, metres.
    pub step_m: f64,
    /// Whether the person appears.
    pub event: bool,
    /// The step at which the person appears (in the middle of that step's burst).
    pub event_step: usize,
    /// Odometry noise per step (standard deviation, each axis), metres.
    pub odometry_sigma_m: f64,
    /// Initial position uncertainty (standard deviation, each axis), metres.
    pub initial_sigma_m: f64,
    /// Seed of odometry, bearing and sensor noise.
    pub seed: u64,
    /// Keep the camera looking forward (pan 0) instead of planning: the baseline.
    pub fixed_forward: bool,
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            steps: 16,
            step_m: 0.5,
            event: false,
            event_step: 5,
            odometry_sigma_m: 0.05,
            initial_sigma_m: 0.1,
            seed: 1,
            fixed_forward: false,
        }
    }
}

/// What happened at one step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepRecord {
    /// Step index.
    pub step: usize,
    /// True position, metres.
    pub true_xy: (f64, f64),
    /// Estimated position after the update, metres.
    pub mu: (f64, f64),
    /// Trace of the position covariance after the update, m^2.
    pub cov_trace: f64,
    /// Chaos degree of the burst, bits.
    pub chaos: f64,
    /// Pan the camera had during this step's burst, degrees.
    pub pan_deg: f64,
    /// Landmarks observed in the burst.
    pub observed: usize,
    /// The planner's decision for the next step.
    pub decision: Decision,
    /// Whether the person was in view in this burst.
    pub person_visible: bool,
    /// Bearing of the person from the true position, degrees.
    pub person_bearing_deg: f64,
    /// Bearing of the person from the next position (where the chosen pan is used), degrees.
    pub person_bearing_next_deg: f64,
    /// Maximum surprise of the burst, bits.
    pub surprise_max: f32,
}

/// The photographs and textures the corridor is built from (any sizes; decoded by the
/// caller, e.g. from the binary's built-in assets or from `assets/`).
#[derive(Clone, Debug)]
pub struct CorridorImages {
    /// The person who appears (and a poster cut from it): the astronaut photograph.
    pub astronaut: RgbImage,
    /// Wall texture (brick).
    pub brick: RgbImage,
    /// Floor texture (gravel).
    pub gravel: RgbImage,
    /// Poster photographs: coffee, rocket, cat.
    pub coffee: RgbImage,
    /// See `coffee`.
    pub rocket: RgbImage,
    /// See `coffee`.
    pub chelsea: RgbImage,
}

impl CorridorImages {
    /// The images by the names of the built-in assets (`astronaut.png`, `brick.png`,
    /// `gravel.png`, `coffee.png`, `rocket.jpg`, `chelsea.png`), each read by `read`.
    pub fn load<E>(mut read: impl FnMut(&str) -> std::result::Result<RgbImage, E>) -> std::result::Result<Self, E> {
        Ok(Self {
            astronaut: read("astronaut.png")?,
            brick: read("brick.png")?,
            gravel: read("gravel.png")?,
            coffee: read("coffee.png")?,
            rocket: read("rocket.jpg")?,
            chelsea: read("chelsea.png")?,
        })
    }
}

/// A `w` x `h` crop at (`x`, `y`) of `img`, clamped to the image.
fn crop(img: &RgbImage, x: usize, y: usize, w: usize, h: usize) -> RgbImage {
    let (iw, ih) = img.size();
    let (w, h) = (w.min(iw - x.min(iw - 1)), h.min(ih - y.min(ih - 1)));
    RgbImage::F32(Plane::from_fn(w.max(1), h.max(1), |i, j| img.get_f32((x + i).min(iw - 1), (y + j).min(ih - 1))))
}

/// The corridor of the experiment: brick walls, gravel floor, posters cut from the coffee,
/// rocket and cat photographs, and the astronaut as the person.
pub fn corridor(images: &CorridorImages) -> Result<Corridor> {
    let tex = CorridorTextures {
        wall: images.brick.clone(),
        floor: images.gravel.clone(),
        posters: vec![
            crop(&images.coffee, 150, 40, 300, 300),
            crop(&images.rocket, 200, 60, 240, 240),
            crop(&images.chelsea, 120, 20, 240, 240),
            crop(&images.astronaut, 0, 0, 160, 160),
        ],
        person: crop(&images.astronaut, 100, 0, 300, 512),
    };
    Ok(Corridor::new(CorridorConfig::default(), &tex)?)
}

impl RunConfig {
    fn validate(&self) -> Result<()> {
        use ocellus_image::check;
        (|| {
            check::within("steps", self.steps, 1, 100_000)?;
            check::between("step_m", self.step_m, 0.0, 100.0)?;
            check::within("odometry_sigma_m", self.odometry_sigma_m, 0.0, 10.0)?;
            check::within("initial_sigma_m", self.initial_sigma_m, 1e-6, 10.0)
        })()
        .map_err(SimError::InvalidConfig)
    }
}

/// Runs the experiment; returns one record per step. `on_step` sees each step's record with
/// the last frame of its burst as it happens, so that frames are written, not kept: memory
/// per step stays at the record's size (about a kilobyte) whatever the number of steps.
///
/// The saliency (ace2009 with flicker) → surprise → chaos chain is the library's
/// [`StreamEngine`], reset at each burst (the camera has moved 0.5 m and turned). The callback's
/// error type `E` is the caller's (e.g. `anyhow::Error`); the simulation's own errors convert
/// into it.
pub fn run<E: From<SimError>>(
    cfg: &RunConfig,
    world: &Corridor,
    mut on_step: impl FnMut(&StepRecord, &RgbImage) -> std::result::Result<(), E>,
) -> std::result::Result<Vec<StepRecord>, E> {
    cfg.validate()?;
    let (w, h) = world.config().image_size;
    let mut stream = StreamEngine::new(StreamConfig::default(), w, h).map_err(SimError::from)?;
    let (mw, _) = stream.saliency_engine().map_size();
    let landmarks: Vec<Landmark> = world.landmarks().into_iter().map(|(x, y)| Landmark { x, y }).collect();
    let planner_cfg = PlannerConfig {
        hfov_deg: world.config().hfov_deg,
        deg_per_cell: world.config().hfov_deg / mw as f64,
        ..PlannerConfig::default()
    };
    let sigma_bearing = planner_cfg.bearing_sigma_deg.to_radians();
    let mut planner = ViewPlanner::new(planner_cfg, landmarks.clone()).map_err(SimError::from)?;
    let mut rng = SplitMix64::new(cfg.seed);
    let y0 = world.config().width_m / 2.0;
    let s0 = cfg.initial_sigma_m * cfg.initial_sigma_m;
    let (mut mu, mut cov) = (Vector2::new(0.0, y0), Matrix2::new(s0, 0.0, 0.0, s0));
    let q = cfg.odometry_sigma_m * cfg.odometry_sigma_m;
    let mut pan = 0.0f64;
    let person = world.config().person;
    let mut records = Vec::with_capacity(cfg.steps);
    for k in 0..cfg.steps {
        let truth = Vector2::new(k as f64 * cfg.step_m, y0);
        if k > 0 {
            // Odometry: the commanded step plus noise; the belief's covariance grows.
            let n = Vector2::new(rng.normal(), rng.normal()) * cfg.odometry_sigma_m;
            mu += Vector2::new(cfg.step_m, 0.0) + n;
            cov += Matrix2::new(q, 0.0, 0.0, q);
        }
        // The burst: three frames from the true pose at the current pan.
        stream.reset_temporal();
        let mut s = 0.0;
        let mut frame = None;
        for b in 0..3 {
            let show = cfg.event && (k > cfg.event_step || (k == cfg.event_step && b == 2));
            let img = world.render(truth.x, truth.y, pan, show, cfg.seed ^ ((k * 3 + b) as u64) << 8);
            if let Some(c) = stream.process(&img, pan as f32, 0.0).map_err(SimError::from)?.chaos {
                s = c;
            }
            frame = Some(img);
        }
        // Landmark bearings from the true pose, with noise, update the belief.
        let seen = planner.visible_landmarks(&truth, 0.0, pan);
        let obs: Vec<(Landmark, f64)> =
            seen.iter().map(|l| (*l, bearing(&truth, l) + rng.normal() * sigma_bearing)).collect();
        (mu, cov) = bearing_update(&mu, &cov, &obs, sigma_bearing).map_err(SimError::from)?;
        // Plan for where the next observation happens: one step further, after its odometry.
        let (mu_next, cov_next) = (mu + Vector2::new(cfg.step_m, 0.0), cov + Matrix2::new(q, 0.0, 0.0, q));
        let mut decision =
            planner.decide(&mu_next, &cov_next, 0.0, pan, stream.surprise_map(), s).map_err(SimError::from)?;
        if cfg.fixed_forward {
            decision.pan_deg = 0.0;
        }
        let bearing_from = |x: f64| (person.y_m - truth.y).atan2(person.x_m - x).to_degrees();
        let person_bearing_deg = bearing_from(truth.x);
        let in_burst = cfg.event && k >= cfg.event_step;
        let record = StepRecord {
            step: k,
            true_xy: (truth.x, truth.y),
            mu: (mu.x, mu.y),
            cov_trace: cov.trace(),
            chaos: s,
            pan_deg: pan,
            observed: seen.len(),
            person_visible: in_burst && world.column_of(person_bearing_deg, pan).is_some(),
            person_bearing_deg,
            person_bearing_next_deg: bearing_from(truth.x + cfg.step_m),
            surprise_max: stream.surprise_map().min_max().1,
            decision: decision.clone(),
        };
        let Some(frame) = frame else { return Err(SimError::InvalidConfig("a burst without frames".into()).into()) };
        on_step(&record, &frame)?;
        records.push(record);
        pan = decision.pan_deg;
    }
    Ok(records)
}
