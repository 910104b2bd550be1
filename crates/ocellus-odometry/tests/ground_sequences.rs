//! The seed's visual odometry on generated ground sequences built from the real textures.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use ocellus_eval::trajectory::{final_drift, path_length, PlanarPose};
use ocellus_image::Plane;
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::robust::{fit_rigid, window_measurements, RobustConfig};
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};

fn textures() -> [Plane<f32>; 3] {
    ["brick.png", "grass.png", "gravel.png"]
        .map(|n| ocellus_io::read_image(ocellus_testdata::asset(n)).unwrap().to_grey())
}

/// Runs the odometry over a scene: (final drift in % of the path, final heading error in
/// degrees).
fn run(scene: &GroundScene, robust: bool) -> (f64, f64) {
    run_with(scene, robust, |_| {})
}

/// [`run`] with the configuration changed by `change` first.
fn run_with(scene: &GroundScene, robust: bool, change: impl FnOnce(&mut OdometryConfig)) -> (f64, f64) {
    let c = scene.config();
    // 1 ground pixel = 0.5 mm: a camera 0.3 m up with a 600 px focal length.
    let mount = Mount { right_m: c.mount_px[0] * c.metres_per_px, forward_m: c.mount_px[1] * c.metres_per_px };
    let mut cfg =
        if robust { OdometryConfig::robust(0.3, 600.0, mount) } else { OdometryConfig::seed(0.3, 600.0, mount) };
    change(&mut cfg);
    let mut vo = VisualOdometry::new(cfg).unwrap();
    let mut truth = Vec::with_capacity(scene.len());
    for k in 0..scene.len() {
        vo.step(&scene.frame(k).unwrap()).unwrap();
        let (x, y, yaw) = scene.pose_m(k).unwrap();
        truth.push(PlanarPose::new(k as f64, x, y, yaw));
    }
    let e = vo.pose();
    let end = truth[truth.len() - 1];
    final_drift(&PlanarPose::new(end.time_s, e.x, e.y, e.theta), &end, path_length(&truth)).unwrap()
}

#[test]
fn seed_mode_tracks_grass_and_brick() {
    let t = textures();
    // Integer flows drift: the seed reports about 0.5 % on grass and gravel and 4.5 % on brick,
    // whose mortar lines make windows slide along them. The bounds catch a broken filter or
    // sign (hundreds of percent), not the method's own error.
    for (texture, bound) in [(GroundTexture::Grass, 4.0), (GroundTexture::Brick, 25.0)] {
        let cfg = GroundConfig { frames: 120, ..GroundConfig::easy(texture, 1) };
        let (drift, heading) = run(&GroundScene::new(cfg, t.clone()).unwrap(), false);
        println!("seed mode, {texture:?}, 120 frames: drift {drift:.3} % of the path, heading error {heading:.3} deg");
        assert!(drift < bound && heading < 2.0, "{texture:?}: drift {drift} %, heading {heading} deg");
    }
}

#[test]
fn robust_mode_stays_within_a_tenth_of_a_percent_on_brick_and_gravel() {
    // Issue 7's target is a mean final drift of 0.10 % (easy) and a heading error of 0.1
    // degree; one seed each here, over 120 frames, with some margin for the single run.
    let t = textures();
    for texture in [GroundTexture::Brick, GroundTexture::Gravel] {
        let cfg = GroundConfig { frames: 120, ..GroundConfig::easy(texture, 2) };
        let (drift, heading) = run(&GroundScene::new(cfg, t.clone()).unwrap(), true);
        println!(
            "robust mode, {texture:?}, 120 frames: drift {drift:.3} % of the path, heading error {heading:.3} deg"
        );
        assert!(drift < 0.2 && heading < 0.2, "{texture:?}: drift {drift} %, heading {heading} deg");
    }
}

