//! Runs the robust odometry over pre-rendered frames repeatedly: a profiling aid.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use ocellus_image::Plane;
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};

fn main() {
    let textures: [Plane<f32>; 3] = ["brick.png", "grass.png", "gravel.png"]
        .map(|n| ocellus_io::read_image(ocellus_testdata::asset(n)).unwrap().to_luma8().map(|v| v as f32));
    let scene = GroundScene::new(GroundConfig { frames: 40, ..GroundConfig::easy(GroundTexture::Mosaic, 1) }, textures)
        .unwrap();
    let frames: Vec<Plane<u8>> = (0..scene.len()).map(|k| scene.frame(k).unwrap()).collect();
    let mut t = Vec::new();
    for _ in 0..25 {
        let mut vo = VisualOdometry::new(OdometryConfig::robust(0.3, 600.0, Mount::default())).unwrap();
        for f in &frames {
            let s = std::time::Instant::now();
            vo.step(f).unwrap();
            t.push(s.elapsed().as_secs_f64() * 1e3);
        }
    }
    t.sort_by(f64::total_cmp);
    println!("robust median {:.3} ms", t[t.len() / 2]);
}
