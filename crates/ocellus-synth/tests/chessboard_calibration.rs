//! Calibration from rendered images: views of a chessboard over a real photo, rendered through
//! a known distorted camera with sensor noise; the corners are detected and the camera is
//! calibrated from them, and both are compared with the truth.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use ocellus_geometry::camera::Intrinsics;
use ocellus_geometry::chessboard::{find_chessboard, ChessboardOptions};
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::zhang::{calibrate, PlanarView, ZhangOptions};
use ocellus_image::resample::{resize, ResampleMethod};
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;
use ocellus_synth::chessboard::{Board, BoardCamera};

fn background(w: usize, h: usize) -> Plane<f32> {
    let grey = ocellus_io::read_image(ocellus_testdata::asset("coffee.png")).unwrap().to_grey();
    resize(ocellus_image::Backend::Auto, &grey, w, h, ResampleMethod::Bilinear).unwrap()
}

#[test]
fn detected_corners_calibrate_the_rendering_camera() {
    let k = Intrinsics { fx: 640.0, fy: 636.0, cx: 324.0, cy: 236.0, skew: 0.0 };
    let d = Distortion { k1: -0.22, k2: 0.06, k3: 0.0, p1: 0.0008, p2: -0.0005 };
    let cam = BoardCamera::new(k, d, 640, 480).unwrap();
    let board = Board::new(9, 6, 25.0).unwrap();
    let bg = background(640, 480);
    let mut rng = SplitMix64::new(11);
    let mut views = Vec::new();
    let (mut sq, mut n, mut worst) = (0.0, 0usize, 0.0f64);
    for v in 0..10 {
        let pose = cam.random_pose(&board, 0.7, &mut rng).unwrap();
        let img = cam.render(&board, &pose, Some(&bg), 3, 2.0, v).unwrap();
        let found = find_chessboard(&img, 9, 6, &ChessboardOptions::default()).unwrap();
        let truth = cam.corners(&board, &pose).unwrap();
        // The detector may return the board turned by 180 degrees.
        let same = (found[0][0] - truth[0][0]).hypot(found[0][1] - truth[0][1]);
        let turned = (found[0][0] - truth[53][0]).hypot(found[0][1] - truth[53][1]);
        let truth: Vec<[f64; 2]> = if same <= turned { truth } else { truth.into_iter().rev().collect() };
        for (f, t) in found.iter().zip(&truth) {
            let e = (f[0] - t[0]).hypot(f[1] - t[1]);
            sq += e * e;
            n += 1;
            worst = worst.max(e);
        }
        views.push(PlanarView { object: board.inner_corners(), image: found });
    }
    let rms = (sq / n as f64).sqrt();
    println!("corner error over 10 views: rms {rms:.4} px, worst {worst:.4} px");
    assert!(rms < 0.1 && worst < 0.4, "corner rms {rms}, worst {worst}");
    let cal = calibrate(&views, &ZhangOptions::default()).unwrap();
    let e = &cal.intrinsics;
    println!(
        "calibrated: fx {:.2} fy {:.2} cx {:.2} cy {:.2} k1 {:.4} k2 {:.4} p1 {:.5} p2 {:.5} k3 {:.4}, rms {:.4} px",
        e.fx,
        e.fy,
        e.cx,
        e.cy,
        cal.distortion.k1,
        cal.distortion.k2,
        cal.distortion.p1,
        cal.distortion.p2,
        cal.distortion.k3,
        cal.rms_px
    );
    assert!((e.fx - k.fx).abs() / k.fx < 0.005 && (e.fy - k.fy).abs() / k.fy < 0.005, "{e:?}");
    assert!((e.cx - k.cx).abs() < 2.0 && (e.cy - k.cy).abs() < 2.0, "{e:?}");
    // Distortion is compared by its effect where the boards were seen: each corner pixel
    // undistorted by the true and by the calibrated camera must land at the same place
    // (k3 is free, as in OpenCV, so beyond the boards the polynomial may differ).
    let mut worst_undist = 0.0f64;
    for v in &views {
        for p in &v.image {
            let a = d.undistort_pixel(&k, p[0], p[1]).unwrap();
            let b = cal.distortion.undistort_pixel(e, p[0], p[1]).unwrap();
            worst_undist = worst_undist.max((a.0 - b.0).hypot(a.1 - b.1));
        }
    }
    println!("undistortion difference over the seen corners: worst {worst_undist:.3} px");
    assert!(worst_undist < 1.0, "undistortion differs by {worst_undist} px");
    // With k3 held at its true value 0, k1 and k2 themselves come back.
    let fixed = calibrate(&views, &ZhangOptions { k3: false, ..Default::default() }).unwrap();
    println!("k3 fixed: k1 {:.4} k2 {:.4}", fixed.distortion.k1, fixed.distortion.k2);
    assert!(
        (fixed.distortion.k1 - d.k1).abs() < 0.01 && (fixed.distortion.k2 - d.k2).abs() < 0.02,
        "{:?}",
        fixed.distortion
    );
    assert!(cal.rms_px < 0.15, "reprojection rms {}", cal.rms_px);
}

#[test]
fn a_missing_board_is_a_clear_error() {
    let bg = background(320, 240);
    let err = find_chessboard(&bg, 9, 6, &ChessboardOptions::default()).unwrap_err();
    assert!(err.to_string().contains("not found"), "{err}");
    let flat = Plane::from_fn(64, 64, |_, _| 0.5f32);
    assert!(find_chessboard(&flat, 9, 6, &ChessboardOptions::default()).is_err());
}
