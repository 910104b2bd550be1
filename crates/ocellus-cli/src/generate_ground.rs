//! `ocellus generate ground` (also `ocellus synth ground`): a ground-facing camera over a
//! floor of real textures with known planar motion, for visual odometry.

use crate::assets;
use crate::ranges;
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use ocellus_geometry::camera::Intrinsics;
use ocellus_geometry::camera_file::{self, CameraFile};
use ocellus_geometry::distortion::Distortion;
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use ocellus_io::tum::TumPose;
use ocellus_io::y4m::Y4mWriter;
use ocellus_synth::ground::{encoders, GroundConfig, GroundScene, GroundTexture, FOCAL_PX};
use std::io::Write;
use std::path::PathBuf;

/// Floor texture.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TextureArg {
    /// Brick paving.
    Brick,
    /// Grass.
    Grass,
    /// Gravel.
    Gravel,
    /// Tiles of all three.
    Mosaic,
    /// Dim, smoothed grass with 8 grey levels of texture.
    LowContrast,
    /// Gravel shrunk by 4: grains a few pixels across.
    FineGrained,
    /// A 20-pixel square of gravel repeated (periodic with the seed's search window).
    Repetitive,
}

/// Arguments of `ocellus generate ground`.
#[derive(Args, Debug)]
pub struct GroundArgs {
    /// Floor texture.
    #[arg(long, value_enum, default_value = "mosaic")]
    texture: TextureArg,
    /// Seed of the tiles, the motion and the noise. Range: any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The hard variant: noise sigma 5, motion blur, +-5 % gain flicker, +-1 % height oscillation.
    #[arg(long)]
    hard: bool,
    /// Number of frames (200 Hz). Range: 2..=100000.
    #[arg(long, default_value_t = 200, value_parser = ranges::within(2usize, 100_000))]
    frames: usize,
    /// Write one Y4M video instead of PNG frames.
    #[arg(long)]
    y4m: bool,
    /// Render as a real camera sees: pixels integrating light over their area (2x2 samples),
    /// lens distortion k1 = -0.05 (in camera.toml, so that odometry undistorts it) and 25 %
    /// vignetting at the corners; --supersample, --k1 and --vignetting override each part.
    #[arg(long)]
    real_camera: bool,
    /// Point samples per pixel side, averaged over the pixel's area (1: one point sample at
    /// the pixel's centre). Default 1, or 2 with --real-camera. Range: 1..=8.
    #[arg(long, value_parser = ranges::within(1usize, 8))]
    supersample: Option<usize>,
    /// Radial lens distortion k1 (normalized coordinates, focal 600 px), written to
    /// camera.toml. Default 0, or -0.05 with --real-camera. Range: -0.5..=0.5.
    #[arg(long, value_parser = ranges::within(-0.5f64, 0.5), allow_hyphen_values = true)]
    k1: Option<f64>,
    /// Brightness lost at the image corners (0.25: corners at 75 %). Default 0, or 0.25 with
    /// --real-camera. Range: 0..=0.95.
    #[arg(long, value_parser = ranges::within(0.0f32, 0.95))]
    vignetting: Option<f32>,
    /// Rolling shutter: rows read from top to bottom over this fraction of the frame interval,
    /// each row seen at its own pose (the frame's timestamp is the middle row's; 0: a global
    /// shutter). Range: 0..=1.
    #[arg(long, default_value_t = 0.0, value_parser = ranges::within(0.0f64, 1.0))]
    rolling_shutter: f64,
    /// Output folder: frames/frame_NNNNN.png (or sequence.y4m), groundtruth.tum (the robot's
    /// rotation centre, metres), encoders.csv (30 Hz wheel odometry with slip events; the true
    /// slip per reading in encoder_slips.csv),
    /// camera.toml (focal 600 px, height 0.3 m, mount 5 cm ahead: 0.5 mm per ground pixel).
    #[arg(long, default_value = "ocellus-ground")]
    out: PathBuf,
}

/// The floor textures (brick, grass, gravel) of the built-in assets, grey in [0, 1].
pub fn textures() -> Result<[Plane<f32>; 3]> {
    let load = |name: &str| -> Result<Plane<f32>> { Ok(assets::decode(name)?.to_grey()) };
    Ok([load("brick.png")?, load("grass.png")?, load("gravel.png")?])
}

