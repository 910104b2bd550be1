//! The pinhole camera (SPEC 5.1): intrinsics, pose, the 3x4 projection matrix.

use crate::{GeometryError, Result};
use nalgebra::{Matrix3, Matrix3x4, Vector2, Vector3, Vector4};
use serde::{Deserialize, Serialize};

/// Intrinsic parameters in pixels: focal lengths `f kx`, `f ky`, principal point, skew.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Intrinsics {
    /// Focal length times horizontal pixels per unit length, pixels.
    pub fx: f64,
    /// Focal length times vertical pixels per unit length, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Skew (0 for rectangular pixels).
    pub skew: f64,
}

impl Intrinsics {
    /// From a focal length and pixel pitch in millimetres (square pixels, no skew).
    pub fn from_mm(focal_mm: f64, pixel_mm: f64, cx: f64, cy: f64) -> Result<Self> {
        if !(focal_mm > 0.0 && pixel_mm > 0.0 && focal_mm.is_finite() && pixel_mm.is_finite()) {
            return Err(GeometryError::Invalid(format!("focal {focal_mm} mm, pixel {pixel_mm} mm")));
        }
        let f = focal_mm / pixel_mm;
        Ok(Self { fx: f, fy: f, cx, cy, skew: 0.0 })
    }

    /// Square pixels of focal length `focal_px`, no skew, the principal point at the centre
    /// of a `width` x `height` image (pixel centres at integers: ((w - 1) / 2, (h - 1) / 2)).
    pub fn centred(focal_px: f64, width: usize, height: usize) -> Self {
        Self { fx: focal_px, fy: focal_px, cx: (width as f64 - 1.0) / 2.0, cy: (height as f64 - 1.0) / 2.0, skew: 0.0 }
    }

    /// The calibration matrix K.
    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::new(self.fx, self.skew, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0)
    }

    /// From an upper-triangular K (normalized so that K[2][2] = 1).
    pub fn from_matrix(k: &Matrix3<f64>) -> Result<Self> {
        let s = k[(2, 2)];
        if s == 0.0 || !s.is_finite() {
            return Err(GeometryError::Degenerate("K[2][2] is zero".into()));
        }
        Ok(Self { fx: k[(0, 0)] / s, fy: k[(1, 1)] / s, cx: k[(0, 2)] / s, cy: k[(1, 2)] / s, skew: k[(0, 1)] / s })
    }
}

/// A calibrated camera: `x ~ K [R | t] X`, pose from world to camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    /// Intrinsics.
    pub k: Intrinsics,
    /// Rotation world -> camera (proper, det = +1).
    pub r: Matrix3<f64>,
    /// Translation world -> camera.
    pub t: Vector3<f64>,
}

impl PinholeCamera {
    /// The 3x4 projection matrix `K [R | t]`.
    pub fn projection_matrix(&self) -> Matrix3x4<f64> {
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.r);
        rt.set_column(3, &self.t);
        self.k.matrix() * rt
    }

    /// The camera centre in world coordinates, `-R^T t`.
    pub fn centre(&self) -> Vector3<f64> {
        -self.r.transpose() * self.t
    }

    /// Pixel of world point `x` and its depth along the optical axis; an error for points
    /// behind the camera (depth <= 0).
    pub fn project(&self, x: &Vector3<f64>) -> Result<(Vector2<f64>, f64)> {
        let xc = self.r * x + self.t;
        if xc.z <= 0.0 || xc.z.is_nan() {
            return Err(GeometryError::BehindCamera { depth: xc.z });
        }
        let k = &self.k;
        let (u, v) = (xc.x / xc.z, xc.y / xc.z);
        Ok((Vector2::new(k.fx * u + k.skew * v + k.cx, k.fy * v + k.cy), xc.z))
    }

    /// The ray through a pixel: (camera centre, unit direction) in world coordinates.
    pub fn back_project(&self, px: &Vector2<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let k = &self.k;
        let v = (px.y - k.cy) / k.fy;
        let u = (px.x - k.cx - k.skew * v) / k.fx;
        let d = self.r.transpose() * Vector3::new(u, v, 1.0);
        (self.centre(), d.normalize())
    }
}

