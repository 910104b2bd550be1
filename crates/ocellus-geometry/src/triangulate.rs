//! Triangulation of points seen by calibrated cameras (SPEC 5.5).
//!
//! - [`two_view_seed`]: the seed's form: with P scaled so that p34 = 1, four equations
//!   `(p1 - x p3) . (X, Y, Z) = x - p14` (two per view), three unknowns, least squares through
//!   the 3x3 normal equations.
//! - [`n_view`]: the homogeneous form for any number of views: `x p3 - p1`, `y p3 - p2` rows
//!   of a 2N x 4 system, the solution the smallest eigenvector of A^T A.
//!
//! Each result says whether the point is in front of every camera. [`check_rig`] refuses
//! camera sets that cannot triangulate at all (a singular projection matrix, or every camera
//! at one centre: a pure rotation sees no depth).

use crate::{GeometryError, Result};
use nalgebra::{Matrix3, Matrix3x4, Matrix4, SymmetricEigen, Vector3, Vector4};

/// A triangulated point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangulated {
    /// The point.
    pub point: Vector3<f64>,
    /// `true` when its depth is positive in every view.
    pub in_front: bool,
}

fn in_front<'a>(mut ps: impl Iterator<Item = &'a Matrix3x4<f64>>, x: &Vector3<f64>) -> bool {
    // Depth sign: w of P X times the sign of det(M) (for P = K[R|t] scaled by any s).
    ps.all(|p| {
        let w = (*p * Vector4::new(x.x, x.y, x.z, 1.0)).z;
        let det = p.fixed_view::<3, 3>(0, 0).determinant();
        w * det.signum() > 0.0
    })
}

/// The centre of a finite projective camera, `-M^-1 p4`, or an error when `M` (the left 3x3
/// of `P`) is singular: an all-zero or affine camera has no centre in front of it.
pub fn camera_centre(p: &Matrix3x4<f64>) -> Result<Vector3<f64>> {
    let m = p.fixed_view::<3, 3>(0, 0).into_owned();
    let norm = m.norm();
    // det scales with the cube of the matrix, so compare it with the cube of its norm.
    let det = m.determinant();
    if !(norm > 0.0 && norm.is_finite()) || det.abs() <= 1e-12 * norm.powi(3) {
        return Err(GeometryError::Degenerate(
            "the projection matrix is singular (all zero, or an affine camera without a centre)".into(),
        ));
    }
    let inv = m.try_inverse().ok_or_else(|| GeometryError::Degenerate("the projection matrix is singular".into()))?;
    Ok(-(inv * p.fixed_view::<3, 1>(0, 3)))
}

/// Checks that `ps` can triangulate: every matrix finite and non-singular, and at least two
/// centres apart by more than 1e-9 of the rig's size (cameras at one centre differ only by a
/// rotation, and a rotation carries no depth). The error names the camera (0-based).
pub fn check_rig(ps: &[Matrix3x4<f64>]) -> Result<()> {
    if ps.len() < 2 {
        return Err(GeometryError::TooFewViews { what: "triangulation", need: 2, got: ps.len() });
    }
    let mut centres = Vec::with_capacity(ps.len());
    for (k, p) in ps.iter().enumerate() {
        if p.iter().any(|v| !v.is_finite()) {
            return Err(GeometryError::Invalid(format!("camera {k}: the projection matrix is not finite")));
        }
        let c = camera_centre(p).map_err(|e| GeometryError::Degenerate(format!("camera {k}: {e}")))?;
        centres.push(c);
    }
    let size = centres.iter().map(|c| c.norm()).fold(1.0, f64::max);
    let baseline = centres.iter().flat_map(|a| centres.iter().map(move |b| (a - b).norm())).fold(0.0, f64::max);
    if baseline <= 1e-9 * size {
        return Err(GeometryError::Degenerate(
            "every camera has the same centre (identical cameras or a pure rotation): there is no baseline to triangulate from"
                .into(),
        ));
    }
    Ok(())
}

