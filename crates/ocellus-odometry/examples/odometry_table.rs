//! Prints the accuracy table of issue 7: final drift (% of the path) and heading error of the
//! seed and robust modes on generated sequences, 3 seeds per floor (the four textures and
//! the low-contrast, fine-grained and repetitive floors), easy and hard, 200 frames each. `cargo run --release -p ocellus-odometry --example odometry_table`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use ocellus_eval::trajectory::{final_drift, path_length, PlanarPose};
use ocellus_image::Plane;
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};

fn main() {
    let textures: [Plane<f32>; 3] = ["brick.png", "grass.png", "gravel.png"]
        .map(|n| ocellus_io::read_image(ocellus_testdata::asset(n)).unwrap().to_grey());
    println!("texture      variant  mode    drift % (3 seeds)           mean   heading deg (3 seeds)        mean");
    for texture in GroundTexture::ALL {
        for hard in [false, true] {
            let mut rows = [(Vec::new(), Vec::new()), (Vec::new(), Vec::new())];
            for seed in 1..=3 {
                let cfg = if hard { GroundConfig::hard(texture, seed) } else { GroundConfig::easy(texture, seed) };
                let scene = GroundScene::new(cfg, textures.clone()).unwrap();
                let frames: Vec<Plane<u8>> = (0..scene.len()).map(|k| scene.frame(k).unwrap()).collect();
                let mount = Mount {
                    right_m: cfg.mount_px[0] * cfg.metres_per_px,
                    forward_m: cfg.mount_px[1] * cfg.metres_per_px,
                };
                for (mi, vo_cfg) in [OdometryConfig::seed(0.3, 600.0, mount), OdometryConfig::robust(0.3, 600.0, mount)]
                    .into_iter()
                    .enumerate()
                {
                    let mut vo = VisualOdometry::new(vo_cfg).unwrap();
                    let mut truth = Vec::with_capacity(frames.len());
                    for (k, f) in frames.iter().enumerate() {
                        vo.step(f).unwrap();
                        let (x, y, yaw) = scene.pose_m(k).unwrap();
                        truth.push(PlanarPose::new(k as f64, x, y, yaw));
                    }
                    let (e, end) = (vo.pose(), truth[truth.len() - 1]);
                    let est = PlanarPose::new(end.time_s, e.x, e.y, e.theta);
                    let (drift, heading) = final_drift(&est, &end, path_length(&truth)).unwrap();
                    rows[mi].0.push(drift);
                    rows[mi].1.push(heading);
                }
            }
            for (mi, (d, h)) in rows.iter().enumerate() {
                let f = |v: &Vec<f64>| v.iter().map(|x| format!("{x:7.3}")).collect::<Vec<_>>().join(" ");
                let mean = |v: &Vec<f64>| v.iter().sum::<f64>() / v.len() as f64;
                println!(
                    "{:<12} {:<8} {:<7} {}  {:7.3}   {}  {:7.3}",
                    texture.name(),
                    if hard { "hard" } else { "easy" },
                    if mi == 0 { "seed" } else { "robust" },
                    f(d),
                    mean(d),
                    f(h),
                    mean(h)
                );
            }
        }
    }
}
