//! Runs the robust odometry over pre-rendered frames repeatedly: a profiling aid.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use ocellus_image::Plane;
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::spline::SmoothedFrame;
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
    // Stage split, as a stream does it: smoothing one frame (each frame is smoothed once),
    // the integer search, the windows' Lucas-Kanade (the search again inside it), the fit.
    let cfg = ocellus_odometry::robust::RobustConfig::default();
    let (w, h) = frames[0].size();
    let rect = ocellus_odometry::robust::lk_rect(w, h, &cfg).unwrap();
    let backend = cfg.flow.backend;
    let smoothed: Vec<SmoothedFrame> = frames
        .iter()
        .map(|f| {
            let mut s = SmoothedFrame::default();
            s.update(backend, f, cfg.smooth_sigma_px, rect).unwrap();
            s
        })
        .collect();
    let mut t = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    let mut scratch = SmoothedFrame::default();
    for _ in 0..10 {
        for (k, f) in frames.windows(2).enumerate() {
            let s = std::time::Instant::now();
            scratch.update(backend, &f[1], cfg.smooth_sigma_px, rect).unwrap();
            t[0].push(s.elapsed().as_secs_f64() * 1e3);
            let s = std::time::Instant::now();
            let _ = ocellus_odometry::sad_flow::window_flows(&f[0], &f[1], &cfg.flow).unwrap();
            t[1].push(s.elapsed().as_secs_f64() * 1e3);
            let s = std::time::Instant::now();
            let m = ocellus_odometry::robust::window_measurements_smoothed(
                &f[0],
                &f[1],
                &smoothed[k],
                &smoothed[k + 1],
                &cfg,
            )
            .unwrap();
            t[2].push(s.elapsed().as_secs_f64() * 1e3);
            let s = std::time::Instant::now();
            let _ = ocellus_odometry::robust::fit_rigid(&m, &cfg).unwrap();
            t[3].push(s.elapsed().as_secs_f64() * 1e3);
        }
    }
    let [a, b, c, d] = t.map(|mut v| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    });
    println!(
        "medians: smoothing a frame {a:.3} ms, integer search {b:.3} ms, search + Lucas-Kanade {c:.3} ms (Lucas-Kanade {:.3} ms), fit {d:.3} ms",
        c - b
    );
}