/// The seed's two-view least squares (P scaled to p34 = 1 internally).
pub fn two_view_seed(p1: &Matrix3x4<f64>, x1: [f64; 2], p2: &Matrix3x4<f64>, x2: [f64; 2]) -> Result<Triangulated> {
    let mut ata = Matrix3::zeros();
    let mut atb = Vector3::zeros();
    for (p, x) in [(p1, x1), (p2, x2)] {
        if !(x[0].is_finite() && x[1].is_finite()) {
            return Err(GeometryError::NonFinite { what: "image point", index: 0 });
        }
        let s = p[(2, 3)];
        if s == 0.0 || !s.is_finite() {
            return Err(GeometryError::Degenerate("p34 = 0: the seed's form needs p34 != 0 (use n_view)".into()));
        }
        let p = p / s;
        for (row, c) in [(0, x[0]), (1, x[1])] {
            let a = Vector3::new(p[(row, 0)] - p[(2, 0)] * c, p[(row, 1)] - p[(2, 1)] * c, p[(row, 2)] - p[(2, 2)] * c);
            let b = c - p[(row, 3)];
            ata += a * a.transpose();
            atb += a * b;
        }
    }
    let inv = ata.try_inverse().ok_or_else(|| GeometryError::Degenerate("rays are parallel".into()))?;
    let point = inv * atb;
    Ok(Triangulated { point, in_front: in_front([p1, p2].into_iter(), &point) })
}

/// Homogeneous least squares over any number (>= 2) of views.
pub fn n_view(views: &[(&Matrix3x4<f64>, [f64; 2])]) -> Result<Triangulated> {
    if views.len() < 2 {
        return Err(GeometryError::TooFewPoints { what: "triangulation", need: 2, got: views.len() });
    }
    let mut ata = Matrix4::zeros();
    for (i, (p, x)) in views.iter().enumerate() {
        if !(x[0].is_finite() && x[1].is_finite()) {
            return Err(GeometryError::NonFinite { what: "image point", index: i });
        }
        // Rows scaled by the norm of p3 so that views with differently scaled P weigh alike.
        let p3 = p.row(2).transpose();
        let w = 1.0 / p3.fixed_rows::<3>(0).norm().max(1e-300);
        for (row, c) in [(0, x[0]), (1, x[1])] {
            let a = (p3 * c - p.row(row).transpose()) * w;
            ata += a * a.transpose();
        }
    }
    let h = smallest_eigenvector(&ata);
    if h[3].abs() < 1e-12 * h.norm() {
        return Err(GeometryError::Degenerate("the point is at infinity (parallel rays)".into()));
    }
    let point = Vector3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3]);
    Ok(Triangulated { point, in_front: in_front(views.iter().map(|v| v.0), &point) })
}

/// The unit eigenvector of the smallest eigenvalue of a symmetric positive semi-definite
/// 4x4 matrix (the right singular vector of A for `m = A^T A`).
///
/// Inverse iteration (Golub & Van Loan, Matrix Computations, 7.6.1): repeated solves with
/// one LU factorization converge by the ratio of the two smallest eigenvalues per step,
/// which for triangulation is the noise over the geometry (three steps are usually enough),
/// at a tenth of the cost of a full eigen-decomposition. A full decomposition is the fallback
/// when the iteration does not settle.
fn smallest_eigenvector(m: &Matrix4<f64>) -> Vector4<f64> {
    if let Some(v) = inverse_iteration(m) {
        return v;
    }
    let eig = SymmetricEigen::new(*m);
    let (imin, _) =
        eig.eigenvalues.iter().enumerate().fold((0, f64::INFINITY), |b, (i, &v)| if v < b.1 { (i, v) } else { b });
    eig.eigenvectors.column(imin).into_owned()
}

