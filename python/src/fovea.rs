//! Foveal vision (SPEC 4): the log-polar map, registration by log-polar phase correlation,
//! and vergence at the fovea.

use crate::{dims, err, plane_f32, to_numpy};
use numpy::{PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use ocellus_fovea::logpolar::{Fields, LogPolarConfig, LogPolarMap};
use ocellus_fovea::register::{register as register_images, Mode, RegisterOptions};
use ocellus_fovea::vergence::{vergence as vergence_at, VergenceOptions};
use ocellus_image::Plane;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A grey uint8 plane from an H x W uint8 array, or the mean of an H x W x 3 one's channels.
fn grey_u8(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Plane<u8>> {
    let a: PyReadonlyArrayDyn<'_, u8> = obj
        .extract()
        .map_err(|_| pyo3::exceptions::PyTypeError::new_err(format!("{what} must be a uint8 numpy array")))?;
    let (h, w) = dims(a.shape(), what)?;
    let v = a.as_array();
    Ok(match a.shape().len() {
        2 => Plane::from_fn(w, h, |x, y| v[[y, x]]),
        _ => Plane::from_fn(w, h, |x, y| {
            ((u16::from(v[[y, x, 0]]) + u16::from(v[[y, x, 1]]) + u16::from(v[[y, x, 2]]) + 1) / 3) as u8
        }),
    })
}

/// A log-polar (retino-cortical) map for images of one size (SPEC 4.1): `rings` log rings
/// between `fovea_radius` and `max_radius` and `fovea_rings` linear rings inside, `sectors`
/// sectors, about `centre` (x, y). Defaults: 128 x 128 about the image centre, max_radius
/// half the smaller side. `fields`: "pyramid" (fast, the default) or "area" (exact
/// annular-sector averages).
#[pyclass(module = "ocellus._ocellus")]
struct LogPolar {
    map: LogPolarMap,
}

#[pymethods]
impl LogPolar {
    #[new]
    #[pyo3(signature = (width, height, rings = 128, sectors = 128, fovea_radius = None, max_radius = None,
                        fovea_rings = None, centre = None, fields = "pyramid"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        width: usize,
        height: usize,
        rings: usize,
        sectors: usize,
        fovea_radius: Option<f64>,
        max_radius: Option<f64>,
        fovea_rings: Option<usize>,
        centre: Option<(f64, f64)>,
        fields: &str,
    ) -> PyResult<Self> {
        crate::check_frame_size(width, height)?;
        let mut cfg = LogPolarConfig { rings, sectors, ..LogPolarConfig::for_image(width, height) };
        if let Some(r) = max_radius {
            cfg.max_radius = r;
        }
        if let Some(r) = fovea_radius {
            cfg.fovea_radius = r;
            cfg.fovea_rings = r.round().max(1.0) as usize;
        }
        if let Some(f) = fovea_rings {
            cfg.fovea_rings = f;
        }
        if let Some((x, y)) = centre {
            cfg.centre = [x, y];
        }
        cfg.fields = match fields {
            "pyramid" => Fields::Pyramid,
            "area" => Fields::Area,
            other => return Err(err(format!("fields {other:?}: \"pyramid\" or \"area\""))),
        };
        let map = py.detach(|| LogPolarMap::new(&cfg, width, height)).map_err(err)?;
        Ok(Self { map })
    }

    /// The cortical image (rows x sectors, float32) of a grey uint8 or float32 image (H x W),
    /// or of an RGB uint8 image (H x W x 3; rows x sectors x 3).
    fn forward<'py>(&self, py: Python<'py>, image: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let map = &self.map;
        if let Ok(a) = image.extract::<PyReadonlyArrayDyn<'_, u8>>() {
            if a.shape().len() == 3 {
                let (h, w) = dims(a.shape(), "image")?;
                let v = a.as_array();
                let rgb = Plane::from_fn(w, h, |x, y| [v[[y, x, 0]], v[[y, x, 1]], v[[y, x, 2]]]);
                let [r, g, b] = py.detach(|| map.sample_rgb(&rgb)).map_err(err)?;
                let (cw, ch) = r.size();
                let flat: Vec<f32> =
                    (0..ch * cw).flat_map(|i| [r.as_slice()[i], g.as_slice()[i], b.as_slice()[i]]).collect();
                let arr = numpy::ndarray::Array3::from_shape_vec((ch, cw, 3), flat).map_err(err)?;
                return Ok(numpy::PyArray3::from_owned_array(py, arr).into_any());
            }
            let grey = grey_u8(image, "image")?;
            let out = py.detach(|| map.sample_grey(&grey)).map_err(err)?;
            return Ok(to_numpy(py, out)?.into_any());
        }
        let img = plane_f32(image, "image")?;
        let out = py.detach(|| map.sample_f32(&img)).map_err(err)?;
        Ok(to_numpy(py, out)?.into_any())
    }

    /// The image (H x W, float32) a cortical image (rows x sectors) maps back to, for display.
    fn inverse<'py>(&self, py: Python<'py>, cortex: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let c = plane_f32(cortex, "cortical image")?;
        let map = &self.map;
        let out = py.detach(|| map.inverse(&c)).map_err(err)?;
        to_numpy(py, out)
    }

    /// Rows of the cortical image (fovea rings + log rings).
    #[getter]
    fn rows(&self) -> usize {
        self.map.rows()
    }

    /// Sectors (columns of the cortical image).
    #[getter]
    fn sectors(&self) -> usize {
        self.map.sectors()
    }

    /// Image pixels per cortical cell.
    #[getter]
    fn compression_ratio(&self) -> f64 {
        self.map.compression_ratio()
    }

    /// The ring ratio a = (max_radius / fovea_radius)^(1 / rings).
    #[getter]
    fn ring_ratio(&self) -> f64 {
        self.map.config().ring_ratio()
    }
}

