//! A sphere seen by a camera: its image circle (through lens distortion) and the ray-sphere
//! intersection a renderer needs. Used by the ball tracker and the ball-world generator.

use crate::camera::PinholeCamera;
use crate::distortion::Distortion;
use nalgebra::Vector3;

/// The image circle `[x, y, r]` (pixels) of a sphere of `radius` centred at `centre` (world
/// coordinates, the camera's length unit), through the lens distortion. `None` when the
/// sphere is not wholly in front of the camera.
///
/// A sphere's silhouette in a pinhole image is an ellipse: the section of the cone of rays
/// tangent to it. With `alpha` the sphere's angular radius (`sin alpha = R / d`, d the
/// distance of its centre from the camera centre) and `theta` the angle of its centre off
/// the optical axis, in units of the focal length the ellipse has the semi-axes
/// `sin alpha cos alpha / D` (radial) and `sin alpha / sqrt(D)` (tangential), with
/// `D = cos^2 theta - sin^2 alpha`, and its centre lies `sin theta cos theta / D` from the
/// principal point, outward of the centre's own projection. The circle returned has the
/// centre and the area of that ellipse mapped through the lens distortion (from the
/// distorted ends of its axes). On the optical axis it
/// is exact: `r = f R / sqrt(d^2 - R^2)`; off it, a circle fitted to a ball's pixels gives its
/// depth without the bias of the centre's projection and the on-axis radius (1.4 % too small
/// 10 degrees off the axis).
pub fn project_sphere(
    camera: &PinholeCamera,
    distortion: &Distortion,
    centre: &Vector3<f64>,
    radius: f64,
) -> Option<[f64; 3]> {
    let xc = camera.r * centre + camera.t;
    let d2 = xc.norm_squared();
    if !(xc.z > radius && d2 > radius * radius && radius > 0.0) {
        return None;
    }
    let d = d2.sqrt();
    let sin_a = radius / d;
    let cos_t = xc.z / d;
    let big_d = cos_t * cos_t - sin_a * sin_a;
    if big_d <= 0.0 {
        // Some tangent ray runs parallel to the image plane: no bounded silhouette.
        return None;
    }
    let cos_a = (1.0 - sin_a * sin_a).sqrt();
    let (semi_radial, semi_tangential) = (sin_a * cos_a / big_d, sin_a / big_d.sqrt());
    // The ellipse's centre, normalized image coordinates: along the centre's own direction.
    let rho = xc.x.hypot(xc.y);
    let (er, rc) = if rho > 0.0 { ([xc.x / rho, xc.y / rho], (rho / d) * cos_t / big_d) } else { ([1.0, 0.0], 0.0) };
    let et = [-er[1], er[0]];
    // The ends of the two axes, through the lens: their mean is the centre and the two
    // conjugate half-diameters they span give the area, to first order in the lens's
    // curvature over the ellipse.
    let k = &camera.k;
    // In normalized coordinates, as the lens model works (no round trip through pixels).
    let end = |a: f64, b: f64| {
        let (xd, yd) = distortion.distort(rc * er[0] + a * er[0] + b * et[0], rc * er[1] + a * er[1] + b * et[1]);
        (k.fx * xd + k.skew * yd + k.cx, k.fy * yd + k.cy)
    };
    let (a0, a1) = (end(semi_radial, 0.0), end(-semi_radial, 0.0));
    let (b0, b1) = (end(0.0, semi_tangential), end(0.0, -semi_tangential));
    let cx = 0.25 * (a0.0 + a1.0 + b0.0 + b1.0);
    let cy = 0.25 * (a0.1 + a1.1 + b0.1 + b1.1);
    let (ux, uy) = (0.5 * (a0.0 - a1.0), 0.5 * (a0.1 - a1.1));
    let (vx, vy) = (0.5 * (b0.0 - b1.0), 0.5 * (b0.1 - b1.1));
    let r = (ux * vy - uy * vx).abs().sqrt();
    (cx.is_finite() && cy.is_finite() && r.is_finite() && r > 0.0).then_some([cx, cy, r])
}

