//! Views of a printed chessboard through a known, distorted camera: ground truth for
//! corner detection and planar calibration.
//!
//! Each output pixel averages `supersample x supersample` samples (an area-integrating sensor,
//! so edges are anti-aliased the way a real camera's are). A sample's pixel position is
//! undistorted (through a per-pixel table of the inverse distortion, interpolated bilinearly
//! between pixel centres), turned into a ray, intersected with the board plane, and shaded:
//! black squares 0.1, white squares and the white margin 0.9, the background image elsewhere.
//! Grey values are in [0, 1]; noise sigma is given in 8-bit grey levels.

use crate::{Result, SynthError};
use nalgebra::{Rotation3, Vector3};
use ocellus_geometry::camera::Intrinsics;
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::zhang::{project_view, Pose};
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;

/// A chessboard: `cols` x `rows` inner corners, so (cols + 1) x (rows + 1) squares, on a white
/// sheet. Board coordinates: the first inner corner at (0, 0), x along a row, y down the
/// columns, z = 0 on the board, in the units of `square`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Board {
    /// Inner corners per row.
    pub cols: usize,
    /// Inner corners per column.
    pub rows: usize,
    /// Square side, board units (e.g. millimetres).
    pub square: f64,
    /// White margin around the outer squares, board units.
    pub margin: f64,
}

impl Board {
    /// A board with a margin of one square; errors for fewer than 2x2 inner corners or a
    /// non-positive square.
    pub fn new(cols: usize, rows: usize, square: f64) -> Result<Self> {
        if cols < 2 || rows < 2 || square.is_nan() || square <= 0.0 || !square.is_finite() {
            return Err(SynthError::InvalidConfig(format!("board {cols}x{rows} inner corners, square {square}")));
        }
        Ok(Self { cols, rows, square, margin: square })
    }

    /// Inner corners in board units, row by row.
    pub fn inner_corners(&self) -> Vec<[f64; 2]> {
        (0..self.rows)
            .flat_map(|r| (0..self.cols).map(move |c| [c as f64 * self.square, r as f64 * self.square]))
            .collect()
    }

    /// The sheet's outline (outer corners of the margin), board units.
    pub fn outline(&self) -> [[f64; 2]; 4] {
        let (x0, y0) = (-self.square - self.margin, -self.square - self.margin);
        let (x1, y1) = (self.cols as f64 * self.square + self.margin, self.rows as f64 * self.square + self.margin);
        [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }

    /// Grey value at a board point, `None` off the sheet.
    fn shade(&self, x: f64, y: f64) -> Option<f32> {
        let [[x0, y0], _, [x1, y1], _] = self.outline();
        if !(x >= x0 && x <= x1 && y >= y0 && y <= y1) {
            return None;
        }
        let (i, j) = ((x / self.square).floor() + 1.0, (y / self.square).floor() + 1.0);
        let on_squares = i >= 0.0 && j >= 0.0 && i <= self.cols as f64 && j <= self.rows as f64;
        let black = on_squares && (i as i64 + j as i64) % 2 == 0;
        Some(if black { 0.1 } else { 0.9 })
    }
}

/// A camera that renders boards: intrinsics, distortion, image size, and the undistortion
/// table built once.
#[derive(Clone, Debug)]
pub struct BoardCamera {
    /// Intrinsics, pixels.
    pub intrinsics: Intrinsics,
    /// Lens distortion.
    pub distortion: Distortion,
    width: usize,
    height: usize,
    /// Undistorted normalized coordinates at pixel centres -1..=width, -1..=height.
    table: Vec<[f64; 2]>,
}

impl BoardCamera {
    /// Builds the camera; an error if the distortion cannot be inverted inside the image.
    pub fn new(intrinsics: Intrinsics, distortion: Distortion, width: usize, height: usize) -> Result<Self> {
        if width == 0 || height == 0 || width > 1 << 14 || height > 1 << 14 {
            return Err(SynthError::InvalidConfig(format!("image size {width}x{height}")));
        }
        let (tw, th) = (width + 2, height + 2);
        let mut table = Vec::with_capacity(tw * th);
        for y in 0..th {
            for x in 0..tw {
                let (u, v) = distortion
                    .undistort_pixel(&intrinsics, x as f64 - 1.0, y as f64 - 1.0)
                    .map_err(|e| SynthError::InvalidConfig(format!("distortion at pixel ({x}, {y}): {e}")))?;
                let yn = (v - intrinsics.cy) / intrinsics.fy;
                table.push([(u - intrinsics.cx - intrinsics.skew * yn) / intrinsics.fx, yn]);
            }
        }
        Ok(Self { intrinsics, distortion, width, height, table })
    }

