//! Parallel (rectified) stereo with explicit units (SPEC 5.4).
//!
//! Two identical cameras with parallel optical axes, the right one `baseline` to the right of
//! the left one. A point at depth z is seen at `x_l` and `x_r` (pixels); the disparity
//! `d = x_l - x_r = b f / z`, so `z = b f / d` in the units of the baseline.

use crate::{GeometryError, Result};

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

#[cfg(test)]
mod tests {
    use super::*;

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