/// The nearest intersection of the ray `origin + s dir` (s > 0, `dir` unit) with the sphere:
/// the distance s, or `None` when the ray misses.
pub fn ray_sphere(origin: &Vector3<f64>, dir: &Vector3<f64>, centre: &Vector3<f64>, radius: f64) -> Option<f64> {
    let oc = origin - centre;
    let b = oc.dot(dir);
    let c = oc.norm_squared() - radius * radius;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let s = -b - disc.sqrt();
    (s > 0.0).then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Intrinsics;
    use nalgebra::{Matrix3, Vector2};

    #[test]
    fn the_circle_is_the_silhouette() {
        // Without distortion, rays through the circle's rim graze the sphere: for a sphere on
        // the optical axis the silhouette is exactly a circle of the stated radius.
        let k = Intrinsics { fx: 600.0, fy: 600.0, cx: 319.5, cy: 239.5, skew: 0.0 };
        let cam = PinholeCamera { k, r: Matrix3::identity(), t: Vector3::zeros() };
        let c = Vector3::new(0.0, 0.0, 2.0);
        let [x, y, r] = project_sphere(&cam, &Distortion::default(), &c, 0.1).unwrap();
        assert!((x - 319.5).abs() < 1e-9 && (y - 239.5).abs() < 1e-9);
        let hit = |px: f64| {
            let (o, d) = cam.back_project(&Vector2::new(px, 239.5));
            ray_sphere(&o, &d, &c, 0.1)
        };
        assert!(hit(319.5 + r - 1e-3).is_some());
        assert!(hit(319.5 + r + 1e-3).is_none());
        // The distance along the axis is d - R.
        assert!((hit(319.5).unwrap() - 1.9).abs() < 1e-12);
        // Off the axis and through a barrel lens: the circle has the area and the centroid
        // of the pixels whose rays hit the sphere (counted on a 1/16 px grid).
        let dist = Distortion { k1: -0.25, k2: 0.08, k3: 0.0, p1: 0.001, p2: -0.0005 };
        for (c, rad) in [(Vector3::new(0.45, -0.3, 1.6), 0.05), (Vector3::new(-0.6, 0.4, 2.0), 0.1)] {
            let [x, y, r] = project_sphere(&cam, &dist, &c, rad).unwrap();
            let (mut n, mut sx, mut sy) = (0.0, 0.0, 0.0);
            let step = 1.0 / 16.0;
            let half = (1.5 * r / step) as i64;
            for j in -half..=half {
                for i in -half..=half {
                    let (u, v) = (x + i as f64 * step, y + j as f64 * step);
                    let (uu, vu) = dist.undistort_pixel(&k, u, v).unwrap();
                    let (o, d) = cam.back_project(&Vector2::new(uu, vu));
                    if ray_sphere(&o, &d, &c, rad).is_some() {
                        n += 1.0;
                        sx += u;
                        sy += v;
                    }
                }
            }
            let area_r = (n * step * step / std::f64::consts::PI).sqrt();
            assert!((area_r - r).abs() < 1e-3 * r, "radius {r} vs the silhouette's {area_r}");
            // The lens bends the ellipse a little, so its centroid moves by a fraction of a
            // pixel from the distorted centre (second order in the circle's size).
            let off = (sx / n - x).hypot(sy / n - y);
            assert!(off < 0.005 * r, "({x}, {y}) vs ({}, {}), r {r}", sx / n, sy / n);
            // The on-axis radius at the centre's projection, the old approximation, is off.
            let on_axis = k.fx * rad / (c.norm_squared() - rad * rad).sqrt();
            assert!((on_axis - area_r).abs() > 0.01 * r);
        }
        // Behind the camera or straddling it: no circle.
        assert!(project_sphere(&cam, &Distortion::default(), &Vector3::new(0.0, 0.0, 0.05), 0.1).is_none());
    }
}
