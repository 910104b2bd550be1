//! Robust mode, beyond the seed: sub-pixel flow with its own uncertainty per window, and one
//! robust fit of the camera motion over all windows.
//!
//! 1. Every window's integer SAD match ([`crate::sad_flow::window_flows`]) is refined by
//!    Gauss-Newton steps of Lucas-Kanade on the block (Lucas & Kanade 1981): with the image
//!    gradients g of frame n at the matched block, the correction solves
//!    `(sum g g^T) d = -sum g (I_n - I_n-1)`. The 2x2 structure tensor `sum g g^T` is also the
//!    window's information: a block on a straight mortar line constrains the flow across the
//!    line only (the aperture problem), and a flat block nothing; blocks whose smaller
//!    eigenvalue is below `min_texture` are dropped.
//! 2. The camera's planar motion (right, forward, turn) is fitted to all the windows at once
//!    with the exact rigid model (not its first-order Jacobian), by iteratively reweighted
//!    Gauss-Newton with Cauchy weights (scale `cauchy_px`), so that windows on moving or
//!    mismatched texture cannot pull it; windows with residuals beyond `reject_px` after
//!    convergence are dropped and the fit repeated.
//!
//! Rigid model (pixels, relative to the principal point, image y down; the camera moves by
//! `r` to the right and `f` forward and turns clockwise by `w`): a floor point at (u, v) in
//! frame n-1 is seen at `u' = (u - r) cos w + (v + f) sin w`, `v' = -(u - r) sin w + (v + f) cos w`.

use crate::sad_flow::{window_flows, SadFlowConfig};
use crate::{OdometryError, Result};
use nalgebra::{Matrix3, Matrix4, Vector4};
use ocellus_image::Plane;

/// Parameters of the robust measurement.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobustConfig {
    /// The integer search (all windows are used; none is dropped for being on the border).
    pub flow: SadFlowConfig,
    /// Lucas-Kanade steps per window.
    pub lk_steps: usize,
    /// Least texture kept: smaller eigenvalue of the structure tensor per block pixel
    /// (grey levels squared per pixel squared).
    pub min_texture: f64,
    /// Scale of the Cauchy weights, pixels.
    pub cauchy_px: f64,
    /// Residual beyond which a window is dropped after the first fit, pixels.
    pub reject_px: f64,
}

impl Default for RobustConfig {
    /// The seed's search, 2 Lucas-Kanade steps, texture at least 4, Cauchy scale 0.3 px,
    /// rejection at 1 px.
    fn default() -> Self {
        Self { flow: SadFlowConfig::default(), lk_steps: 2, min_texture: 4.0, cauchy_px: 0.3, reject_px: 1.0 }
    }
}

/// One window's sub-pixel measurement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowMeasurement {
    /// Block centre in frame n-1 relative to the principal point, pixels.
    pub u: f64,
    /// Block centre relative to the principal point, pixels (y down).
    pub v: f64,
    /// Flow, pixels.
    pub du: f64,
    /// Flow, pixels.
    pub dv: f64,
    /// Information of (du, dv): the structure tensor over the noise variance (1 / px^2).
    pub info: [[f64; 2]; 2],
}

/// Bilinear sample with clamping.
fn at(img: &Plane<u8>, x: f64, y: f64) -> f64 {
    let (w, h) = (img.width() as f64, img.height() as f64);
    let (x, y) = (x.clamp(0.0, w - 1.0), y.clamp(0.0, h - 1.0));
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(img.width() - 1), (y0 + 1).min(img.height() - 1));
    let (ax, ay) = (x - x0 as f64, y - y0 as f64);
    let g = |xx: usize, yy: usize| img.get(xx, yy) as f64;
    let top = g(x0, y0) + ax * (g(x1, y0) - g(x0, y0));
    let bot = g(x0, y1) + ax * (g(x1, y1) - g(x0, y1));
    top + ay * (bot - top)
}

/// `x.floor()` without the library call that baseline x86-64 (no SSE4.1 `roundsd`) makes for
/// it; exact for |x| < 2^52, which covers every pixel coordinate.
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// Mean grey level of the central `region` x `region` pixels, over every other row and
/// column (40,000 samples for the defaults: plenty for a gain).
fn region_mean(img: &Plane<u8>, region: usize) -> f64 {
    let (w, h) = img.size();
    let (rw, rh) = (region.min(w), region.min(h));
    let (x0, y0) = ((w - rw) / 2, (h - rh) / 2);
    let (mut s, mut n) = (0u64, 0u64);
    for y in (y0..y0 + rh).step_by(2) {
        for &v in img.row(y)[x0..x0 + rw].iter().step_by(2) {
            s += v as u64;
            n += 1;
        }
    }
    s as f64 / n.max(1) as f64
}

