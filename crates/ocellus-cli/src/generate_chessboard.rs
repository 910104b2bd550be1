//! `ocellus generate chessboard`: views of a chessboard through a known distorted camera, with
//! the true camera and corners, for trying and checking calibration.

use crate::assets;
use crate::calibrate_planar::{parse_length_mm, parse_pair};
use crate::ranges;
use anyhow::{Context, Result};
use clap::Args;
use ocellus_geometry::camera::Intrinsics;
use ocellus_geometry::camera_file::{self, CameraFile};
use ocellus_geometry::distortion::Distortion;
use ocellus_image::resample::{resize, ResampleMethod};
use ocellus_image::rng::SplitMix64;
use ocellus_synth::chessboard::{Board, BoardCamera};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `ocellus generate chessboard`.
#[derive(Args, Debug)]
pub struct ChessboardArgs {
    /// Output folder: view_NN.png, camera_truth.toml, corners_truth.csv (`view,X,Y,u,v`, the
    /// input format of `ocellus calibrate planar`).
    #[arg(long, default_value = "ocellus-chessboard")]
    out: PathBuf,
    /// Number of views. Range: 1..=1000.
    #[arg(long, default_value_t = 12, value_parser = ranges::within(1usize, 1000))]
    views: usize,
    /// Inner corners per row x per column. Range: 2..=64 each.
    #[arg(long, default_value = "9x6")]
    board: String,
    /// Square side with unit (`25mm`, `2.5cm`); board coordinates in the CSV are millimetres.
    /// Range: above 0, at most 1000 m.
    #[arg(long, default_value = "25mm")]
    square: String,
    /// Camera to render through (camera file); default: 640x480, fx 640, fy 636, k1 -0.22,
    /// k2 0.06, p1 0.0008, p2 -0.0005.
    #[arg(long)]
    camera: Option<PathBuf>,
    /// Largest board tilt, degrees. Range: 0..=70.
    #[arg(long, default_value_t = 40.0, value_parser = ranges::within(0.0f64, 70.0))]
    max_tilt_deg: f64,
    /// Sensor noise, standard deviation in grey levels. Range: 0..=100.
    #[arg(long, default_value_t = 2.0, value_parser = ranges::within(0.0f32, 100.0))]
    noise: f32,
    /// Seed of the poses and the noise. Range: any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs the subcommand.
pub fn run(a: ChessboardArgs) -> Result<()> {
    let (cols, rows) = parse_pair(&a.board, "--board", crate::calibrate_planar::BOARD_RANGE)?;
    let board = Board::new(cols, rows, parse_length_mm(&a.square)?)?;
    let truth = match &a.camera {
        Some(p) => camera_file::read(p)?,
        None => CameraFile {
            image_size: Some([640, 480]),
            intrinsics: Intrinsics { fx: 640.0, fy: 636.0, cx: 324.0, cy: 236.0, skew: 0.0 },
            distortion: Distortion { k1: -0.22, k2: 0.06, k3: 0.0, p1: 0.0008, p2: -0.0005 },
            height_m: None,
            mount_right_m: None,
            mount_forward_m: None,
        },
    };
    let [w, h] = truth.image_size.context("the camera file needs image_size = [width, height] to render")?;
    let cam = BoardCamera::new(truth.intrinsics, truth.distortion, w, h)?;
    let photo = assets::decode("coffee.png")?.to_grey();
    let background = resize(ocellus_image::Backend::Auto, &photo, w, h, ResampleMethod::Bilinear)?;
    crate::output_files::create_dir(&a.out)?;
    camera_file::write(&a.out.join("camera_truth.toml"), &truth)?;
    let csv_path = a.out.join("corners_truth.csv");
    let mut csv = crate::output_files::create_file(&csv_path)?;
    writeln!(csv, "view,X_mm,Y_mm,u_px,v_px")?;
    let mut rng = SplitMix64::new(a.seed);
    for v in 0..a.views {
        let pose = cam.random_pose(&board, a.max_tilt_deg.to_radians(), &mut rng)?;
        let img = cam.render(&board, &pose, Some(&background), 3, a.noise, a.seed.wrapping_mul(1000) + v as u64)?;
        let grey = ocellus_image::convert::to_grey8(&img, 0.0, 1.0);
        ocellus_io::write_png(a.out.join(format!("view_{v:02}.png")), &grey)?;
        let corners = cam.corners(&board, &pose).context("a corner is behind the camera")?;
        for (o, p) in board.inner_corners().iter().zip(corners) {
            writeln!(csv, "{v},{},{},{:.6},{:.6}", o[0], o[1], p[0], p[1])?;
        }
    }
    csv.flush()?;
    outln!(
        "{} views of a {cols}x{rows} board written to {} (view_NN.png, camera_truth.toml, corners_truth.csv)",
        a.views,
        a.out.display()
    );
    Ok(())
}
