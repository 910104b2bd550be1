//! `ocellus._ocellus`: the Python module of ocellus (PyO3 + rust-numpy).
//!
//! Conventions, the same as the Rust library's (`ocellus_image`): arrays are row-major
//! (C order), indexed `[y, x]`; images are `uint8` (0..255) or `float32` (0..1) arrays of
//! H x W (grey, replicated to R = G = B) or H x W x 3 (RGB); pixel centres sit at integer
//! coordinates. Maps come back as `float32` arrays that own the Rust buffer (no copy).
//! Inputs are read once into the library's planes (one copy; strided arrays are read through
//! their strides). Every heavy call releases the GIL. Errors raise `ocellus.OcellusError`, a
//! subclass of `ValueError`, with the library's message.

use numpy::ndarray::Array2;
use numpy::{PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use ocellus_attention::{SaliencyConfig, SaliencyEngine as Engine};
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

mod eval;
mod fovea;
mod geometry;
mod odometry;
mod stream;
mod tracking;

create_exception!(
    _ocellus,
    OcellusError,
    PyValueError,
    "An error of the ocellus library (bad input, impossible parameters); the message says which."
);

/// A library error as a Python exception.
pub(crate) fn err(e: impl std::fmt::Display) -> PyErr {
    OcellusError::new_err(e.to_string())
}

/// An input image: a uint8 or float32 array of H x W or H x W x 3.
pub(crate) fn image_from(obj: &Bound<'_, PyAny>) -> PyResult<RgbImage> {
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'_, u8>>() {
        let v = a.as_array();
        let (h, w) = dims(a.shape(), "image")?;
        let plane = match a.shape().len() {
            2 => Plane::from_fn(w, h, |x, y| [v[[y, x]]; 3]),
            _ => match a.as_slice() {
                // C-contiguous: whole rows at once.
                Ok(s) => Plane::from_vec(w, h, rgb_pixels(s)).map_err(err)?,
                Err(_) => Plane::from_fn(w, h, |x, y| [v[[y, x, 0]], v[[y, x, 1]], v[[y, x, 2]]]),
            },
        };
        return Ok(RgbImage::U8(plane));
    }
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'_, f32>>() {
        let v = a.as_array();
        let (h, w) = dims(a.shape(), "image")?;
        if v.iter().any(|x| !x.is_finite()) {
            return Err(err("the image has NaN or infinite values"));
        }
        let plane = match a.shape().len() {
            2 => Plane::from_fn(w, h, |x, y| [v[[y, x]]; 3]),
            _ => Plane::from_fn(w, h, |x, y| [v[[y, x, 0]], v[[y, x, 1]], v[[y, x, 2]]]),
        };
        return Ok(RgbImage::F32(plane));
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "an image must be a numpy array of uint8 or float32, got {}",
        obj.get_type().name()?
    )))
}

/// Interleaved RGB bytes as pixels: one memcpy (`[u8; 3]` has the bytes' layout), not a
/// loop over pixels.
fn rgb_pixels(bytes: &[u8]) -> Vec<[u8; 3]> {
    let (pixels, _) = bytes.as_chunks::<3>();
    pixels.to_vec()
}

/// Refuses frame sizes whose buffers could not be allocated (an allocation failure would abort
/// the interpreter): at most `ocellus_io::DEFAULT_MAX_PIXELS` pixels, as images read from files.
pub(crate) fn check_frame_size(width: usize, height: usize) -> PyResult<()> {
    let pixels = (width as u64).saturating_mul(height as u64);
    if width == 0 || height == 0 || pixels > ocellus_io::DEFAULT_MAX_PIXELS {
        return Err(err(format!("a {width}x{height} frame: need 1..={} pixels", ocellus_io::DEFAULT_MAX_PIXELS)));
    }
    Ok(())
}

/// (height, width) of an H x W or H x W x 3 array, non-empty.
pub(crate) fn dims(shape: &[usize], what: &str) -> PyResult<(usize, usize)> {
    let ok = match shape {
        [h, w] | [h, w, 3] => *h > 0 && *w > 0,
        _ => false,
    };
    if !ok {
        return Err(err(format!("{what} must be a non-empty H x W or H x W x 3 array, got shape {shape:?}")));
    }
    Ok((shape[0], shape[1]))
}

/// A float plane from a 2D array of any real dtype numpy can cast to float64.
pub(crate) fn plane_f64(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Plane<f64>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj, "float64"))?;
    let a: PyReadonlyArrayDyn<'_, f64> = a.extract()?;
    let shape = a.shape();
    if shape.len() != 2 || shape[0] == 0 || shape[1] == 0 {
        return Err(err(format!("{what} must be a non-empty 2D array, got shape {shape:?}")));
    }
    let v = a.as_array();
    Ok(Plane::from_fn(shape[1], shape[0], |x, y| v[[y, x]]))
}

