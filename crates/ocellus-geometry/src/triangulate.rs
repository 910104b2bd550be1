//! Triangulation of points seen by calibrated cameras (SPEC 5.5).
//!
//! - [`two_view_seed`]: the seed's form: with P scaled so that p34 = 1, four equations
//!   `(p1 - x p3) . (X, Y, Z) = x - p14` (two per view), three unknowns, least squares through
//!   the 3x3 normal equations.
//! - [`n_view`]: the homogeneous form for any number of views: `x p3 - p1`, `y p3 - p2` rows
//!   of a 2N x 4 system, the solution the smallest eigenvector of A^T A.
//!
//! Each result says whether the point is in front of every camera.

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

fn in_front(ps: &[&Matrix3x4<f64>], x: &Vector3<f64>) -> bool {
    // Depth sign: w of P X times the sign of det(M) (for P = K[R|t] scaled by any s).
    ps.iter().all(|p| {
        let w = (*p * Vector4::new(x.x, x.y, x.z, 1.0)).z;
        let det = p.fixed_view::<3, 3>(0, 0).determinant();
        w * det.signum() > 0.0
    })
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
    Ok(Triangulated { point, in_front: in_front(&[p1, p2], &point) })
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
    let eig = SymmetricEigen::new(ata);
    let (imin, _) =
        eig.eigenvalues.iter().enumerate().fold((0, f64::INFINITY), |b, (i, &v)| if v < b.1 { (i, v) } else { b });
    let h = eig.eigenvectors.column(imin);
    if h[3].abs() < 1e-12 * h.norm() {
        return Err(GeometryError::Degenerate("the point is at infinity (parallel rays)".into()));
    }
    let point = Vector3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3]);
    let ps: Vec<&Matrix3x4<f64>> = views.iter().map(|v| v.0).collect();
    Ok(Triangulated { point, in_front: in_front(&ps, &point) })
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
}
