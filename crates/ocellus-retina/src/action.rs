//! Actions and their motor codes (SPEC 8.1).
//!
//! An action moves the eye; the pixel at offset p afterwards shows the source point
//! `c + T(p)` of the image, with c the gaze point before it:
//! - shift by (dx, dy) pixels: `T(p) = p + (dx, dy)`;
//! - rotate by theta and dilate by log-scale s (zoom in by e^s): `T(p) = e^-s R(theta) p`,
//!   R rotating from +x towards +y.
//!
//! The 2D motor space holds (dx, dy) in pixels for translations and (theta in radians, s) for
//! rotation + dilation. The motor code q of an action is one of:
//! - one-hot over the cells of a grid tiling the space (experiment 1 by default: 60 fixed
//!   motor fields as 10 x 6 cells, each triplet's action anywhere inside its cell);
//! - one-hot over a list of discrete action values (experiment 1 as first built: one fixed
//!   motor field per exact value on the two axes);
//! - the bilinear weights of its point over a grid of motor cells spanning the space
//!   (experiment 2: 15 x 15 cells), a population code that sums to 1.

use crate::{Result, RetinaError};

/// What an action does.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Action {
    /// Shift by (dx, dy) pixels.
    Shift {
        /// Pixels, +x right.
        dx: f64,
        /// Pixels, +y down.
        dy: f64,
    },
    /// Rotate by `theta` radians and dilate by log-scale `s`.
    RotateDilate {
        /// Radians, from +x towards +y.
        theta: f64,
        /// Natural log of the zoom factor.
        s: f64,
    },
}

impl Action {
    /// Where the pixel at offset `p` samples the source after the action, relative to the
    /// gaze point before it.
    pub fn map(&self, p: [f64; 2]) -> [f64; 2] {
        match *self {
            Action::Shift { dx, dy } => [p[0] + dx, p[1] + dy],
            Action::RotateDilate { theta, s } => {
                let (sn, cs) = theta.sin_cos();
                let k = (-s).exp();
                [k * (cs * p[0] - sn * p[1]), k * (sn * p[0] + cs * p[1])]
            }
        }
    }

    /// The action's point in its 2D motor space.
    pub fn motor_point(&self) -> [f64; 2] {
        match *self {
            Action::Shift { dx, dy } => [dx, dy],
            Action::RotateDilate { theta, s } => [theta, s],
        }
    }

    /// The share of the disc of `radius` pixels after the action that shows what the disc
    /// showed before it, in [0, 1]: what i1 holds of i0, the part of it that any sensor could
    /// predict. A shift by d keeps the lens where two discs d apart overlap, a share
    /// `(2 / pi) (acos x - x sqrt(1 - x^2))` with x = d / 2r (nothing beyond d = 2r). A
    /// rotation about the gaze point keeps everything, a zoom in (s > 0) too, and a zoom out
    /// keeps the central disc of radius r e^s, a share e^2s.
    pub fn kept_share(&self, radius: f64) -> f64 {
        match *self {
            Action::Shift { dx, dy } => {
                let x = (dx.hypot(dy) / (2.0 * radius)).min(1.0);
                if x.is_nan() {
                    return 0.0;
                }
                (2.0 / std::f64::consts::PI) * (x.acos() - x * (1.0 - x * x).max(0.0).sqrt())
            }
            Action::RotateDilate { s, .. } => (2.0 * s).exp().min(1.0),
        }
    }

    /// How far any pixel within `radius` of the gaze point may sample from it, pixels.
    pub fn reach(&self, radius: f64) -> f64 {
        match *self {
            Action::Shift { dx, dy } => radius + dx.hypot(dy),
            Action::RotateDilate { s, .. } => radius * (-s).exp(),
        }
    }
}

/// Which actions an experiment uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ActionKinds {
    /// Horizontal and vertical shifts.
    Translation,
    /// Rotations and dilations.
    RotationDilation,
    /// All four (experiment 1 only: its motor fields are one per value, no shared 2D space).
    All,
}

impl std::str::FromStr for ActionKinds {
    type Err = RetinaError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "translation" => Ok(Self::Translation),
            "rotation-dilation" => Ok(Self::RotationDilation),
            "all" => Ok(Self::All),
            _ => Err(RetinaError::Invalid(format!("actions '{s}': use translation, rotation-dilation or all"))),
        }
    }
}

