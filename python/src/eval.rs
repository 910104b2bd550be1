//! The saliency metrics of `ocellus_eval::metrics` (MIT/Tuebingen benchmark definitions):
//! maps are 2D arrays of any real dtype, fixations N x 2 integer arrays of (x, y) pixels.

use crate::{err, plane_f64};
use ocellus_eval::metrics;
use ocellus_image::Plane;
use pyo3::prelude::*;

/// Fixations from an N x 2 array (or sequence) of (x, y).
fn fixations(obj: &Bound<'_, PyAny>) -> PyResult<Vec<(usize, usize)>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj,))?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != 2 {
        return Err(err(format!("fixations must be an N x 2 array of (x, y), got shape {shape:?}")));
    }
    let v: Vec<[i64; 2]> = a.call_method0("tolist")?.extract()?;
    v.into_iter()
        .map(|[x, y]| match (usize::try_from(x), usize::try_from(y)) {
            (Ok(x), Ok(y)) => Ok((x, y)),
            _ => Err(err(format!("fixation ({x}, {y}) has a negative coordinate"))),
        })
        .collect()
}

/// A density metric of two maps of one size, the GIL released.
fn density_metric(
    py: Python<'_>,
    saliency: &Bound<'_, PyAny>,
    density: &Bound<'_, PyAny>,
    metric: fn(&Plane<f64>, &Plane<f64>) -> ocellus_eval::Result<f64>,
) -> PyResult<f64> {
    let (s, d) = (plane_f64(saliency, "saliency")?, plane_f64(density, "density")?);
    py.detach(|| metric(&s, &d)).map_err(err)
}

/// `cc(saliency, density)`: Pearson's linear correlation coefficient of two maps of one size.
#[pyfunction]
fn cc(py: Python<'_>, saliency: &Bound<'_, PyAny>, density: &Bound<'_, PyAny>) -> PyResult<f64> {
    density_metric(py, saliency, density, metrics::cc)
}

/// `sim(saliency, density)`: histogram intersection of the two maps as distributions.
#[pyfunction]
fn sim(py: Python<'_>, saliency: &Bound<'_, PyAny>, density: &Bound<'_, PyAny>) -> PyResult<f64> {
    density_metric(py, saliency, density, metrics::sim)
}

/// `kl(saliency, density)`: KL divergence of the density from the saliency map, in nats.
#[pyfunction]
fn kl(py: Python<'_>, saliency: &Bound<'_, PyAny>, density: &Bound<'_, PyAny>) -> PyResult<f64> {
    density_metric(py, saliency, density, metrics::kl)
}

/// `nss(saliency, fixations)`: normalized scanpath saliency.
#[pyfunction]
fn nss(py: Python<'_>, saliency: &Bound<'_, PyAny>, fixations: &Bound<'_, PyAny>) -> PyResult<f64> {
    let (s, f) = (plane_f64(saliency, "saliency")?, self::fixations(fixations)?);
    py.detach(|| metrics::nss(&s, &f)).map_err(err)
}

/// `auc_judd(saliency, fixations, seed=0)`: AUC-Judd (ties broken by seeded jitter).
#[pyfunction]
#[pyo3(signature = (saliency, fixations, seed = 0))]
fn auc_judd(py: Python<'_>, saliency: &Bound<'_, PyAny>, fixations: &Bound<'_, PyAny>, seed: u64) -> PyResult<f64> {
    let (s, f) = (plane_f64(saliency, "saliency")?, self::fixations(fixations)?);
    py.detach(|| metrics::auc_judd(&s, &f, seed)).map_err(err)
}

/// `auc_borji(saliency, fixations, splits=100, step=0.1, seed=0)`: AUC-Borji, negatives drawn
/// uniformly over the map.
#[pyfunction]
#[pyo3(signature = (saliency, fixations, splits = 100, step = 0.1, seed = 0))]
fn auc_borji(
    py: Python<'_>,
    saliency: &Bound<'_, PyAny>,
    fixations: &Bound<'_, PyAny>,
    splits: usize,
    step: f64,
    seed: u64,
) -> PyResult<f64> {
    let (s, f) = (plane_f64(saliency, "saliency")?, self::fixations(fixations)?);
    py.detach(|| metrics::auc_borji(&s, &f, splits, step, seed)).map_err(err)
}

/// `sauc(saliency, fixations, other_fixations, splits=100, step=0.1, seed=0)`: shuffled AUC,
/// negatives drawn from other images' fixations.
#[pyfunction]
#[pyo3(signature = (saliency, fixations, other_fixations, splits = 100, step = 0.1, seed = 0))]
fn sauc(
    py: Python<'_>,
    saliency: &Bound<'_, PyAny>,
    fixations: &Bound<'_, PyAny>,
    other_fixations: &Bound<'_, PyAny>,
    splits: usize,
    step: f64,
    seed: u64,
) -> PyResult<f64> {
    let s = plane_f64(saliency, "saliency")?;
    let (f, o) = (self::fixations(fixations)?, self::fixations(other_fixations)?);
    py.detach(|| metrics::auc_shuffled(&s, &f, &o, splits, step, seed)).map_err(err)
}

/// `ig(saliency, baseline, fixations)`: information gain over a baseline map, bits per fixation.
#[pyfunction]
fn ig(
    py: Python<'_>,
    saliency: &Bound<'_, PyAny>,
    baseline: &Bound<'_, PyAny>,
    fixations: &Bound<'_, PyAny>,
) -> PyResult<f64> {
    let (s, b) = (plane_f64(saliency, "saliency")?, plane_f64(baseline, "baseline")?);
    let f = self::fixations(fixations)?;
    py.detach(|| metrics::info_gain(&s, &b, &f)).map_err(err)
}

/// Adds the metrics to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    for f in [
        wrap_pyfunction!(cc, m)?,
        wrap_pyfunction!(sim, m)?,
        wrap_pyfunction!(kl, m)?,
        wrap_pyfunction!(nss, m)?,
        wrap_pyfunction!(auc_judd, m)?,
        wrap_pyfunction!(auc_borji, m)?,
        wrap_pyfunction!(sauc, m)?,
        wrap_pyfunction!(ig, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