#[test]
fn the_robust_mode_follows_the_camera_height() {
    // The hard variant's camera height oscillates by 1 % over 37 frames (image scale
    // 1 + 0.01 sin(2 pi t / 37), the generator's documented model); here without noise, blur
    // or flicker, so the height is the only thing wrong with a fixed-height model.
    let cfg = GroundConfig { frames: 120, height_oscillation: 0.01, ..GroundConfig::easy(GroundTexture::Gravel, 1) };
    let scene = GroundScene::new(cfg, textures()).unwrap();
    let mut vo_cfg = OdometryConfig::robust(0.3, 600.0, Mount { right_m: 0.0, forward_m: 0.0 });
    vo_cfg.robust.height_pull = 0.0;
    let mut vo = VisualOdometry::new(vo_cfg).unwrap();
    let mut worst = 0.0f64;
    for k in 0..scene.len() {
        let step = vo.step(&scene.frame(k).unwrap()).unwrap();
        let truth = 0.3 * (1.0 + 0.01 * (std::f64::consts::TAU * k as f64 / 37.0).sin());
        worst = worst.max((step.height_m - truth).abs());
    }
    println!("height followed within {:.4} mm of the truth (oscillation 3 mm)", worst * 1e3);
    assert!(worst < 0.2e-3, "height error {worst} m");
    // Followed (the default pull) against fixed at the calibrated height: less drift.
    let (followed, _) = run(&scene, true);
    let (fixed, _) = run_with(&scene, true, |c| c.robust.height_pull = 1.0);
    println!("drift with the height followed {followed:.4} %, fixed {fixed:.4} %");
    assert!(followed < 0.5 * fixed, "followed {followed} %, fixed {fixed} %");
}

#[test]
fn a_constant_height_is_not_followed_into_noise() {
    // The real-camera low-contrast floor (no lens, which this test would have to undistort):
    // its camera height is constant, and its image-scale changes are the noisiest of the
    // floors. Followed whole, their noise moves the height; shrunk by the measured
    // signal-to-noise ratio (`height_noise_frames`), much less.
    let cfg = GroundConfig { frames: 120, k1: 0.0, ..GroundConfig::easy(GroundTexture::LowContrast, 1).real_camera() };
    let scene = GroundScene::new(cfg, textures()).unwrap();
    let worst = |window: f64| {
        let mut vo_cfg = OdometryConfig::robust(0.3, 600.0, Mount { right_m: 0.0, forward_m: 0.05 });
        vo_cfg.robust.height_noise_frames = window;
        let mut vo = VisualOdometry::new(vo_cfg).unwrap();
        (0..scene.len()).map(|k| (vo.step(&scene.frame(k).unwrap()).unwrap().height_m - 0.3).abs()).fold(0.0, f64::max)
    };
    let (whole, shrunk) = (worst(0.0), worst(32.0));
    println!("height off by up to {:.4} mm followed whole, {:.4} mm shrunk", whole * 1e3, shrunk * 1e3);
    assert!(shrunk < 0.5 * whole, "whole {whole} m, shrunk {shrunk} m");
}

#[test]
fn robust_mode_holds_on_low_contrast_fine_grained_and_repetitive_floors_seen_by_a_real_camera() {
    // Before Lucas-Kanade ran on smoothed frames with a noise-relative texture test, these
    // drifted 0.07-0.15 % (seed 1, 200 frames): bilinear interpolation pulled every flow
    // toward whole pixels on fine texture, and an absolute texture threshold dropped the
    // low-contrast floor's windows. Now about 0.002-0.02 %.
    let t = textures();
    for texture in [GroundTexture::LowContrast, GroundTexture::FineGrained, GroundTexture::Repetitive] {
        // Area-integrating pixels and vignetting; no lens, which this test would have to
        // undistort (the CLI tests do).
        let cfg = GroundConfig { frames: 120, k1: 0.0, ..GroundConfig::easy(texture, 1).real_camera() };
        let (drift, heading) = run(&GroundScene::new(cfg, t.clone()).unwrap(), true);
        println!(
            "robust mode, {texture:?}, real camera, 120 frames: drift {drift:.4} %, heading error {heading:.4} deg"
        );
        assert!(drift < 0.05 && heading < 0.05, "{texture:?}: drift {drift} %, heading {heading} deg");
    }
}

