//! The ball world seen by a moving camera (SPEC 3.4, 7): the eyes of an active stereo head.
//!
//! The world of [`BallWorld`] with its background photo on a plane at [`BACKGROUND_DEPTH_M`]
//! in front of the reference camera, sized so that the reference camera sees exactly the
//! photo; any other pinhole camera (no lens distortion: the eyes are ideal pinholes) sees that
//! plane (the photo's border pixels continue beyond it) and the ball, ray-traced with 2x2
//! samples and Lambert shading, plus the world's lighting change and sensor noise. Occluders
//! and the distractor of the reference view are not part of these views.

use crate::ball_world::{circle_box, lambert, BallWorld, SUBSAMPLES};
use crate::{Result, SynthError};
use nalgebra::{Vector2, Vector3};
use ocellus_geometry::camera::PinholeCamera;
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::sphere::{project_sphere, ray_sphere};
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;

/// Distance of the background plane from the reference camera, metres.
pub const BACKGROUND_DEPTH_M: f64 = 8.0;

/// Frame `k` of `world` seen by `camera` (world to camera) at `width` x `height`; `seed`
/// chooses this view's noise.
pub fn render_view(
    world: &BallWorld,
    k: usize,
    camera: &PinholeCamera,
    width: usize,
    height: usize,
    seed: u64,
) -> Result<Plane<[u8; 3]>> {
    let len = world.len();
    let (pos, _) = world.state(k).ok_or(SynthError::NoSuchFrame { index: k, len })?;
    if !(1..=8192).contains(&width) || !(1..=8192).contains(&height) {
        return Err(SynthError::InvalidConfig(format!("view size {width}x{height} is outside 1..=8192 per side")));
    }
    let cfg = world.config();
    let bg = world.background();
    let reference = world.camera().k;
    let (bw, bh) = bg.size();
    // The background pixel a world point on the plane falls on in the reference view.
    let bg_at = |p: &Vector3<f64>| -> [f32; 3] {
        let u = reference.fx * p.x / BACKGROUND_DEPTH_M + reference.cx;
        let v = reference.fy * p.y / BACKGROUND_DEPTH_M + reference.cy;
        let (u, v) = (u.round().clamp(0.0, bw as f64 - 1.0) as usize, v.round().clamp(0.0, bh as f64 - 1.0) as usize);
        bg.get(u, v)
    };
    let ball = Vector3::from(pos);
    let r = cfg.radius_m;
    let colour = cfg.colour.map(f32::from);
    let centre = camera.centre();
    let ray = |x: f64, y: f64| camera.back_project(&Vector2::new(x, y)).1;
    let mut img: Plane<[f32; 3]> = Plane::from_fn(width, height, |x, y| {
        let d = ray(x as f64, y as f64);
        if d.z <= 1e-9 {
            return bg.get(bw / 2, bh / 2);
        }
        let s = (BACKGROUND_DEPTH_M - centre.z) / d.z;
        bg_at(&(centre + s * d))
    });
    if let Some(circle) = project_sphere(camera, &Distortion::default(), &ball, r) {
        let (xs, ys) = circle_box(circle, 2.0, width, height);
        for y in ys {
            for x in xs.clone() {
                let mut acc = [0.0f32; 3];
                let mut hits = 0;
                for (sx, sy) in SUBSAMPLES {
                    let d = ray(x as f64 + sx, y as f64 + sy);
                    if let Some(t) = ray_sphere(&centre, &d, &ball, r) {
                        let c = lambert(&ball, &(centre + t * d), r, colour);
                        (0..3).for_each(|i| acc[i] += c[i]);
                        hits += 1;
                    }
                }
                if hits > 0 {
                    let b = img.get(x, y);
                    let a = hits as f32 / 4.0;
                    img.set(x, y, std::array::from_fn(|i| acc[i] / 4.0 + (1.0 - a) * b[i]));
                }
            }
        }
    }
    let gain = world.gain(k);
    let mut noise = SplitMix64::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k as u64);
    let sigma = cfg.noise_sigma;
    Ok(Plane::from_fn(width, height, |x, y| {
        let p = img.get(x, y);
        std::array::from_fn(|i| {
            let n = if sigma > 0.0 { sigma * noise.normal() } else { 0.0 };
            (p[i] as f64 * gain[i] as f64 + n).round().clamp(0.0, 255.0) as u8
        })
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ball_world::{BallWorldConfig, Trajectory};
    use nalgebra::Matrix3;
    use ocellus_geometry::camera::Intrinsics;

    #[test]
    fn a_turned_camera_sees_the_ball_where_it_projects() {
        let load =
            |n: &str| ocellus_io::read_image(ocellus_testdata::data_file(n)).unwrap().to_u8().map(|p| p.map(f32::from));
        let cfg = BallWorldConfig { noise_sigma: 0.0, ..BallWorldConfig::new(Trajectory::Approach, 3) };
        let world = BallWorld::new(cfg, &load("rocket.jpg"), &load("gravel.png")).unwrap();
        let (p, _) = world.state(10).unwrap();
        // A camera 3 cm to the left, turned 5 degrees right.
        let a = 5f64.to_radians();
        let rot = Matrix3::new(a.cos(), 0.0, a.sin(), 0.0, 1.0, 0.0, -a.sin(), 0.0, a.cos());
        let c = Vector3::new(-0.03, 0.0, 0.0);
        let k = Intrinsics { fx: 300.0, fy: 300.0, cx: 159.5, cy: 119.5, skew: 0.0 };
        let cam = PinholeCamera { k, r: rot.transpose(), t: -(rot.transpose() * c) };
        let img = render_view(&world, 10, &cam, 320, 240, 1).unwrap();
        let [x, y, r] = project_sphere(&cam, &Distortion::default(), &Vector3::from(p), 0.05).unwrap();
        assert!(r > 3.0);
        let px = img.get(x.round() as usize, y.round() as usize);
        assert!(px[0] > 90 && px[0] as i32 > px[2] as i32 + 50, "{px:?} at ({x}, {y})");
        // Outside the ball: the background photo, not the ball's colour.
        let out = img.get((x + 3.0 * r).round().min(319.0) as usize, y.round() as usize);
        assert_ne!(out, px);
        assert!(render_view(&world, 999, &cam, 320, 240, 1).is_err());
    }
}
