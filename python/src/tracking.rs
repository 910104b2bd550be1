//! Particle filters (SPEC 7): resampling and the effective sample size, and the boosted 3D
//! ball tracker of the lecture.

use crate::{err, image_from};
use nalgebra::{Matrix3, Vector3};
use numpy::ndarray::Array2;
use numpy::PyArray2;
use ocellus_estimation::resampling::Resampler;
use ocellus_geometry::camera::{Intrinsics, PinholeCamera};
use ocellus_geometry::distortion::Distortion;
use ocellus_image::rng::SplitMix64;
use ocellus_tracking::colour::{Circle, ColourModel};
use ocellus_tracking::motion::Floor;
use ocellus_tracking::tracker::{BallTracker as Tracker, TrackerConfig};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Normalized weights from a sequence of non-negative numbers.
fn weights(w: Vec<f64>) -> PyResult<Vec<f64>> {
    if w.is_empty() || !w.iter().all(|v| v.is_finite() && *v >= 0.0) {
        return Err(err("weights must be a non-empty sequence of finite numbers >= 0"));
    }
    let s: f64 = w.iter().sum();
    if s <= 0.0 {
        return Err(err("the weights sum to 0"));
    }
    Ok(w.into_iter().map(|v| v / s).collect())
}

/// `resample(weights, scheme="systematic", seed=1)`: parent indices (increasing) of
/// `len(weights)` offspring (SPEC 7.1): "systematic" (the seed's Algorithm 2), "stratified",
/// "multinomial" or "residual". The weights are normalized first.
#[pyfunction]
#[pyo3(signature = (weights, scheme = "systematic", seed = 1))]
fn resample(py: Python<'_>, weights: Vec<f64>, scheme: &str, seed: u64) -> PyResult<Vec<usize>> {
    let r = match scheme {
        "systematic" => Resampler::Systematic,
        "stratified" => Resampler::Stratified,
        "multinomial" => Resampler::Multinomial,
        "residual" => Resampler::Residual,
        other => return Err(err(format!("scheme {other:?}: systematic, stratified, multinomial or residual"))),
    };
    let w = self::weights(weights)?;
    let mut out = Vec::with_capacity(w.len());
    py.detach(|| r.resample(&w, &mut SplitMix64::new(seed), &mut out)).map_err(err)?;
    Ok(out)
}

/// `effective_sample_size(weights)`: 1 / sum(w_i^2) of the normalized weights, particles.
#[pyfunction]
fn effective_sample_size(weights: Vec<f64>) -> PyResult<f64> {
    let w = self::weights(weights)?;
    Ok(1.0 / w.iter().map(|v| v * v).sum::<f64>())
}

/// The 3D ball tracker (SPEC 7.3, 7.4): a particle filter over the ball's centre and
/// velocity in the camera frame (metres, y down), weighed by the colour likelihood of its
/// image circle, boosted by colour-blob detections. `BallTracker(K, radius_m, colour=None,
/// patch=None, distortion=None, particles=4000, boost=0.2, fps=30.0, seed=1, gravity=0.0,
/// accel_sigma=10.0, floor_y=None, restitution=0.8)`: the colour model is one RGB colour
/// (`colour`), or the disc `patch` = (image, x, y, r) of a frame; `distortion` in OpenCV's
/// order (k1, k2, p1, p2[, k3]); `gravity` m/s^2 along y; `floor_y` the level floor's y.
#[pyclass(module = "ocellus._ocellus")]
struct BallTracker {
    tracker: Tracker,
}

