//! `ocellus generate ball`: a coloured ball moving in 3D in front of a real photo, filmed by
//! a known camera: frames, per-frame truth and the camera file (tracking ground truth).

use crate::assets;
use crate::ranges;
use anyhow::Result;
use clap::{Args, ValueEnum};
use ocellus_geometry::camera_file::{self, CameraFile};
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use ocellus_io::y4m::Y4mWriter;
use ocellus_synth::ball_world::{BallTruth, BallWorld, BallWorldConfig, Occlusion, Trajectory};
use std::io::Write;
use std::path::{Path, PathBuf};

/// How the ball moves.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TrajectoryArg {
    /// A lob from the left, bouncing on the floor (gravity).
    Throw,
    /// Dropped, bouncing while drifting away (gravity).
    Bounce,
    /// Towards the camera and away again, weaving sideways (no gravity).
    Approach,
}

/// Occluders in front of the ball.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum OcclusionArg {
    /// None.
    None,
    /// A pillar hiding up to half of the ball.
    Partial,
    /// A panel hiding it wholly for --occluded-frames frames.
    Full,
    /// Both.
    Both,
}

/// Background photo.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum BackgroundArg {
    /// A rocket on its launch pad (sky, rocket, grass).
    Rocket,
    /// An astronaut's portrait (with orange patches: hard for an orange ball).
    Astronaut,
    /// A cat.
    Chelsea,
    /// A cup of coffee (orange-brown: hard).
    Coffee,
}

/// Arguments of `ocellus generate ball`.
#[derive(Args, Debug)]
pub struct BallArgs {
    /// How the ball moves.
    #[arg(long, value_enum, default_value = "throw")]
    trajectory: TrajectoryArg,
    /// Number of frames. Range: 6..=100000.
    #[arg(long, default_value_t = 60, value_parser = ranges::within(6usize, 100_000))]
    frames: usize,
    /// Frame rate, Hz. Range: 1..=1000.
    #[arg(long, default_value_t = 30.0, value_parser = ranges::within(1.0f64, 1000.0))]
    fps: f64,
    /// Occluders (patches of the gravel photo).
    #[arg(long, value_enum, default_value = "both")]
    occlusion: OcclusionArg,
    /// Frames of full occlusion. Range: 1..=1000, and 4 below --frames.
    #[arg(long, default_value_t = 10, value_parser = ranges::within(1usize, 1000))]
    occluded_frames: usize,
    /// Add a static second ball of a similar, redder colour.
    #[arg(long)]
    distractor: bool,
    /// Dim the light to 65 % (blue to 55 %) over the middle fifth of the sequence.
    #[arg(long)]
    lighting_change: bool,
    /// Sensor noise, standard deviation in 8-bit levels. Range: 0..=100.
    #[arg(long, default_value_t = 3.0, value_parser = ranges::within(0.0f64, 100.0))]
    noise: f64,
    /// Ball radius, metres. Range: 0.005..=1.
    #[arg(long, default_value_t = 0.05, value_parser = ranges::within(0.005f64, 1.0))]
    radius_m: f64,
    /// Background photo.
    #[arg(long, value_enum, default_value = "rocket")]
    background: BackgroundArg,
    /// Seed of the start's jitter and the noise. Range: any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write one Y4M video instead of PNG frames.
    #[arg(long)]
    y4m: bool,
    /// Output folder: frames/frame_NNNNN.png (or sequence.y4m), truth.csv (per frame: time,
    /// 3D centre and velocity, image circle, visible fraction), camera.toml (640x480, focal
    /// 600 px, barrel distortion; world = camera frame, y down).
    #[arg(long, default_value = "ocellus-ball")]
    out: PathBuf,
}

/// The header of truth.csv.
pub const TRUTH_HEADER: &str = "frame,time_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,u_px,v_px,r_px,visible_fraction";

/// Loads a built-in photo as f32 RGB (0..255).
pub fn photo(name: &str) -> Result<Plane<[f32; 3]>> {
    Ok(assets::decode(name)?.to_u8().map(|p| p.map(f32::from)))
}

