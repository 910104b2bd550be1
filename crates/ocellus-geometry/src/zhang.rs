//! Planar-target calibration (SPEC 5.3): Zhang's closed form, then Levenberg-Marquardt.
//!
//! Zhang, "A flexible new technique for camera calibration", IEEE TPAMI 22(11), 2000:
//! - each view of the plane z = 0 gives a homography `H = K [r1 r2 t]`; orthonormality of r1,
//!   r2 gives two linear equations in `B = K^-T K^-1` (section 3.1); three views determine
//!   the five intrinsics (skew included), which are read off B in closed form (appendix B);
//! - each view's pose follows from `K^-1 H` (section 3.1), made a proper rotation by SVD;
//! - everything is then refined by minimizing the pixel reprojection error over the
//!   intrinsics (fx, fy, cx, cy; zero skew, as in OpenCV), the distortion (k1, k2, p1, p2, k3,
//!   see [`crate::distortion`]) and every pose (section 3.2 and 3.3), with Levenberg-Marquardt
//!   on analytic derivatives. Rotations are updated multiplicatively, `R <- exp([d]x) R`.
//!
//! The normal equations have one dense 9x9 block for the camera and one 6x6 block per view;
//! they are solved by the Schur complement, so the cost grows linearly with the views.
//! Parameter standard deviations come from the inverse normal matrix at the optimum scaled by
//! the residual variance `sum r^2 / (2 N - parameters)`, the usual (and OpenCV's) estimate.

use crate::camera::Intrinsics;
use crate::distortion::Distortion;
use crate::homography::homography;
use crate::{check_finite, GeometryError, Result};
use nalgebra::{Matrix3, Matrix6, Rotation3, SMatrix, SVector, SymmetricEigen, Vector3, Vector6};

/// One view of a planar target.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarView {
    /// Target points on the plane z = 0, in target units (e.g. millimetres).
    pub object: Vec<[f64; 2]>,
    /// Their pixels in the image (x right, y down; pixel centres at integers).
    pub image: Vec<[f64; 2]>,
}

/// What the refinement estimates beyond fx, fy, cx, cy and the poses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZhangOptions {
    /// Estimate the radial k1 and k2 (otherwise they stay 0, and so do k3 and p1, p2).
    pub radial: bool,
    /// Estimate k3 as well (OpenCV's default; needs wide-angle views to be well determined).
    pub k3: bool,
    /// Estimate the tangential p1, p2.
    pub tangential: bool,
    /// Levenberg-Marquardt iterations at most.
    pub max_iterations: usize,
}

impl Default for ZhangOptions {
    /// OpenCV's `calibrateCamera` defaults: k1, k2, p1, p2, k3 all estimated; 100 iterations.
    fn default() -> Self {
        Self { radial: true, k3: true, tangential: true, max_iterations: 100 }
    }
}

/// A view's pose: target plane to camera, `X_c = R (x, y, 0) + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation target -> camera (proper).
    pub r: Matrix3<f64>,
    /// Translation target -> camera, target units.
    pub t: Vector3<f64>,
}

/// Result of [`calibrate`].
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarCalibration {
    /// Refined intrinsics (skew 0).
    pub intrinsics: Intrinsics,
    /// Refined distortion.
    pub distortion: Distortion,
    /// Refined pose of every view.
    pub poses: Vec<Pose>,
    /// Zhang's closed-form intrinsics before refinement.
    pub closed_form: Intrinsics,
    /// RMS reprojection error over all points, pixels.
    pub rms_px: f64,
    /// RMS reprojection error per view, pixels.
    pub per_view_rms_px: Vec<f64>,
    /// Standard deviations in OpenCV's order fx, fy, cx, cy (pixels), k1, k2, p1, p2, k3;
    /// 0 for parameters held fixed.
    pub std_dev: [f64; 9],
    /// Levenberg-Marquardt iterations run.
    pub iterations: usize,
}

/// Camera parameters in OpenCV order: fx, fy, cx, cy, k1, k2, p1, p2, k3.
type Camera9 = [f64; 9];

