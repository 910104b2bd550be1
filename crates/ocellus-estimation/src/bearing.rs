//! Extended Kalman filter update of a 2D position from bearings to known landmarks.
//!
//! Measurement of landmark l from position p = (x, y) with known heading theta:
//! `z = atan2(l_y - y, l_x - x) - theta + noise`, noise N(0, sigma^2) in radians. Its Jacobian
//! with respect to (x, y) is `H = [(l_y - y) / r^2, -(l_x - x) / r^2]`, r the range. With n
//! bearings the update in information form, `P' = (P^-1 + sum H_i^T H_i / sigma^2)^-1`, equals
//! the usual EKF update and only inverts 2x2 matrices.

use crate::{EstimationError, Result};
use nalgebra::{Matrix2, RowVector2, Vector2};

/// A landmark position in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landmark {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
}

/// Bearing of `l` from `p` in the world frame, radians in (-pi, pi].
pub fn bearing(p: &Vector2<f64>, l: &Landmark) -> f64 {
    (l.y - p.y).atan2(l.x - p.x)
}

/// Jacobian of the bearing with respect to the position; `None` when the landmark is at the
/// position (no bearing).
fn jacobian(p: &Vector2<f64>, l: &Landmark) -> Option<RowVector2<f64>> {
    let (dx, dy) = (l.x - p.x, l.y - p.y);
    let r2 = dx * dx + dy * dy;
    (r2 > 1e-12).then(|| RowVector2::new(dy / r2, -dx / r2))
}

fn check(mu: &Vector2<f64>, p: &Matrix2<f64>, sigma: f64) -> Result<Matrix2<f64>> {
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(EstimationError::InvalidInput(format!("bearing noise {sigma} rad must be > 0")));
    }
    if !mu.iter().all(|v| v.is_finite()) {
        return Err(EstimationError::InvalidInput("non-finite position".into()));
    }
    let ok = p.iter().all(|v| v.is_finite()) && p[(0, 0)] > 0.0 && p.determinant() > 0.0;
    match p.try_inverse() {
        Some(inv) if ok => Ok(inv),
        _ => Err(EstimationError::NotPositiveDefinite { what: "position covariance", detail: format!("{p:?}") }),
    }
}

/// The posterior covariance after observing the bearings of `landmarks` from `mu` (the
/// predicted update used to score view directions: it does not depend on the measured values).
pub fn bearing_update_covariance(
    mu: &Vector2<f64>,
    p: &Matrix2<f64>,
    landmarks: &[Landmark],
    sigma_rad: f64,
) -> Result<Matrix2<f64>> {
    let mut info = check(mu, p, sigma_rad)?;
    let w = 1.0 / (sigma_rad * sigma_rad);
    for l in landmarks {
        if let Some(h) = jacobian(mu, l) {
            info += h.transpose() * h * w;
        }
    }
    info.try_inverse()
        .ok_or_else(|| EstimationError::NotPositiveDefinite { what: "information", detail: format!("{info:?}") })
}

/// One EKF update with measured bearings `(landmark, z)` (world frame, radians): returns the
/// posterior mean and covariance. Innovations are wrapped to (-pi, pi].
pub fn bearing_update(
    mu: &Vector2<f64>,
    p: &Matrix2<f64>,
    observations: &[(Landmark, f64)],
    sigma_rad: f64,
) -> Result<(Vector2<f64>, Matrix2<f64>)> {
    let mut info = check(mu, p, sigma_rad)?;
    let w = 1.0 / (sigma_rad * sigma_rad);
    let mut rhs = Vector2::zeros();
    for (l, z) in observations {
        if !z.is_finite() {
            return Err(EstimationError::InvalidInput(format!("bearing {z}")));
        }
        if let Some(h) = jacobian(mu, l) {
            let innovation = (z - bearing(mu, l) + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            info += h.transpose() * h * w;
            rhs += h.transpose() * (innovation * w);
        }
    }
    let post = info
        .try_inverse()
        .ok_or_else(|| EstimationError::NotPositiveDefinite { what: "information", detail: format!("{info:?}") })?;
    Ok((mu + post * rhs, post))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed_single_landmark() {
        // Landmark 3 m ahead: H = [0, -1/3]; P = I, sigma = 0.1:
        // P' = diag(1, 1 / (1 + (1/9) / 0.01)) = diag(1, 9/109).
        let (mu, p) = (Vector2::new(0.0, 0.0), Matrix2::identity());
        let l = Landmark { x: 3.0, y: 0.0 };
        let post = bearing_update_covariance(&mu, &p, &[l], 0.1).unwrap();
        assert!((post[(0, 0)] - 1.0).abs() < 1e-12 && (post[(1, 1)] - 9.0 / 109.0).abs() < 1e-12);
        assert!(post[(0, 1)].abs() < 1e-12);
        // A bearing 0.05 rad larger (landmark further left): the robot is further right (-y):
        // mu' = P' H^T 0.05 / 0.01 = (0, -(9/109) * 5 / 3).
        let (m, p2) = bearing_update(&mu, &p, &[(l, 0.05)], 0.1).unwrap();
        assert!((m.y + 9.0 / 109.0 * 5.0 / 3.0).abs() < 1e-12 && m.x.abs() < 1e-12);
        assert_eq!(p2, post);
    }

    #[test]
    fn more_landmarks_more_certainty_and_bad_input() {
        let (mu, p) = (Vector2::new(1.0, 1.25), Matrix2::new(0.04, 0.0, 0.0, 0.04));
        let a = Landmark { x: 4.0, y: 2.5 };
        let b = Landmark { x: 4.0, y: 0.0 };
        let one = bearing_update_covariance(&mu, &p, &[a], 0.02).unwrap();
        let two = bearing_update_covariance(&mu, &p, &[a, b], 0.02).unwrap();
        assert!(two.trace() < one.trace() && one.trace() < p.trace());
        assert_eq!(
            bearing_update_covariance(&mu, &p, &[], 0.02).unwrap(),
            p.try_inverse().unwrap().try_inverse().unwrap()
        );
        assert!(bearing_update_covariance(&mu, &p, &[a], 0.0).is_err());
        assert!(bearing_update_covariance(&mu, &Matrix2::zeros(), &[a], 0.1).is_err());
        assert!(bearing_update(&mu, &p, &[(a, f64::NAN)], 0.1).is_err());
        // A landmark at the robot's position gives no bearing and is skipped, not a NaN.
        let on = Landmark { x: 1.0, y: 1.25 };
        assert!(bearing_update_covariance(&mu, &p, &[on], 0.1).unwrap().iter().all(|v| v.is_finite()));
    }
}
