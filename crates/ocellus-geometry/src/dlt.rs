//! Camera calibration from 3D-2D correspondences by the direct linear transform (SPEC 5.2).
//!
//! - [`dlt_linear`]: the seed's form: `p34 = 1`, 11 unknowns, two equations per point,
//!   least squares `p = (C^T C)^-1 C^T c`. Simple, but `p34 = 1` assumes the world origin is
//!   in front of the camera at a moderate scale; with world units in millimetres and the
//!   target 2 m away the equations are badly scaled and the estimate degrades.
//! - [`dlt`]: the robust form (Hartley & Zisserman, Multiple View Geometry, alg. 7.1): 2D
//!   points moved to their centroid and scaled to mean distance sqrt 2, 3D points to sqrt 3;
//!   P is the right null vector of the 2N x 12 system (smallest eigenvector of A^T A), then
//!   denormalized. No assumption on p34.
//! - [`reprojection`]: per-point pixel errors, their RMS, and the seed's E.
//! - [`decompose`]: P = K [R | t] by RQ, with positive focal lengths and a proper rotation.

use crate::camera::{Intrinsics, PinholeCamera};
use crate::{check_finite, GeometryError, Result};
use nalgebra::{Matrix3, Matrix3x4, Matrix4, SMatrix, SVector, SymmetricEigen, Vector3, Vector4};

fn check(points3: &[[f64; 3]], points2: &[[f64; 2]]) -> Result<()> {
    if points3.len() != points2.len() {
        return Err(GeometryError::Invalid(format!("{} 3D points but {} 2D points", points3.len(), points2.len())));
    }
    if points3.len() < 6 {
        return Err(GeometryError::TooFewPoints { what: "DLT calibration", need: 6, got: points3.len() });
    }
    check_finite("3D points", points3)?;
    check_finite("2D points", points2)?;
    // Coplanar 3D points leave P undetermined: the smallest spread must not vanish.
    let n = points3.len() as f64;
    let c = points3.iter().fold(Vector3::zeros(), |a, p| a + Vector3::from(*p)) / n;
    let cov = points3.iter().fold(Matrix3::zeros(), |a, p| {
        let d = Vector3::from(*p) - c;
        a + d * d.transpose()
    });
    let ev = SymmetricEigen::new(cov).eigenvalues;
    let (lo, hi) = (ev.min(), ev.max());
    if hi <= 0.0 || lo <= 1e-12 * hi {
        return Err(GeometryError::Degenerate(
            "the 3D points are coplanar (or collinear): the 3D DLT needs depth".into(),
        ));
    }
    Ok(())
}

/// Refuses a fitted P without perspective. Points an affine camera could have made are fitted
/// exactly by a P whose third row has a vanishing rotation part; scaling that row to unit norm
/// would then report focal lengths of 1e14 px with zero reprojection error.
fn check_perspective(p: &Matrix3x4<f64>) -> Result<()> {
    let third = Vector3::new(p[(2, 0)], p[(2, 1)], p[(2, 2)]).norm();
    let top = p.fixed_view::<2, 3>(0, 0).norm();
    if third <= 1e-9 * top {
        return Err(GeometryError::Degenerate(
            "the points fit a camera without perspective (an affine camera: P's third row vanishes); \
             use points spread in depth, seen by a perspective camera"
                .into(),
        ));
    }
    Ok(())
}

/// The seed's linear DLT with `p34 = 1`.
pub fn dlt_linear(points3: &[[f64; 3]], points2: &[[f64; 2]]) -> Result<Matrix3x4<f64>> {
    check(points3, points2)?;
    let mut ata = SMatrix::<f64, 11, 11>::zeros();
    let mut atb = SVector::<f64, 11>::zeros();
    for (p, q) in points3.iter().zip(points2) {
        let [x, y, z] = *p;
        let [u, v] = *q;
        let r1 = SVector::<f64, 11>::from_row_slice(&[x, y, z, 1.0, 0.0, 0.0, 0.0, 0.0, -u * x, -u * y, -u * z]);
        let r2 = SVector::<f64, 11>::from_row_slice(&[0.0, 0.0, 0.0, 0.0, x, y, z, 1.0, -v * x, -v * y, -v * z]);
        ata += r1 * r1.transpose() + r2 * r2.transpose();
        atb += r1 * u + r2 * v;
    }
    let sol = ata.lu().solve(&atb).ok_or_else(|| GeometryError::Degenerate("singular normal equations".into()))?;
    let mut p = Matrix3x4::zeros();
    for i in 0..11 {
        p[(i / 4, i % 4)] = sol[i];
    }
    p[(2, 3)] = 1.0;
    if p.iter().any(|v| !v.is_finite()) {
        return Err(GeometryError::Degenerate("non-finite solution".into()));
    }
    check_perspective(&p)?;
    Ok(p)
}