fn check_views(views: &[PlanarView]) -> Result<()> {
    if views.len() < 3 {
        return Err(GeometryError::TooFewViews { what: "planar calibration", need: 3, got: views.len() });
    }
    for v in views {
        if v.object.len() != v.image.len() {
            return Err(GeometryError::Invalid(format!(
                "a view has {} target points but {} image points",
                v.object.len(),
                v.image.len()
            )));
        }
        check_finite("target points", &v.object)?;
        check_finite("image points", &v.image)?;
    }
    Ok(())
}

/// Zhang's v_ij row from the columns i, j of H.
fn v_row(h: &Matrix3<f64>, i: usize, j: usize) -> Vector6<f64> {
    let (a, b) = (h.column(i), h.column(j));
    Vector6::new(
        a[0] * b[0],
        a[0] * b[1] + a[1] * b[0],
        a[1] * b[1],
        a[2] * b[0] + a[0] * b[2],
        a[2] * b[1] + a[1] * b[2],
        a[2] * b[2],
    )
}

/// Zhang's closed-form intrinsics (with skew) and poses, ignoring distortion.
pub fn closed_form(views: &[PlanarView]) -> Result<(Intrinsics, Vec<Pose>)> {
    check_views(views)?;
    let hs = views.iter().map(|v| homography(&v.object, &v.image)).collect::<Result<Vec<_>>>()?;
    // Pixel coordinates are conditioned first (Hartley's argument again): Hn = N H, Kn = N K.
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
    for v in views {
        for p in &v.image {
            sx += p[0];
            sy += p[1];
            n += 1.0;
        }
    }
    let (cx0, cy0) = (sx / n, sy / n);
    let spread =
        views.iter().flat_map(|v| &v.image).map(|p| ((p[0] - cx0).abs()).max((p[1] - cy0).abs())).fold(0.0, f64::max);
    if spread.is_nan() || spread <= 0.0 {
        return Err(GeometryError::Degenerate("all image points coincide".into()));
    }
    let s = 1.0 / spread;
    let nmat = Matrix3::new(s, 0.0, -s * cx0, 0.0, s, -s * cy0, 0.0, 0.0, 1.0);
    let mut vtv = Matrix6::zeros();
    for h in &hs {
        let hn = nmat * h;
        let hn = hn / hn.norm();
        let r1 = v_row(&hn, 0, 1);
        let r2 = v_row(&hn, 0, 0) - v_row(&hn, 1, 1);
        vtv += r1 * r1.transpose() + r2 * r2.transpose();
    }
    let eig = SymmetricEigen::new(vtv);
    let mut order: Vec<usize> = (0..6).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let degenerate = || {
        GeometryError::Degenerate(
            "the views do not determine the intrinsics: tilt the target differently between views".into(),
        )
    };
    let determined = eig.eigenvalues[order[1]] > 1e-12 * eig.eigenvalues[order[5]];
    if !determined {
        return Err(degenerate());
    }
    let mut b = eig.eigenvectors.column(order[0]).into_owned();
    if b[0] < 0.0 {
        b = -b;
    }
    let (b11, b12, b22, b13, b23, b33) = (b[0], b[1], b[2], b[3], b[4], b[5]);
    let den = b11 * b22 - b12 * b12;
    if !(den > 0.0 && b11 > 0.0) {
        return Err(degenerate());
    }
    let v0 = (b12 * b13 - b11 * b23) / den;
    let lambda = b33 - (b13 * b13 + v0 * (b12 * b13 - b11 * b23)) / b11;
    let positive = lambda / b11 > 0.0;
    if !positive {
        return Err(degenerate());
    }
    let alpha = (lambda / b11).sqrt();
    let beta = (lambda * b11 / den).sqrt();
    let gamma = -b12 * alpha * alpha * beta / lambda;
    let u0 = gamma * v0 / beta - b13 * alpha * alpha / lambda;
    let kn = Matrix3::new(alpha, gamma, u0, 0.0, beta, v0, 0.0, 0.0, 1.0);
    let nmat_inv = Matrix3::new(spread, 0.0, cx0, 0.0, spread, cy0, 0.0, 0.0, 1.0);
    let k = Intrinsics::from_matrix(&(nmat_inv * kn))?;
    let k_inv = k.matrix().try_inverse().ok_or_else(degenerate)?;
    let poses = hs.iter().map(|h| pose_from_homography(&k_inv, h)).collect::<Result<Vec<_>>>()?;
    Ok((k, poses))
}