/// A float32 grey plane from a 2D array of any real dtype.
pub(crate) fn plane_f32(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Plane<f32>> {
    let p = plane_f64(obj, what)?;
    if !p.as_slice().iter().all(|v| v.is_finite()) {
        return Err(err(format!("{what} has NaN or infinite values")));
    }
    Ok(p.map(|v| v as f32))
}

/// A numpy array that owns `p`'s pixels (moved, not copied, when the plane is contiguous).
pub(crate) fn to_numpy<'py>(py: Python<'py>, p: Plane<f32>) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let (w, h) = p.size();
    let a = Array2::from_shape_vec((h, w), p.into_vec()).map_err(err)?;
    Ok(PyArray2::from_owned_array(py, a))
}

/// A dict as a JSON value (through Python's json module: every value a dict of numbers,
/// strings, lists and dicts can hold).
pub(crate) fn json_of(d: &Bound<'_, PyDict>) -> PyResult<serde_json::Value> {
    let text = d.py().import("json")?.call_method1("dumps", (d,))?.extract::<String>()?;
    serde_json::from_str(&text).map_err(err)
}

/// A saliency configuration: a preset with a dict of overrides, by the command-line
/// program's rule (`ocellus_attention::overrides`: nested tables merged key by key, channels
/// added by kind unless `replace_channels`).
fn config_from(preset: &str, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<SaliencyConfig> {
    let over = overrides.map(json_of).transpose()?.unwrap_or(serde_json::Value::Null);
    ocellus_attention::overrides::saliency_config(preset, over).map_err(err)
}

/// The saliency engine for frames of one size (SPEC 1): build once, then `process` each
/// frame; all buffers are reused.
///
/// One engine serves one thread at a time: a call while another thread's call runs on the
/// same engine raises `RuntimeError` (an engine per thread is the parallel pattern).
#[pyclass(module = "ocellus._ocellus")]
struct SaliencyEngine {
    engine: Engine,
    /// The engine's own frame buffer, which `input` shows to Python without a copy (8-bit
    /// RGB, the frame size; never resized, so the memory stays where the view points).
    frame: RgbImage,
}

#[pymethods]
impl SaliencyEngine {
    /// `SaliencyEngine(width, height, preset="ace2009", config=None)`: `config` is a dict of
    /// overrides of the preset's fields (e.g. `{"normalization": {"kind": "none"}}`).
    #[new]
    #[pyo3(signature = (width, height, preset = "ace2009", config = None))]
    fn new(width: usize, height: usize, preset: &str, config: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        check_frame_size(width, height)?;
        let cfg = config_from(preset, config)?;
        let engine = Engine::new(cfg, width, height).map_err(err)?;
        Ok(Self { engine, frame: RgbImage::U8(Plane::new(width, height)) })
    }

    /// The engine's frame buffer as a writable uint8 H x W x 3 numpy array that shares the
    /// engine's memory: fill it in place (e.g. `cv2.imdecode` or a camera driver writing into
    /// it, or `buf[:] = frame`) and call `process_input()`; no pixel is copied on the way in.
    /// The view keeps the engine alive.
    #[getter]
    fn input<'py>(this: Bound<'py, Self>) -> PyResult<Bound<'py, numpy::PyArray3<u8>>> {
        // A mutable borrow: Python writes through the pointer this view is made from.
        let mut engine = this.borrow_mut();
        let RgbImage::U8(plane) = &mut engine.frame else {
            return Err(err("the frame buffer is not 8-bit"));
        };
        let (w, h) = plane.size();
        let bytes = plane.as_contiguous_mut().ok_or_else(|| err("the frame buffer is not contiguous"))?;
        let view = numpy::ndarray::ArrayViewMut3::from_shape((h, w, 3), bytes.as_flattened_mut()).map_err(err)?;
        // SAFETY: `frame` is never resized or replaced, so the memory stays valid while the
        // engine lives, and the engine (`container`) is kept alive by the array's base.
        let container = this.clone().into_any();
        Ok(unsafe { numpy::PyArray3::borrow_from_array(&view, container) })
    }

    /// The saliency map of the frame in `input` (filled in place). The GIL stays held while
    /// it runs, so no Python code writes the buffer while the engine reads it.
    fn process_input<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let map = self.engine.process(&self.frame).map_err(err)?.clone();
        to_numpy(py, map)
    }

    /// The saliency map of `image` at the map level (1/16 of the frame per side for the
    /// presets), float32 H' x W'.
    fn process<'py>(&mut self, py: Python<'py>, image: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let img = image_from(image)?;
        let engine = &mut self.engine;
        let map = py.detach(|| engine.process(&img).cloned()).map_err(err)?;
        to_numpy(py, map)
    }

    /// The last frame's conspicuity maps, by channel name ("intensity", "colour",
    /// "orientation", ...), after their weights.
    fn conspicuity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, m) in self.engine.conspicuity_maps() {
            d.set_item(name, to_numpy(py, m.clone())?)?;
        }
        Ok(d)
    }

    /// The last saliency map resampled (bilinear) to the frame size.
    fn full_size<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let mut out = Plane::default();
        let engine = &mut self.engine;
        py.detach(|| engine.saliency_full_size(&mut out)).map_err(err)?;
        to_numpy(py, out)
    }

    /// The last frame's time per stage, milliseconds.
    fn timings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, t) in self.engine.timings().stages() {
            d.set_item(name, t.as_secs_f64() * 1e3)?;
        }
        Ok(d)
    }

    /// Milliseconds of each of `repeats` calls of the engine on `image`, timed inside Rust
    /// with no Python in the loop: the reference for the binding's overhead
    /// (`examples/bench_overhead.py` times `process` from Python beside it).
    fn time_in_rust(&mut self, py: Python<'_>, image: &Bound<'_, PyAny>, repeats: usize) -> PyResult<Vec<f64>> {
        let img = image_from(image)?;
        let engine = &mut self.engine;
        py.detach(|| {
            (0..repeats)
                .map(|_| {
                    let t = std::time::Instant::now();
                    engine.process(&img).map(|_| t.elapsed().as_secs_f64() * 1e3)
                })
                .collect::<ocellus_attention::Result<Vec<f64>>>()
        })
        .map_err(err)
    }

    /// (width, height) of the frames this engine takes.
    #[getter]
    fn frame_size(&self) -> (usize, usize) {
        self.engine.frame_size()
    }

    /// (width, height) of its maps.
    #[getter]
    fn map_size(&self) -> (usize, usize) {
        self.engine.map_size()
    }

    fn __repr__(&self) -> String {
        let ((w, h), (mw, mh)) = (self.engine.frame_size(), self.engine.map_size());
        format!("SaliencyEngine({w}x{h} -> {mw}x{mh}, backend {})", self.engine.backend().name())
    }
}

