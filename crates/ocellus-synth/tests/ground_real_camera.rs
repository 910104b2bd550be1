//! The real-camera rendering of `ocellus_synth::ground` (area pixels, lens distortion,
//! vignetting) against independent references: a box filter's smoothing, a flat floor's
//! corner factor, and the geometry crate's own undistortion.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_image::Plane;
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture, FOCAL_PX, TILE};

/// Smooth but unique patterns (as the unit tests use), so that frames are comparable by
/// resampling.
fn textures() -> [Plane<f32>; 3] {
    std::array::from_fn(|i| {
        Plane::from_fn(TILE, TILE, |x, y| {
            let (x, y) = (x as f32, y as f32);
            (128.0 + 60.0 * ((x * 0.07 + i as f32).sin() * (y * 0.05).cos()) + 30.0 * ((x + 2.0 * y) * 0.031).sin())
                / 255.0
        })
    })
}

/// A noiseless `width` x `height` sequence of two frames.
fn two_frames(width: usize, height: usize, texture: GroundTexture, seed: u64) -> GroundConfig {
    GroundConfig { width, height, frames: 2, noise_sigma: 0.0, ..GroundConfig::easy(texture, seed) }
}

fn small(texture: GroundTexture) -> GroundConfig {
    GroundConfig { width: 96, height: 64, frames: 30, noise_sigma: 0.0, ..GroundConfig::easy(texture, 3) }
}

/// A real photo's texture (fine detail that point samples alias), as the CLI loads it.
fn photo_textures() -> [Plane<f32>; 3] {
    let load = |n: &str| -> Plane<f32> { ocellus_io::read_image(ocellus_testdata::asset(n)).unwrap().to_grey() };
    [load("brick.png"), load("grass.png"), load("gravel.png")]
}

fn mean(p: &Plane<u8>, x0: usize, y0: usize, x1: usize, y1: usize) -> f64 {
    let n = ((x1 - x0) * (y1 - y0)) as f64;
    (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).map(|(x, y)| f64::from(p.get(x, y))).sum::<f64>() / n
}

#[test]
fn pixels_that_integrate_their_area_keep_the_brightness_and_lose_the_aliasing() {
    let cfg = two_frames(160, 120, GroundTexture::Gravel, 1);
    let point = GroundScene::new(cfg, photo_textures()).unwrap().frame(1).unwrap();
    let area = GroundScene::new(GroundConfig { supersample: 4, ..cfg }, photo_textures()).unwrap().frame(1).unwrap();
    let (mp, ma) = (mean(&point, 0, 0, 160, 120), mean(&area, 0, 0, 160, 120));
    assert!((mp - ma).abs() < 0.5, "mean grey {mp} vs {ma}");
    // Total variation between neighbours: a box filter over each pixel smooths what a
    // point sample of the bilinear texture keeps.
    let tv = |p: &Plane<u8>| -> f64 {
        (0..120)
            .flat_map(|y| (1..160).map(move |x| (x, y)))
            .map(|(x, y)| (f64::from(p.get(x, y)) - f64::from(p.get(x - 1, y))).abs())
            .sum()
    };
    let (tp, ta) = (tv(&point), tv(&area));
    assert!(ta < 0.97 * tp, "variation point {tp} vs area {ta}");
    // One sample per pixel is the point-sampled rendering, exactly.
    let one =
        GroundScene::new(GroundConfig { supersample: 1, k1: 0.0, vignetting: 0.0, ..cfg }, photo_textures()).unwrap();
    assert_eq!(one.frame(1).unwrap(), point);
}

#[test]
fn vignetting_darkens_the_corners_by_the_share_asked() {
    let flat = [
        Plane::from_fn(TILE, TILE, |_, _| 0.8f32),
        Plane::from_fn(TILE, TILE, |_, _| 0.8),
        Plane::from_fn(TILE, TILE, |_, _| 0.8),
    ];
    let cfg = GroundConfig { vignetting: 0.3, ..small(GroundTexture::Brick) };
    let f = GroundScene::new(cfg, flat).unwrap().frame(0).unwrap();
    let lit = (0.8f32 * 255.0).round();
    // Corner pixel: r = r_corner; centre: r about 0.
    assert!((f32::from(f.get(0, 0)) - (0.7 * 0.8f32 * 255.0).round()).abs() <= 1.0, "{}", f.get(0, 0));
    assert!((f32::from(f.get(48, 32)) - lit).abs() <= 1.0, "{}", f.get(48, 32));
}