/// The pose of one view from `K^-1 H = lambda [r1 r2 t]`, the rotation made proper by SVD.
fn pose_from_homography(k_inv: &Matrix3<f64>, h: &Matrix3<f64>) -> Result<Pose> {
    let m = k_inv * h;
    let mut lambda = 1.0 / m.column(0).norm();
    if m[(2, 2)] * lambda < 0.0 {
        lambda = -lambda; // the target must be in front of the camera (t_z > 0)
    }
    let r1 = m.column(0) * lambda;
    let r2 = m.column(1) * lambda;
    let r3 = r1.cross(&r2);
    let q = Matrix3::from_columns(&[r1, r2, r3]);
    let svd = q.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Err(GeometryError::Degenerate("pose SVD failed".into()));
    };
    let mut r = u * vt;
    if r.determinant() < 0.0 {
        r = -r;
    }
    let t = m.column(2) * lambda;
    if !(t.iter().all(|v| v.is_finite()) && r.iter().all(|v| v.is_finite())) {
        return Err(GeometryError::Degenerate("non-finite pose from a homography".into()));
    }
    Ok(Pose { r, t: t.into_owned() })
}

/// A projected pixel with its derivatives by the camera (9) and the pose (rotation 3,
/// translation 3); `None` for a point at or behind the camera.
fn project_with_jacobian(
    c: &Camera9,
    pose: &Pose,
    p: [f64; 2],
) -> Option<([f64; 2], SMatrix<f64, 2, 9>, SMatrix<f64, 2, 6>)> {
    let [fx, fy, cx, cy, k1, k2, p1, p2, k3] = *c;
    let rx = pose.r * Vector3::new(p[0], p[1], 0.0);
    let xc = rx + pose.t;
    if xc.z.is_nan() || xc.z <= 0.0 {
        return None;
    }
    let iz = 1.0 / xc.z;
    let (x, y) = (xc.x * iz, xc.y * iz);
    let r2 = x * x + y * y;
    let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    let xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    let yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    let pix = [fx * xd + cx, fy * yd + cy];

    let mut jc = SMatrix::<f64, 2, 9>::zeros();
    let (r4, r6) = (r2 * r2, r2 * r2 * r2);
    jc[(0, 0)] = xd;
    jc[(0, 2)] = 1.0;
    jc[(1, 1)] = yd;
    jc[(1, 3)] = 1.0;
    let dx = [x * r2, x * r4, 2.0 * x * y, r2 + 2.0 * x * x, x * r6];
    let dy = [y * r2, y * r4, r2 + 2.0 * y * y, 2.0 * x * y, y * r6];
    for i in 0..5 {
        jc[(0, 4 + i)] = fx * dx[i];
        jc[(1, 4 + i)] = fy * dy[i];
    }
    // d(xd, yd) / d(x, y).
    let drad = 2.0 * (k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2));
    let a11 = radial + x * drad * x + 2.0 * p1 * y + 6.0 * p2 * x;
    let a12 = x * drad * y + 2.0 * p1 * x + 2.0 * p2 * y;
    let a21 = y * drad * x + 2.0 * p1 * x + 2.0 * p2 * y;
    let a22 = radial + y * drad * y + 6.0 * p1 * y + 2.0 * p2 * x;
    // d(u, v) / d(Xc) = diag(fx, fy) A d(x, y)/d(Xc).
    let dn = SMatrix::<f64, 2, 3>::new(iz, 0.0, -x * iz, 0.0, iz, -y * iz);
    let a = SMatrix::<f64, 2, 2>::new(fx * a11, fx * a12, fy * a21, fy * a22);
    let duv = a * dn;
    // dXc/d(rotation) = -[R X]x, dXc/dt = I.
    let skew = Matrix3::new(0.0, -rx.z, rx.y, rx.z, 0.0, -rx.x, -rx.y, rx.x, 0.0);
    let drot = -(duv * skew);
    let mut jp = SMatrix::<f64, 2, 6>::zeros();
    jp.fixed_view_mut::<2, 3>(0, 0).copy_from(&drot);
    jp.fixed_view_mut::<2, 3>(0, 3).copy_from(&duv);
    Some((pix, jc, jp))
}