impl ActionKinds {
    /// Name as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Translation => "translation",
            Self::RotationDilation => "rotation-dilation",
            Self::All => "all",
        }
    }
}

/// Largest action magnitudes, relative to the disc radius `r` pixels: shifts up to r / 2
/// pixels, rotations up to 30 degrees, dilations up to e^0.3 (1.35x). At the rim the
/// largest rotation moves a pixel by 0.52 r and the largest dilation by 0.26-0.35 r: the
/// two action sets displace the periphery about equally, so only their geometry differs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ActionRanges {
    /// Largest shift, pixels.
    pub shift_px: f64,
    /// Largest rotation, radians.
    pub rotation_rad: f64,
    /// Largest |log-scale|.
    pub log_scale: f64,
}

impl ActionRanges {
    /// The defaults for a disc of radius `r` pixels.
    pub fn for_radius(r: f64) -> Self {
        Self { shift_px: 0.5 * r, rotation_rad: 30f64.to_radians(), log_scale: 0.3 }
    }

    /// Checks the ranges are finite and positive.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("shift", self.shift_px), ("rotation", self.rotation_rad), ("log-scale", self.log_scale)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(RetinaError::Invalid(format!("largest {name} {v} must be finite and positive")));
            }
        }
        Ok(())
    }

    /// The `count` discrete action values of experiment 1, spread evenly over the kinds:
    /// for two kinds, each axis gets `count / 2` values `+-j max / (count / 4)`, j = 1..;
    /// for all four, each kind gets `m = count / 4` values `(-1)^j (j + 1) max / m`.
    pub fn discrete(&self, kinds: ActionKinds, count: usize) -> Result<Vec<Action>> {
        self.validate()?;
        let per_axis = match kinds {
            ActionKinds::All => 4,
            _ => 2,
        };
        if count == 0
            || !count.is_multiple_of(2 * per_axis) && kinds != ActionKinds::All
            || !count.is_multiple_of(per_axis)
        {
            return Err(RetinaError::Invalid(format!(
                "{count} action values cannot be spread evenly over the {} actions",
                kinds.name()
            )));
        }
        let m = count / per_axis;
        // Signed magnitudes in (0, 1], never the zero action (it would repeat across axes):
        // +-1/h, ..., +-1 for two kinds; 1/m, -2/m, 3/m, ... for all four (m may be odd).
        let signed: Vec<f64> = match kinds {
            ActionKinds::All => {
                (0..m).map(|j| if j % 2 == 0 { 1.0 } else { -1.0 } * (j + 1) as f64 / m as f64).collect()
            }
            _ => {
                let h = m / 2;
                (1..=h).flat_map(|j| [-(j as f64) / h as f64, j as f64 / h as f64]).collect()
            }
        };
        let (t, r, l) = (self.shift_px, self.rotation_rad, self.log_scale);
        let mut out = Vec::with_capacity(count);
        let shift = |out: &mut Vec<Action>| {
            out.extend(signed.iter().map(|&v| Action::Shift { dx: v * t, dy: 0.0 }));
            out.extend(signed.iter().map(|&v| Action::Shift { dx: 0.0, dy: v * t }));
        };
        let rotdil = |out: &mut Vec<Action>| {
            out.extend(signed.iter().map(|&v| Action::RotateDilate { theta: v * r, s: 0.0 }));
            out.extend(signed.iter().map(|&v| Action::RotateDilate { theta: 0.0, s: v * l }));
        };
        match kinds {
            ActionKinds::Translation => shift(&mut out),
            ActionKinds::RotationDilation => rotdil(&mut out),
            ActionKinds::All => {
                shift(&mut out);
                rotdil(&mut out);
            }
        }
        Ok(out)
    }

    /// The motor space's extent [lo, hi] per axis for a 2D action kind.
    pub fn extent(&self, kinds: ActionKinds) -> Result<[[f64; 2]; 2]> {
        self.validate()?;
        match kinds {
            ActionKinds::Translation => Ok([[-self.shift_px, self.shift_px], [-self.shift_px, self.shift_px]]),
            ActionKinds::RotationDilation => {
                Ok([[-self.rotation_rad, self.rotation_rad], [-self.log_scale, self.log_scale]])
            }
            ActionKinds::All => Err(RetinaError::Invalid(
                "a 2D motor space holds translations or rotation + dilation, not all four actions".into(),
            )),
        }
    }

    /// How `count` motor fields tile the 2D motor space of `kinds`: `(nx, ny)` cells along the
    /// first axis (dx or rotation) and the second (dy or log-scale), `nx` the smallest divisor
    /// of `count` not below its square root (60: 10 x 6; 20: 5 x 4).
    pub fn cells(&self, kinds: ActionKinds, count: usize) -> Result<(usize, usize)> {
        self.extent(kinds)?;
        let nx = (1..=count).find(|&d| count.is_multiple_of(d) && d * d >= count).ok_or_else(|| {
            RetinaError::Invalid(format!("{count} motor fields cannot tile the motor space: at least one is needed"))
        })?;
        Ok((nx, count / nx))
    }

    /// An action of a 2D kind inside cell `cell` (row-major over `cells`, see
    /// [`cells`](Self::cells)) of the motor space, at the cell's relative point `u` in
    /// [0, 1)^2.
    pub fn in_cell(&self, kinds: ActionKinds, cells: (usize, usize), cell: usize, u: [f64; 2]) -> Result<Action> {
        let (nx, ny) = cells;
        if nx == 0 || ny == 0 || cell >= nx * ny {
            return Err(RetinaError::Invalid(format!("cell {cell} of a {nx} x {ny} motor grid")));
        }
        let (ix, iy) = (cell % nx, cell / nx);
        self.uniform(kinds, [(ix as f64 + u[0]) / nx as f64, (iy as f64 + u[1]) / ny as f64])
    }

    /// The mean of [`Action::kept_share`] over the actions of a 2D kind drawn uniformly from
    /// the motor space (a 200 x 200 midpoint grid): how much of what the eye sees after an
    /// action it saw before, on average.
    pub fn mean_kept_share(&self, kinds: ActionKinds, radius: f64) -> Result<f64> {
        const N: usize = 200;
        let mut sum = 0.0;
        for j in 0..N {
            for i in 0..N {
                let u = [(i as f64 + 0.5) / N as f64, (j as f64 + 0.5) / N as f64];
                sum += self.uniform(kinds, u)?.kept_share(radius);
            }
        }
        Ok(sum / (N * N) as f64)
    }

    /// A uniform random action of a 2D kind, from two uniforms in [0, 1).
    pub fn uniform(&self, kinds: ActionKinds, u: [f64; 2]) -> Result<Action> {
        let e = self.extent(kinds)?;
        let a = e[0][0] + u[0] * (e[0][1] - e[0][0]);
        let b = e[1][0] + u[1] * (e[1][1] - e[1][0]);
        Ok(match kinds {
            ActionKinds::Translation => Action::Shift { dx: a, dy: b },
            _ => Action::RotateDilate { theta: a, s: b },
        })
    }
}

