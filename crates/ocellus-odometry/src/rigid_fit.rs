//! The robust mode's fit of the camera's planar motion (right, forward, turn) to all the
//! windows' sub-pixel flows at once ([`crate::robust`], step 2): the exact rigid model (not its
//! first-order Jacobian), by iteratively reweighted Gauss-Newton with Cauchy weights (scale
//! `cauchy_px`), so that windows on moving or mismatched texture cannot pull it; windows with
//! residuals beyond `reject_px` after convergence are dropped and the fit repeated.
//!
//! Rigid model (pixels, relative to the principal point, image y down; the camera moves by
//! `r` to the right and `f` forward and turns clockwise by `w`): a floor point at (u, v) in
//! frame n-1 is seen at `u' = (u - r) cos w + (v + f) sin w`, `v' = -(u - r) sin w + (v + f) cos w`.

use crate::robust::{RobustConfig, WindowMeasurement};
use crate::{OdometryError, Result};
use nalgebra::{Matrix3, Matrix4, Vector4};

/// A fitted camera motion over one frame (pixels, radians) and its information matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidMotion {
    /// Rightward, pixels.
    pub right_px: f64,
    /// Forward, pixels.
    pub forward_px: f64,
    /// Clockwise turn, radians.
    pub turn_rad: f64,
    /// Information of (right, forward, turn).
    pub info: Matrix3<f64>,
    /// Windows kept.
    pub inliers: usize,
    /// Image scale change k: frame n is frame n-1 magnified by 1 + k about the principal point.
    pub scale_change: f64,
}

/// Predicted position of (u, v) after the motion (r, f, w) and an image scale change k (the
/// camera height changing: the model has no use for it, but fitting it keeps the radial flow
/// it causes out of the other three), and its derivatives by (r, f, w, k).
fn predict(u: f64, v: f64, p: &Vector4<f64>) -> ([f64; 2], [[f64; 4]; 2]) {
    predict_with(u, v, p, p[2].sin_cos())
}

/// [`predict`] with the sine and cosine of the turn given (they are the same for every window).
#[inline(always)]
fn predict_with(u: f64, v: f64, p: &Vector4<f64>, (s, c): (f64, f64)) -> ([f64; 2], [[f64; 4]; 2]) {
    let (r, f, k) = (p[0], p[1], p[3]);
    let (a, b) = (u - r, v + f);
    let (ru, rv) = (a * c + b * s, -a * s + b * c);
    let m = 1.0 + k;
    ([m * ru, m * rv], [[-c * m, s * m, (-a * s + b * c) * m, ru], [s * m, c * m, (-a * c - b * s) * m, rv]])
}

/// The measurements of [`fit_rigid`] by component, padded with windows of weight 0 to a
/// multiple of [`FIT_LANES`], so that the lanes of [`rigid_normal_equations`] are vectors.
struct FitPoints {
    /// u, v, u + du, v + dv, the information's four entries, 2 / its trace, the weight (1 or 0).
    cols: [Vec<f64>; 10],
}

/// Windows summed side by side in [`rigid_normal_equations`]: four f64 lanes are one AVX2
/// register.
const FIT_LANES: usize = 4;

impl FitPoints {
    fn new(meas: &[WindowMeasurement]) -> Self {
        let n = meas.len().div_ceil(FIT_LANES) * FIT_LANES;
        let col = |f: &dyn Fn(&WindowMeasurement) -> f64| {
            let mut c: Vec<f64> = meas.iter().map(f).collect();
            c.resize(n, 0.0);
            c
        };
        Self {
            cols: [
                col(&|m| m.u),
                col(&|m| m.v),
                col(&|m| m.u + m.du),
                col(&|m| m.v + m.dv),
                col(&|m| m.info[0][0]),
                col(&|m| m.info[0][1]),
                col(&|m| m.info[1][0]),
                col(&|m| m.info[1][1]),
                col(&|m| 1.0 / ((m.info[0][0] + m.info[1][1]).max(1e-12) * 0.5)),
                col(&|_| 1.0),
            ],
        }
    }

    /// Keeps the windows marked in `keep` (the rest weigh 0).
    fn keep(&mut self, keep: &[bool]) {
        for (w, &k) in self.cols[9].iter_mut().zip(keep) {
            *w = if k { 1.0 } else { 0.0 };
        }
    }
}

ocellus_image::dispatch_kernel!(
    /// The normal equations of one reweighted Gauss-Newton step of [`fit_rigid`] at the motion
    /// `p` (right, forward, turn, scale change): the upper triangle of `sum J^T W J`, row by
    /// row, and `sum J^T W e`, with W each window's information times its Cauchy weight (scale
    /// `cauchy_px`) on the residual's length in pixels. In [`FIT_LANES`] running sums per
    /// entry, added at the end: the same order, and so the same result, on every backend.
    fn rigid_normal_equations => rigid_normal_equations_generic(pts: &FitPoints, p: &Vector4<f64>, cauchy_px: f64) -> ([f64; 10], [f64; 4])
);