/// Sum of squared pixel residuals, or `None` if a point falls behind its camera.
fn cost(views: &[PlanarView], c: &Camera9, poses: &[Pose]) -> Option<f64> {
    let mut s = 0.0;
    for (v, pose) in views.iter().zip(poses) {
        for (o, q) in v.object.iter().zip(&v.image) {
            let (p, _, _) = project_with_jacobian(c, pose, *o)?;
            s += (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
        }
    }
    Some(s)
}

/// The normal equations in block form.
struct Normal {
    a: SMatrix<f64, 9, 9>,
    ga: SVector<f64, 9>,
    b: Vec<SMatrix<f64, 9, 6>>,
    c: Vec<Matrix6<f64>>,
    gc: Vec<Vector6<f64>>,
}

fn normal_equations(views: &[PlanarView], c: &Camera9, poses: &[Pose], free: &[bool; 9]) -> Option<Normal> {
    let mut n = Normal {
        a: SMatrix::zeros(),
        ga: SVector::zeros(),
        b: vec![SMatrix::zeros(); views.len()],
        c: vec![Matrix6::zeros(); views.len()],
        gc: vec![Vector6::zeros(); views.len()],
    };
    for (i, (v, pose)) in views.iter().zip(poses).enumerate() {
        for (o, q) in v.object.iter().zip(&v.image) {
            let (p, mut jc, jp) = project_with_jacobian(c, pose, *o)?;
            for (k, f) in free.iter().enumerate() {
                if !f {
                    jc.column_mut(k).fill(0.0);
                }
            }
            let r = nalgebra::Vector2::new(p[0] - q[0], p[1] - q[1]);
            n.a += jc.transpose() * jc;
            n.ga -= jc.transpose() * r;
            n.b[i] += jc.transpose() * jp;
            n.c[i] += jp.transpose() * jp;
            n.gc[i] -= jp.transpose() * r;
        }
    }
    for (k, f) in free.iter().enumerate() {
        if !f {
            n.a[(k, k)] = 1.0;
        }
    }
    Some(n)
}

/// A damped solution: camera step, pose steps, inverse Schur complement.
type Step = (SVector<f64, 9>, Vec<Vector6<f64>>, SMatrix<f64, 9, 9>);

/// Solves the damped system by the Schur complement; returns the camera step, the pose
/// steps and the inverse Schur complement (the camera block of the inverse normal matrix).
fn solve(n: &Normal, lambda: f64) -> Option<Step> {
    let mut s = n.a;
    for k in 0..9 {
        s[(k, k)] += lambda * n.a[(k, k)];
    }
    let mut rhs = n.ga;
    let mut c_inv = Vec::with_capacity(n.c.len());
    for i in 0..n.c.len() {
        let mut c = n.c[i];
        for k in 0..6 {
            c[(k, k)] += lambda * n.c[i][(k, k)];
        }
        let ci = c.cholesky()?.inverse();
        let bci = n.b[i] * ci;
        s -= bci * n.b[i].transpose();
        rhs -= bci * n.gc[i];
        c_inv.push(ci);
    }
    let s_inv = s.cholesky()?.inverse();
    let da = s_inv * rhs;
    let dp = (0..n.c.len()).map(|i| c_inv[i] * (n.gc[i] - n.b[i].transpose() * da)).collect();
    Some((da, dp, s_inv))
}

fn apply_step(c: &Camera9, poses: &[Pose], da: &SVector<f64, 9>, dp: &[Vector6<f64>]) -> (Camera9, Vec<Pose>) {
    let c2 = std::array::from_fn(|k| c[k] + da[k]);
    let p2 = poses
        .iter()
        .zip(dp)
        .map(|(p, d)| {
            let rot = Rotation3::new(Vector3::new(d[0], d[1], d[2]));
            Pose { r: rot.matrix() * p.r, t: p.t + Vector3::new(d[3], d[4], d[5]) }
        })
        .collect();
    (c2, p2)
}

/// Calibrates a camera from three or more views of a planar target: closed form, then
/// Levenberg-Marquardt over intrinsics, distortion and poses.
pub fn calibrate(views: &[PlanarView], options: &ZhangOptions) -> Result<PlanarCalibration> {
    let (k0, mut poses) = closed_form(views)?;
    let mut c: Camera9 = [k0.fx, k0.fy, k0.cx, k0.cy, 0.0, 0.0, 0.0, 0.0, 0.0];
    let free = [
        true,
        true,
        true,
        true,
        options.radial,
        options.radial,
        options.tangential,
        options.tangential,
        options.radial && options.k3,
    ];
    let diverged = || GeometryError::Degenerate("refinement put a target point behind the camera".into());
    let mut current = cost(views, &c, &poses).ok_or_else(diverged)?;
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < options.max_iterations {
        iterations += 1;
        let n = normal_equations(views, &c, &poses, &free).ok_or_else(diverged)?;
        let mut improved = false;
        while lambda < 1e12 {
            let step = solve(&n, lambda);
            if let Some((da, dp, _)) = step {
                let (c2, p2) = apply_step(&c, &poses, &da, &dp);
                if let Some(next) = cost(views, &c2, &p2) {
                    if next <= current {
                        let decrease = current - next;
                        c = c2;
                        poses = p2;
                        lambda = (lambda / 10.0).max(1e-12);
                        improved = decrease > 1e-12 * current.max(1e-300);
                        current = next;
                        break;
                    }
                }
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let n = normal_equations(views, &c, &poses, &free).ok_or_else(diverged)?;
    let (_, _, s_inv) = solve(&n, 0.0)
        .ok_or_else(|| GeometryError::Degenerate("the normal matrix is singular at the optimum".into()))?;
    let points: usize = views.iter().map(|v| v.object.len()).sum();
    let dof = (2 * points) as f64 - (free.iter().filter(|f| **f).count() + 6 * views.len()) as f64;
    let sigma2 = if dof > 0.0 { current / dof } else { f64::NAN };
    let std_dev = std::array::from_fn(|k| if free[k] { (sigma2 * s_inv[(k, k)]).max(0.0).sqrt() } else { 0.0 });
    let per_view_rms_px = views
        .iter()
        .zip(&poses)
        .map(|(v, p)| {
            let e = cost(std::slice::from_ref(v), &c, std::slice::from_ref(p)).unwrap_or(f64::INFINITY);
            (e / v.object.len().max(1) as f64).sqrt()
        })
        .collect();
    Ok(PlanarCalibration {
        intrinsics: Intrinsics { fx: c[0], fy: c[1], cx: c[2], cy: c[3], skew: 0.0 },
        distortion: Distortion { k1: c[4], k2: c[5], p1: c[6], p2: c[7], k3: c[8] },
        poses,
        closed_form: k0,
        rms_px: (current / points.max(1) as f64).sqrt(),
        per_view_rms_px,
        std_dev,
        iterations,
    })
}

/// Projects target points of a view through a calibrated camera (for residual plots and
/// synthetic data); `None` for a point behind the camera.
pub fn project_view(k: &Intrinsics, d: &Distortion, pose: &Pose, object: &[[f64; 2]]) -> Option<Vec<[f64; 2]>> {
    let c = [k.fx, k.fy, k.cx, k.cy, d.k1, d.k2, d.p1, d.p2, d.k3];
    object.iter().map(|o| project_with_jacobian(&c, pose, *o).map(|(p, _, _)| p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::rng::SplitMix64;

    /// Inner corners of a cols x rows board with `square` spacing, row by row.
    fn board(cols: usize, rows: usize, square: f64) -> Vec<[f64; 2]> {
        (0..rows).flat_map(|r| (0..cols).map(move |c| [c as f64 * square, r as f64 * square])).collect()
    }

    fn views(k: &Intrinsics, d: &Distortion, n: usize, noise: f64, seed: u64) -> (Vec<PlanarView>, Vec<Pose>) {
        let obj = board(9, 6, 25.0);
        let mut rng = SplitMix64::new(seed);
        let (mut out, mut poses) = (Vec::new(), Vec::new());
        while out.len() < n {
            let r = Rotation3::from_euler_angles(
                (rng.unit() - 0.5) * 1.0,
                (rng.unit() - 0.5) * 1.0,
                (rng.unit() - 0.5) * 0.6,
            );
            // Board centre near the optical axis, 350-550 mm away.
            let centre = Vector3::new(100.0, 62.5, 0.0);
            let t = Vector3::new((rng.unit() - 0.5) * 80.0, (rng.unit() - 0.5) * 60.0, 350.0 + 200.0 * rng.unit())
                - r * centre;
            let pose = Pose { r: *r.matrix(), t };
            let Some(img) = project_view(k, d, &pose, &obj) else { continue };
            if img.iter().any(|p| p[0] < 0.0 || p[1] < 0.0 || p[0] > 639.0 || p[1] > 479.0) {
                continue;
            }
            let image = img.iter().map(|p| [p[0] + noise * rng.normal(), p[1] + noise * rng.normal()]).collect();
            out.push(PlanarView { object: obj.clone(), image });
            poses.push(pose);
        }
        (out, poses)
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let c: Camera9 = [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 0.001, -0.002, 0.01];
        let pose =
            Pose { r: *Rotation3::from_euler_angles(0.3, -0.2, 0.1).matrix(), t: Vector3::new(-50.0, 20.0, 400.0) };
        let p = [60.0, 90.0];
        let (_, jc, jp) = project_with_jacobian(&c, &pose, p).unwrap();
        for k in 0..9 {
            let h = 1e-6 * c[k].abs().max(1e-3);
            let (mut a, mut b) = (c, c);
            a[k] += h;
            b[k] -= h;
            let (pa, _, _) = project_with_jacobian(&a, &pose, p).unwrap();
            let (pb, _, _) = project_with_jacobian(&b, &pose, p).unwrap();
            for r in 0..2 {
                let num = (pa[r] - pb[r]) / (2.0 * h);
                assert!(
                    (num - jc[(r, k)]).abs() < 1e-5 * (1.0 + num.abs()),
                    "camera {k} row {r}: {num} vs {}",
                    jc[(r, k)]
                );
            }
        }
        for k in 0..6 {
            let h = 1e-6;
            let mut d = Vector6::zeros();
            d[k] = h;
            let (_, pa) = apply_step(&c, &[pose], &SVector::zeros(), &[d]);
            let (_, pb) = apply_step(&c, &[pose], &SVector::zeros(), &[-d]);
            let (qa, _, _) = project_with_jacobian(&c, &pa[0], p).unwrap();
            let (qb, _, _) = project_with_jacobian(&c, &pb[0], p).unwrap();
            for r in 0..2 {
                let num = (qa[r] - qb[r]) / (2.0 * h);
                assert!(
                    (num - jp[(r, k)]).abs() < 1e-4 * (1.0 + num.abs()),
                    "pose {k} row {r}: {num} vs {}",
                    jp[(r, k)]
                );
            }
        }
    }

    #[test]
    fn closed_form_is_exact_without_distortion_and_noise() {
        let k = Intrinsics { fx: 812.0, fy: 806.0, cx: 318.0, cy: 243.0, skew: 0.0 };
        let (vs, truth) = views(&k, &Distortion::default(), 5, 0.0, 3);
        let (est, poses) = closed_form(&vs).unwrap();
        assert!((est.fx - k.fx).abs() < 1e-6 && (est.fy - k.fy).abs() < 1e-6, "{est:?}");
        assert!((est.cx - k.cx).abs() < 1e-6 && (est.cy - k.cy).abs() < 1e-6 && est.skew.abs() < 1e-6, "{est:?}");
        for (p, q) in poses.iter().zip(&truth) {
            assert!((p.r - q.r).norm() < 1e-8 && (p.t - q.t).norm() < 1e-5);
        }
    }

    #[test]
    fn refinement_recovers_distortion_exactly_without_noise() {
        let k = Intrinsics { fx: 812.0, fy: 806.0, cx: 318.0, cy: 243.0, skew: 0.0 };
        let d = Distortion { k1: -0.25, k2: 0.08, k3: 0.0, p1: 0.001, p2: -0.0008 };
        let (vs, _) = views(&k, &d, 10, 0.0, 4);
        let cal = calibrate(&vs, &ZhangOptions::default()).unwrap();
        assert!(cal.rms_px < 1e-6, "rms {}", cal.rms_px);
        let e = &cal.intrinsics;
        assert!((e.fx - k.fx).abs() < 1e-4 && (e.fy - k.fy).abs() < 1e-4 && (e.cx - k.cx).abs() < 1e-4, "{e:?}");
        let g = &cal.distortion;
        assert!((g.k1 - d.k1).abs() < 1e-6 && (g.k2 - d.k2).abs() < 1e-5 && (g.p1 - d.p1).abs() < 1e-8, "{g:?}");
    }

    #[test]
    fn noisy_views_give_small_focal_error_and_honest_std_devs() {
        // 0.5 px noise, 10 views of a 9x6 board tilted up to 29 degrees, 20 trials: the mean
        // focal error, and how often the truth lies within 3 standard deviations (the error
        // depends on the tilts; scripts/opencv/compare_zhang.py runs OpenCV on equal data).
        let k = Intrinsics { fx: 812.0, fy: 806.0, cx: 318.0, cy: 243.0, skew: 0.0 };
        let d = Distortion { k1: -0.25, k2: 0.08, k3: 0.0, p1: 0.001, p2: -0.0008 };
        let (mut err, mut within) = (0.0, 0);
        for seed in 0..20 {
            let (vs, _) = views(&k, &d, 10, 0.5, 100 + seed);
            let cal = calibrate(&vs, &ZhangOptions::default()).unwrap();
            err += (cal.intrinsics.fx - k.fx).abs() / k.fx / 20.0;
            within += usize::from((cal.intrinsics.fx - k.fx).abs() < 3.0 * cal.std_dev[0]);
            // Per-point distance RMS of 0.5 px per axis noise: 0.5 sqrt 2.
            assert!((cal.rms_px - 0.5 * 2f64.sqrt()).abs() < 0.1, "rms {}", cal.rms_px);
        }
        println!("Zhang + LM, 10 views of 9x6, 0.5 px: mean focal error {:.3} %, within 3 sd {within}/20", err * 100.0);
        assert!(err < 0.006, "mean focal error {err}");
        assert!(within >= 17, "{within}/20 within 3 sd");
    }

    #[test]
    fn degenerate_inputs_are_clear_errors() {
        let k = Intrinsics { fx: 800.0, fy: 800.0, cx: 320.0, cy: 240.0, skew: 0.0 };
        let (vs, _) = views(&k, &Distortion::default(), 4, 0.0, 5);
        assert!(matches!(
            calibrate(&vs[..2], &ZhangOptions::default()),
            Err(GeometryError::TooFewViews { got: 2, .. })
        ));
        // Three fronto-parallel views (pure translations) leave the focal length undetermined.
        let obj = board(9, 6, 25.0);
        let flat: Vec<PlanarView> = (0..3)
            .map(|i| {
                let z = 400.0 + 50.0 * i as f64;
                let image = obj
                    .iter()
                    .map(|p| [800.0 * (p[0] - 100.0) / z + 320.0, 800.0 * (p[1] - 60.0) / z + 240.0])
                    .collect();
                PlanarView { object: obj.clone(), image }
            })
            .collect();
        assert!(matches!(calibrate(&flat, &ZhangOptions::default()), Err(GeometryError::Degenerate(_))));
        let mut nan = vs.clone();
        nan[1].image[4][0] = f64::NAN;
        assert!(matches!(calibrate(&nan, &ZhangOptions::default()), Err(GeometryError::NonFinite { .. })));
    }
}
