//! Camera calibration from generated chessboard views: a 9x6 board over a real photograph,
//! rendered through a known distorted camera with sensor noise; the corners are detected and
//! Zhang's method with Levenberg-Marquardt recovers the camera, compared with the truth.
//!
//! `cargo run --release -p ocellus-synth --example calibrate_chessboards`

use ocellus_geometry::camera::Intrinsics;
use ocellus_geometry::chessboard::{find_chessboard, ChessboardOptions};
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::zhang::{calibrate, PlanarView, ZhangOptions};
use ocellus_image::resample::{resize, ResampleMethod};
use ocellus_image::rng::SplitMix64;
use ocellus_synth::chessboard::{Board, BoardCamera};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let truth = Intrinsics { fx: 640.0, fy: 636.0, cx: 324.0, cy: 236.0, skew: 0.0 };
    let lens = Distortion { k1: -0.22, k2: 0.06, k3: 0.0, p1: 0.0008, p2: -0.0005 };
    let camera = BoardCamera::new(truth, lens, 640, 480)?;
    let board = Board::new(9, 6, 25.0)?; // 25 mm squares
    let photo = ocellus_io::read_image(ocellus_testdata::asset("coffee.png"))?.to_grey();
    let background = resize(ocellus_image::Backend::Auto, &photo, 640, 480, ResampleMethod::Bilinear)?;
    let mut rng = SplitMix64::new(7);
    let mut views = Vec::new();
    for k in 0..10 {
        let pose = camera.random_pose(&board, 0.7, &mut rng)?;
        // 3x3 supersampling, noise sigma 2 grey levels.
        let image = camera.render(&board, &pose, Some(&background), 3, 2.0, k)?;
        match find_chessboard(&image, 9, 6, &ChessboardOptions::default()) {
            Ok(corners) => views.push(PlanarView { object: board.inner_corners(), image: corners }),
            Err(e) => println!("view {k}: skipped ({e})"),
        }
    }
    let cal = calibrate(&views, &ZhangOptions::default())?;
    let k = &cal.intrinsics;
    println!("{} views, reprojection RMS {:.4} px", views.len(), cal.rms_px);
    println!(
        "fx {:.2} (true {}), fy {:.2} ({}), cx {:.2} ({}), cy {:.2} ({})",
        k.fx, truth.fx, k.fy, truth.fy, k.cx, truth.cx, k.cy, truth.cy
    );
    println!("k1 {:.4} (true {}), k2 {:.4} ({})", cal.distortion.k1, lens.k1, cal.distortion.k2, lens.k2);
    Ok(())
}
