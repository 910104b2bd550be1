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

/// The resampler named `scheme`.
fn resampler(scheme: &str) -> PyResult<Resampler> {
    Ok(match scheme {
        "systematic" => Resampler::Systematic,
        "stratified" => Resampler::Stratified,
        "multinomial" => Resampler::Multinomial,
        "residual" => Resampler::Residual,
        other => return Err(err(format!("scheme {other:?}: systematic, stratified, multinomial or residual"))),
    })
}

/// `resample(weights, scheme="systematic", seed=1)`: parent indices (increasing) of
/// `len(weights)` offspring (SPEC 7.1): "systematic" (the seed's Algorithm 2), "stratified",
/// "multinomial" or "residual". The weights are normalized first.
#[pyfunction]
#[pyo3(signature = (weights, scheme = "systematic", seed = 1))]
fn resample(py: Python<'_>, weights: Vec<f64>, scheme: &str, seed: u64) -> PyResult<Vec<usize>> {
    let r = resampler(scheme)?;
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

/// A generic particle filter over states of D numbers (SPEC 7.1), with the model written
/// over the whole cloud in numpy: `ParticleFilter(states, resample_below=0.5,
/// scheme="systematic", seed=1)`, `states` N x D. Weights are kept as logs; the filter
/// resamples when the ESS falls below `resample_below` x N (1: the seed's SIR, every step;
/// 0: SIS, never).
#[pyclass(module = "ocellus._ocellus")]
struct ParticleFilter {
    filter: ocellus_estimation::particle_filter::ParticleFilter<Vec<f64>>,
    dim: usize,
}

/// The rows of an N x D float64 array (any real dtype) with `n` rows, or any `n` when None.
fn cloud(obj: &Bound<'_, PyAny>, n: Option<usize>, dim: Option<usize>) -> PyResult<Vec<Vec<f64>>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj, "float64"))?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let ok = shape.len() == 2
        && shape[0] > 0
        && shape[1] > 0
        && n.is_none_or(|n| shape[0] == n)
        && dim.is_none_or(|d| shape[1] == d);
    if !ok {
        return Err(err(format!("states must be an N x D array (N = {n:?}, D = {dim:?}), got shape {shape:?}")));
    }
    let rows: Vec<Vec<f64>> = a.call_method0("tolist")?.extract()?;
    if rows.iter().flatten().any(|v| v.is_nan()) {
        return Err(err("states hold NaN"));
    }
    Ok(rows)
}

/// A length-`n` float64 vector from a sequence or array (a scalar 0 is not allowed).
fn vector(obj: &Bound<'_, PyAny>, n: usize, what: &str) -> PyResult<Vec<f64>> {
    let np = obj.py().import("numpy")?;
    let v: Vec<f64> =
        np.call_method1("asarray", (obj, "float64"))?.call_method0("ravel")?.call_method0("tolist")?.extract()?;
    if v.len() != n {
        return Err(err(format!("{what} has {} entries for {n} particles", v.len())));
    }
    Ok(v)
}

fn states_array<'py>(py: Python<'py>, s: &[Vec<f64>], dim: usize) -> Bound<'py, PyArray2<f64>> {
    PyArray2::from_owned_array(py, Array2::from_shape_fn((s.len(), dim), |(i, j)| s[i][j]))
}

#[pymethods]
impl ParticleFilter {
    #[new]
    #[pyo3(signature = (states, resample_below = 0.5, scheme = "systematic", seed = 1))]
    fn new(states: &Bound<'_, PyAny>, resample_below: f64, scheme: &str, seed: u64) -> PyResult<Self> {
        let s = cloud(states, None, None)?;
        let dim = s[0].len();
        if !(0.0..=1.0).contains(&resample_below) {
            return Err(err(format!("resample_below {resample_below} is outside [0, 1]")));
        }
        let resampler = resampler(scheme)?;
        let cfg = ocellus_estimation::particle_filter::FilterConfig { resample_below, resampler, seed };
        let filter = ocellus_estimation::particle_filter::ParticleFilter::new(cfg, s).map_err(err)?;
        Ok(Self { filter, dim })
    }

    /// One step: `propose(states) -> new_states` (N x D; or `(new_states, log_ratio)` with
    /// `log_ratio[i] = ln p(x_i | x'_i) - ln q(x_i | x'_i, z)` for a proposal other than the
    /// motion model), then `log_likelihood(new_states) -> (N,)`, `ln p(z | x_i)`. Returns
    /// {"ess" (before resampling), "resampled", "log_evidence"}. The callables hold the
    /// GIL; draw their randomness from a seeded numpy Generator for reproducible runs.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        propose: &Bound<'py, PyAny>,
        log_likelihood: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (n, dim) = (self.filter.particles().len(), self.dim);
        let out = propose.call1((states_array(py, self.filter.particles(), dim),))?;
        let (moved, ratio) = match out.extract::<(Bound<'py, PyAny>, Bound<'py, PyAny>)>() {
            Ok((s, r)) if out.is_instance_of::<pyo3::types::PyTuple>() => (s, Some(r)),
            _ => (out, None),
        };
        let moved = cloud(&moved, Some(n), Some(dim))?;
        let ratio = ratio.map(|r| vector(&r, n, "the proposal's log ratio")).transpose()?;
        let mut moved = Some(moved);
        self.filter.propose_with(|p, inc| {
            if let Some(m) = moved.take() {
                p.iter_mut().zip(m).for_each(|(a, b)| *a = b);
            }
            if let Some(r) = &ratio {
                inc.copy_from_slice(r);
            }
        });
        let ll = log_likelihood.call1((states_array(py, self.filter.particles(), dim),))?;
        let ll = vector(&ll, n, "the log likelihood")?;
        let report = self.filter.weigh_proposed_with(|_, out| out.copy_from_slice(&ll)).map_err(err)?;
        let d = PyDict::new(py);
        d.set_item("ess", report.ess)?;
        d.set_item("resampled", report.resampled)?;
        d.set_item("log_evidence", report.log_evidence)?;
        Ok(d)
    }

    /// The particles, N x D.
    #[getter]
    fn states<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        states_array(py, self.filter.particles(), self.dim)
    }

    /// The normalized weights.
    #[getter]
    fn weights(&self) -> Vec<f64> {
        self.filter.weights()
    }

    /// The effective sample size of the current weights, particles.
    #[getter]
    fn ess(&self) -> f64 {
        self.filter.ess()
    }

    /// The weighted mean state.
    fn mean(&self) -> Vec<f64> {
        let w = self.filter.weights();
        let mut m = vec![0.0; self.dim];
        for (p, wi) in self.filter.particles().iter().zip(w) {
            m.iter_mut().zip(p).for_each(|(a, v)| *a += wi * v);
        }
        m
    }
}

/// The 3D ball tracker (SPEC 7.3, 7.4): a particle filter over the ball's centre and
/// velocity in the camera frame (metres, y down), weighed by the colour likelihood of its
/// image circle, boosted by colour-blob detections. `BallTracker(K, radius_m, colour=None,
/// patch=None, distortion=None, particles=16000, boost=0.2, fps=30.0, seed=1, gravity=0.0,
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
    #[pyo3(signature = (k, radius_m, colour = None, patch = None, distortion = None, particles = 16000, boost = 0.2,
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
    m.add_class::<ParticleFilter>()?;
    m.add_class::<BallTracker>()
}
