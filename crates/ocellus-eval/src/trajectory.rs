//! How far an estimated planar trajectory is from the truth (SPEC 6): final drift as a
//! percentage of the path, final heading error, absolute trajectory error (ATE, RMSE of the
//! positions) and relative pose error over one step (RPE, translation part), after pairing
//! the poses by time.
//!
//! Poses are planar: x and y in metres in a fixed world frame, yaw in radians about +z. The
//! metrics follow Sturm et al., "A benchmark for the evaluation of RGB-D SLAM systems", IROS
//! 2012 (ATE and RPE), without alignment: odometry starts at the true pose.
//!
//! ```
//! use ocellus_eval::trajectory::{errors, PlanarPose};
//! let truth: Vec<PlanarPose> = (0..5).map(|k| PlanarPose::new(k as f64, k as f64, 0.0, 0.0)).collect();
//! let est: Vec<PlanarPose> = truth.iter().map(|p| PlanarPose { y_m: 0.1 * p.x_m, ..*p }).collect();
//! let e = errors(&est, &truth, 0.01).unwrap();
//! assert!((e.final_drift_percent - 10.0).abs() < 1e-9); // 0.4 m off after a 4 m path
//! ```

use crate::{EvalError, Result};

/// A pose of a robot on the ground plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarPose {
    /// Time stamp, seconds.
    pub time_s: f64,
    /// Position, metres.
    pub x_m: f64,
    /// Position, metres.
    pub y_m: f64,
    /// Heading, radians about +z.
    pub yaw_rad: f64,
}

impl PlanarPose {
    /// A pose from its time, position and heading.
    pub fn new(time_s: f64, x_m: f64, y_m: f64, yaw_rad: f64) -> Self {
        Self { time_s, x_m, y_m, yaw_rad }
    }

    fn distance(&self, o: &PlanarPose) -> f64 {
        (self.x_m - o.x_m).hypot(self.y_m - o.y_m)
    }
}

/// An angle wrapped to (-pi, pi], radians.
pub fn wrap_angle(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

/// Length of the polyline through the positions, metres.
pub fn path_length(poses: &[PlanarPose]) -> f64 {
    poses.windows(2).map(|w| w[0].distance(&w[1])).sum()
}

/// Final position error in percent of `path_m`, and the final heading error in degrees, of an
/// estimated end pose against the true one.
pub fn final_drift(estimate: &PlanarPose, truth: &PlanarPose, path_m: f64) -> Result<(f64, f64)> {
    if !(path_m.is_finite() && path_m > 0.0) {
        return Err(EvalError::Undefined { metric: "drift", why: format!("the true path has length {path_m} m") });
    }
    Ok((100.0 * estimate.distance(truth) / path_m, wrap_angle(estimate.yaw_rad - truth.yaw_rad).to_degrees().abs()))
}

/// For each true pose, the index of the estimate nearest in time if it is within `max_dt_s`
/// seconds: `(estimate index, truth index)` pairs, in time order. Both lists must be sorted
/// by time (TUM files are; see `ocellus_io::tum`); one pass, linear in their lengths.
pub fn pair_by_time(estimate: &[PlanarPose], truth: &[PlanarPose], max_dt_s: f64) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    let mut j = 0;
    for (i, g) in truth.iter().enumerate() {
        while j + 1 < estimate.len()
            && (estimate[j + 1].time_s - g.time_s).abs() <= (estimate[j].time_s - g.time_s).abs()
        {
            j += 1;
        }
        if estimate.get(j).is_some_and(|e| (e.time_s - g.time_s).abs() <= max_dt_s) {
            pairs.push((j, i));
        }
    }
    pairs
}

/// The errors of an estimated trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajectoryErrors {
    /// Poses paired by time.
    pub pairs: usize,
    /// Length of the true path over the paired poses, metres.
    pub path_m: f64,
    /// Final position error, percent of the path.
    pub final_drift_percent: f64,
    /// Final heading error, degrees.
    pub final_heading_deg: f64,
    /// Absolute trajectory error: RMSE of the positions, metres.
    pub ate_rmse_m: f64,
    /// The same after the rigid motion (rotation and translation, no scale) that best lays the
    /// estimated positions onto the true ones, metres: the error in the path's shape, not in
    /// where it started or which way it set off.
    pub ate_aligned_rmse_m: f64,
    /// Relative pose error over one step, translation part: RMSE, metres.
    pub rpe_rmse_m: f64,
}