#[test]
fn a_distorted_frame_undistorted_by_its_own_model_is_the_pinhole_frame() {
    use ocellus_geometry::camera::Intrinsics;
    use ocellus_geometry::distortion::{remap_bilinear, undistort_maps, Distortion};
    let cfg = two_frames(320, 240, GroundTexture::Mosaic, 2);
    let pinhole = GroundScene::new(cfg, textures()).unwrap().frame(1).unwrap();
    let lens = GroundScene::new(GroundConfig { k1: -0.2, ..cfg }, textures()).unwrap().frame(1).unwrap();
    let k = Intrinsics { fx: FOCAL_PX, fy: FOCAL_PX, cx: 159.5, cy: 119.5, skew: 0.0 };
    let d = Distortion { k1: -0.2, ..Distortion::default() };
    let (mx, my) = undistort_maps(&k, &d, 320, 240);
    let back = remap_bilinear(&lens.map(f32::from), &mx, &my, 0.0).unwrap();
    let diff = |a: &Plane<f32>, x: usize, y: usize| (a.get(x, y) - f32::from(pinhole.get(x, y))).abs();
    // Inside a margin (the remap reads outside the frame near the border).
    let pts: Vec<(usize, usize)> = (12..228).flat_map(|y| (12..308).map(move |x| (x, y))).collect();
    let mean_diff = pts.iter().map(|&(x, y)| f64::from(diff(&back, x, y))).sum::<f64>() / pts.len() as f64;
    assert!(mean_diff < 1.0, "undistorted lens frame vs pinhole frame: {mean_diff} grey levels");
    // The distortion is visible before undistortion (the corners move by 4 px).
    let raw = pts
        .iter()
        .map(|&(x, y)| f64::from((f32::from(lens.get(x, y)) - f32::from(pinhole.get(x, y))).abs()))
        .sum::<f64>()
        / pts.len() as f64;
    assert!(raw > 3.0 * mean_diff, "raw {raw} vs undistorted {mean_diff}");
}

#[test]
fn unusable_real_camera_settings_are_refused() {
    let ok = small(GroundTexture::Grass);
    for cfg in [
        GroundConfig { supersample: 0, ..ok },
        GroundConfig { supersample: 9, ..ok },
        GroundConfig { k1: f64::NAN, ..ok },
        GroundConfig { k1: 0.8, ..ok },
        GroundConfig { vignetting: 1.0, ..ok },
        GroundConfig { vignetting: -0.1, ..ok },
    ] {
        assert!(GroundScene::new(cfg, textures()).is_err(), "{cfg:?}");
    }
    assert!(GroundScene::new(ok.real_camera(), textures()).is_ok());
}

#[test]
fn a_rolling_shutter_shows_each_row_at_its_own_time() {
    // Straight ahead at 2 px per frame, rows read over the whole frame interval: the top row
    // is seen half a frame early, when the floor lay 1 px higher in the image (image y points
    // backwards), the bottom row half a frame late, the middle row on time.
    let still = GroundConfig {
        height: 65,
        forward_px: 2.0,
        forward_spread_px: 0.0,
        lateral_px: 0.0,
        yaw_deg: 0.0,
        yaw_spread_deg: 0.0,
        ..small(GroundTexture::Gravel)
    };
    let global = GroundScene::new(still, textures()).unwrap().frame(5).unwrap();
    let rolling =
        GroundScene::new(GroundConfig { rolling_shutter: 1.0, ..still }, textures()).unwrap().frame(5).unwrap();
    let close = |a: &[u8], b: &[u8]| a.iter().zip(b).all(|(p, q)| p.abs_diff(*q) <= 1);
    assert!(close(rolling.row(32), global.row(32)));
    assert!(close(rolling.row(0), global.row(1)));
    assert!(close(rolling.row(64), global.row(63)));
    assert!(!close(rolling.row(0), global.row(0)), "the top row moved");
    assert!(GroundScene::new(GroundConfig { rolling_shutter: 1.5, ..still }, textures()).is_err());
}