/// `logpolar(image, **options)`: the cortical image of one image (see `LogPolar`).
#[pyfunction]
#[pyo3(signature = (image, rings = 128, sectors = 128, fovea_radius = None, max_radius = None, centre = None,
                    fields = "pyramid"))]
#[allow(clippy::too_many_arguments)]
fn logpolar<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    rings: usize,
    sectors: usize,
    fovea_radius: Option<f64>,
    max_radius: Option<f64>,
    centre: Option<(f64, f64)>,
    fields: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let shape: Vec<usize> = image.getattr("shape")?.extract()?;
    let (h, w) = dims(&shape, "image")?;
    let lp = LogPolar::new(py, w, h, rings, sectors, fovea_radius, max_radius, None, centre, fields)?;
    lp.forward(py, image)
}

/// `register(a, b, rings=256, sectors=512, radius_ratio=40.0, mode="direct")`: rotation and
/// scale of grey image `b` relative to `a` (SPEC 4.3), as a dict: angle_deg (from +x
/// towards +y), scale, translation (x, y; "spectrum" mode only), peak.
#[pyfunction]
#[pyo3(signature = (a, b, rings = 256, sectors = 512, radius_ratio = 40.0, mode = "direct"))]
fn register<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    rings: usize,
    sectors: usize,
    radius_ratio: f64,
    mode: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let mode = match mode {
        "direct" => Mode::Direct,
        "spectrum" => Mode::Spectrum,
        other => return Err(err(format!("mode {other:?}: \"direct\" or \"spectrum\""))),
    };
    let (pa, pb) = (plane_f32(a, "a")?, plane_f32(b, "b")?);
    let opts = RegisterOptions { mode, rings, sectors, radius_ratio };
    let r = py.detach(|| register_images(&pa, &pb, &opts)).map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("angle_deg", r.angle_deg)?;
    d.set_item("scale", r.scale)?;
    d.set_item("translation", (r.translation[0], r.translation[1]))?;
    d.set_item("peak", r.peak)?;
    Ok(d)
}

/// `vergence(left, right, gaze, min_disparity=0, max_disparity=64)`: the horizontal
/// disparity (x_left - x_right, pixels) at `gaze` (x, y in the left image) from the
/// log-polar foveas of a rectified pair of grey (or RGB, averaged) uint8 images, as a dict:
/// disparity_px, score (normalized correlation, 1 identical).
#[pyfunction]
#[pyo3(signature = (left, right, gaze, min_disparity = 0, max_disparity = 64))]
fn vergence<'py>(
    py: Python<'py>,
    left: &Bound<'py, PyAny>,
    right: &Bound<'py, PyAny>,
    gaze: (f64, f64),
    min_disparity: i64,
    max_disparity: i64,
) -> PyResult<Bound<'py, PyDict>> {
    let (l, r) = (grey_u8(left, "left")?, grey_u8(right, "right")?);
    let opts = VergenceOptions { min_disparity, max_disparity, ..VergenceOptions::default() };
    let v = py.detach(|| vergence_at(&l, &r, [gaze.0, gaze.1], &opts)).map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("disparity_px", v.disparity_px)?;
    d.set_item("score", v.score)?;
    Ok(d)
}

/// Adds the foveal functions and classes to the module.
pub(crate) fn register_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<LogPolar>()?;
    m.add_function(wrap_pyfunction!(logpolar, m)?)?;
    m.add_function(wrap_pyfunction!(register, m)?)?;
    m.add_function(wrap_pyfunction!(vergence, m)?)?;
    Ok(())
}