/// The Lucas-Kanade normal equations of one block: `[sum gx^2, sum gx gy, sum gy^2,
/// sum gx e, sum gy e]` with the gradients g and differences e of frame n (times `gain`)
/// warped by (dx, dy) against frame n-1. The warp has one fractional part for the whole block,
/// so frame n is resampled once into a patch with a one-pixel border and the gradients are
/// central differences there (the same as sampling at +-1 pixel).
#[allow(clippy::too_many_arguments)]
fn lk_sums(
    prev: &Plane<u8>,
    cur: &Plane<u8>,
    bx: f64,
    by: f64,
    b: usize,
    dx: f64,
    dy: f64,
    gain: f64,
    patch: &mut Vec<f32>,
) -> [f64; 5] {
    let n = b + 2;
    let (sx, sy) = (bx - 1.0 + dx, by - 1.0 + dy);
    let (fx, fy) = (floor(sx), floor(sy));
    let (ax, ay) = ((sx - fx) as f32, (sy - fy) as f32);
    patch.clear();
    let inside = fx >= 0.0 && fy >= 0.0 && fx as usize + n < cur.width() && fy as usize + n < cur.height();
    if inside && b == 8 {
        let mut p = [0.0f32; 100];
        patch8(cur, fx as usize, fy as usize, ax, ay, &mut p);
        return lk_sums8(prev, bx, by, &p, gain as f32);
    }
    if inside {
        let (ix, iy) = (fx as usize, fy as usize);
        if ax == 0.0 && ay == 0.0 {
            // An integer offset (the first step): a plain copy.
            for j in 0..n {
                patch.extend(cur.row(iy + j)[ix..ix + n].iter().map(|&v| v as f32));
            }
        } else {
            let (w00, w10, w01, w11) = ((1.0 - ax) * (1.0 - ay), ax * (1.0 - ay), (1.0 - ax) * ay, ax * ay);
            for j in 0..n {
                let (r0, r1) = (&cur.row(iy + j)[ix..ix + n + 1], &cur.row(iy + j + 1)[ix..ix + n + 1]);
                for i in 0..n {
                    patch.push(
                        w00 * r0[i] as f32 + w10 * r0[i + 1] as f32 + w01 * r1[i] as f32 + w11 * r1[i + 1] as f32,
                    );
                }
            }
        }
    } else {
        for j in 0..n {
            for i in 0..n {
                patch.push(at(cur, sx + i as f64, sy + j as f64) as f32);
            }
        }
    }
    let g = gain as f32;
    if b == 8 {
        return lk_sums8(prev, bx, by, patch, g);
    }
    let mut s = [0.0f64; 5];
    for j in 1..=b {
        let prow = prev.row((by as usize + j - 1).min(prev.height() - 1));
        let x0 = (bx as usize).min(prev.width() - b);
        let prow = &prow[x0..x0 + b];
        let (up, mid, down) =
            (&patch[(j - 1) * n..j * n], &patch[j * n..(j + 1) * n], &patch[(j + 1) * n..(j + 2) * n]);
        // One row's sums in f32 (at most 8 terms), accumulated in f64.
        let mut r = [0.0f32; 5];
        for i in 1..=b {
            let gx = 0.5 * g * (mid[i + 1] - mid[i - 1]);
            let gy = 0.5 * g * (down[i] - up[i]);
            let e = g * mid[i] - prow[i - 1] as f32;
            r[0] += gx * gx;
            r[1] += gx * gy;
            r[2] += gy * gy;
            r[3] += gx * e;
            r[4] += gy * e;
        }
        for k in 0..5 {
            s[k] += r[k] as f64;
        }
    }
    s
}