/// The file name of a background choice.
pub fn background_file(b: BackgroundArg) -> &'static str {
    match b {
        BackgroundArg::Rocket => "rocket.jpg",
        BackgroundArg::Astronaut => "astronaut.png",
        BackgroundArg::Chelsea => "chelsea.png",
        BackgroundArg::Coffee => "coffee.png",
    }
}

/// Writes one truth row (`r_px` 0 when the ball is not in front of the camera).
pub fn write_truth_row(w: &mut impl Write, t: &BallTruth) -> std::io::Result<()> {
    let [u, v, r] = t.circle.unwrap_or([0.0; 3]);
    let (p, q) = (t.position, t.velocity);
    writeln!(
        w,
        "{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{u:.3},{v:.3},{r:.3},{:.4}",
        t.frame, t.time_s, p[0], p[1], p[2], q[0], q[1], q[2], t.visible_fraction
    )
}

/// The library's occlusion choice.
pub fn occlusion_of(a: OcclusionArg) -> Occlusion {
    match a {
        OcclusionArg::None => Occlusion::None,
        OcclusionArg::Partial => Occlusion::Partial,
        OcclusionArg::Full => Occlusion::Full,
        OcclusionArg::Both => Occlusion::Both,
    }
}

/// Runs the subcommand.
pub fn run(a: BallArgs) -> Result<()> {
    let trajectory = match a.trajectory {
        TrajectoryArg::Throw => Trajectory::Throw,
        TrajectoryArg::Bounce => Trajectory::Bounce,
        TrajectoryArg::Approach => Trajectory::Approach,
    };
    let occlusion = occlusion_of(a.occlusion);
    let cfg = BallWorldConfig {
        frames: a.frames,
        fps: a.fps,
        occlusion,
        full_occlusion_frames: a.occluded_frames,
        distractor: a.distractor,
        lighting_change: a.lighting_change,
        noise_sigma: a.noise,
        radius_m: a.radius_m,
        ..BallWorldConfig::new(trajectory, a.seed)
    };
    let world = BallWorld::new(cfg, &photo(background_file(a.background))?, &photo("gravel.png")?)?;
    write_world(&world, &a.out, a.y4m)?;
    outln!(
        "{} frames {}x{} ({:?}, {:?} occlusion{}{}) written to {} with truth.csv and camera.toml",
        world.len(),
        cfg.width,
        cfg.height,
        trajectory,
        occlusion,
        if a.distractor { ", distractor" } else { "" },
        if a.lighting_change { ", lighting change" } else { "" },
        a.out.display()
    );
    if let Some((y, e)) = trajectory.floor() {
        outln!("the floor is at y = {y} m (restitution {e}): track with --gravity 9.81 --floor-y {y}");
    }
    Ok(())
}

/// Writes the frames, truth.csv and camera.toml of `world` to `out`.
pub fn write_world(world: &BallWorld, out: &Path, y4m: bool) -> Result<()> {
    let cfg = world.config();
    crate::output_files::create_dir(out)?;
    let create = |name: &str| crate::output_files::create_file(&out.join(name));
    let fps = (cfg.fps.round() as u32).max(1);
    let mut video =
        if y4m { Some(Y4mWriter::new(create("sequence.y4m")?, cfg.width, cfg.height, (fps, 1))?) } else { None };
    if !y4m {
        crate::output_files::create_dir(&out.join("frames"))?;
    }
    let mut truth = create("truth.csv")?;
    writeln!(truth, "{TRUTH_HEADER}")?;
    for k in 0..world.len() {
        let (f, t) = world.frame(k)?;
        match &mut video {
            Some(w) => w.write_frame(&RgbImage::U8(f))?,
            None => ocellus_io::write_png(out.join("frames").join(format!("frame_{k:05}.png")), &f)?,
        }
        write_truth_row(&mut truth, &t)?;
    }
    if let Some(w) = video {
        w.finish()?;
    }
    truth.flush()?;
    let cam = CameraFile {
        image_size: Some([cfg.width, cfg.height]),
        intrinsics: world.camera().k,
        distortion: cfg.distortion,
        height_m: None,
        mount_right_m: None,
        mount_forward_m: None,
    };
    camera_file::write(&out.join("camera.toml"), &cam)?;
    Ok(())
}
