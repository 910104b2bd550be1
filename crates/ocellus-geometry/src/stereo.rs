//! Parallel (rectified) stereo with explicit units (SPEC 5.4).
//!
//! Two identical cameras with parallel optical axes, the right one `baseline` to the right of
//! the left one. A point at depth z is seen at `x_l` and `x_r` (pixels); the disparity
//! `d = x_l - x_r = b f / z`, so `z = b f / d` in the units of the baseline.

use crate::{GeometryError, Result};
use ocellus_image::Plane;

/// Focal length in pixels from the focal length and the pixel pitch, both in millimetres.
pub fn focal_px_from_mm(focal_mm: f64, pixel_pitch_mm: f64) -> Result<f64> {
    if !(focal_mm > 0.0 && pixel_pitch_mm > 0.0 && focal_mm.is_finite() && pixel_pitch_mm.is_finite()) {
        return Err(GeometryError::Invalid(format!("focal {focal_mm} mm, pixel pitch {pixel_pitch_mm} mm")));
    }
    Ok(focal_mm / pixel_pitch_mm)
}

/// A rectified stereo rig.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParallelStereo {
    /// Distance between the optical centres (its unit is the unit of depths).
    pub baseline: f64,
    /// Focal length, pixels.
    pub focal_px: f64,
}

impl ParallelStereo {
    /// Depth of a point with disparity `d` pixels: `b f / d`. Zero disparity is an error
    /// (infinite depth); a negative one too (the point would be behind the rig).
    pub fn depth(&self, disparity_px: f64) -> Result<f64> {
        if disparity_px == 0.0 {
            return Err(GeometryError::InfiniteDepth);
        }
        if !(disparity_px > 0.0 && disparity_px.is_finite()) {
            return Err(GeometryError::Invalid(format!("disparity {disparity_px} px")));
        }
        Ok(self.baseline * self.focal_px / disparity_px)
    }

    /// Disparity in pixels of a point at depth `z`.
    pub fn disparity(&self, depth: f64) -> Result<f64> {
        if !(depth > 0.0 && depth.is_finite()) {
            return Err(GeometryError::Invalid(format!("depth {depth}")));
        }
        Ok(self.baseline * self.focal_px / depth)
    }

    /// The 3D point (left camera frame, units of the baseline) of pixel (x, y) with disparity
    /// d, for a principal point (cx, cy).
    pub fn point(&self, x: f64, y: f64, disparity_px: f64, cx: f64, cy: f64) -> Result<[f64; 3]> {
        let z = self.depth(disparity_px)?;
        Ok([(x - cx) * z / self.focal_px, (y - cy) * z / self.focal_px, z])
    }
}

/// A 3D point of a disparity map: where it is and which left-image pixel it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudPoint {
    /// Position in the left camera frame (x right, y down, z forward), units of the baseline.
    pub xyz: [f32; 3],
    /// The left-image pixel (column, row).
    pub pixel: (usize, usize),
}

/// Depth map and point cloud of a disparity map (pixels, NaN where invalid) of a rectified
/// pair: `Z = b f / (d + doffs)`, with `(x - cx, y - cy) Z / f` across, for the left camera's
/// principal point `(cx, cy)` in pixels (pixel centres at integers). `doffs` is the
/// difference of the two principal points' x (Middlebury's doffs; 0 for a common one).
/// Invalid pixels, and total disparities of zero or less (at or beyond infinity), are NaN in
/// the depth map and absent from the cloud.
pub fn depth_and_points(
    disparity: &Plane<f32>,
    rig: &ParallelStereo,
    principal_point: [f64; 2],
    doffs: f64,
) -> Result<(Plane<f32>, Vec<CloudPoint>)> {
    let [cx, cy] = principal_point;
    if !(cx.is_finite() && cy.is_finite() && doffs.is_finite()) {
        return Err(GeometryError::Invalid(format!("principal point ({cx}, {cy}) and doffs {doffs} must be finite")));
    }
    let (w, h) = disparity.size();
    let mut depth = Plane::from_fn(w, h, |_, _| f32::NAN);
    let mut points = Vec::new();
    for y in 0..h {
        for (x, &d) in disparity.row(y).iter().enumerate() {
            if !d.is_finite() {
                continue;
            }
            if let Ok(p) = rig.point(x as f64, y as f64, d as f64 + doffs, cx, cy) {
                depth.set(x, y, p[2] as f32);
                points.push(CloudPoint { xyz: [p[0] as f32, p[1] as f32, p[2] as f32], pixel: (x, y) });
            }
        }
    }
    Ok((depth, points))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_and_points_of_a_fronto_parallel_plane() {
        // A plane 2 m away seen with f = 500 px, b = 0.1 m: disparity 25 px everywhere but
        // one invalid pixel and one at infinity.
        let rig = ParallelStereo { baseline: 0.1, focal_px: 500.0 };
        let mut d = Plane::from_fn(8, 6, |_, _| 25.0f32);
        d.set(1, 1, f32::NAN);
        d.set(2, 1, -5.0);
        let (depth, pts) = depth_and_points(&d, &rig, [3.0, 2.0], 5.0).unwrap();
        // With doffs 5 the total disparity is 30 px: Z = 0.1 * 500 / 30.
        let z = 0.1 * 500.0 / 30.0;
        assert_eq!(pts.len(), 8 * 6 - 2);
        assert!(depth.get(1, 1).is_nan() && depth.get(2, 1).is_nan());
        assert!((depth.get(5, 4) as f64 - z).abs() < 1e-6);
        // The principal point maps to x = y = 0; a pixel 2 to its right to 2 Z / f.
        let at = |x, y| pts.iter().find(|p| p.pixel == (x, y)).unwrap().xyz;
        assert!(at(3, 2)[0].abs() < 1e-7 && at(3, 2)[1].abs() < 1e-7);
        assert!((at(5, 2)[0] as f64 - 2.0 * z / 500.0).abs() < 1e-6);
        assert!(depth_and_points(&d, &rig, [f64::NAN, 0.0], 0.0).is_err());
    }

    #[test]
    fn seed_exercise_ten_metres() {
        // b = 10 cm, f = 6 mm, 1024 px over 6 mm, d = 10 px -> z = 10.24 m; in centimetres 1024.
        let f = focal_px_from_mm(6.0, 6.0 / 1024.0).unwrap();
        assert!((f - 1024.0).abs() < 1e-9);
        let m = ParallelStereo { baseline: 0.10, focal_px: f };
        assert!((m.depth(10.0).unwrap() - 10.24).abs() < 1e-12);
        let cm = ParallelStereo { baseline: 10.0, focal_px: f };
        assert!((cm.depth(10.0).unwrap() - 1024.0).abs() < 1e-9);
        assert!((m.disparity(10.24).unwrap() - 10.0).abs() < 1e-12);
        assert_eq!(m.depth(0.0), Err(GeometryError::InfiniteDepth));
        assert!(m.depth(-1.0).is_err() && m.depth(f64::NAN).is_err());
        let p = m.point(612.0, 384.0, 10.0, 512.0, 384.0).unwrap();
        assert!((p[0] - 1.0).abs() < 1e-12 && p[1] == 0.0);
    }
}