/// `saliency(image, preset="ace2009", config=None, conspicuity=False, full_size=False)`: the
/// saliency map of one image (float32, at the map level). With `conspicuity` or `full_size`,
/// a dict with "saliency" and "conspicuity" (a dict by channel) and/or "full_size".
#[pyfunction]
#[pyo3(signature = (image, preset = "ace2009", config = None, conspicuity = false, full_size = false))]
fn saliency<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    preset: &str,
    config: Option<&Bound<'py, PyDict>>,
    conspicuity: bool,
    full_size: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let img = image_from(image)?;
    let (w, h) = img.size();
    let cfg = config_from(preset, config)?;
    let (mut engine, map) = py
        .detach(|| -> ocellus_attention::Result<_> {
            let mut e = Engine::new(cfg, w, h)?;
            let m = e.process(&img)?.clone();
            Ok((e, m))
        })
        .map_err(err)?;
    if !conspicuity && !full_size {
        return Ok(to_numpy(py, map)?.into_any());
    }
    let d = PyDict::new(py);
    d.set_item("saliency", to_numpy(py, map)?)?;
    if conspicuity {
        let c = PyDict::new(py);
        for (name, m) in engine.conspicuity_maps() {
            c.set_item(name, to_numpy(py, m.clone())?)?;
        }
        d.set_item("conspicuity", c)?;
    }
    if full_size {
        let mut out = Plane::default();
        py.detach(|| engine.saliency_full_size(&mut out)).map_err(err)?;
        d.set_item("full_size", to_numpy(py, out)?)?;
    }
    Ok(d.into_any())
}

/// `read_image(path)`: an image file (PNG, JPEG, PNM) as uint8 H x W x 3, decoded as the
/// command-line program decodes it (16-bit files reduced to 8 bits).
#[pyfunction]
fn read_image<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let img = py.detach(|| ocellus_io::read_image(&path)).map_err(err)?.to_u8();
    let (w, h) = img.size();
    let flat: Vec<u8> = img.into_vec().into_iter().flatten().collect();
    let a = numpy::ndarray::Array3::from_shape_vec((h, w, 3), flat).map_err(err)?;
    Ok(numpy::PyArray3::from_owned_array(py, a).into_any())
}

/// The saliency presets.
#[pyfunction]
fn presets() -> Vec<&'static str> {
    SaliencyConfig::PRESETS.to_vec()
}

/// The module.
#[pymodule]
fn _ocellus(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("OcellusError", m.py().get_type::<OcellusError>())?;
    m.add_class::<SaliencyEngine>()?;
    m.add_function(wrap_pyfunction!(saliency, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    eval::register(m)?;
    fovea::register_module(m)?;
    geometry::register(m)?;
    odometry::register(m)?;
    stream::register(m)?;
    tracking::register(m)?;
    Ok(())
}
