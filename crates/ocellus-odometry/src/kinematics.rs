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
    }
}