#[test]
fn standing_still_gives_no_motion_and_turning_in_place_the_right_heading() {
    let t = textures();
    let still = GroundConfig {
        frames: 20,
        forward_px: 0.0,
        forward_spread_px: 0.0,
        lateral_px: 0.0,
        yaw_deg: 0.0,
        yaw_spread_deg: 0.0,
        ..GroundConfig::easy(GroundTexture::Gravel, 2)
    };
    let s = GroundScene::new(still, t.clone()).unwrap();
    let cfg = OdometryConfig::seed(0.3, 600.0, Mount { right_m: 0.0, forward_m: 0.05 });
    for c in [cfg, OdometryConfig::robust(0.3, 600.0, cfg.mount)] {
        let mut vo = VisualOdometry::new(c).unwrap();
        for k in 0..s.len() {
            vo.step(&s.frame(k).unwrap()).unwrap();
        }
        let p = vo.pose();
        // Noise only: the seed's integer flows are exactly zero; sub-pixel ones nearly.
        assert!(p.x.hypot(p.y) < 2e-5 && p.theta.abs() < 1e-4, "{:?}: {p:?}", c.mode);
    }
    // Turning in place by 0.3 degrees per frame about the rotation centre (camera 5 cm
    // ahead, so the image both turns and slides).
    let turn = GroundConfig { yaw_deg: 0.3, frames: 40, ..still };
    let s = GroundScene::new(turn, t.clone()).unwrap();
    let mut vo = VisualOdometry::new(cfg).unwrap();
    for k in 0..s.len() {
        vo.step(&s.frame(k).unwrap()).unwrap();
    }
    let (p, truth) = (vo.pose(), s.pose_m(s.len() - 1).unwrap());
    println!(
        "turn in place: heading {:.3} deg (truth {:.3}), position ({:.2}, {:.2}) mm",
        p.theta.to_degrees(),
        truth.2.to_degrees(),
        p.x * 1e3,
        p.y * 1e3
    );
    assert!((p.theta - truth.2).abs().to_degrees() < 0.5);
    assert!(p.x.hypot(p.y) < 0.005, "the rotation centre stays put: {p:?}");
}

#[test]
fn a_blank_floor_is_a_reported_failure() {
    let flat = Plane::from_fn(640, 480, |_, _| 120u8);
    for cfg in
        [OdometryConfig::seed(0.3, 600.0, Mount::default()), OdometryConfig::robust(0.3, 600.0, Mount::default())]
    {
        let mut vo = VisualOdometry::new(cfg).unwrap();
        vo.step(&flat).unwrap();
        let s = vo.step(&flat).unwrap();
        assert!(s.failure.is_some() && s.flows.is_empty(), "{:?}", cfg.mode);
        assert!(vo.step(&Plane::new(100, 100)).is_err());
    }
}

