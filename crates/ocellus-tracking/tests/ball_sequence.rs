//! A 3D ball tracked by the SIR filter with the colour likelihood, on a rendered sequence:
//! an orange ball of 5 cm radius flies across a real photograph, seen by a camera with lens
//! distortion; the estimate is compared with the known trajectory.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use nalgebra::{Matrix3, Vector3};
use ocellus_estimation::particle_filter::{FilterConfig, ParticleFilter};
use ocellus_geometry::camera::{Intrinsics, PinholeCamera};
use ocellus_geometry::distortion::Distortion;
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;
use ocellus_tracking::ball::{project_ball, BallModel, BallState};
use ocellus_tracking::colour::{BinnedFrame, ColourModel};

const DT: f64 = 1.0 / 30.0;
const RADIUS: f64 = 0.05;

fn camera() -> (PinholeCamera, Distortion) {
    let k = Intrinsics { fx: 600.0, fy: 600.0, cx: 319.5, cy: 239.5, skew: 0.0 };
    let d = Distortion { k1: -0.12, k2: 0.02, k3: 0.0, p1: 0.0005, p2: -0.0003 };
    (PinholeCamera { k, r: Matrix3::identity(), t: Vector3::zeros() }, d)
}

/// The true centre at frame `k`: across the view and away from the camera, slightly curved.
fn truth(k: usize) -> Vector3<f64> {
    let t = k as f64 * DT;
    Vector3::new(-0.35 + 0.5 * t, -0.12 + 0.15 * t + 0.2 * t * t, 1.8 + 0.4 * t)
}

/// Frame `k`: the astronaut photo (stretched to 640x480) with the shaded ball and noise.
fn frame(k: usize, photo: &Plane<[u8; 3]>, rng: &mut SplitMix64) -> Plane<[u8; 3]> {
    let (cam, dist) = camera();
    let c = project_ball(&cam, &dist, &truth(k), RADIUS).unwrap();
    let (pw, ph) = photo.size();
    Plane::from_fn(640, 480, |x, y| {
        let (dx, dy) = (x as f64 - c.x, y as f64 - c.y);
        let base = if dx * dx + dy * dy <= c.r * c.r {
            let shade = 1.0 - 0.35 * (dx + dy) / (2.0 * c.r);
            [245.0 * shade, 120.0 * shade, 25.0 * shade]
        } else {
            photo.get(x * pw / 640, y * ph / 480).map(f64::from)
        };
        base.map(|v| (v + 3.0 * rng.normal()).round().clamp(0.0, 255.0) as u8)
    })
}

#[test]
fn sir_tracks_the_ball_in_3d() {
    let photo = ocellus_io::read_image(ocellus_testdata::data_file("astronaut.png")).unwrap().to_u8();
    let mut rng = SplitMix64::new(3);
    let frames: Vec<Plane<[u8; 3]>> = (0..45).map(|k| frame(k, &photo, &mut rng)).collect();
    let (camera, distortion) = camera();
    // The colour model from the first frame's ball (as a user would pick a patch).
    let c0 = project_ball(&camera, &distortion, &truth(0), RADIUS).unwrap();
    let colour = ColourModel::from_patch(&frames[0], ocellus_tracking::colour::Circle { r: 0.8 * c0.r, ..c0 }).unwrap();
    let model =
        BallModel { camera, distortion, radius_m: RADIUS, dt_s: DT, accel_sigma: 3.0, gravity: [0.0; 3], colour };
    model.validate().unwrap();
    // Start near the first position (10 cm, 0.5 m/s spread), as after a detection.
    let mut init = SplitMix64::new(11);
    let p0 = truth(0);
    let particles: Vec<BallState> = (0..3000)
        .map(|_| BallState {
            position: [p0.x + 0.03 * init.normal(), p0.y + 0.03 * init.normal(), p0.z + 0.1 * init.normal()],
            velocity: [0.5 * init.normal(), 0.5 * init.normal(), 0.5 * init.normal()],
        })
        .collect();
    let mut pf = ParticleFilter::new(FilterConfig::default(), particles).unwrap();
    let mut binned = BinnedFrame::default();
    let (mut err3, mut errs_px, mut depth) = (0.0, Vec::new(), 0.0);
    for (k, f) in frames.iter().enumerate().skip(1) {
        binned.update(f);
        pf.step(&model, &binned).unwrap();
        let est = Vector3::from(pf.mean(|s| s.position));
        let t = truth(k);
        err3 += (est - t).norm_squared();
        depth += t.z;
        let (ce, ct) = (
            model.circle(&BallState { position: est.into(), velocity: [0.0; 3] }).unwrap(),
            project_ball(&camera, &distortion, &t, RADIUS).unwrap(),
        );
        errs_px.push((ce.x - ct.x).hypot(ce.y - ct.y));
    }
    let n = (frames.len() - 1) as f64;
    let (rmse, mean_depth) = ((err3 / n).sqrt(), depth / n);
    errs_px.sort_by(f64::total_cmp);
    let median_px = errs_px[errs_px.len() / 2];
    println!(
        "3D RMSE {:.4} m = {:.2} % of the mean depth {mean_depth:.2} m; median image-centre error {median_px:.2} px",
        rmse,
        100.0 * rmse / mean_depth
    );
    assert!(median_px <= 2.0, "median image-centre error {median_px} px");
    // 3.8 % when this was written; issue 16 asks for 2 % of the finished tracker.
    assert!(rmse <= 0.05 * mean_depth, "3D RMSE {rmse} m at {mean_depth} m");
}