/// Inverse iteration with an LDL^T factorization written out for 4x4 (no pivoting: the
/// matrix is positive semi-definite; a non-positive pivot gives up).
fn inverse_iteration(m: &Matrix4<f64>) -> Option<Vector4<f64>> {
    let scale = m.trace();
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    let a: [[f64; 4]; 4] = std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)] / scale));
    // A = L D L^T.
    let mut l = [[0.0f64; 4]; 4];
    let mut d = [0.0f64; 4];
    for j in 0..4 {
        let mut dj = a[j][j];
        for k in 0..j {
            dj -= l[j][k] * l[j][k] * d[k];
        }
        // A pivot at rounding level means an exact null space: nudge it, the iteration then
        // converges in one step.
        if dj.is_nan() || dj < -1e-9 {
            return None;
        }
        d[j] = dj.max(1e-300);
        l[j][j] = 1.0;
        for i in j + 1..4 {
            let mut v = a[i][j];
            for k in 0..j {
                v -= l[i][k] * l[j][k] * d[k];
            }
            l[i][j] = v / d[j];
        }
    }
    let mut x = [0.5f64; 4];
    for _ in 0..30 {
        // Solve L z = x, D w = z, L^T y = w.
        let mut y = x;
        for i in 0..4 {
            for k in 0..i {
                y[i] -= l[i][k] * y[k];
            }
        }
        for i in 0..4 {
            y[i] /= d[i];
        }
        for i in (0..4).rev() {
            for k in i + 1..4 {
                y[i] -= l[k][i] * y[k];
            }
        }
        let n = (y.iter().map(|v| v * v).sum::<f64>()).sqrt();
        if !(n.is_finite() && n > 0.0) {
            return None;
        }
        let y = y.map(|v| v / n);
        let (mut dm, mut dp) = (0.0, 0.0);
        for i in 0..4 {
            dm += (y[i] - x[i]).powi(2);
            dp += (y[i] + x[i]).powi(2);
        }
        x = y;
        if dm.min(dp) < 1e-26 {
            return Some(Vector4::from(x));
        }
    }
    None
}

