//! Camera geometry (SPEC 5): the DLT and its decomposition, triangulation, planar (Zhang)
//! calibration from chessboard images, undistortion, and dense stereo (block matching, SGM).
//! Matrices are float64 numpy arrays; pixels are (x, y) with centres at integers.

use crate::{err, image_from, to_numpy};
use nalgebra::{Matrix3, Matrix3x4};
use numpy::ndarray::Array2;
use numpy::{PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use ocellus_geometry::block_matching::{block_match, BlockMatching};
use ocellus_geometry::camera::Intrinsics;
use ocellus_geometry::chessboard::{find_chessboard, ChessboardOptions};
use ocellus_geometry::distortion::{remap_bilinear, undistort_maps, Distortion};
use ocellus_geometry::dlt as dlt_mod;
use ocellus_geometry::sgm::{sgm, Sgm};
use ocellus_geometry::triangulate::{check_rig, n_view};
use ocellus_geometry::zhang::{calibrate, PlanarView, ZhangOptions};
use ocellus_image::Plane;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// An N x K float64 array (or nested sequence) as rows of K.
fn rows<const K: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; K]>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj, "float64"))?;
    let a: PyReadonlyArrayDyn<'_, f64> = a.extract()?;
    let shape = a.shape();
    if shape.len() != 2 || shape[1] != K {
        return Err(err(format!("{what} must be an N x {K} array, got shape {shape:?}")));
    }
    let v = a.as_array();
    Ok((0..shape[0]).map(|i| std::array::from_fn(|k| v[[i, k]])).collect())
}

/// A 3 x 4 projection matrix.
fn projection(obj: &Bound<'_, PyAny>) -> PyResult<Matrix3x4<f64>> {
    let r = rows::<4>(obj, "a projection matrix")?;
    if r.len() != 3 {
        return Err(err(format!("a projection matrix must be 3 x 4, got {} rows", r.len())));
    }
    Ok(Matrix3x4::from_fn(|i, j| r[i][j]))
}

fn matrix_to_numpy<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &nalgebra::SMatrix<f64, R, C>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = Array2::from_shape_fn((R, C), |(i, j)| m[(i, j)]);
    Ok(PyArray2::from_owned_array(py, a))
}

fn k_matrix(k: &Intrinsics) -> Matrix3<f64> {
    Matrix3::new(k.fx, k.skew, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0)
}

/// Intrinsics from a 3 x 3 camera matrix [[fx, s, cx], [0, fy, cy], [0, 0, 1]].
fn intrinsics(obj: &Bound<'_, PyAny>) -> PyResult<Intrinsics> {
    let r = rows::<3>(obj, "the camera matrix")?;
    if r.len() != 3 {
        return Err(err("the camera matrix must be 3 x 3"));
    }
    let k = Intrinsics { fx: r[0][0], fy: r[1][1], cx: r[0][2], cy: r[1][2], skew: r[0][1] };
    if ![k.fx, k.fy, k.cx, k.cy, k.skew].iter().all(|v| v.is_finite()) || k.fx <= 0.0 || k.fy <= 0.0 {
        return Err(err("the camera matrix needs finite values and positive focal lengths"));
    }
    Ok(k)
}

/// Distortion from OpenCV's order (k1, k2, p1, p2[, k3]).
fn distortion(d: Vec<f64>) -> PyResult<Distortion> {
    if !(4..=5).contains(&d.len()) || !d.iter().all(|v| v.is_finite()) {
        return Err(err("distortion must be 4 or 5 finite numbers: k1, k2, p1, p2[, k3]"));
    }
    Ok(Distortion { k1: d[0], k2: d[1], p1: d[2], p2: d[3], k3: d.get(4).copied().unwrap_or(0.0) })
}

