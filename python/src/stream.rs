//! Attention over a video stream (SPEC 2.1-2.2, 3): saliency with flicker, Bayesian
//! surprise, the context chaos degree and winner-take-all with habituation and inhibition of
//! return on an ego-sphere, frame by frame in order.

use crate::{err, image_from, json_of, to_numpy};
use ocellus_attention::overrides::merge;
use ocellus_attention::stream::{StreamConfig, StreamEngine as Engine};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The stream engine: `StreamEngine(width, height, config=None)`, `config` a dict of
/// overrides of the defaults (ace2009 saliency with a flicker channel, surprise, chaos,
/// attention; e.g. `{"deg_per_px": 0.05, "attention": {...}}`). Feed frames in order with
/// `process(image, pan_deg=0.0, tilt_deg=0.0)`, the camera's orientation in degrees.
#[pyclass(module = "ocellus._ocellus")]
struct StreamEngine {
    engine: Engine,
}

#[pymethods]
impl StreamEngine {
    #[new]
    #[pyo3(signature = (width, height, config = None))]
    fn new(width: usize, height: usize, config: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        crate::check_frame_size(width, height)?;
        let mut cfg = StreamConfig::default();
        if let Some(o) = config {
            let mut base = serde_json::to_value(&cfg).map_err(err)?;
            merge(&mut base, json_of(o)?);
            cfg = serde_json::from_value(base).map_err(|e| err(format!("stream configuration: {e}")))?;
        }
        Ok(Self { engine: Engine::new(cfg, width, height).map_err(err)? })
    }

    /// One frame: {"frame", "saliency", "surprise" (bits), "inhibition" (maps at the map
    /// level), "chaos" (bits, None for the first two frames), "familiar", "fixation" (None, or
    /// {"x", "y" (pixels), "azimuth_deg", "elevation_deg", "reason" ("salient" or
    /// "surprising"), "saccade" (whether the gaze moved there this frame)})}.
    #[pyo3(signature = (image, pan_deg = 0.0, tilt_deg = 0.0))]
    fn process<'py>(
        &mut self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
        pan_deg: f32,
        tilt_deg: f32,
    ) -> PyResult<Bound<'py, PyDict>> {
        if !(pan_deg.is_finite() && tilt_deg.is_finite()) {
            return Err(err("pan and tilt must be finite"));
        }
        let img = image_from(image)?;
        let engine = &mut self.engine;
        let (frame, saliency, surprise, inhibition, chaos, familiar, fixation) = py
            .detach(|| {
                engine.process(&img, pan_deg, tilt_deg).map(|f| {
                    (
                        f.frame,
                        f.saliency.clone(),
                        f.surprise.clone(),
                        f.inhibition.clone(),
                        f.chaos,
                        f.familiar,
                        f.fixation,
                    )
                })
            })
            .map_err(err)?;
        let d = PyDict::new(py);
        d.set_item("frame", frame)?;
        d.set_item("saliency", to_numpy(py, saliency)?)?;
        d.set_item("surprise", to_numpy(py, surprise)?)?;
        d.set_item("inhibition", to_numpy(py, inhibition)?)?;
        d.set_item("chaos", chaos)?;
        d.set_item("familiar", familiar)?;
        match fixation {
            None => d.set_item("fixation", py.None())?,
            Some(f) => {
                let fx = PyDict::new(py);
                fx.set_item("x", f.x)?;
                fx.set_item("y", f.y)?;
                fx.set_item("azimuth_deg", f.azimuth_deg)?;
                fx.set_item("elevation_deg", f.elevation_deg)?;
                fx.set_item("reason", f.reason.as_str())?;
                fx.set_item("saccade", f.saccade)?;
                d.set_item("fixation", fx)?;
            }
        }
        Ok(d)
    }

    /// Forgets the previous frames' temporal state (flicker, chaos) after a cut.
    fn reset_temporal(&mut self) {
        self.engine.reset_temporal();
    }

    /// Frames processed.
    #[getter]
    fn frames(&self) -> usize {
        self.engine.frames()
    }
}

/// Adds the stream engine to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<StreamEngine>()
}
