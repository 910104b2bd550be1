//! Planar poses of a robot on the floor: position and heading, as the odometry and the floor
//! generator use them.
//!
//! Frame: x right, y down on the floor (as an image seen from above), headings clockwise from
//! "up" (-y), in radians; lengths in whatever unit the caller uses (metres or ground pixels).
//! The robot frame is (right, forward).

/// A planar pose: position of the robot's rotation centre and its heading.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose2 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// Heading, radians, clockwise from up.
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
        let [x, y] = self.point(right, forward);
        Pose2 { x, y, theta: self.theta + dtheta }
    }

    /// The point at `(right, forward)` in the robot frame, in the world.
    pub fn point(&self, right: f64, forward: f64) -> [f64; 2] {
        let (r, f) = self.axes();
        [self.x + r[0] * right + f[0] * forward, self.y + r[1] * right + f[1] * forward]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forward_is_up_and_right_is_right_at_heading_zero() {
        let p = Pose2::default().step(1.0, 2.0, 0.5);
        assert_eq!((p.x, p.y, p.theta), (1.0, -2.0, 0.5));
        // A quarter turn clockwise: forward becomes +x.
        let q = Pose2 { theta: std::f64::consts::FRAC_PI_2, ..Default::default() }.step(0.0, 1.0, 0.0);
        assert!((q.x - 1.0).abs() < 1e-12 && q.y.abs() < 1e-12);
    }
}