/// `dlt(points3, points2, method="svd")`: the projection matrix P (3 x 4) from N >= 6 3D-2D
/// correspondences (SPEC 5.2), by Hartley-normalized SVD ("svd") or the seed's p34 = 1 least
/// squares ("linear"), with its reprojection RMS in pixels: {"P", "rms_px"}.
#[pyfunction]
#[pyo3(signature = (points3, points2, method = "svd"))]
fn dlt<'py>(
    py: Python<'py>,
    points3: &Bound<'py, PyAny>,
    points2: &Bound<'py, PyAny>,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let (p3, p2) = (rows::<3>(points3, "points3")?, rows::<2>(points2, "points2")?);
    let p = match method {
        "svd" => py.detach(|| dlt_mod::dlt(&p3, &p2)),
        "linear" => py.detach(|| dlt_mod::dlt_linear(&p3, &p2)),
        other => return Err(err(format!("method {other:?}: \"svd\" or \"linear\""))),
    }
    .map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("P", matrix_to_numpy(py, &p)?)?;
    d.set_item("rms_px", dlt_mod::reprojection(&p, &p3, &p2).rms_px)?;
    Ok(d)
}

/// `decompose(P)`: P = K [R | t] as {"K", "R", "t"} (K with positive diagonal, R proper).
#[pyfunction]
fn decompose<'py>(py: Python<'py>, p: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    let cam = dlt_mod::decompose(&projection(p)?).map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("K", matrix_to_numpy(py, &k_matrix(&cam.k))?)?;
    d.set_item("R", matrix_to_numpy(py, &cam.r)?)?;
    d.set_item("t", (cam.t.x, cam.t.y, cam.t.z))?;
    Ok(d)
}

/// `triangulate(projections, points)`: the 3D point seen at `points[i]` (x, y) by camera
/// `projections[i]` (3 x 4), two views or more, by SVD (SPEC 5.5): {"point", "in_front"}.
/// Cameras sharing a centre are refused.
#[pyfunction]
fn triangulate<'py>(
    py: Python<'py>,
    projections: Vec<Bound<'py, PyAny>>,
    points: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let ps = projections.iter().map(projection).collect::<PyResult<Vec<_>>>()?;
    let xs = rows::<2>(points, "points")?;
    if xs.len() != ps.len() {
        return Err(err(format!("{} points for {} cameras", xs.len(), ps.len())));
    }
    // Cameras at one centre see no depth: refused, as the command-line program does.
    check_rig(&ps).map_err(err)?;
    let views: Vec<(&Matrix3x4<f64>, [f64; 2])> = ps.iter().zip(xs).collect();
    let t = n_view(&views).map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("point", (t.point.x, t.point.y, t.point.z))?;
    d.set_item("in_front", t.in_front)?;
    Ok(d)
}

/// `undistort(image, K, distortion)`: the image of the same camera without lens distortion
/// (bilinear; outside the source 0), float32 in the input's grey levels (RGB averaged to
/// grey by the library's weights). `distortion` in OpenCV's order k1, k2, p1, p2[, k3].
#[pyfunction]
fn undistort<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    k: &Bound<'py, PyAny>,
    distortion: Vec<f64>,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let img = image_from(image)?;
    let (k, d) = (intrinsics(k)?, self::distortion(distortion)?);
    let grey = img.to_grey();
    let scale = if matches!(img, ocellus_image::convert::RgbImage::U8(_)) { 255.0 } else { 1.0 };
    let out = py
        .detach(|| {
            let (w, h) = grey.size();
            let (mx, my) = undistort_maps(&k, &d, w, h);
            remap_bilinear(&grey.map(|v| v * scale), &mx, &my, 0.0)
        })
        .map_err(err)?;
    to_numpy(py, out)
}

