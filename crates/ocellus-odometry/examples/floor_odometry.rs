//! Visual odometry of a camera looking down at a generated floor of real textures, moving on
//! a known path at 200 Hz: the estimated trajectory against the truth (SPEC 6).
//!
//! `cargo run --release -p ocellus-odometry --example floor_odometry`

use ocellus_eval::trajectory::{self, PlanarPose};
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let textures = ["brick.png", "grass.png", "gravel.png"].map(ocellus_testdata::asset);
    let textures = textures.map(|p| ocellus_io::read_image(p).map(|i| i.to_grey()));
    let [a, b, c] = textures;
    let cfg = GroundConfig { frames: 200, ..GroundConfig::easy(GroundTexture::Mosaic, 1) };
    let scene = GroundScene::new(cfg, [a?, b?, c?])?;
    let cfg = scene.config();
    // The generated camera: 0.3 m above the floor, focal 600 px, mounted off the rotation centre.
    let mount = Mount { right_m: cfg.mount_px[0] * cfg.metres_per_px, forward_m: cfg.mount_px[1] * cfg.metres_per_px };
    let mut vo = VisualOdometry::new(OdometryConfig::robust(0.3, 600.0, mount))?;
    let (mut truth, mut estimate) = (Vec::new(), Vec::new());
    let t = std::time::Instant::now();
    for k in 0..scene.len() {
        vo.step(&scene.frame(k)?)?;
        let (x, y, yaw) = scene.pose_m(k).ok_or("frame past the end")?;
        let (e, time_s) = (vo.pose(), k as f64 / 200.0);
        truth.push(PlanarPose::new(time_s, x, y, yaw));
        estimate.push(PlanarPose::new(time_s, e.x, e.y, e.theta));
    }
    let ms = t.elapsed().as_secs_f64() * 1e3 / scene.len() as f64;
    let e = trajectory::errors(&estimate, &truth, 1e-6)?;
    println!("{} frames, path {:.3} m, {ms:.2} ms per frame (frames rendered in the loop)", scene.len(), e.path_m);
    println!("final drift {:.3} % of the path, heading error {:.3} deg", e.final_drift_percent, e.final_heading_deg);
    println!("ATE RMSE {:.3} mm, RPE per frame RMSE {:.4} mm", e.ate_rmse_m * 1e3, e.rpe_rmse_m * 1e3);
    Ok(())
}
