//! Visual odometry of a camera looking down at a generated floor of real textures, moving on
//! a known path at 200 Hz: the estimated pose against the truth (SPEC 6).
//!
//! `cargo run --release -p ocellus-odometry --example floor_odometry`

use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let textures = ["brick.png", "grass.png", "gravel.png"].map(ocellus_testdata::asset);
    let textures = textures.map(|p| ocellus_io::read_image(p).map(|i| i.to_luma8().map(|v| v as f32)));
    let [a, b, c] = textures;
    let scene =
        GroundScene::new(GroundConfig { frames: 200, ..GroundConfig::easy(GroundTexture::Mosaic, 1) }, [a?, b?, c?])?;
    let cfg = scene.config();
    // The generated camera: 0.3 m above the floor, focal 600 px, mounted off the rotation centre.
    let mount = Mount { right_m: cfg.mount_px[0] * cfg.metres_per_px, forward_m: cfg.mount_px[1] * cfg.metres_per_px };
    let mut vo = VisualOdometry::new(OdometryConfig::robust(0.3, 600.0, mount))?;
    let (mut path_m, mut last) = (0.0, scene.pose_m(0).ok_or("empty scene")?);
    let t = std::time::Instant::now();
    for k in 0..scene.len() {
        vo.step(&scene.frame(k)?)?;
        let p = scene.pose_m(k).ok_or("frame past the end")?;
        path_m += (p.0 - last.0).hypot(p.1 - last.1);
        last = p;
    }
    let ms = t.elapsed().as_secs_f64() * 1e3 / scene.len() as f64;
    let est = vo.pose();
    let err_m = (est.x - last.0).hypot(est.y - last.1);
    println!("{} frames, path {:.3} m, {ms:.2} ms per frame (frames rendered in the loop)", scene.len(), path_m);
    println!("true end ({:.4}, {:.4}) m, {:.2} deg", last.0, last.1, last.2.to_degrees());
    println!(
        "estimated ({:.4}, {:.4}) m, {:.2} deg: drift {:.3} % of the path",
        est.x,
        est.y,
        est.theta.to_degrees(),
        100.0 * err_m / path_m
    );
    Ok(())
}
