//! Planar poses and the robot kinematics of seed eq. 20: a camera mounted at an offset from
//! the robot's rotation centre moves on a circle when the robot turns in place.

/// A planar pose: position of the robot's rotation centre (metres, world x right, y down as
/// the first image) and heading (radians, clockwise from the first image's up).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose2 {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians.
    pub theta: f64,
}

impl Pose2 {
    /// Unit vectors of the robot's right and forward directions in the world.
    pub fn axes(&self) -> ([f64; 2], [f64; 2]) {
        let (s, c) = self.theta.sin_cos();
        ([c, s], [s, -c])
    }

    /// Moves by `right`, `forward` (robot frame of this pose) and turns by `dtheta`.
    pub fn step(&self, right: f64, forward: f64, dtheta: f64) -> Pose2 {
        let (r, f) = self.axes();
        Pose2 {
            x: self.x + r[0] * right + f[0] * forward,
            y: self.y + r[1] * right + f[1] * forward,
            theta: self.theta + dtheta,
        }
    }
}

impl Pose2 {
    /// The robot pose after its camera moved by (`camera_right`, `camera_forward`) in the
    /// robot frame of this pose and turned by `turn`, exactly: the camera position follows,
    /// and the rotation centre is found back from the mount offset at the new heading.
    pub fn moved_by_camera(&self, camera_right: f64, camera_forward: f64, turn: f64, mount: &Mount) -> Pose2 {
        let (r, f) = self.axes();
        let cam = [
            self.x + mount.right_m * r[0] + mount.forward_m * f[0] + camera_right * r[0] + camera_forward * f[0],
            self.y + mount.right_m * r[1] + mount.forward_m * f[1] + camera_right * r[1] + camera_forward * f[1],
        ];
        let theta = self.theta + turn;
        let next = Pose2 { x: 0.0, y: 0.0, theta };
        let (r2, f2) = next.axes();
        Pose2 {
            x: cam[0] - mount.right_m * r2[0] - mount.forward_m * f2[0],
            y: cam[1] - mount.right_m * r2[1] - mount.forward_m * f2[1],
            theta,
        }
    }
}

/// Where the camera sits relative to the rotation centre, metres (robot frame).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
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
        let p = Pose2::default().step(1.0, 2.0, 0.5);
        assert_eq!((p.x, p.y, p.theta), (1.0, -2.0, 0.5));
        // Exactly: turning in place by a large angle moves the camera on a circle.
        let q = Pose2 { x: 1.0, y: 2.0, theta: 0.3 };
        let turn = 1.2;
        let t = Pose2 { x: 0.0, y: 0.0, theta: q.theta + turn };
        let cam0 = [q.x + 0.2 * q.axes().1[0], q.y + 0.2 * q.axes().1[1]];
        let cam1 = [q.x + 0.2 * t.axes().1[0], q.y + 0.2 * t.axes().1[1]];
        // The camera displacement in the robot frame of q.
        let (r, f) = q.axes();
        let d = [cam1[0] - cam0[0], cam1[1] - cam0[1]];
        let moved = q.moved_by_camera(d[0] * r[0] + d[1] * r[1], d[0] * f[0] + d[1] * f[1], turn, &m);
        assert!((moved.x - q.x).abs() < 1e-12 && (moved.y - q.y).abs() < 1e-12 && (moved.theta - 1.5).abs() < 1e-12);
    }
}