/// Runs the subcommand.
pub fn run(a: GroundArgs) -> Result<()> {
    let texture = match a.texture {
        TextureArg::Brick => GroundTexture::Brick,
        TextureArg::Grass => GroundTexture::Grass,
        TextureArg::Gravel => GroundTexture::Gravel,
        TextureArg::Mosaic => GroundTexture::Mosaic,
        TextureArg::LowContrast => GroundTexture::LowContrast,
        TextureArg::FineGrained => GroundTexture::FineGrained,
        TextureArg::Repetitive => GroundTexture::Repetitive,
    };
    let base = if a.hard { GroundConfig::hard(texture, a.seed) } else { GroundConfig::easy(texture, a.seed) };
    let base = if a.real_camera { base.real_camera() } else { base };
    let cfg = GroundConfig {
        frames: a.frames,
        supersample: a.supersample.unwrap_or(base.supersample),
        k1: a.k1.unwrap_or(base.k1),
        vignetting: a.vignetting.unwrap_or(base.vignetting),
        rolling_shutter: a.rolling_shutter,
        ..base
    };
    let scene = GroundScene::new(cfg, textures()?)?;
    crate::output_files::create_dir(&a.out)?;
    let create =
        |name: &str| -> Result<crate::output_files::OutputFile> { crate::output_files::create_file(&a.out.join(name)) };
    let mut y4m =
        if a.y4m { Some(Y4mWriter::new(create("sequence.y4m")?, cfg.width, cfg.height, (200, 1))?) } else { None };
    if !a.y4m {
        crate::output_files::create_dir(&a.out.join("frames"))?;
    }
    let mut truth = Vec::with_capacity(scene.len());
    for k in 0..scene.len() {
        let f = scene.frame(k)?;
        match &mut y4m {
            Some(w) => w.write_frame(&RgbImage::U8(f.map(|v| [v, v, v])))?,
            None => {
                ocellus_io::write_png(a.out.join("frames").join(format!("frame_{k:05}.png")), &f)?;
            }
        }
        let (x, y, th) = scene.pose_m(k).context("pose")?;
        truth.push(TumPose::planar(scene.time_s(k), x, y, th));
    }
    if let Some(w) = y4m {
        w.finish()?;
    }
    ocellus_io::tum::write(a.out.join("groundtruth.tum"), &truth)?;
    // What the wheels report, in the layout `ocellus odometry --encoders` reads; the slip they
    // cannot know is ground truth and goes to its own file.
    let mut enc = create("encoders.csv")?;
    let mut slips = create("encoder_slips.csv")?;
    writeln!(enc, "time_s,forward_m,yaw_rad")?;
    writeln!(slips, "time_s,slip_m")?;
    for e in encoders(&scene, 30.0, 0.5, 0.002, a.seed)? {
        writeln!(enc, "{:.6},{:.9},{:.9}", e.time_s, e.forward_m, e.yaw_rad)?;
        writeln!(slips, "{:.6},{:.6}", e.time_s, e.slip_m)?;
    }
    enc.flush()?;
    slips.flush()?;
    // 0.3 m over a focal of 600 px: one ground pixel is the config's 0.5 mm.
    let cam = CameraFile {
        image_size: Some([cfg.width, cfg.height]),
        intrinsics: Intrinsics::centred(FOCAL_PX, cfg.width, cfg.height),
        distortion: Distortion { k1: cfg.k1, ..Distortion::default() },
        height_m: Some(0.3),
        mount_right_m: Some(cfg.mount_px[0] * cfg.metres_per_px),
        mount_forward_m: Some(cfg.mount_px[1] * cfg.metres_per_px),
    };
    camera_file::write(&a.out.join("camera.toml"), &cam)?;
    outln!(
        "{} frames {}x{} ({}{}) written to {} with groundtruth.tum, encoders.csv, encoder_slips.csv, camera.toml",
        scene.len(),
        cfg.width,
        cfg.height,
        texture.name(),
        match (a.hard, cfg.supersample > 1 || cfg.k1 != 0.0 || cfg.vignetting > 0.0) {
            (false, false) => "",
            (true, false) => ", hard",
            (false, true) => ", real camera",
            (true, true) => ", hard, real camera",
        },
        a.out.display()
    );
    Ok(())
}
