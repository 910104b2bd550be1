//! The robot kinematics of seed eq. 20: a camera mounted at an offset from
//! the robot's rotation centre moves on a circle when the robot turns in place.

pub use ocellus_geometry::planar::Pose2;

/// The robot pose after its camera moved by (`camera_right`, `camera_forward`) in the robot
/// frame of `pose` and turned by `turn`, exactly: the camera position follows, and the
/// rotation centre is found back from the mount offset at the new heading.
pub fn moved_by_camera(pose: &Pose2, camera_right: f64, camera_forward: f64, turn: f64, mount: &Mount) -> Pose2 {
    let cam = pose.point(mount.right_m + camera_right, mount.forward_m + camera_forward);
    let at_cam = Pose2 { x: cam[0], y: cam[1], theta: pose.theta + turn };
    let [x, y] = at_cam.point(-mount.right_m, -mount.forward_m);
    Pose2 { x, y, theta: at_cam.theta }
}

/// Where the camera sits relative to the rotation centre, metres (robot frame).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mount {
    /// To the right of the rotation centre, metres.
    pub right_m: f64,
    /// Ahead of the rotation centre, metres.
    pub forward_m: f64,
}

/// Robot motion (right, forward, turn) over one frame from the camera's motion over that frame
/// (right and forward in the robot frame, metres; turn in radians): the camera's translation
/// includes the arc `turn x offset` it travels when the robot turns (seed eq. 20, to first
/// order in the turn).
pub fn robot_motion(camera_right_m: f64, camera_forward_m: f64, turn_rad: f64, mount: &Mount) -> (f64, f64, f64) {
    (camera_right_m - mount.forward_m * turn_rad, camera_forward_m + mount.right_m * turn_rad, turn_rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_in_place_moves_the_camera_but_not_the_robot() {
        // Camera 0.2 m ahead; the robot turns by 0.01 rad: the camera moves 2 mm to the
        // right (first order) and the robot not at all.
        let m = Mount { right_m: 0.0, forward_m: 0.2 };
        let (r, f, t) = robot_motion(0.002, 0.0, 0.01, &m);
        assert!(r.abs() < 1e-12 && f.abs() < 1e-12 && t == 0.01);
        // Exactly: turning in place by a large angle moves the camera on a circle.
        let q = Pose2 { x: 1.0, y: 2.0, theta: 0.3 };
        let turn = 1.2;
        let t = Pose2 { x: 0.0, y: 0.0, theta: q.theta + turn };
        let cam0 = [q.x + 0.2 * q.axes().1[0], q.y + 0.2 * q.axes().1[1]];
        let cam1 = [q.x + 0.2 * t.axes().1[0], q.y + 0.2 * t.axes().1[1]];
        // The camera displacement in the robot frame of q.
        let (r, f) = q.axes();
        let d = [cam1[0] - cam0[0], cam1[1] - cam0[1]];
        let moved = moved_by_camera(&q, d[0] * r[0] + d[1] * r[1], d[0] * f[0] + d[1] * f[1], turn, &m);
        assert!((moved.x - q.x).abs() < 1e-12 && (moved.y - q.y).abs() < 1e-12 && (moved.theta - 1.5).abs() < 1e-12);
    }
}