/// How an action becomes the motor vector q.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum MotorCode {
    /// One cell per listed action value (compared exactly).
    OneHot(Vec<Action>),
    /// An `nx x ny` grid of cells tiling `extent` (row-major, the first axis fastest): q is
    /// one-hot over the cell that holds the action's point (a point on an inner edge belongs
    /// to the cell above it, up to rounding; the outer edges to the cells they close).
    Cells {
        /// Cells along the first motor axis.
        nx: usize,
        /// Cells along the second.
        ny: usize,
        /// [lo, hi] of each motor axis.
        extent: [[f64; 2]; 2],
    },
    /// A `cells x cells` grid spanning `extent`; an action's point spreads bilinearly over
    /// the four nearest cell centres (cell centres at the grid's nodes, edges included).
    Grid {
        /// Cells per axis (>= 2).
        cells: usize,
        /// [lo, hi] of each motor axis.
        extent: [[f64; 2]; 2],
    },
}

impl MotorCode {
    /// Number of motor cells (the length of q).
    pub fn len(&self) -> usize {
        match self {
            MotorCode::OneHot(v) => v.len(),
            MotorCode::Cells { nx, ny, .. } => nx * ny,
            MotorCode::Grid { cells, .. } => cells * cells,
        }
    }

    /// True when there are no cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Writes q for `action` into `q` (length [`len`](Self::len)).
    pub fn encode(&self, action: &Action, q: &mut [f64]) -> Result<()> {
        q.iter_mut().for_each(|v| *v = 0.0);
        match self {
            MotorCode::OneHot(values) => {
                let i = values
                    .iter()
                    .position(|v| v == action)
                    .ok_or_else(|| RetinaError::Invalid(format!("{action:?} is not one of the motor values")))?;
                q[i] = 1.0;
            }
            MotorCode::Cells { nx, ny, extent } => {
                let p = action.motor_point();
                let mut idx = [0usize; 2];
                for (a, n) in [*nx, *ny].into_iter().enumerate() {
                    let [lo, hi] = extent[a];
                    let t = (p[a] - lo) / (hi - lo) * n as f64;
                    if n == 0 || !(t.is_finite() && (-1e-9..=n as f64 + 1e-9).contains(&t)) {
                        return Err(RetinaError::Invalid(format!("{action:?} lies outside the motor space")));
                    }
                    idx[a] = (t.max(0.0).floor() as usize).min(n - 1);
                }
                q[idx[1] * nx + idx[0]] = 1.0;
            }
            MotorCode::Grid { cells, extent } => {
                let n = *cells;
                if n < 2 {
                    return Err(RetinaError::Invalid(format!("a motor grid needs at least 2 cells per axis, not {n}")));
                }
                let p = action.motor_point();
                let mut idx = [(0usize, 0.0f64); 2];
                for a in 0..2 {
                    let [lo, hi] = extent[a];
                    let t = (p[a] - lo) / (hi - lo) * (n - 1) as f64;
                    if !(t.is_finite() && (-1e-9..=(n - 1) as f64 + 1e-9).contains(&t)) {
                        return Err(RetinaError::Invalid(format!("{action:?} lies outside the motor space")));
                    }
                    let t = t.clamp(0.0, (n - 1) as f64);
                    let i = (t.floor() as usize).min(n - 2);
                    idx[a] = (i, t - i as f64);
                }
                let ((ix, fx), (iy, fy)) = (idx[0], idx[1]);
                q[iy * n + ix] += (1.0 - fx) * (1.0 - fy);
                q[iy * n + ix + 1] += fx * (1.0 - fy);
                q[(iy + 1) * n + ix] += (1.0 - fx) * fy;
                q[(iy + 1) * n + ix + 1] += fx * fy;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kept_share_is_what_a_pixel_count_finds() {
        // Independent reference: the share of points on a fine grid over the disc whose source
        // after the action (`map`) lies inside the disc before it.
        let r = 30.0;
        let brute = |a: &Action| {
            let (mut kept, mut all) = (0usize, 0usize);
            let step = r / 150.0;
            for j in -150..=150 {
                for i in -150..=150 {
                    let p = [i as f64 * step, j as f64 * step];
                    if p[0].hypot(p[1]) <= r {
                        all += 1;
                        let q = a.map(p);
                        kept += usize::from(q[0].hypot(q[1]) <= r);
                    }
                }
            }
            kept as f64 / all as f64
        };
        for a in [
            Action::Shift { dx: 0.0, dy: 0.0 },
            Action::Shift { dx: 15.0, dy: 0.0 },
            Action::Shift { dx: -21.0, dy: 21.0 },
            Action::Shift { dx: 0.0, dy: 59.0 },
            Action::Shift { dx: 70.0, dy: 10.0 },
            Action::RotateDilate { theta: 2.5, s: 0.0 },
            Action::RotateDilate { theta: -1.0, s: 0.7 },
            Action::RotateDilate { theta: 0.3, s: -0.5 },
            Action::RotateDilate { theta: 0.0, s: -1.5 },
        ] {
            let (got, want) = (a.kept_share(r), brute(&a));
            assert!((got - want).abs() < 0.01, "{a:?}: {got} vs {want}");
        }
        // Both action sets at experiment 1's default ranges keep about as much on average.
        let d = ActionRanges::for_radius(r);
        let scaled = |k: f64| ActionRanges {
            shift_px: k * d.shift_px,
            rotation_rad: k * d.rotation_rad,
            log_scale: k * d.log_scale,
        };
        let rd = scaled(5.0).mean_kept_share(ActionKinds::RotationDilation, r).unwrap();
        // Half the zooms keep all, the others e^2s: (1 + (1 - e^-3) / 3) / 2.
        assert!((rd - (1.0 + (1.0 - (-3f64).exp()) / 3.0) / 2.0).abs() < 1e-3, "{rd}");
        assert!(scaled(5.0).mean_kept_share(ActionKinds::All, r).is_err());
    }

    #[test]
    fn actions_map_points_as_defined() {
        let a = Action::RotateDilate { theta: std::f64::consts::FRAC_PI_2, s: 2f64.ln() };
        // A quarter turn takes +x to +y; zooming in 2x halves the sampling offset.
        let q = a.map([4.0, 0.0]);
        assert!((q[0]).abs() < 1e-12 && (q[1] - 2.0).abs() < 1e-12);
        assert_eq!(Action::Shift { dx: 1.5, dy: -2.0 }.map([1.0, 1.0]), [2.5, -1.0]);
    }

    #[test]
    fn experiment_one_has_sixty_distinct_values() {
        let r = ActionRanges::for_radius(30.23);
        for kinds in [ActionKinds::Translation, ActionKinds::RotationDilation, ActionKinds::All] {
            let v = r.discrete(kinds, 60).unwrap();
            assert_eq!(v.len(), 60);
            for i in 0..60 {
                for j in 0..i {
                    assert_ne!(v[i], v[j], "{kinds:?} {i} {j}");
                }
            }
        }
        assert!(r.discrete(ActionKinds::Translation, 58).is_err());
    }

    #[test]
    fn cells_tile_the_motor_space_and_code_their_actions() {
        let r = ActionRanges::for_radius(30.23);
        assert_eq!(r.cells(ActionKinds::RotationDilation, 60).unwrap(), (10, 6));
        assert_eq!(r.cells(ActionKinds::Translation, 20).unwrap(), (5, 4));
        assert_eq!(r.cells(ActionKinds::Translation, 7).unwrap(), (7, 1));
        assert!(r.cells(ActionKinds::All, 60).is_err());
        assert!(r.cells(ActionKinds::Translation, 0).is_err());
        let kinds = ActionKinds::RotationDilation;
        let code = MotorCode::Cells { nx: 10, ny: 6, extent: r.extent(kinds).unwrap() };
        let mut q = vec![0.0; code.len()];
        assert_eq!(q.len(), 60);
        for cell in 0..60 {
            for u in [[0.001, 0.001], [0.5, 0.25], [0.999, 0.999]] {
                let a = r.in_cell(kinds, (10, 6), cell, u).unwrap();
                code.encode(&a, &mut q).unwrap();
                assert_eq!(q[cell], 1.0, "cell {cell} at {u:?}");
                assert_eq!(q.iter().sum::<f64>(), 1.0);
            }
        }
        // Cell 13 of 10 x 6 is column 3, row 1: rotation in [-12, -6] degrees, log-scale in
        // [-0.2, -0.1].
        let Action::RotateDilate { theta, s } = r.in_cell(kinds, (10, 6), 13, [0.5, 0.5]).unwrap() else {
            panic!("a rotation-dilation cell gives a rotation-dilation")
        };
        assert!((theta.to_degrees() + 9.0).abs() < 1e-9 && (s + 0.15).abs() < 1e-12);
        // The outer edge belongs to the last cell; beyond it is refused.
        code.encode(&Action::RotateDilate { theta: r.rotation_rad, s: r.log_scale }, &mut q).unwrap();
        assert_eq!(q[59], 1.0);
        assert!(code.encode(&Action::RotateDilate { theta: 1.0, s: 0.0 }, &mut q).is_err());
        assert!(r.in_cell(kinds, (10, 6), 60, [0.0, 0.0]).is_err());
    }

    #[test]
    fn grid_codes_are_bilinear_and_sum_to_one() {
        let code = MotorCode::Grid { cells: 15, extent: [[-1.0, 1.0], [-2.0, 2.0]] };
        let mut q = vec![0.0; 225];
        // A node: all weight on one cell.
        code.encode(&Action::Shift { dx: -1.0, dy: -2.0 }, &mut q).unwrap();
        assert_eq!(q[0], 1.0);
        code.encode(&Action::Shift { dx: 0.03, dy: 1.1 }, &mut q).unwrap();
        assert!((q.iter().sum::<f64>() - 1.0).abs() < 1e-12 && q.iter().filter(|&&v| v > 0.0).count() <= 4);
        // The weighted mean of the cell centres is the point itself.
        let (mut x, mut y) = (0.0, 0.0);
        for (i, w) in q.iter().enumerate() {
            x += w * (-1.0 + 2.0 * (i % 15) as f64 / 14.0);
            y += w * (-2.0 + 4.0 * (i / 15) as f64 / 14.0);
        }
        assert!((x - 0.03).abs() < 1e-12 && (y - 1.1).abs() < 1e-12);
        assert!(code.encode(&Action::Shift { dx: 1.5, dy: 0.0 }, &mut q).is_err());
    }
}
