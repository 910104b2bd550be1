//! Runs the robust odometry over pre-rendered frames repeatedly: a profiling aid.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use ocellus_image::Plane;
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};

fn main() {
    let textures: [Plane<f32>; 3] = ["brick.png", "grass.png", "gravel.png"]
        .map(|n| ocellus_io::read_image(ocellus_testdata::asset(n)).unwrap().to_grey());
    // The texture as the first argument (brick, grass, gravel; mosaic by default).
    let texture = match std::env::args().nth(1).as_deref() {
        Some("brick") => GroundTexture::Brick,
        Some("grass") => GroundTexture::Grass,
        Some("gravel") => GroundTexture::Gravel,
        _ => GroundTexture::Mosaic,
    };
    let scene = GroundScene::new(GroundConfig { frames: 40, ..GroundConfig::easy(texture, 1) }, textures).unwrap();
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
    // Stage split: integer search, search + Lucas-Kanade, fit.
    let cfg = ocellus_odometry::robust::RobustConfig::default();
    let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..10 {
        for w in frames.windows(2) {
            let s = std::time::Instant::now();
            let _ = ocellus_odometry::sad_flow::window_flows(&w[0], &w[1], &cfg.flow).unwrap();
            a.push(s.elapsed().as_secs_f64() * 1e3);
            let s = std::time::Instant::now();
            let m = ocellus_odometry::robust::window_measurements(&w[0], &w[1], &cfg).unwrap();
            b.push(s.elapsed().as_secs_f64() * 1e3);
            let s = std::time::Instant::now();
            let _ = ocellus_odometry::robust::fit_rigid(&m, &cfg).unwrap();
            c.push(s.elapsed().as_secs_f64() * 1e3);
        }
    }
    for v in [&mut a, &mut b, &mut c] {
        v.sort_by(f64::total_cmp);
    }
    println!("search {:.3} ms, search + LK {:.3} ms, fit {:.3} ms", a[a.len() / 2], b[b.len() / 2], c[c.len() / 2]);
}