/// `(x, y) -> (x, y, 1)`.
pub fn to_homogeneous(p: &Vector3<f64>) -> Vector4<f64> {
    Vector4::new(p.x, p.y, p.z, 1.0)
}

/// `(x, y, z, w) -> (x/w, y/w, z/w)`; an error for a point at infinity (w = 0).
pub fn from_homogeneous(p: &Vector4<f64>) -> Result<Vector3<f64>> {
    if p.w == 0.0 || !p.w.is_finite() {
        return Err(GeometryError::Degenerate("homogeneous point at infinity (w = 0)".into()));
    }
    Ok(Vector3::new(p.x / p.w, p.y / p.w, p.z / p.w))
}

/// Thin-lens equation `1/Z' + 1/Z = 1/f`: the image distance Z' of an object at distance Z
/// (same units). An object at the focal distance images at infinity: an error.
pub fn thin_lens_image_distance(focal: f64, object_distance: f64) -> Result<f64> {
    if !(focal > 0.0 && object_distance > 0.0) {
        return Err(GeometryError::Invalid(format!("focal {focal}, object distance {object_distance}")));
    }
    let inv = 1.0 / focal - 1.0 / object_distance;
    if inv.abs() < 1e-15 / focal {
        return Err(GeometryError::Degenerate("object at the focal distance images at infinity".into()));
    }
    Ok(1.0 / inv)
}

/// Size in the image plane of an object of size `s` at distance `z` through focal length `f`
/// (pinhole similar triangles, same units): `f s / z`.
pub fn image_size(focal: f64, size: f64, distance: f64) -> Result<f64> {
    if !(distance > 0.0 && focal > 0.0) {
        return Err(GeometryError::Invalid(format!("focal {focal}, distance {distance}")));
    }
    Ok(focal * size / distance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn camera() -> PinholeCamera {
        let r = *Rotation3::from_euler_angles(0.1, -0.2, 0.05).matrix();
        PinholeCamera {
            k: Intrinsics { fx: 800.0, fy: 780.0, cx: 320.0, cy: 240.0, skew: 0.5 },
            r,
            t: Vector3::new(0.1, -0.2, 3.0),
        }
    }

    #[test]
    fn seed_exercise_disc_at_two_metres() {
        // A 50 cm radius disc at 2 m through f = 4 mm images with a 1 mm radius.
        assert!((image_size(4.0, 500.0, 2000.0).unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn projection_matrix_project_and_back_project_agree() {
        let c = camera();
        let p = c.projection_matrix();
        let x = Vector3::new(0.3, -0.1, 1.5);
        let (px, depth) = c.project(&x).unwrap();
        let h = p * to_homogeneous(&x);
        assert!((h.x / h.z - px.x).abs() < 1e-9 && (h.y / h.z - px.y).abs() < 1e-9 && (h.z - depth).abs() < 1e-12);
        let (o, d) = c.back_project(&px);
        let along = (x - o).normalize();
        assert!((along - d).norm() < 1e-12);
        let behind = c.centre() - c.r.transpose() * Vector3::new(0.0, 0.0, 1.0);
        assert!(matches!(c.project(&behind), Err(GeometryError::BehindCamera { .. })));
    }

    #[test]
    fn thin_lens_and_homogeneous() {
        // f = 50 mm, object at 1 m: image at 1/(1/50 - 1/1000) = 52.63 mm.
        assert!((thin_lens_image_distance(50.0, 1000.0).unwrap() - 1000.0 / 19.0).abs() < 1e-9);
        assert!(thin_lens_image_distance(50.0, 50.0).is_err());
        assert!(from_homogeneous(&Vector4::new(1.0, 2.0, 3.0, 0.0)).is_err());
        assert_eq!(from_homogeneous(&Vector4::new(2.0, 4.0, 6.0, 2.0)).unwrap(), Vector3::new(1.0, 2.0, 3.0));
        let k = Intrinsics::from_mm(6.0, 6.0 / 1024.0, 512.0, 384.0).unwrap();
        assert!((k.fx - 1024.0).abs() < 1e-9);
        assert_eq!(Intrinsics::from_matrix(&(k.matrix() * 2.0)).unwrap(), k);
    }
}