/// Similarity that moves points to their centroid and scales them to mean distance `target`.
pub(crate) fn normalizer<const D: usize>(pts: &[[f64; D]], target: f64) -> Result<(Vec<[f64; D]>, f64, [f64; D])> {
    let n = pts.len() as f64;
    let mut c = [0.0; D];
    for p in pts {
        for k in 0..D {
            c[k] += p[k] / n;
        }
    }
    let mean = pts.iter().map(|p| (0..D).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>().sqrt()).sum::<f64>() / n;
    if mean.is_nan() || mean <= 0.0 {
        return Err(GeometryError::Degenerate("all points coincide".into()));
    }
    let s = target / mean;
    Ok((pts.iter().map(|p| std::array::from_fn(|k| (p[k] - c[k]) * s)).collect(), s, c))
}

/// The normalized DLT: P up to scale, scaled so that the third row's rotation part has unit
/// norm and points in front of the camera have positive depth.
pub fn dlt(points3: &[[f64; 3]], points2: &[[f64; 2]]) -> Result<Matrix3x4<f64>> {
    check(points3, points2)?;
    let (n3, s3, c3) = normalizer(points3, 3f64.sqrt())?;
    let (n2, s2, c2) = normalizer(points2, 2f64.sqrt())?;
    let mut ata = SMatrix::<f64, 12, 12>::zeros();
    for (p, q) in n3.iter().zip(&n2) {
        let [x, y, z] = *p;
        let [u, v] = *q;
        let r1 = SVector::<f64, 12>::from_row_slice(&[x, y, z, 1.0, 0.0, 0.0, 0.0, 0.0, -u * x, -u * y, -u * z, -u]);
        let r2 = SVector::<f64, 12>::from_row_slice(&[0.0, 0.0, 0.0, 0.0, x, y, z, 1.0, -v * x, -v * y, -v * z, -v]);
        ata += r1 * r1.transpose() + r2 * r2.transpose();
    }
    let eig = SymmetricEigen::new(ata);
    let (imin, _) =
        eig.eigenvalues.iter().enumerate().fold((0, f64::INFINITY), |b, (i, &v)| if v < b.1 { (i, v) } else { b });
    let h = eig.eigenvectors.column(imin);
    let mut pn = Matrix3x4::zeros();
    for i in 0..12 {
        pn[(i / 4, i % 4)] = h[i];
    }
    let t2_inv = Matrix3::new(1.0 / s2, 0.0, c2[0], 0.0, 1.0 / s2, c2[1], 0.0, 0.0, 1.0);
    let t3 = Matrix4::new(
        s3,
        0.0,
        0.0,
        -s3 * c3[0],
        0.0,
        s3,
        0.0,
        -s3 * c3[1],
        0.0,
        0.0,
        s3,
        -s3 * c3[2],
        0.0,
        0.0,
        0.0,
        1.0,
    );
    let mut p = t2_inv * pn * t3;
    let scale = Vector3::new(p[(2, 0)], p[(2, 1)], p[(2, 2)]).norm();
    if scale.is_nan() || scale <= 0.0 || p.iter().any(|v| !v.is_finite()) {
        return Err(GeometryError::Degenerate("no finite solution".into()));
    }
    check_perspective(&p)?;
    p /= scale;
    // Points must be in front: make the mean depth positive.
    let depth: f64 = points3.iter().map(|x| (p.row(2) * Vector4::new(x[0], x[1], x[2], 1.0))[0]).sum();
    if depth < 0.0 {
        p = -p;
    }
    Ok(p)
}