/// The RMS distance between matched points (`a[i]` with `b[i]`), in their units: how far
/// triangulated points lie from the true ones. An error for empty or unequal lists.
pub fn rms_distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Result<f64> {
    if a.is_empty() || a.len() != b.len() {
        return Err(GeometryError::Invalid(format!("{} points against {} true points", a.len(), b.len())));
    }
    let sq: f64 = a.iter().zip(b).map(|(p, q)| (p - q).norm_squared()).sum();
    Ok((sq / a.len() as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Intrinsics, PinholeCamera};
    use nalgebra::Rotation3;

    fn cams() -> Vec<PinholeCamera> {
        let k = Intrinsics { fx: 700.0, fy: 700.0, cx: 320.0, cy: 240.0, skew: 0.0 };
        (0..4)
            .map(|i| {
                let r = *Rotation3::from_euler_angles(0.0, -0.1 * i as f64, 0.0).matrix();
                PinholeCamera { k, r, t: Vector3::new(-0.3 * i as f64, 0.0, 0.5) }
            })
            .collect()
    }

    #[test]
    fn rigs_that_cannot_triangulate_are_refused() {
        let ps: Vec<_> = cams().iter().map(|c| c.projection_matrix()).collect();
        assert!(check_rig(&ps).is_ok() && check_rig(&ps[..2]).is_ok());
        assert!(matches!(check_rig(&ps[..1]), Err(GeometryError::TooFewViews { .. })));
        // Identical cameras, and one centre with two orientations (a pure rotation).
        assert!(matches!(check_rig(&[ps[1], ps[1]]), Err(GeometryError::Degenerate(_))));
        let c = cams()[1];
        let turned = PinholeCamera { r: *Rotation3::from_euler_angles(0.0, 0.4, 0.1).matrix() * c.r, ..c };
        let turned = PinholeCamera { t: -(turned.r * c.centre()), ..turned };
        assert!((turned.centre() - c.centre()).norm() < 1e-12);
        let e = check_rig(&[c.projection_matrix(), turned.projection_matrix()]).unwrap_err();
        assert!(e.to_string().contains("same centre"), "{e}");
        // An all-zero matrix and an affine camera, named by index.
        let e = check_rig(&[ps[0], Matrix3x4::zeros()]).unwrap_err();
        assert!(e.to_string().contains("camera 1") && e.to_string().contains("singular"), "{e}");
        let affine = Matrix3x4::new(800.0, 0.0, 0.0, 320.0, 0.0, 800.0, 0.0, 240.0, 0.0, 0.0, 0.0, 1.0);
        assert!(check_rig(&[affine, ps[0]]).is_err());
        let mut nan = ps[0];
        nan[(1, 2)] = f64::NAN;
        assert!(matches!(check_rig(&[nan, ps[1]]), Err(GeometryError::Invalid(_))));
        // The centre is where P maps to zero.
        let h = ps[2] * camera_centre(&ps[2]).unwrap().push(1.0);
        assert!(h.norm() < 1e-9, "{h}");
    }

    #[test]
    fn exact_points_are_recovered_by_both_forms() {
        let cs = cams();
        let ps: Vec<_> = cs.iter().map(|c| c.projection_matrix()).collect();
        let x = Vector3::new(0.2, -0.1, 3.0);
        let px: Vec<[f64; 2]> = cs
            .iter()
            .map(|c| {
                let p = c.project(&x).unwrap().0;
                [p.x, p.y]
            })
            .collect();
        let s = two_view_seed(&ps[0], px[0], &ps[1], px[1]).unwrap();
        assert!((s.point - x).norm() < 1e-9 && s.in_front);
        let views: Vec<_> = ps.iter().zip(&px).map(|(p, x)| (p, *x)).collect();
        let n = n_view(&views).unwrap();
        assert!((n.point - x).norm() < 1e-9 && n.in_front);
        // Scaling a P by -3 changes nothing.
        let neg = ps[1] * -3.0;
        let t = n_view(&[(&ps[0], px[0]), (&neg, px[1])]).unwrap();
        assert!((t.point - x).norm() < 1e-9 && t.in_front);
    }

    #[test]
    fn inverse_iteration_matches_the_eigen_decomposition() {
        let mut seed = 1u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for k in 0..200 {
            // A^T A of random 6x4 matrices, some nearly rank 3.
            let mut a = nalgebra::SMatrix::<f64, 6, 4>::from_fn(|_, _| next());
            if k % 2 == 0 {
                let c = a.column(0) * 0.3 + a.column(1) * 0.2 - a.column(2);
                a.set_column(3, &(c + nalgebra::SVector::<f64, 6>::from_fn(|_, _| 1e-7 * next())));
            }
            let m = a.transpose() * a;
            let v = smallest_eigenvector(&m);
            let eig = SymmetricEigen::new(m);
            let imin = (0..4).min_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j])).unwrap();
            let e = eig.eigenvectors.column(imin);
            let diff = (v - e).norm().min((v + e).norm());
            assert!(diff < 1e-8, "case {k}: {diff}");
        }
    }

    #[test]
    fn points_behind_are_flagged_and_bad_input_is_an_error() {
        let cs = cams();
        let ps: Vec<_> = cs.iter().map(|c| c.projection_matrix()).collect();
        // A point behind both cameras projects to valid pixels; the flag says so.
        let x = Vector3::new(0.1, 0.05, -3.0);
        let px = |p: &Matrix3x4<f64>| {
            let h = p * Vector4::new(x.x, x.y, x.z, 1.0);
            [h.x / h.z, h.y / h.z]
        };
        let t = n_view(&[(&ps[0], px(&ps[0])), (&ps[1], px(&ps[1]))]).unwrap();
        assert!((t.point - x).norm() < 1e-6 && !t.in_front);
        assert!(n_view(&[(&ps[0], [1.0, 2.0])]).is_err());
        assert!(two_view_seed(&ps[0], [f64::NAN, 0.0], &ps[1], [0.0, 0.0]).is_err());
        // The same camera twice: parallel rays.
        assert!(two_view_seed(&ps[0], [100.0, 100.0], &ps[0], [100.0, 100.0]).is_err());
    }

    #[test]
    fn rms_distance_is_the_root_mean_square_of_the_distances() {
        let a = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 1.0, 1.0)];
        let b = [Vector3::new(3.0, 4.0, 0.0), Vector3::new(1.0, 1.0, 1.0)];
        // Distances 5 and 0: sqrt(25 / 2).
        assert!((rms_distance(&a, &b).unwrap() - 12.5f64.sqrt()).abs() < 1e-12);
        assert!(rms_distance(&a, &b[..1]).is_err() && rms_distance(&[], &[]).is_err());
    }
}
