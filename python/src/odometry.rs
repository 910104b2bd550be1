//! Visual odometry of a ground-facing camera (SPEC 6) and the generator of floor sequences
//! with their ground truth.

use crate::{err, plane_f32};
use numpy::ndarray::Array2;
use numpy::{PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use ocellus_image::Plane;
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Focal length of the generated floor camera, pixels (as `ocellus generate ground`'s
/// camera.toml).
const GROUND_FOCAL_PX: f64 = 600.0;

/// The floor textures, built in: brick, grass, gravel (CC0 photographs of the repository).
const TEXTURES: [&[u8]; 3] = [
    include_bytes!("../../assets/brick.png"),
    include_bytes!("../../assets/grass.png"),
    include_bytes!("../../assets/gravel.png"),
];

/// A generated ground sequence (`ocellus generate ground`): a camera looking down at a floor
/// of real textures, moving on a known path; frames are rendered on demand.
/// `GroundSequence(frames=200, texture="mosaic", seed=1, hard=False)`: texture "brick",
/// "grass", "gravel" or "mosaic"; `hard` adds noise, blur, flicker and height changes.
#[pyclass(module = "ocellus._ocellus")]
struct GroundSequence {
    scene: GroundScene,
}

#[pymethods]
impl GroundSequence {
    #[new]
    #[pyo3(signature = (frames = 200, texture = "mosaic", seed = 1, hard = false))]
    fn new(py: Python<'_>, frames: usize, texture: &str, seed: u64, hard: bool) -> PyResult<Self> {
        let texture = match texture {
            "brick" => GroundTexture::Brick,
            "grass" => GroundTexture::Grass,
            "gravel" => GroundTexture::Gravel,
            "mosaic" => GroundTexture::Mosaic,
            other => return Err(err(format!("texture {other:?}: brick, grass, gravel or mosaic"))),
        };
        let base = if hard { GroundConfig::hard(texture, seed) } else { GroundConfig::easy(texture, seed) };
        let cfg = GroundConfig { frames, ..base };
        let scene = py
            .detach(|| -> Result<GroundScene, String> {
                let t = TEXTURES.map(|b| {
                    ocellus_io::decode_image(b, std::path::Path::new("texture.png"))
                        .map(|i| i.to_grey())
                        .map_err(|e| e.to_string())
                });
                let [a, b, c] = t;
                GroundScene::new(cfg, [a?, b?, c?]).map_err(|e| e.to_string())
            })
            .map_err(err)?;
        Ok(Self { scene })
    }

    fn __len__(&self) -> usize {
        self.scene.len()
    }

    /// Frame `k` (uint8, H x W).
    fn frame<'py>(&self, py: Python<'py>, k: usize) -> PyResult<Bound<'py, PyArray2<u8>>> {
        if k >= self.scene.len() {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!("frame {k} of {}", self.scene.len())));
        }
        let scene = &self.scene;
        let f = py.detach(|| scene.frame(k)).map_err(err)?;
        let (w, h) = f.size();
        let a = Array2::from_shape_vec((h, w), f.into_vec()).map_err(err)?;
        Ok(PyArray2::from_owned_array(py, a))
    }

    /// The robot's true pose at frame `k`: (x, y) metres, heading radians (clockwise from
    /// forward), as the odometry reports it.
    fn pose(&self, k: usize) -> PyResult<(f64, f64, f64)> {
        self.scene
            .pose_m(k)
            .ok_or_else(|| pyo3::exceptions::PyIndexError::new_err(format!("frame {k} of {}", self.scene.len())))
    }

    /// Timestamp of frame `k`, seconds.
    fn time_s(&self, k: usize) -> f64 {
        self.scene.time_s(k)
    }

    /// The camera that sees it: {"height_m", "focal_px", "mount": (right_m, forward_m)}, what
    /// `Odometry` needs.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.scene.config();
        let d = PyDict::new(py);
        d.set_item("height_m", c.metres_per_px * GROUND_FOCAL_PX)?;
        d.set_item("focal_px", GROUND_FOCAL_PX)?;
        d.set_item("mount", (c.mount_px[0] * c.metres_per_px, c.mount_px[1] * c.metres_per_px))?;
        Ok(d)
    }
}

/// Visual odometry over a frame stream (SPEC 6): `Odometry(height_m, focal_px,
/// mount=(0.0, 0.0), mode="robust")`, `mount` the camera's (right, forward) offset from the
/// rotation centre in metres; "seed" is the seed's SAD block matching and Kalman filter,
/// "robust" the sub-pixel, robust estimator. Feed undistorted grey frames in order.
#[pyclass(module = "ocellus._ocellus")]
struct Odometry {
    vo: VisualOdometry,
}

#[pymethods]
impl Odometry {
    #[new]
    #[pyo3(signature = (height_m, focal_px, mount = (0.0, 0.0), mode = "robust"))]
    fn new(height_m: f64, focal_px: f64, mount: (f64, f64), mode: &str) -> PyResult<Self> {
        let mount = Mount { right_m: mount.0, forward_m: mount.1 };
        let cfg = match mode {
            "robust" => OdometryConfig::robust(height_m, focal_px, mount),
            "seed" => OdometryConfig::seed(height_m, focal_px, mount),
            other => return Err(err(format!("mode {other:?}: \"robust\" or \"seed\""))),
        };
        Ok(Self { vo: VisualOdometry::new(cfg).map_err(err)? })
    }

    /// One frame (uint8 H x W, or float32 in grey levels 0..255): {"pose": (x, y, theta),
    /// "camera_motion": (right, forward, turn), "camera_motion_sigma", "failure" (None, or
    /// why the motion was predicted instead of measured), "height_m" (the camera height
    /// followed in robust mode)}.
    fn step<'py>(&mut self, py: Python<'py>, frame: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
        let grey: Plane<u8> = match frame.extract::<PyReadonlyArrayDyn<'_, u8>>() {
            Ok(a) => {
                let shape = a.shape();
                if shape.len() != 2 || shape[0] == 0 || shape[1] == 0 {
                    return Err(err(format!("a frame must be a non-empty H x W array, got shape {shape:?}")));
                }
                let v = a.as_array();
                Plane::from_fn(shape[1], shape[0], |x, y| v[[y, x]])
            }
            Err(_) => plane_f32(frame, "frame")?.map(|v| v.round().clamp(0.0, 255.0) as u8),
        };
        let vo = &mut self.vo;
        let s = py.detach(|| vo.step(&grey)).map_err(err)?;
        let d = PyDict::new(py);
        d.set_item("pose", (s.pose.x, s.pose.y, s.pose.theta))?;
        d.set_item("camera_motion", s.camera_motion.to_vec())?;
        d.set_item("camera_motion_sigma", s.camera_motion_sigma.to_vec())?;
        d.set_item("failure", s.failure)?;
        d.set_item("height_m", s.height_m)?;
        Ok(d)
    }

    /// The robot's pose: (x, y) metres, heading radians.
    #[getter]
    fn pose(&self) -> (f64, f64, f64) {
        let p = self.vo.pose();
        (p.x, p.y, p.theta)
    }
}

/// Adds odometry and the ground generator to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<GroundSequence>()?;
    m.add_class::<Odometry>()?;
    Ok(())
}