// `M` only picks the instruction set the dispatch compiles this for: the f64 sums take no
// multiply-add flavour (separate multiplies and adds on every backend).
#[allow(clippy::extra_unused_type_parameters)]
#[inline(always)]
fn rigid_normal_equations_generic<M: ocellus_image::simd::Madd>(
    pts: &FitPoints,
    p: &Vector4<f64>,
    cauchy_px: f64,
) -> ([f64; 10], [f64; 4]) {
    const L: usize = FIT_LANES;
    let sc = p[2].sin_cos();
    let cc = cauchy_px * cauchy_px;
    let mut upper = [[0.0f64; L]; 10];
    let mut grad = [[0.0f64; L]; 4];
    let [us, vs, tus, tvs, w00s, w01s, w10s, w11s, invs, keeps] = &pts.cols;
    let chunks = us.len() / L;
    let lanes = |col: &[f64], i: usize| -> [f64; L] { std::array::from_fn(|l| col[i * L + l]) };
    for i in 0..chunks {
        let (u, v, tu, tv) = (lanes(us, i), lanes(vs, i), lanes(tus, i), lanes(tvs, i));
        let (w00, w01, w10, w11) = (lanes(w00s, i), lanes(w01s, i), lanes(w10s, i), lanes(w11s, i));
        let (inv, keep) = (lanes(invs, i), lanes(keeps, i));
        for l in 0..L {
            let (pred, [j0, j1]) = predict_with(u[l], v[l], p, sc);
            let e = [tu[l] - pred[0], tv[l] - pred[1]];
            // Cauchy weight on the residual's Mahalanobis length in pixels.
            let maha = (e[0] * (w00[l] * e[0] + w01[l] * e[1]) + e[1] * (w10[l] * e[0] + w11[l] * e[1])).max(0.0);
            let rw = keep[l] / (1.0 + maha * inv[l] / cc);
            // J^T W (4x2), then the rank-2 update of the normal matrix's upper triangle.
            let jtw: [[f64; 2]; 4] = std::array::from_fn(|q| {
                [rw * (j0[q] * w00[l] + j1[q] * w10[l]), rw * (j0[q] * w01[l] + j1[q] * w11[l])]
            });
            let mut n = 0;
            for q in 0..4 {
                for t in q..4 {
                    upper[n][l] += jtw[q][0] * j0[t] + jtw[q][1] * j1[t];
                    n += 1;
                }
                grad[q][l] += jtw[q][0] * e[0] + jtw[q][1] * e[1];
            }
        }
    }
    let total = |x: &[f64; L]| x.iter().sum::<f64>();
    (upper.each_ref().map(total), grad.each_ref().map(total))
}