/// `calibrate_chessboard(images, cols, rows, square=1.0)`: Zhang's planar calibration with
/// radial and tangential distortion (SPEC 5.3) from views of a chessboard of `cols` x `rows`
/// inner corners, `square` apart (target units). Views whose corners are not all found are
/// skipped. Returns {"K", "distortion" (k1, k2, p1, p2, k3), "rms_px", "per_view_rms_px",
/// "used" (indices of the views used)}.
#[pyfunction]
#[pyo3(signature = (images, cols, rows, square = 1.0))]
fn calibrate_chessboard<'py>(
    py: Python<'py>,
    images: Vec<Bound<'py, PyAny>>,
    cols: usize,
    rows: usize,
    square: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(square.is_finite() && square > 0.0) {
        return Err(err(format!("square {square}: must be finite and positive")));
    }
    let greys = images.iter().map(|i| image_from(i).map(|g| g.to_grey())).collect::<PyResult<Vec<_>>>()?;
    let object: Vec<[f64; 2]> =
        (0..rows).flat_map(|r| (0..cols).map(move |c| [c as f64 * square, r as f64 * square])).collect();
    let (cal, used) = py
        .detach(|| {
            let mut views = Vec::new();
            let mut used = Vec::new();
            for (i, g) in greys.iter().enumerate() {
                if let Ok(corners) = find_chessboard(g, cols, rows, &ChessboardOptions::default()) {
                    views.push(PlanarView { object: object.clone(), image: corners });
                    used.push(i);
                }
            }
            calibrate(&views, &ZhangOptions::default()).map(|c| (c, used))
        })
        .map_err(err)?;
    let d = PyDict::new(py);
    d.set_item("K", matrix_to_numpy(py, &k_matrix(&cal.intrinsics))?)?;
    let dist = cal.distortion;
    d.set_item("distortion", (dist.k1, dist.k2, dist.p1, dist.p2, dist.k3))?;
    d.set_item("rms_px", cal.rms_px)?;
    d.set_item("per_view_rms_px", cal.per_view_rms_px)?;
    d.set_item("used", used)?;
    Ok(d)
}

/// A grey uint8 plane of a stereo image (RGB reduced with the library's weights).
fn stereo_grey(obj: &Bound<'_, PyAny>) -> PyResult<Plane<u8>> {
    Ok(image_from(obj)?.to_luma8())
}

/// `stereo_bm(left, right, max_disparity=64, block=9)`: disparity (x_left - x_right, pixels,
/// float32; NaN where rejected) of a rectified pair by block matching (SPEC 5.6).
#[pyfunction]
#[pyo3(signature = (left, right, max_disparity = 64, block = 9))]
fn stereo_bm<'py>(
    py: Python<'py>,
    left: &Bound<'py, PyAny>,
    right: &Bound<'py, PyAny>,
    max_disparity: usize,
    block: usize,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let (l, r) = (stereo_grey(left)?, stereo_grey(right)?);
    let p = BlockMatching { max_disparity, block, ..BlockMatching::default() };
    let d = py.detach(|| block_match(&l, &r, &p)).map_err(err)?;
    to_numpy(py, d)
}

/// `stereo_sgm(left, right, max_disparity=64)`: disparity of a rectified pair by semi-global
/// matching on census costs (8 paths; sub-pixel; NaN where rejected).
#[pyfunction]
#[pyo3(signature = (left, right, max_disparity = 64))]
fn stereo_sgm<'py>(
    py: Python<'py>,
    left: &Bound<'py, PyAny>,
    right: &Bound<'py, PyAny>,
    max_disparity: usize,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let (l, r) = (stereo_grey(left)?, stereo_grey(right)?);
    let p = Sgm { max_disparity, ..Sgm::default() };
    let d = py.detach(|| sgm(&l, &r, &p)).map_err(err)?;
    to_numpy(py, d)
}

/// Adds the geometry functions to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    for f in [
        wrap_pyfunction!(dlt, m)?,
        wrap_pyfunction!(decompose, m)?,
        wrap_pyfunction!(triangulate, m)?,
        wrap_pyfunction!(undistort, m)?,
        wrap_pyfunction!(calibrate_chessboard, m)?,
        wrap_pyfunction!(stereo_bm, m)?,
        wrap_pyfunction!(stereo_sgm, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