/// Pairs the poses by time (within `max_dt_s`) and measures the errors; an error when fewer
/// than two poses pair up or the true path does not move.
pub fn errors(estimate: &[PlanarPose], truth: &[PlanarPose], max_dt_s: f64) -> Result<TrajectoryErrors> {
    let pairs: Vec<(PlanarPose, PlanarPose)> =
        pair_by_time(estimate, truth, max_dt_s).into_iter().map(|(i, j)| (estimate[i], truth[j])).collect();
    errors_of_pairs(&pairs)
}

/// The errors of `(estimate, truth)` pairs already matched in time (at least two).
pub fn errors_of_pairs(pairs: &[(PlanarPose, PlanarPose)]) -> Result<TrajectoryErrors> {
    if pairs.len() < 2 {
        return Err(EvalError::Undefined {
            metric: "trajectory errors",
            why: format!("only {} poses pair up in time: do the timestamps match?", pairs.len()),
        });
    }
    let (est, gt): (Vec<PlanarPose>, Vec<PlanarPose>) = pairs.iter().copied().unzip();
    let path_m = path_length(&gt);
    let (last_e, last_g) = pairs[pairs.len() - 1];
    let (final_drift_percent, final_heading_deg) = final_drift(&last_e, &last_g, path_m)
        .map_err(|_| EvalError::Undefined { metric: "drift", why: "the paired true poses do not move".into() })?;
    let ate_rmse_m = (pairs.iter().map(|(e, g)| e.distance(g).powi(2)).sum::<f64>() / pairs.len() as f64).sqrt();
    // One step of each trajectory in the frame of its own first pose.
    let step = |p: &PlanarPose, q: &PlanarPose| {
        let (dx, dy) = (q.x_m - p.x_m, q.y_m - p.y_m);
        let (s, c) = p.yaw_rad.sin_cos();
        (c * dx + s * dy, -s * dx + c * dy)
    };
    let rpe: Vec<f64> = est
        .windows(2)
        .zip(gt.windows(2))
        .map(|(e, g)| {
            let (a, b) = (step(&e[0], &e[1]), step(&g[0], &g[1]));
            (a.0 - b.0).hypot(a.1 - b.1)
        })
        .collect();
    let rpe_rmse_m = (rpe.iter().map(|v| v * v).sum::<f64>() / rpe.len() as f64).sqrt();
    let ate_aligned_rmse_m = aligned_rmse(pairs);
    Ok(TrajectoryErrors {
        pairs: pairs.len(),
        path_m,
        final_drift_percent,
        final_heading_deg,
        ate_rmse_m,
        ate_aligned_rmse_m,
        rpe_rmse_m,
    })
}