/// Reprojection errors of P on the correspondences.
#[derive(Clone, Debug, PartialEq)]
pub struct Reprojection {
    /// Pixel distance per point (infinite for a point projected to infinity).
    pub per_point: Vec<f64>,
    /// Root mean square of the pixel distances.
    pub rms_px: f64,
    /// The seed's `E = |C p - c|^2 / N` (algebraic residual of the p34 = 1 system, P scaled
    /// to p34 = 1; NaN when p34 = 0).
    pub seed_e: f64,
}

/// Reprojection errors (pixels) of `p` on the correspondences.
pub fn reprojection(p: &Matrix3x4<f64>, points3: &[[f64; 3]], points2: &[[f64; 2]]) -> Reprojection {
    let p34 = p[(2, 3)];
    let ps = if p34 != 0.0 { p / p34 } else { Matrix3x4::repeat(f64::NAN) };
    let mut seed = 0.0;
    let per_point: Vec<f64> = points3
        .iter()
        .zip(points2)
        .map(|(x, q)| {
            let hx = Vector4::new(x[0], x[1], x[2], 1.0);
            let h = p * hx;
            // Algebraic residual rows: p1.X - u p3.X (with p34 = 1 the right side is u).
            let hs = ps * hx;
            seed += (hs.x - q[0] * hs.z).powi(2) + (hs.y - q[1] * hs.z).powi(2);
            if h.z == 0.0 {
                f64::INFINITY
            } else {
                ((h.x / h.z - q[0]).powi(2) + (h.y / h.z - q[1]).powi(2)).sqrt()
            }
        })
        .collect();
    let n = per_point.len().max(1) as f64;
    let rms_px = (per_point.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
    Reprojection { per_point, rms_px, seed_e: seed / n }
}

/// Decomposes `P ~ K [R | t]` by RQ: K upper triangular with positive diagonal (K[2][2] = 1),
/// R a proper rotation. The overall scale and sign of P do not matter.
pub fn decompose(p: &Matrix3x4<f64>) -> Result<PinholeCamera> {
    let mut m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into_owned();
    let mut p4 = p.column(3).into_owned();
    let det = m.determinant();
    if !det.is_finite() || det.abs() < 1e-300 {
        return Err(GeometryError::Degenerate("the left 3x3 block of P is singular".into()));
    }
    if det < 0.0 {
        m = -m;
        p4 = -p4;
    }
    // RQ via QR of the row-reversed transpose: with J the exchange matrix, (J M)^T = Q R
    // gives M = (J R^T J)(J Q^T).
    let j = Matrix3::new(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0);
    let qr = (j * m).transpose().qr();
    let (q, r) = (qr.q(), qr.r());
    let mut k = j * r.transpose() * j;
    let mut rot = j * q.transpose();
    let d = Matrix3::from_diagonal(&Vector3::new(k[(0, 0)].signum(), k[(1, 1)].signum(), k[(2, 2)].signum()));
    k *= d;
    rot = d * rot;
    if rot.determinant() < 0.0 {
        // det M > 0 and det K > 0 make this unreachable up to rounding; keep R proper anyway.
        rot = -rot;
        k = -k;
    }
    // P = [K R | p4] = s K' [R | t] with K' = K / s (K'[2][2] = 1) gives t = K^-1 p4.
    let t = k.try_inverse().ok_or_else(|| GeometryError::Degenerate("singular K".into()))? * p4;
    Ok(PinholeCamera { k: Intrinsics::from_matrix(&k)?, r: rot, t })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;
    use ocellus_image::rng::SplitMix64;

    fn camera(scale: f64) -> PinholeCamera {
        PinholeCamera {
            k: Intrinsics { fx: 810.0, fy: 790.0, cx: 322.0, cy: 236.0, skew: 0.0 },
            r: *Rotation3::from_euler_angles(0.2, -0.3, 0.1).matrix(),
            t: Vector3::new(0.05, -0.1, 2.0) * scale,
        }
    }

    /// `n` points in a box in front of the camera (units of `scale`), and their pixels.
    fn data(c: &PinholeCamera, n: usize, scale: f64, noise_px: f64, seed: u64) -> (Vec<[f64; 3]>, Vec<[f64; 2]>) {
        let mut rng = SplitMix64::new(seed);
        let (mut p3, mut p2) = (Vec::new(), Vec::new());
        while p3.len() < n {
            let x = Vector3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5) * 0.8 * scale;
            if let Ok((px, _)) = c.project(&x) {
                p3.push([x.x, x.y, x.z]);
                p2.push([px.x + noise_px * rng.normal(), px.y + noise_px * rng.normal()]);
            }
        }
        (p3, p2)
    }

    #[test]
    fn both_forms_recover_an_exact_camera() {
        let c = camera(1.0);
        let (p3, p2) = data(&c, 20, 1.0, 0.0, 1);
        for p in [dlt(&p3, &p2).unwrap(), dlt_linear(&p3, &p2).unwrap()] {
            let r = reprojection(&p, &p3, &p2);
            assert!(r.rms_px < 1e-6 && r.seed_e < 1e-9, "{r:?}");
            let d = decompose(&p).unwrap();
            assert!((d.k.fx - 810.0).abs() < 1e-6 && (d.k.fy - 790.0).abs() < 1e-6, "{:?}", d.k);
            assert!((d.k.cx - 322.0).abs() < 1e-6 && d.k.skew.abs() < 1e-6);
            assert!((d.r - c.r).norm() < 1e-9 && (d.t - c.t).norm() < 1e-9, "{:?} {:?}", d.r, d.t);
            assert!((d.r.determinant() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn normalized_form_survives_millimetres_at_two_metres() {
        // World in millimetres, target 2 m away, 0.5 px noise, 100 points, 20 trials: the
        // normalized form keeps the focal error small; both are printed.
        let c = camera(1000.0);
        let (mut e_lin, mut e_norm) = (0.0, 0.0);
        for seed in 0..20 {
            let (p3, p2) = data(&c, 100, 1000.0, 0.5, seed);
            let f = |p: Matrix3x4<f64>| (decompose(&p).unwrap().k.fx - 810.0).abs() / 810.0;
            e_norm += f(dlt(&p3, &p2).unwrap()) / 20.0;
            e_lin += f(dlt_linear(&p3, &p2).unwrap()) / 20.0;
        }
        println!(
            "focal error, mm units at 2 m, 0.5 px noise: normalized {:.3} %, p34 = 1 {:.3} %",
            e_norm * 100.0,
            e_lin * 100.0
        );
        assert!(e_norm < 0.005, "normalized DLT focal error {e_norm}");
    }

    #[test]
    fn degenerate_inputs_are_clear_errors() {
        let c = camera(1.0);
        let (p3, p2) = data(&c, 10, 1.0, 0.0, 2);
        assert!(matches!(dlt(&p3[..5], &p2[..5]), Err(GeometryError::TooFewPoints { got: 5, .. })));
        let flat: Vec<[f64; 3]> = p3.iter().map(|p| [p[0], p[1], 0.3]).collect();
        assert!(matches!(dlt(&flat, &p2), Err(GeometryError::Degenerate(_))));
        let mut nan = p3.clone();
        nan[3][1] = f64::NAN;
        assert!(matches!(dlt_linear(&nan, &p2), Err(GeometryError::NonFinite { index: 3, .. })));
        assert!(dlt(&p3, &p2[..9]).is_err());
        assert!(decompose(&Matrix3x4::zeros()).is_err());
    }

    #[test]
    fn points_of_an_affine_camera_are_refused() {
        // An affine camera (third row 0 0 0 1): the DLT would fit it exactly with an
        // enormous focal length; it must say that the data has no perspective instead.
        let a = Matrix3x4::new(800.0, 10.0, 5.0, 320.0, -4.0, 790.0, 12.0, 240.0, 0.0, 0.0, 0.0, 1.0);
        let (p3, _) = data(&camera(1.0), 6, 1.0, 0.0, 3);
        let p2: Vec<[f64; 2]> = p3
            .iter()
            .map(|x| {
                let h = a * Vector4::new(x[0], x[1], x[2], 1.0);
                [h.x / h.z, h.y / h.z]
            })
            .collect();
        for r in [dlt(&p3, &p2), dlt_linear(&p3, &p2)] {
            assert!(matches!(&r, Err(GeometryError::Degenerate(m)) if m.contains("perspective")), "{r:?}");
        }
    }
}
