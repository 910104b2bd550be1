//! Information between Gaussian beliefs.
//!
//! `KL(p || q)` for `p = N(mu_p, S_p)`, `q = N(mu_q, S_q)` in k dimensions (e.g. Bishop,
//! Pattern Recognition and Machine Learning, 2006):
//! `1/2 [ tr(S_q^-1 S_p) + (mu_q - mu_p)^T S_q^-1 (mu_q - mu_p) - k + ln(det S_q / det S_p) ]`
//! nats, divided by ln 2 for bits. (The seed's eq. 4-5 write the normal densities with wrong
//! constants; this is the divergence of the correct densities.)

use crate::{EstimationError, Result};
use nalgebra::{Matrix2, Vector2};

fn check(what: &'static str, s: &Matrix2<f64>) -> Result<f64> {
    let det = s.determinant();
    let ok = s.iter().all(|v| v.is_finite())
        && (s[(0, 1)] - s[(1, 0)]).abs() <= 1e-9 * s.abs().max()
        && s[(0, 0)] > 0.0
        && det > 0.0;
    if ok {
        Ok(det)
    } else {
        Err(EstimationError::NotPositiveDefinite { what, detail: format!("{s:?}") })
    }
}

/// `KL(N(mu_p, s_p) || N(mu_q, s_q))` in bits, 2D.
pub fn kl_bits(mu_p: &Vector2<f64>, s_p: &Matrix2<f64>, mu_q: &Vector2<f64>, s_q: &Matrix2<f64>) -> Result<f64> {
    let (det_p, det_q) = (check("prior covariance", s_p)?, check("posterior covariance", s_q)?);
    if !(mu_p.iter().chain(mu_q.iter()).all(|v| v.is_finite())) {
        return Err(EstimationError::InvalidInput("non-finite mean".into()));
    }
    let Some(q_inv) = s_q.try_inverse() else {
        return Err(EstimationError::NotPositiveDefinite { what: "posterior covariance", detail: format!("{s_q:?}") });
    };
    let d = mu_q - mu_p;
    let nats = 0.5 * ((q_inv * s_p).trace() + (d.transpose() * q_inv * d)[(0, 0)] - 2.0 + (det_q / det_p).ln());
    Ok(nats.max(0.0) / std::f64::consts::LN_2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// KL by numerical integration over a grid covering p's mass (+-8 sigma).
    fn kl_numeric(mu_p: &Vector2<f64>, s_p: &Matrix2<f64>, mu_q: &Vector2<f64>, s_q: &Matrix2<f64>) -> f64 {
        let ln_pdf = |mu: &Vector2<f64>, s: &Matrix2<f64>, x: &Vector2<f64>| {
            let d = x - mu;
            let inv = s.try_inverse().unwrap();
            -0.5 * (d.transpose() * inv * d)[(0, 0)] - (2.0 * std::f64::consts::PI).ln() - 0.5 * s.determinant().ln()
        };
        let (sx, sy) = (s_p[(0, 0)].sqrt() * 8.0, s_p[(1, 1)].sqrt() * 8.0);
        let n = 800;
        let (hx, hy) = (2.0 * sx / n as f64, 2.0 * sy / n as f64);
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let x = Vector2::new(mu_p.x - sx + (i as f64 + 0.5) * hx, mu_p.y - sy + (j as f64 + 0.5) * hy);
                let (lp, lq) = (ln_pdf(mu_p, s_p, &x), ln_pdf(mu_q, s_q, &x));
                sum += lp.exp() * (lp - lq);
            }
        }
        sum * hx * hy / std::f64::consts::LN_2
    }

    #[test]
    fn closed_form_matches_numerical_integration() {
        let cases = [
            (
                Vector2::new(0.0, 0.0),
                Matrix2::new(1.0, 0.3, 0.3, 0.5),
                Vector2::new(0.2, -0.1),
                Matrix2::new(0.6, 0.1, 0.1, 0.4),
            ),
            (
                Vector2::new(1.0, 1.25),
                Matrix2::new(0.05, 0.0, 0.0, 0.02),
                Vector2::new(1.0, 1.25),
                Matrix2::new(0.01, 0.002, 0.002, 0.015),
            ),
        ];
        for (mp, sp, mq, sq) in cases {
            let (c, n) = (kl_bits(&mp, &sp, &mq, &sq).unwrap(), kl_numeric(&mp, &sp, &mq, &sq));
            assert!((c - n).abs() < 1e-3 * (1.0 + n), "closed {c}, numeric {n}");
        }
        let s = Matrix2::new(2.0, 0.5, 0.5, 1.0);
        let m = Vector2::new(1.0, 2.0);
        assert!(kl_bits(&m, &s, &m, &s).unwrap().abs() < 1e-12);
    }

    #[test]
    fn degenerate_covariances_are_errors() {
        let m = Vector2::zeros();
        let good = Matrix2::identity();
        assert!(kl_bits(&m, &Matrix2::new(1.0, 1.0, 1.0, 1.0), &m, &good).is_err());
        assert!(kl_bits(&m, &good, &m, &Matrix2::new(-1.0, 0.0, 0.0, 1.0)).is_err());
        assert!(kl_bits(&m, &good, &m, &Matrix2::new(f64::NAN, 0.0, 0.0, 1.0)).is_err());
        assert!(kl_bits(&Vector2::new(f64::INFINITY, 0.0), &good, &m, &good).is_err());
    }
}