#[test]
fn encoder_fusion_beats_wheels_and_vision_alone() {
    use ocellus_odometry::fusion::{encoder_motion, EncoderReading, Fusion, FusionConfig};
    use ocellus_synth::ground::encoders;
    // Grass, 200 frames; the wheels slip by 2 mm every 0.3 s (at 0.3, 0.6 and 0.9 s), and
    // the camera sees a blank floor for frames 70-109 (0.35-0.55 s, a visual failure between
    // two slips: a slip during a gap is seen by neither sensor).
    let t = textures();
    let cfg = GroundConfig::easy(GroundTexture::Grass, 4);
    let scene = GroundScene::new(cfg, t).unwrap();
    let readings: Vec<EncoderReading> = encoders(&scene, 30.0, 0.3, 0.002, 4)
        .unwrap()
        .iter()
        .map(|e| EncoderReading { time_s: e.time_s, forward_m: e.forward_m, yaw_rad: e.yaw_rad })
        .collect();
    let mount = Mount { right_m: 0.0, forward_m: cfg.mount_px[1] * cfg.metres_per_px };
    let mut vo = VisualOdometry::new(OdometryConfig::robust(0.3, 600.0, mount)).unwrap();
    let mut fusion = Fusion::new(FusionConfig::default(), mount);
    let mut wheels = ocellus_odometry::kinematics::Pose2::default();
    let blank = Plane::from_fn(640, 480, |_, _| 128u8);
    let mut path = 0.0;
    let mut last = scene.pose_m(0).unwrap();
    for k in 0..scene.len() {
        let frame = if (70..110).contains(&k) { blank.clone() } else { scene.frame(k).unwrap() };
        let step = vo.step(&frame).unwrap();
        if k > 0 {
            let w = encoder_motion(&readings, 30.0, scene.time_s(k - 1), scene.time_s(k));
            if let Some((f, y)) = w {
                wheels = wheels.step(0.0, f, y);
            }
            fusion.step(&step, w);
        }
        let p = scene.pose_m(k).unwrap();
        path += ((p.0 - last.0).powi(2) + (p.1 - last.1).powi(2)).sqrt();
        last = p;
    }
    let drift = |p: ocellus_odometry::kinematics::Pose2| 100.0 * (p.x - last.0).hypot(p.y - last.1) / path;
    let (dv, dw, df) = (drift(vo.pose()), drift(wheels), drift(fusion.pose()));
    println!(
        "fusion, grass, a 40-frame blank gap, 3 wheel slips: vision {dv:.3} %, wheels {dw:.3} %, fused {df:.3} % (wheels rejected in {} frames, bridged {})",
        fusion.rejected, fusion.bridged
    );
    assert!(df < dv && df < dw, "vision {dv} %, wheels {dw} %, fused {df} %");
}

#[test]
fn small_turns_are_measured_without_the_resampling_overshoot() {
    // Driving straight at a whole pixel per frame while turning by 0.1 degree: every window's
    // flow is a whole pixel plus a fraction of up to 0.35 px that grows with its distance
    // from the centre. Bilinear resampling shifted such small fractions by a few percent, and
    // the rotation came out 1.7 % (gravel) and 2.1 % (brick) too large (frames smoothed by
    // 1.5 px), frame after frame: a heading error that grows with the path. The spline keeps
    // it within 0.5 %. (On the point-sampled fine-grained floor, whose texels alias, it is
    // 0.75 % short at the default 1 px of smoothing and 0.12 % at 1.5 px.)
    let t = textures();
    let cfg = RobustConfig::default();
    for texture in [GroundTexture::Gravel, GroundTexture::Brick] {
        let scene = GroundScene::new(
            GroundConfig {
                frames: 12,
                forward_px: 3.0,
                forward_spread_px: 0.0,
                lateral_px: 0.0,
                yaw_deg: 0.1,
                yaw_spread_deg: 0.0,
                noise_sigma: 0.0,
                mount_px: [0.0, 0.0],
                ..GroundConfig::easy(texture, 1)
            },
            t.clone(),
        )
        .unwrap();
        let mut errors = Vec::new();
        for k in 1..scene.len() {
            let (a, b) = (scene.frame(k - 1).unwrap(), scene.frame(k).unwrap());
            let fit = fit_rigid(&window_measurements(&a, &b, &cfg).unwrap(), &cfg).unwrap();
            errors.push(fit.turn_rad / scene.motion(k - 1).unwrap().yaw_rad - 1.0);
        }
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        println!("{texture:?}: turn off by {:.3} % on average", 100.0 * mean);
        assert!(mean.abs() < 0.005, "{texture:?}: the turn is off by {:.2} %", 100.0 * mean);
    }
}