/// The 10x10 patch of `cur` (an 8x8 block and its border) whose top-left sample is at
/// (ix + ax, iy + ay), bilinearly: each of the 11 source rows is interpolated along x once
/// and shared by the two patch rows it touches, in fixed-size loops the compiler vectorizes.
fn patch8(cur: &Plane<u8>, ix: usize, iy: usize, ax: f32, ay: f32, out: &mut [f32; 100]) {
    const N: usize = 10;
    let mut rows = [[0.0f32; N]; N + 1];
    for (j, h) in rows.iter_mut().enumerate() {
        let Some(src) = cur.row(iy + j).get(ix..ix + N + 1) else { continue };
        let mut v = [0.0f32; N + 1];
        for (d, &s) in v.iter_mut().zip(src) {
            *d = s as f32;
        }
        for i in 0..N {
            h[i] = v[i] + ax * (v[i + 1] - v[i]);
        }
    }
    for j in 0..N {
        let (t, b) = (&rows[j], &rows[j + 1]);
        for i in 0..N {
            out[j * N + i] = t[i] + ay * (b[i] - t[i]);
        }
    }
}

/// [`lk_sums`] for the default 8x8 block: the sums are kept per column in fixed 8-lane arrays,
/// which the compiler turns into vector code, and reduced once at the end (64 terms in f32
/// lose nothing that matters at grey-level precision).
fn lk_sums8(prev: &Plane<u8>, bx: f64, by: f64, patch: &[f32], g: f32) -> [f64; 5] {
    const B: usize = 8;
    const N: usize = B + 2;
    let mut acc = [[0.0f32; B]; 5];
    let x0 = (bx as usize).min(prev.width() - B);
    for j in 1..=B {
        let prow = &prev.row((by as usize + j - 1).min(prev.height() - 1))[x0..x0 + B];
        let (Some(up), Some(mid), Some(down)) =
            (patch.get((j - 1) * N..j * N), patch.get(j * N..(j + 1) * N), patch.get((j + 1) * N..(j + 2) * N))
        else {
            break;
        };
        for i in 0..B {
            let gx = 0.5 * g * (mid[i + 2] - mid[i]);
            let gy = 0.5 * g * (down[i + 1] - up[i + 1]);
            let e = g * mid[i + 1] - prow[i] as f32;
            acc[0][i] += gx * gx;
            acc[1][i] += gx * gy;
            acc[2][i] += gy * gy;
            acc[3][i] += gx * e;
            acc[4][i] += gy * e;
        }
    }
    acc.map(|lanes| lanes.iter().map(|&v| v as f64).sum())
}

/// Sub-pixel flows of all textured windows between `prev` and `cur`.
pub fn window_measurements(prev: &Plane<u8>, cur: &Plane<u8>, cfg: &RobustConfig) -> Result<Vec<WindowMeasurement>> {
    let windows = window_flows(prev, cur, &cfg.flow)?;
    let (cx, cy) = ((prev.width() as f64 - 1.0) / 2.0, (prev.height() as f64 - 1.0) / 2.0);
    // Brightness robustness: a global gain between the frames (exposure or lighting change),
    // the ratio of the mean grey levels of the searched region.
    let gain = region_mean(prev, cfg.flow.region) / region_mean(cur, cfg.flow.region).max(1e-9);
    let gain = if gain.is_finite() && gain > 0.0 { gain } else { 1.0 };
    let b = cfg.flow.block as i64;
    let half = (b as f64 - 1.0) / 2.0;
    let mut out = Vec::with_capacity(windows.len());
    let mut patch = Vec::new();
    for wf in &windows {
        let Some((fx, fy)) = wf.flow else { continue };
        let (bx, by) = (wf.x - half, wf.y - half);
        let (mut dx, mut dy) = (fx as f64, fy as f64);
        let mut tensor = [[0.0f64; 2]; 2];
        let mut ok = true;
        for _ in 0..cfg.lk_steps.max(1) {
            let [a11, a12, a22, b1, b2] = lk_sums(prev, cur, bx, by, b as usize, dx, dy, gain, &mut patch);
            tensor = [[a11, a12], [a12, a22]];
            let det = a11 * a22 - a12 * a12;
            let n = (b * b) as f64;
            // Smaller eigenvalue per pixel: the texture across the weakest direction.
            let tr = a11 + a22;
            let lmin = 0.5 * (tr - ((a11 - a22).powi(2) + 4.0 * a12 * a12).sqrt()) / n;
            if det.is_nan() || det <= 0.0 || lmin < cfg.min_texture {
                ok = false;
                break;
            }
            let (sx, sy) = ((a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det);
            dx -= sx;
            dy -= sy;
            if (dx - fx as f64).abs() > 1.0 || (dy - fy as f64).abs() > 1.0 {
                ok = false;
                break;
            }
        }
        if ok {
            // Noise of about 2 grey levels per pixel difference.
            let s2 = 2.0 * 2.0 * 2.0;
            out.push(WindowMeasurement {
                u: wf.x - cx,
                v: wf.y - cy,
                du: dx,
                dv: dy,
                info: [[tensor[0][0] / s2, tensor[0][1] / s2], [tensor[1][0] / s2, tensor[1][1] / s2]],
            });
        }
    }
    if out.len() < 3 {
        return Err(OdometryError::NoTexture(format!("only {} textured windows", out.len())));
    }
    Ok(out)
}

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
}

