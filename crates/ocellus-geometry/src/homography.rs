//! Plane-to-image homographies: `x ~ H X` for points X = (x, y, 1) on a plane.
//!
//! Estimated by the normalized DLT (Hartley & Zisserman, Multiple View Geometry, alg. 4.2):
//! both point sets moved to their centroid and scaled to mean distance sqrt 2, H the smallest
//! eigenvector of the 9x9 `A^T A`, then denormalized. Used by planar calibration
//! ([`crate::zhang`]) for its closed-form start and by the chessboard renderer.

use crate::dlt::normalizer;
use crate::{check_finite, GeometryError, Result};
use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen, Vector3};

/// Homography from plane points `from` to image points `to` (at least 4, no three collinear
/// in a way that leaves H undetermined), scaled so that `H[2][2] = 1` where possible.
pub fn homography(from: &[[f64; 2]], to: &[[f64; 2]]) -> Result<Matrix3<f64>> {
    if from.len() != to.len() {
        return Err(GeometryError::Invalid(format!("{} plane points but {} image points", from.len(), to.len())));
    }
    if from.len() < 4 {
        return Err(GeometryError::TooFewPoints { what: "homography", need: 4, got: from.len() });
    }
    check_finite("plane points", from)?;
    check_finite("image points", to)?;
    let (nf, sf, cf) = normalizer(from, 2f64.sqrt())?;
    let (nt, st, ct) = normalizer(to, 2f64.sqrt())?;
    let mut ata = SMatrix::<f64, 9, 9>::zeros();
    for (p, q) in nf.iter().zip(&nt) {
        let [x, y] = *p;
        let [u, v] = *q;
        let r1 = SVector::<f64, 9>::from_row_slice(&[x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y, -u]);
        let r2 = SVector::<f64, 9>::from_row_slice(&[0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y, -v]);
        ata += r1 * r1.transpose() + r2 * r2.transpose();
    }
    let eig = SymmetricEigen::new(ata);
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    // A unique H needs a one-dimensional null space: the second smallest eigenvalue must not
    // vanish as well (collinear points leave a larger one).
    let (l0, l1, lmax) = (eig.eigenvalues[order[0]], eig.eigenvalues[order[1]], eig.eigenvalues[order[8]]);
    let determined = l1 > 1e-10 * lmax && l0.is_finite();
    if !determined {
        return Err(GeometryError::Degenerate("the points do not determine a homography (collinear?)".into()));
    }
    let h = eig.eigenvectors.column(order[0]);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let tf = Matrix3::new(sf, 0.0, -sf * cf[0], 0.0, sf, -sf * cf[1], 0.0, 0.0, 1.0);
    let tt_inv = Matrix3::new(1.0 / st, 0.0, ct[0], 0.0, 1.0 / st, ct[1], 0.0, 0.0, 1.0);
    let mut hm = tt_inv * hn * tf;
    let s = if hm[(2, 2)].abs() > 1e-12 * hm.norm() { hm[(2, 2)] } else { hm.norm() };
    hm /= s;
    if hm.iter().any(|v| !v.is_finite()) || hm.determinant().abs() < 1e-300 {
        return Err(GeometryError::Degenerate("singular homography".into()));
    }
    Ok(hm)
}

/// Applies `h` to a plane point; `None` for a point mapped to infinity.
pub fn apply(h: &Matrix3<f64>, p: [f64; 2]) -> Option<[f64; 2]> {
    let q = h * Vector3::new(p[0], p[1], 1.0);
    (q.z != 0.0).then(|| [q.x / q.z, q.y / q.z])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_homography_and_rejects_collinear_points() {
        let h = Matrix3::new(1.2, 0.1, 30.0, -0.05, 0.9, 12.0, 1e-4, -2e-4, 1.0);
        let from: Vec<[f64; 2]> = (0..12).map(|i| [(i % 4) as f64 * 25.0, (i / 4) as f64 * 25.0]).collect();
        let to: Vec<[f64; 2]> = from.iter().map(|p| apply(&h, *p).unwrap()).collect();
        let est = homography(&from, &to).unwrap();
        assert!((est - h).norm() < 1e-9, "{est}");
        let line: Vec<[f64; 2]> = (0..6).map(|i| [i as f64, 2.0 * i as f64]).collect();
        assert!(matches!(homography(&line, &line), Err(GeometryError::Degenerate(_))));
        assert!(matches!(homography(&from[..3], &to[..3]), Err(GeometryError::TooFewPoints { .. })));
    }
}