    /// Image size (width, height), pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    fn ray(&self, x: f64, y: f64) -> [f64; 2] {
        let tw = self.width + 2;
        let (gx, gy) = ((x + 1.0).clamp(0.0, self.width as f64), (y + 1.0).clamp(0.0, self.height as f64));
        let (x0, y0) = (gx.floor() as usize, gy.floor() as usize);
        let (ax, ay) = (gx - x0 as f64, gy - y0 as f64);
        let at = |xx: usize, yy: usize| self.table[yy * tw + xx];
        let (a, b, c, d) = (at(x0, y0), at(x0 + 1, y0), at(x0, y0 + 1), at(x0 + 1, y0 + 1));
        std::array::from_fn(|k| {
            let top = a[k] + ax * (b[k] - a[k]);
            let bot = c[k] + ax * (d[k] - c[k]);
            top + ay * (bot - top)
        })
    }

    /// True pixel positions of the board's inner corners (row by row), `None` if one is
    /// behind the camera.
    pub fn corners(&self, board: &Board, pose: &Pose) -> Option<Vec<[f64; 2]>> {
        project_view(&self.intrinsics, &self.distortion, pose, &board.inner_corners())
    }

    /// Renders one view; `background` (same size, grey in [0, 1]) shows around the sheet, mid
    /// grey when absent; `noise_sigma` in 8-bit grey levels, seeded.
    pub fn render(
        &self,
        board: &Board,
        pose: &Pose,
        background: Option<&Plane<f32>>,
        supersample: usize,
        noise_sigma: f32,
        seed: u64,
    ) -> Result<Plane<f32>> {
        if let Some(b) = background {
            ocellus_image::check::same_size("background (against the camera)", b.size(), (self.width, self.height))?;
        }
        if !(1..=16).contains(&supersample) {
            return Err(SynthError::InvalidConfig(format!("supersample {supersample} must be 1..=16")));
        }
        let r = pose.r;
        let n = r.column(2).into_owned();
        let nt = n.dot(&pose.t);
        let s = supersample;
        let inv = 1.0 / (s * s) as f32;
        let mut rng = SplitMix64::new(seed);
        let mut out = Plane::new(self.width, self.height);
        for y in 0..self.height {
            for x in 0..self.width {
                let bg = background.map_or(0.5, |b| b.get(x, y));
                let mut acc = 0.0;
                for sy in 0..s {
                    for sx in 0..s {
                        let px = x as f64 + (sx as f64 + 0.5) / s as f64 - 0.5;
                        let py = y as f64 + (sy as f64 + 0.5) / s as f64 - 0.5;
                        let [xn, yn] = self.ray(px, py);
                        let ray = Vector3::new(xn, yn, 1.0);
                        let den = n.dot(&ray);
                        let lambda = if den != 0.0 { nt / den } else { -1.0 };
                        let v = if lambda > 0.0 {
                            let pb = r.transpose() * (ray * lambda - pose.t);
                            board.shade(pb.x, pb.y).unwrap_or(bg)
                        } else {
                            bg
                        };
                        acc += v;
                    }
                }
                let noise = if noise_sigma > 0.0 { noise_sigma / 255.0 * rng.normal() as f32 } else { 0.0 };
                out.set(x, y, (acc * inv + noise).clamp(0.0, 1.0));
            }
        }
        Ok(out)
    }

