//! Radial-tangential lens distortion (Brown-Conrady, as OpenCV and Zhang 2000 use it).
//!
//! On normalized image coordinates (x, y) = ((u - cx) / fx, (v - cy) / fy) with r^2 = x^2 + y^2:
//! `x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)`,
//! `y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y`.
//! Undistortion inverts this by fixed-point iteration, with a convergence check.

use crate::camera::Intrinsics;
use crate::{GeometryError, Result};
use serde::{Deserialize, Serialize};

/// Distortion coefficients (dimensionless, on normalized coordinates).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Distortion {
    /// Radial r^2 coefficient.
    pub k1: f64,
    /// Radial r^4 coefficient.
    pub k2: f64,
    /// Radial r^6 coefficient.
    pub k3: f64,
    /// Tangential coefficient p1.
    pub p1: f64,
    /// Tangential coefficient p2.
    pub p2: f64,
}

/// Iterations allowed to [`Distortion::undistort`].
const MAX_ITERATIONS: usize = 100;

impl Distortion {
    /// Distorts normalized coordinates.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        (
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// Undistorts normalized coordinates: the (x, y) with `distort(x, y) = (xd, yd)`, to
    /// 1e-12; an error if the iteration does not converge (distortion too strong there).
    pub fn undistort(&self, xd: f64, yd: f64) -> Result<(f64, f64)> {
        if !(xd.is_finite() && yd.is_finite()) {
            return Err(GeometryError::NonFinite { what: "distorted point", index: 0 });
        }
        let (mut x, mut y) = (xd, yd);
        let mut residual = f64::INFINITY;
        for _ in 0..MAX_ITERATIONS {
            let (dx, dy) = self.distort(x, y);
            let (ex, ey) = (dx - xd, dy - yd);
            residual = (ex * ex + ey * ey).sqrt();
            if residual < 1e-12 {
                return Ok((x, y));
            }
            if !residual.is_finite() {
                break;
            }
            x -= ex;
            y -= ey;
        }
        Err(GeometryError::NoConvergence { what: "undistortion", iterations: MAX_ITERATIONS, residual })
    }

    /// Distorts a pixel of an ideal pinhole camera `k`.
    pub fn distort_pixel(&self, k: &Intrinsics, u: f64, v: f64) -> (f64, f64) {
        let y = (v - k.cy) / k.fy;
        let x = (u - k.cx - k.skew * y) / k.fx;
        let (xd, yd) = self.distort(x, y);
        (k.fx * xd + k.skew * yd + k.cx, k.fy * yd + k.cy)
    }

    /// Undistorts a pixel of camera `k`.
    pub fn undistort_pixel(&self, k: &Intrinsics, u: f64, v: f64) -> Result<(f64, f64)> {
        let yd = (v - k.cy) / k.fy;
        let xd = (u - k.cx - k.skew * yd) / k.fx;
        let (x, y) = self.undistort(xd, yd)?;
        Ok((k.fx * x + k.skew * y + k.cx, k.fy * y + k.cy))
    }
}

/// Remap tables that undistort whole images: for each pixel (x, y) of the undistorted image of
/// camera `k`, the position `(map_x, map_y)` in the distorted image to sample (bilinear). Built
/// once per camera; applying it is one pass over the image ([`remap_bilinear`]).
pub fn undistort_maps(
    k: &Intrinsics,
    d: &Distortion,
    width: usize,
    height: usize,
) -> (ocellus_image::Plane<f32>, ocellus_image::Plane<f32>) {
    let mut mx = ocellus_image::Plane::new(width, height);
    let mut my = ocellus_image::Plane::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let (u, v) = d.distort_pixel(k, x as f64, y as f64);
            mx.set(x, y, u as f32);
            my.set(x, y, v as f32);
        }
    }
    (mx, my)
}

/// Samples `src` at the positions of the maps (bilinear; outside the image gives `fill`).
pub fn remap_bilinear(
    src: &ocellus_image::Plane<f32>,
    map_x: &ocellus_image::Plane<f32>,
    map_y: &ocellus_image::Plane<f32>,
    fill: f32,
) -> Result<ocellus_image::Plane<f32>> {
    ocellus_image::check::same_size("remap table y (against x)", map_y.size(), map_x.size())?;
    let (w, h) = (src.width() as f32, src.height() as f32);
    Ok(ocellus_image::Plane::from_fn(map_x.width(), map_x.height(), |x, y| {
        let (u, v) = (map_x.get(x, y), map_y.get(x, y));
        if !(u >= 0.0 && v >= 0.0 && u <= w - 1.0 && v <= h - 1.0) {
            return fill;
        }
        ocellus_image::resample::sample_bilinear(src, u, v)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undistort_inverts_distort() {
        let d = Distortion { k1: -0.28, k2: 0.07, k3: -0.002, p1: 0.001, p2: -0.0005 };
        let k = Intrinsics { fx: 820.0, fy: 815.0, cx: 330.0, cy: 245.0, skew: 0.0 };
        for &(u, v) in &[(0.0, 0.0), (639.0, 479.0), (330.0, 245.0), (100.0, 400.0)] {
            let (ud, vd) = d.distort_pixel(&k, u, v);
            let (uu, vu) = d.undistort_pixel(&k, ud, vd).unwrap();
            assert!((uu - u).abs() < 1e-6 && (vu - v).abs() < 1e-6, "({u}, {v}) -> ({uu}, {vu})");
        }
        assert_eq!(Distortion::default().distort(0.3, -0.2), (0.3, -0.2));
    }

    #[test]
    fn remap_undoes_a_rendered_distortion() {
        // Render a smooth image through the distortion (each distorted pixel samples the ideal
        // image at its undistorted position), then undistort it with the tables.
        let k = Intrinsics { fx: 200.0, fy: 200.0, cx: 79.5, cy: 59.5, skew: 0.0 };
        let d = Distortion { k1: -0.2, k2: 0.05, ..Default::default() };
        let ideal = |x: f64, y: f64| ((x * 0.11).sin() + (y * 0.07).cos()) as f32;
        let distorted = ocellus_image::Plane::from_fn(160, 120, |x, y| {
            let (u, v) = d.undistort_pixel(&k, x as f64, y as f64).unwrap();
            ideal(u, v)
        });
        let (mx, my) = undistort_maps(&k, &d, 160, 120);
        let back = remap_bilinear(&distorted, &mx, &my, f32::NAN).unwrap();
        let mut worst = 0.0f32;
        for y in 10..110 {
            for x in 10..150 {
                let e = back.get(x, y);
                if e.is_finite() {
                    worst = worst.max((e - ideal(x as f64, y as f64)).abs());
                }
            }
        }
        assert!(worst < 0.01, "worst error {worst}");
    }

    #[test]
    fn hopeless_distortion_is_reported() {
        let d = Distortion { k1: -5.0, ..Default::default() };
        assert!(matches!(d.undistort(3.0, 3.0), Err(GeometryError::NoConvergence { .. })));
        assert!(d.undistort(f64::NAN, 0.0).is_err());
    }
}
