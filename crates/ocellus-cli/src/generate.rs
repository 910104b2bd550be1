//! `ocellus generate`: ground-truth sequences built from the built-in real images.

use crate::assets;
use crate::ranges;
use anyhow::Result;
use clap::{Args, Subcommand, ValueEnum};
use ocellus_io::y4m::Y4mWriter;
use ocellus_synth::attention_scenes::{Scenario, SceneConfig, SceneGenerator};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus generate`.
#[derive(Args, Debug)]
pub struct GenerateArgs {
    #[command(subcommand)]
    what: What,
}

#[derive(Subcommand, Debug)]
enum What {
    /// Sequences for surprise, context chaos and attention: a still scene with sensor noise, an
    /// object appearing suddenly, or a steady camera pan, over a panorama of the built-in photos.
    Attention(AttentionArgs),
    /// Views of a chessboard over a real photo, rendered through a known distorted camera, with
    /// the true camera and corner positions (try `ocellus calibrate chessboard` on them).
    Chessboard(crate::generate_chessboard::ChessboardArgs),
    /// A camera looking down at a floor of real textures (brick, grass, gravel, mosaic, and
    /// low-contrast, fine-grained and repetitive floors made from them) with known planar
    /// motion at 200 Hz: frames, TUM ground truth, wheel encoders (odometry).
    Ground(crate::generate_ground::GroundArgs),
    /// A shaded coloured ball thrown, bouncing or approaching in 3D in front of a real photo,
    /// through a known distorted camera, with occluders, a distractor, a lighting change and
    /// noise: frames, truth.csv and camera.toml (try `ocellus track` on them).
    Ball(crate::generate_ball::BallArgs),
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum ScenarioArg {
    Static,
    Sudden,
    Pan,
}

#[derive(Args, Debug)]
struct AttentionArgs {
    /// What happens.
    #[arg(long, value_enum, default_value = "sudden")]
    scenario: ScenarioArg,
    /// Output folder: frames/frame_NNNNN.png (or sequence.y4m), truth.csv, pan_tilt.csv.
    #[arg(long, default_value = "ocellus-sequence")]
    out: PathBuf,
    /// Number of frames. Range: 2..=100000.
    #[arg(long, default_value_t = 30, value_parser = ranges::within(2usize, 100_000))]
    frames: usize,
    /// First frame showing the object [default: 15]; `--scenario sudden` only. Range:
    /// 1..=100000, and below --frames.
    #[arg(long, value_parser = ranges::within(1usize, 100_000))]
    event_frame: Option<usize>,
    /// Seed of the sensor noise. Range: any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sensor noise, standard deviation in grey levels. Range: 0..=100.
    #[arg(long, default_value_t = 2.0, value_parser = ranges::within(0.0f32, 100.0))]
    noise: f32,
    /// Pan speed, pixels per frame [default: 6]; `--scenario pan` only. Range: -100..=100.
    #[arg(long, value_parser = ranges::within(-100.0f32, 100.0))]
    pan_px_per_frame: Option<f32>,
    /// Write one Y4M video instead of PNG frames.
    #[arg(long)]
    y4m: bool,
}

/// Coffee, rocket and astronaut side by side as the world; the cat as the sudden object.
pub fn scene(cfg: SceneConfig) -> Result<SceneGenerator> {
    let img = assets::decode;
    let world = [img("coffee.png")?, img("rocket.jpg")?, img("astronaut.png")?];
    Ok(SceneGenerator::new(cfg, &world, &img("chelsea.png")?)?)
}

struct Out {
    out: PathBuf,
    y4m: bool,
}

/// Runs the subcommand.
pub fn run(a: GenerateArgs) -> Result<()> {
    let a = match a.what {
        What::Attention(a) => a,
        What::Chessboard(a) => return crate::generate_chessboard::run(a),
        What::Ground(a) => return crate::generate_ground::run(a),
        What::Ball(a) => return crate::generate_ball::run(a),
    };
    let scenario = match a.scenario {
        ScenarioArg::Static => Scenario::Static,
        ScenarioArg::Sudden => Scenario::SuddenObject,
        ScenarioArg::Pan => Scenario::Pan,
    };
    if a.event_frame.is_some() && !matches!(scenario, Scenario::SuddenObject) {
        anyhow::bail!("--event-frame belongs to --scenario sudden; this scenario has no event");
    }
    if a.pan_px_per_frame.is_some() && !matches!(scenario, Scenario::Pan) {
        anyhow::bail!("--pan-px-per-frame belongs to --scenario pan; this scenario does not pan");
    }
    let (event_frame, pan_px_per_frame) = (a.event_frame.unwrap_or(15), a.pan_px_per_frame.unwrap_or(6.0));
    if matches!(scenario, Scenario::SuddenObject) && event_frame >= a.frames {
        anyhow::bail!("--event-frame {event_frame} must be below --frames {}: the object would never appear", a.frames);
    }
    let cfg = SceneConfig {
        frames: a.frames,
        event_frame,
        seed: a.seed,
        noise_sigma: a.noise,
        pan_px_per_frame,
        ..SceneConfig::new(scenario)
    };
    write_sequence(cfg, &a.out, a.y4m)
}

/// Writes a sequence to `out`: frames/ (or sequence.y4m), truth.csv, pan_tilt.csv.
pub fn write_sequence(cfg: SceneConfig, out: &Path, y4m: bool) -> Result<()> {
    let scenario = cfg.scenario;
    let g = scene(cfg)?;
    let a = Out { out: out.to_path_buf(), y4m };
    crate::output_files::create_dir(&a.out)?;
    let create =
        |name: &str| -> Result<crate::output_files::OutputFile> { crate::output_files::create_file(&a.out.join(name)) };
    let mut truth = create("truth.csv")?;
    writeln!(truth, "frame,pan_deg,tilt_deg,object_x,object_y,object_w,object_h,event")?;
    let mut pan_tilt = create("pan_tilt.csv")?;
    writeln!(pan_tilt, "frame,pan_deg,tilt_deg")?;
    let c = g.config();
    let mut y4m = if a.y4m { Some(Y4mWriter::new(create("sequence.y4m")?, c.width, c.height, (30, 1))?) } else { None };
    let frames_dir = a.out.join("frames");
    if !a.y4m {
        crate::output_files::create_dir(&frames_dir)?;
    }
    for k in 0..g.len() {
        let (frame, t) = g.frame(k)?;
        match &mut y4m {
            Some(w) => w.write_frame(&frame)?,
            None => ocellus_io::write_png(frames_dir.join(format!("frame_{k:05}.png")), &frame.to_u8())?,
        }
        let o = t.object.map(|r| format!("{},{},{},{}", r.x, r.y, r.w, r.h)).unwrap_or_else(|| ",,,".into());
        writeln!(truth, "{k},{:.4},{:.4},{o},{}", t.pan_deg, t.tilt_deg, u8::from(t.event))?;
        writeln!(pan_tilt, "{k},{:.4},{:.4}", t.pan_deg, t.tilt_deg)?;
    }
    if let Some(w) = y4m {
        w.finish()?;
    }
    truth.flush()?;
    pan_tilt.flush()?;
    outln!(
        "{} frames {}x{} ({}) written to {} ({}), with truth.csv and pan_tilt.csv",
        g.len(),
        c.width,
        c.height,
        format!("{scenario:?}").to_lowercase(),
        a.out.display(),
        if a.y4m { "sequence.y4m" } else { "frames/" }
    );
    Ok(())
}