    /// A random pose that shows the whole sheet: tilted by up to `max_tilt_rad` about a
    /// random axis in the board plane, turned in-plane by up to 30 degrees, filling 35-75 % of
    /// the image width, somewhere in the image. An error after 10,000 failed draws.
    pub fn random_pose(&self, board: &Board, max_tilt_rad: f64, rng: &mut SplitMix64) -> Result<Pose> {
        let [a, _, c, _] = board.outline();
        let centre = Vector3::new(0.5 * (a[0] + c[0]), 0.5 * (a[1] + c[1]), 0.0);
        let sheet_w = c[0] - a[0];
        for _ in 0..10_000 {
            let axis_angle = rng.unit() * std::f64::consts::TAU;
            let tilt = max_tilt_rad * rng.unit();
            let axis = Vector3::new(axis_angle.cos(), axis_angle.sin(), 0.0);
            let spin = Rotation3::from_axis_angle(&Vector3::z_axis(), (rng.unit() - 0.5) * 60f64.to_radians());
            let r = Rotation3::new(axis * tilt) * spin;
            let frac = 0.35 + 0.4 * rng.unit();
            let z = sheet_w * self.intrinsics.fx / (frac * self.width as f64);
            let offset = Vector3::new(
                (rng.unit() - 0.5) * (1.0 - frac) * self.width as f64 / self.intrinsics.fx * z,
                (rng.unit() - 0.5) * 0.5 * self.height as f64 / self.intrinsics.fy * z,
                z,
            );
            let pose = Pose { r: *r.matrix(), t: offset - r * centre };
            let Some(outline) = project_view(&self.intrinsics, &self.distortion, &pose, &board.outline()) else {
                continue;
            };
            let inside = outline.iter().all(|p| {
                p[0] >= 2.0 && p[1] >= 2.0 && p[0] <= self.width as f64 - 3.0 && p[1] <= self.height as f64 - 3.0
            });
            if inside {
                return Ok(pose);
            }
        }
        Err(SynthError::InvalidConfig("no pose shows the whole board: the board is too large for the view".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_lie_on_rendered_x_junctions() {
        // The four squares around each true corner, sampled a third of a square inside
        // along the board's diagonals, must alternate black and white.
        let k = Intrinsics { fx: 700.0, fy: 700.0, cx: 319.5, cy: 239.5, skew: 0.0 };
        let d = Distortion { k1: -0.2, k2: 0.05, ..Default::default() };
        let cam = BoardCamera::new(k, d, 640, 480).unwrap();
        let board = Board::new(9, 6, 25.0).unwrap();
        let pose = cam.random_pose(&board, 0.5, &mut SplitMix64::new(3)).unwrap();
        let img = cam.render(&board, &pose, None, 4, 0.0, 0).unwrap();
        let q = board.square / 3.0;
        for (i, c) in board.inner_corners().iter().enumerate() {
            let quads = [[c[0] - q, c[1] - q], [c[0] + q, c[1] - q], [c[0] + q, c[1] + q], [c[0] - q, c[1] + q]];
            let px = project_view(&k, &d, &pose, &quads).unwrap();
            let v: Vec<f32> = px.iter().map(|p| img.get(p[0].round() as usize, p[1].round() as usize)).collect();
            // Square (i, j) is black when i + j is even, counting from the top-left square.
            let (ci, cj) = (i % board.cols, i / board.cols);
            let top_left_black = (ci + cj) % 2 == 0;
            let want = if top_left_black { [0.1, 0.9, 0.1, 0.9] } else { [0.9, 0.1, 0.9, 0.1] };
            for (got, want) in v.iter().zip(want) {
                assert!((got - want).abs() < 0.05, "corner {i}: {v:?}");
            }
        }
    }
}