/// Fits the rigid motion to the measurements (see the module doc).
pub fn fit_rigid(meas: &[WindowMeasurement], cfg: &RobustConfig) -> Result<RigidMotion> {
    if meas.len() < 3 {
        return Err(OdometryError::NoTexture(format!("{} windows cannot determine the motion", meas.len())));
    }
    // Start from the median flow (a pure translation).
    let mut us: Vec<f64> = meas.iter().map(|m| m.du).collect();
    let mut vs: Vec<f64> = meas.iter().map(|m| m.dv).collect();
    let mid = meas.len() / 2;
    let (_, &mut u_mid, _) = us.select_nth_unstable_by(mid, f64::total_cmp);
    let (_, &mut v_mid, _) = vs.select_nth_unstable_by(mid, f64::total_cmp);
    let mut p = Vector4::new(-u_mid, v_mid, 0.0, 0.0);
    let mut keep = vec![true; meas.len()];
    let mut info = Matrix4::zeros();
    let mut soa = FitPoints::new(meas);
    for round in 0..2 {
        for _ in 0..8 {
            let (upper, grad) = rigid_normal_equations(cfg.flow.backend, &soa, &p, cfg.cauchy_px);
            let mut a = Matrix4::zeros();
            let mut k = 0;
            for r in 0..4 {
                for c in r..4 {
                    (a[(r, c)], a[(c, r)]) = (upper[k], upper[k]);
                    k += 1;
                }
            }
            let g = Vector4::from(grad);
            let step = a
                .try_inverse()
                .ok_or_else(|| OdometryError::NoTexture("the windows do not determine the motion".into()))?
                * g;
            p += step;
            info = a;
            // 1e-5 px (or rad) is far below what the flows resolve.
            if step.norm() < 1e-5 {
                break;
            }
        }
        if round == 0 {
            for (m, k) in meas.iter().zip(keep.iter_mut()) {
                let (pred, _) = predict(m.u, m.v, &p);
                let (ex, ey) = (m.u + m.du - pred[0], m.v + m.dv - pred[1]);
                // Squared lengths: `hypot` took as long as a step of the fit.
                *k = ex * ex + ey * ey <= cfg.reject_px * cfg.reject_px;
            }
            if keep.iter().filter(|k| **k).count() < 3 {
                return Err(OdometryError::NoTexture("fewer than 3 windows agree on a motion".into()));
            }
            soa.keep(&keep);
        }
    }
    // The information of the three motion parameters with the scale marginalized out.
    let singular = || OdometryError::NoTexture("the windows do not determine the motion".into());
    let cov = info.try_inverse().ok_or_else(singular)?;
    let info3 = cov.fixed_view::<3, 3>(0, 0).into_owned().try_inverse().ok_or_else(singular)?;
    Ok(RigidMotion {
        right_px: p[0],
        forward_px: p[1],
        turn_rad: p[2],
        info: info3,
        inliers: keep.iter().filter(|k| **k).count(),
        scale_change: p[3],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::Backend;

    #[test]
    fn the_fit_normal_equations_are_the_direct_sums_on_every_backend() {
        let mut rng = ocellus_image::rng::SplitMix64::new(11);
        let meas: Vec<WindowMeasurement> = (0..37)
            .map(|_| {
                let (a, b, c) = (rng.unit() * 50.0, rng.unit() * 10.0 - 5.0, rng.unit() * 40.0);
                WindowMeasurement {
                    u: rng.unit() * 400.0 - 200.0,
                    v: rng.unit() * 400.0 - 200.0,
                    du: rng.unit() * 6.0 - 3.0,
                    dv: rng.unit() * 6.0 - 3.0,
                    info: [[a, b], [b, c]],
                }
            })
            .collect();
        let keep: Vec<bool> = (0..meas.len()).map(|k| k % 5 != 2).collect();
        let mut pts = FitPoints::new(&meas);
        pts.keep(&keep);
        let p = Vector4::new(0.8, -1.3, 0.01, 0.003);
        let cauchy = 0.3;
        // Window by window, as written in the module doc.
        let (mut a, mut g) = (Matrix4::<f64>::zeros(), Vector4::<f64>::zeros());
        for (m, _) in meas.iter().zip(&keep).filter(|(_, k)| **k) {
            let (pred, j) = predict(m.u, m.v, &p);
            let e = nalgebra::Vector2::new(m.u + m.du - pred[0], m.v + m.dv - pred[1]);
            let w = nalgebra::Matrix2::new(m.info[0][0], m.info[0][1], m.info[1][0], m.info[1][1]);
            let px2 = (e.transpose() * w * e)[0] / (0.5 * (m.info[0][0] + m.info[1][1]));
            let jm = nalgebra::Matrix2x4::from_fn(|r, c| j[r][c]);
            let rw = 1.0 / (1.0 + px2 / (cauchy * cauchy));
            a += jm.transpose() * w * jm * rw;
            g += jm.transpose() * w * e * rw;
        }
        let mut got = Vec::new();
        for backend in [Backend::Scalar, Backend::Auto] {
            let (upper, grad) = rigid_normal_equations(backend, &pts, &p, cauchy);
            let mut k = 0;
            for r in 0..4 {
                for c in r..4 {
                    assert!(
                        (upper[k] - a[(r, c)]).abs() <= 1e-9 * a[(r, c)].abs().max(1.0),
                        "{r},{c}: {} vs {}",
                        upper[k],
                        a[(r, c)]
                    );
                    k += 1;
                }
                assert!((grad[r] - g[r]).abs() <= 1e-9 * a[(r, r)].abs().max(1.0), "{r}: {} vs {}", grad[r], g[r]);
            }
            got.push((upper.map(f64::to_bits), grad.map(f64::to_bits)));
        }
        // The same sums in the same order on every backend.
        assert_eq!(got[0], got[1]);
    }

    #[test]
    fn the_fit_inverts_the_model_exactly_and_resists_outliers() {
        let truth = Vector4::new(0.37, 2.81, 0.004, 0.002);
        let mut meas = Vec::new();
        for j in 0..10 {
            for i in 0..10 {
                let (u, v) = (-180.0 + 40.0 * i as f64, -180.0 + 40.0 * j as f64);
                let (p, _) = predict(u, v, &truth);
                // The aperture: every third window only sees the x component.
                let info = if (i + j) % 3 == 0 { [[50.0, 0.0], [0.0, 1e-6]] } else { [[50.0, 5.0], [5.0, 40.0]] };
                let bad = i == 3 && j < 4; // four windows on a moving object
                let (du, dv) = if bad { (3.0, -4.0) } else { (p[0] - u, p[1] - v) };
                let dv = if (i + j) % 3 == 0 && !bad { dv + 0.7 } else { dv }; // unseen component wrong
                meas.push(WindowMeasurement { u, v, du, dv, info });
            }
        }
        let m = fit_rigid(&meas, &RobustConfig::default()).unwrap();
        assert!((m.right_px - truth[0]).abs() < 1e-3 && (m.forward_px - truth[1]).abs() < 1e-3, "{m:?}");
        assert!((m.turn_rad - truth[2]).abs() < 1e-5, "{m:?}");
        assert!(m.inliers == 96, "{}", m.inliers);
    }
}
