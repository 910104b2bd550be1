//! The brightness gain field of the robust odometry (see
//! [`RobustConfig::gain_field`](crate::robust::RobustConfig::gain_field)).

/// The brightness ratio between the frames over the image, relative to the global gain: a
/// quadratic in the window position (pixels from the principal point over 256), fitted to
/// the windows' own gains weighted by their information with Cauchy weights. A lens's
/// vignetting makes the ratio of a moving floor point's brightness a smooth function of where
/// it is; one field through hundreds of windows is far less noisy than each window's own gain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GainField([f64; 6]);

impl GainField {
    pub(crate) fn flat() -> Self {
        Self([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    }

    fn basis(u: f64, v: f64) -> [f64; 6] {
        let (x, y) = (u / 256.0, v / 256.0);
        [1.0, x, y, x * x, x * y, y * y]
    }

    pub(crate) fn at(&self, u: f64, v: f64) -> f64 {
        Self::basis(u, v).iter().zip(&self.0).map(|(a, b)| a * b).sum()
    }

    /// Fits `[u, v, relative gain, information]` points; flat with fewer than 12 or a
    /// singular system.
    pub(crate) fn fit(pts: &[[f64; 4]]) -> Self {
        if pts.len() < 12 {
            return Self::flat();
        }
        let mut q = Self::flat();
        // The scale of the Cauchy weights: the median of each point's standard deviation.
        let mut sd: Vec<f64> = pts.iter().map(|p| 1.0 / p[3].max(1e-300).sqrt()).collect();
        let mid = sd.len() / 2;
        let (_, &mut scale, _) = sd.select_nth_unstable_by(mid, f64::total_cmp);
        for _ in 0..4 {
            let mut a = nalgebra::SMatrix::<f64, 6, 6>::zeros();
            let mut g = nalgebra::SVector::<f64, 6>::zeros();
            for p in pts {
                let e = (p[2] - q.at(p[0], p[1])) / scale;
                let w = p[3] / (1.0 + e * e);
                let phi = Self::basis(p[0], p[1]);
                // The lower triangle only: the Cholesky factorization reads no other.
                for r in 0..6 {
                    for c in 0..=r {
                        a[(r, c)] += w * phi[r] * phi[c];
                    }
                    g[r] += w * phi[r] * p[2];
                }
            }
            let Some(ch) = a.cholesky() else { return Self::flat() };
            let x = ch.solve(&g);
            if x.iter().any(|v| !v.is_finite()) {
                return Self::flat();
            }
            q = Self([x[0], x[1], x[2], x[3], x[4], x[5]]);
        }
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_recovers_a_quadratic_and_resists_an_outlier() {
        let truth = GainField([1.002, -0.003, 0.001, -0.004, 0.0005, -0.002]);
        let mut pts: Vec<[f64; 4]> = (0..20)
            .flat_map(|i| (0..20).map(move |j| (i as f64 * 20.0 - 190.0, j as f64 * 20.0 - 190.0)))
            .map(|(u, v)| [u, v, truth.at(u, v), 1e6])
            .collect();
        pts[57][2] += 0.2;
        let fit = GainField::fit(&pts);
        for (u, v) in [(0.0, 0.0), (-190.0, 170.0), (150.0, -90.0)] {
            assert!((fit.at(u, v) - truth.at(u, v)).abs() < 1e-4, "{u} {v}: {} vs {}", fit.at(u, v), truth.at(u, v));
        }
        // Too few points, or none with information, give the flat field.
        assert_eq!(GainField::fit(&pts[..11]), GainField::flat());
        let blind: Vec<[f64; 4]> = pts.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
        assert_eq!(GainField::fit(&blind), GainField::flat());
    }
}