/// The position RMSE of `(estimate, truth)` pairs after the best rigid 2D alignment of the
/// estimate onto the truth, in closed form (Horn 1987; Umeyama 1991 without scale): with
/// `a` and `b` the positions about their centroids, the rotation is
/// `atan2(sum(a_x b_y - a_y b_x), sum(a . b))` and the translation joins the centroids.
pub fn aligned_rmse(pairs: &[(PlanarPose, PlanarPose)]) -> f64 {
    let n = pairs.len().max(1) as f64;
    let mean = |f: &dyn Fn(&(PlanarPose, PlanarPose)) -> f64| pairs.iter().map(f).sum::<f64>() / n;
    let (ex, ey) = (mean(&|p| p.0.x_m), mean(&|p| p.0.y_m));
    let (gx, gy) = (mean(&|p| p.1.x_m), mean(&|p| p.1.y_m));
    let centred = |(e, g): &(PlanarPose, PlanarPose)| ([e.x_m - ex, e.y_m - ey], [g.x_m - gx, g.y_m - gy]);
    let (mut dot, mut cross) = (0.0, 0.0);
    for p in pairs {
        let (a, b) = centred(p);
        dot += a[0] * b[0] + a[1] * b[1];
        cross += a[0] * b[1] - a[1] * b[0];
    }
    let (s, c) = cross.atan2(dot).sin_cos();
    let sq: f64 = pairs
        .iter()
        .map(|p| {
            let (a, b) = centred(p);
            (c * a[0] - s * a[1] - b[0]).powi(2) + (s * a[0] + c * a[1] - b[1]).powi(2)
        })
        .sum();
    (sq / n).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64) -> Vec<PlanarPose> {
        (0..n)
            .map(|k| {
                let a = k as f64 * 0.01;
                PlanarPose::new(k as f64 * 0.005, r * a.sin(), r * (1.0 - a.cos()), a)
            })
            .collect()
    }

    #[test]
    fn closed_forms_on_a_circle() {
        let truth = circle(101, 2.0);
        // The arc of 1 rad on a 2 m circle is 2 m long (the chords, to 1e-5).
        assert!((path_length(&truth) - 2.0).abs() < 1e-4);
        let e = errors(&truth, &truth, 1e-6).unwrap();
        assert_eq!((e.pairs, e.ate_rmse_m, e.rpe_rmse_m, e.final_drift_percent), (101, 0.0, 0.0, 0.0));
        // Shifted by 3 cm everywhere: ATE 3 cm, RPE 0, drift 3 cm over the path, heading 0.
        let shifted: Vec<PlanarPose> = truth.iter().map(|p| PlanarPose { x_m: p.x_m + 0.03, ..*p }).collect();
        let e = errors(&shifted, &truth, 1e-6).unwrap();
        assert!((e.ate_rmse_m - 0.03).abs() < 1e-12 && e.rpe_rmse_m < 1e-12);
        assert!((e.final_drift_percent - 3.0 / e.path_m).abs() < 1e-9 && e.final_heading_deg < 1e-9);
        // A heading 2 degrees off at the end; angles wrap across +-180.
        let (_, h) =
            final_drift(&PlanarPose::new(0.0, 0.0, 0.0, 3.13), &PlanarPose::new(0.0, 0.0, 0.0, -3.13), 1.0).unwrap();
        assert!((h - (2.0 * std::f64::consts::PI - 6.26).to_degrees()).abs() < 1e-9, "{h}");
    }

    #[test]
    fn pairing_and_undefined_cases() {
        let truth = circle(10, 1.0);
        let late: Vec<PlanarPose> = truth.iter().map(|p| PlanarPose { time_s: p.time_s + 1.0, ..*p }).collect();
        assert!(errors(&late, &truth, 0.001).is_err());
        let still: Vec<PlanarPose> = truth.iter().map(|p| PlanarPose { x_m: 0.0, y_m: 0.0, ..*p }).collect();
        assert!(errors(&still, &still, 0.001).is_err());
        // Every other estimate: each true pose pairs with its own time or not at all.
        let half: Vec<PlanarPose> = truth.iter().step_by(2).copied().collect();
        assert_eq!(pair_by_time(&half, &truth, 1e-6).len(), 5);
        assert_eq!(pair_by_time(&half, &truth, 0.006).len(), 10);
        assert!((wrap_angle(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn the_aligned_ate_removes_a_rigid_motion_and_matches_a_search_over_angles() {
        let truth = circle(101, 2.0);
        // The truth turned by 0.3 rad about (1, -2) and moved: no shape error at all.
        let (s, c) = 0.3f64.sin_cos();
        let moved: Vec<PlanarPose> = truth
            .iter()
            .map(|p| {
                let (x, y) = (p.x_m - 1.0, p.y_m + 2.0);
                PlanarPose { x_m: c * x - s * y + 0.5, y_m: s * x + c * y - 0.7, ..*p }
            })
            .collect();
        let e = errors(&moved, &truth, 1e-6).unwrap();
        assert!(e.ate_aligned_rmse_m < 1e-12 && e.ate_rmse_m > 0.5, "{e:?}");
        // A wobbly estimate: the closed form equals the best over a fine search of angles
        // (each with its best translation, the centroids joined).
        let wobbly: Vec<PlanarPose> = moved
            .iter()
            .enumerate()
            .map(|(k, p)| PlanarPose {
                x_m: p.x_m + 0.01 * (k as f64 * 0.7).sin(),
                y_m: p.y_m + 0.02 * (k as f64 * 0.3).cos(),
                ..*p
            })
            .collect();
        let pairs: Vec<(PlanarPose, PlanarPose)> = wobbly.iter().copied().zip(truth.iter().copied()).collect();
        let closed = aligned_rmse(&pairs);
        let n = pairs.len() as f64;
        let (ex, ey) = (pairs.iter().map(|p| p.0.x_m).sum::<f64>() / n, pairs.iter().map(|p| p.0.y_m).sum::<f64>() / n);
        let (gx, gy) = (pairs.iter().map(|p| p.1.x_m).sum::<f64>() / n, pairs.iter().map(|p| p.1.y_m).sum::<f64>() / n);
        let searched = (0..200_000)
            .map(|i| {
                let (s, c) = (i as f64 / 200_000.0 * std::f64::consts::TAU).sin_cos();
                let sq: f64 = pairs
                    .iter()
                    .map(|(e, g)| {
                        let (ax, ay, bx, by) = (e.x_m - ex, e.y_m - ey, g.x_m - gx, g.y_m - gy);
                        (c * ax - s * ay - bx).powi(2) + (s * ax + c * ay - by).powi(2)
                    })
                    .sum();
                (sq / n).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(closed <= searched + 1e-12 && searched - closed < 1e-6, "closed {closed}, searched {searched}");
        assert!(closed > 0.005, "{closed}");
    }
}