/// Predicted position of (u, v) after the motion (r, f, w) and an image scale change k (the
/// camera height changing: the model has no use for it, but fitting it keeps the radial flow
/// it causes out of the other three), and its derivatives by (r, f, w, k).
fn predict(u: f64, v: f64, p: &Vector4<f64>) -> ([f64; 2], [[f64; 4]; 2]) {
    predict_with(u, v, p, p[2].sin_cos())
}

/// [`predict`] with the sine and cosine of the turn given (they are the same for every window).
fn predict_with(u: f64, v: f64, p: &Vector4<f64>, (s, c): (f64, f64)) -> ([f64; 2], [[f64; 4]; 2]) {
    let (r, f, k) = (p[0], p[1], p[3]);
    let (a, b) = (u - r, v + f);
    let (ru, rv) = (a * c + b * s, -a * s + b * c);
    let m = 1.0 + k;
    ([m * ru, m * rv], [[-c * m, s * m, (-a * s + b * c) * m, ru], [s * m, c * m, (-a * c - b * s) * m, rv]])
}

/// Fits the rigid motion to the measurements (see the module doc).
pub fn fit_rigid(meas: &[WindowMeasurement], cfg: &RobustConfig) -> Result<RigidMotion> {
    if meas.len() < 3 {
        return Err(OdometryError::NoTexture(format!("{} windows cannot determine the motion", meas.len())));
    }
    // Start from the median flow (a pure translation).
    let mut us: Vec<f64> = meas.iter().map(|m| m.du).collect();
    let mut vs: Vec<f64> = meas.iter().map(|m| m.dv).collect();
    us.sort_by(f64::total_cmp);
    vs.sort_by(f64::total_cmp);
    let mut p = Vector4::new(-us[us.len() / 2], vs[vs.len() / 2], 0.0, 0.0);
    let mut keep = vec![true; meas.len()];
    let mut info = Matrix4::zeros();
    for round in 0..2 {
        for _ in 0..8 {
            let mut a = Matrix4::zeros();
            let mut g = Vector4::zeros();
            let sc = p[2].sin_cos();
            for (m, &k) in meas.iter().zip(&keep) {
                if !k {
                    continue;
                }
                let (pred, j) = predict_with(m.u, m.v, &p, sc);
                let e = [m.u + m.du - pred[0], m.v + m.dv - pred[1]];
                let w = &m.info;
                // Cauchy weight on the residual's Mahalanobis length in pixels.
                let maha =
                    (e[0] * (w[0][0] * e[0] + w[0][1] * e[1]) + e[1] * (w[1][0] * e[0] + w[1][1] * e[1])).max(0.0);
                let scale = (w[0][0] + w[1][1]).max(1e-12) * 0.5;
                let px2 = maha / scale;
                let rw = 1.0 / (1.0 + px2 / (cfg.cauchy_px * cfg.cauchy_px));
                // J^T W (4x2) once, then the rank-2 update of the 4x4 normal matrix.
                let jtw: [[f64; 2]; 4] =
                    std::array::from_fn(|r| std::array::from_fn(|l| rw * (j[0][r] * w[0][l] + j[1][r] * w[1][l])));
                for r in 0..4 {
                    for c in r..4 {
                        a[(r, c)] += jtw[r][0] * j[0][c] + jtw[r][1] * j[1][c];
                    }
                    g[r] += jtw[r][0] * e[0] + jtw[r][1] * e[1];
                }
            }
            for r in 0..4 {
                for c in 0..r {
                    a[(r, c)] = a[(c, r)];
                }
            }
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
                let e = (m.u + m.du - pred[0]).hypot(m.v + m.dv - pred[1]);
                *k = e <= cfg.reject_px;
            }
            if keep.iter().filter(|k| **k).count() < 3 {
                return Err(OdometryError::NoTexture("fewer than 3 windows agree on a motion".into()));
            }
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
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