#[pymethods]
impl BallTracker {
    #[new]
    #[pyo3(signature = (k, radius_m, colour = None, patch = None, distortion = None, particles = 4000, boost = 0.2,
                        fps = 30.0, seed = 1, gravity = 0.0, accel_sigma = 10.0, floor_y = None, restitution = 0.8))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        k: &Bound<'_, PyAny>,
        radius_m: f64,
        colour: Option<(u8, u8, u8)>,
        patch: Option<(Bound<'_, PyAny>, f64, f64, f64)>,
        distortion: Option<Vec<f64>>,
        particles: usize,
        boost: f64,
        fps: f64,
        seed: u64,
        gravity: f64,
        accel_sigma: f64,
        floor_y: Option<f64>,
        restitution: f64,
    ) -> PyResult<Self> {
        let np = k.py().import("numpy")?;
        let km: Vec<Vec<f64>> = np.call_method1("asarray", (k, "float64"))?.call_method0("tolist")?.extract()?;
        if km.len() != 3 || km.iter().any(|r| r.len() != 3) {
            return Err(err("K must be a 3 x 3 camera matrix"));
        }
        let intrinsics = Intrinsics { fx: km[0][0], fy: km[1][1], cx: km[0][2], cy: km[1][2], skew: km[0][1] };
        let d = match distortion {
            None => Distortion::default(),
            Some(d) if (4..=5).contains(&d.len()) && d.iter().all(|v| v.is_finite()) => {
                Distortion { k1: d[0], k2: d[1], p1: d[2], p2: d[3], k3: d.get(4).copied().unwrap_or(0.0) }
            }
            Some(_) => return Err(err("distortion must be 4 or 5 finite numbers: k1, k2, p1, p2[, k3]")),
        };
        let model = match (colour, patch) {
            (Some((r, g, b)), None) => ColourModel::from_colour([r, g, b]),
            (None, Some((img, x, y, r))) => {
                let frame = image_from(&img)?.to_u8();
                ColourModel::from_patch(&frame, Circle { x, y, r }).map_err(err)?
            }
            _ => return Err(err("give the ball's colour: colour=(r, g, b) or patch=(image, x, y, r), one of them")),
        };
        if !(fps.is_finite() && fps > 0.0) {
            return Err(err(format!("fps {fps}: must be positive")));
        }
        let mut cfg = TrackerConfig::at_fps(fps);
        cfg.particles = particles;
        cfg.boost = boost;
        cfg.filter.seed = seed;
        cfg.motion.gravity = [0.0, gravity, 0.0];
        cfg.motion.accel_sigma = accel_sigma;
        cfg.motion.floor = floor_y.map(|y| Floor::below(y, radius_m, restitution));
        let camera = PinholeCamera { k: intrinsics, r: Matrix3::identity(), t: Vector3::zeros() };
        Ok(Self { tracker: Tracker::new(cfg, camera, d, radius_m, model).map_err(err)? })
    }

    /// One RGB frame (uint8 H x W x 3): {"frame", "position", "velocity" (None before the
    /// start), "circle" (x, y, r pixels), "ess", "score", "lost", "detections"}.
    fn process<'py>(&mut self, py: Python<'py>, frame: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
        let f = image_from(frame)?.to_u8();
        let tracker = &mut self.tracker;
        let e = py.detach(|| tracker.process(&f)).map_err(err)?;
        let d = PyDict::new(py);
        d.set_item("frame", e.frame)?;
        d.set_item("position", e.position.map(|p| p.to_vec()))?;
        d.set_item("velocity", e.velocity.map(|v| v.to_vec()))?;
        d.set_item("circle", e.circle.map(|c| (c.x, c.y, c.r)))?;
        d.set_item("ess", e.ess)?;
        d.set_item("score", e.score)?;
        d.set_item("lost", e.lost)?;
        d.set_item("detections", e.detections)?;
        Ok(d)
    }

    /// The particles as an N x 6 float64 array: x, y, z (m), vx, vy, vz (m/s).
    #[getter]
    fn particles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = self.tracker.particles();
        let a =
            Array2::from_shape_fn((p.len(), 6), |(i, j)| if j < 3 { p[i].position[j] } else { p[i].velocity[j - 3] });
        Ok(PyArray2::from_owned_array(py, a))
    }
}

/// Adds the particle-filter functions and the tracker to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(resample, m)?)?;
    m.add_function(wrap_pyfunction!(effective_sample_size, m)?)?;
    m.add_class::<BallTracker>()
}
