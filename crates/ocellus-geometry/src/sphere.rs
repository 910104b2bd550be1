//! A sphere seen by a camera: its image circle (through lens distortion) and the ray-sphere
//! intersection a renderer needs. Used by the ball tracker and the ball-world generator.

use crate::camera::PinholeCamera;
use crate::distortion::Distortion;
use nalgebra::Vector3;

/// The image circle `[x, y, r]` (pixels) of a sphere of `radius` centred at `centre` (world
/// coordinates, the camera's length unit): the centre's pixel and the radius
/// `f R / sqrt(d^2 - R^2)` (the sphere's angular radius, d its distance from the camera
/// centre, f the horizontal focal length), both through the lens distortion, the radius
/// measured along x. `None` when the sphere is not wholly in front of the camera.
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
    let (px, _) = camera.project(centre).ok()?;
    let r_px = camera.k.fx * radius / (d2 - radius * radius).sqrt();
    let (cx, cy) = distortion.distort_pixel(&camera.k, px.x, px.y);
    let (ex, ey) = distortion.distort_pixel(&camera.k, px.x + r_px, px.y);
    let r = (ex - cx).hypot(ey - cy);
    (cx.is_finite() && cy.is_finite() && r.is_finite()).then_some([cx, cy, r])
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
        // Behind the camera or straddling it: no circle.
        assert!(project_sphere(&cam, &Distortion::default(), &Vector3::new(0.0, 0.0, 0.05), 0.1).is_none());
    }
}
