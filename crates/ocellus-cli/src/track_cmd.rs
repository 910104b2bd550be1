//! `ocellus track`: the 3D ball tracker on frames (an image folder, a Y4M or a video);
//! `ocellus track eval`: a track against truth; `ocellus track study`: the accuracy figures
//! on generated sequences.

use crate::frames::for_each_frame;
use crate::generate_ball::{photo, TRUTH_HEADER};
use crate::plot::{self, Plot, Series};
use crate::ranges;
use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use ocellus_eval::tracking::{score, EstimateFrame, TrackingScores, TruthFrame};
use ocellus_geometry::camera::PinholeCamera;
use ocellus_geometry::camera_file;
use ocellus_image::{draw, Plane};
use ocellus_io::video_writer::VideoWriter;
use ocellus_sim::ball_tracking::study;
use ocellus_synth::ball_world::Trajectory;
use ocellus_tracking::colour::{Circle, ColourModel};
use ocellus_tracking::motion::Floor;
use ocellus_tracking::tracker::{BallTracker, TrackEstimate, TrackerConfig, DEFAULT_PARTICLES, MAX_PARTICLES};
use plotters::style::RGBColor;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus track`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct TrackArgs {
    #[command(subcommand)]
    sub: Option<Sub>,
    /// Frames: an image folder, a Y4M file or a video.
    #[arg(required = true)]
    input: Option<PathBuf>,
    /// Camera file (TOML/JSON): intrinsics and distortion; world = camera frame (x right, y
    /// down, z forward).
    #[arg(long, required = true)]
    camera: Option<PathBuf>,
    /// Ball radius, metres. Range: above 0, at most 10.
    #[arg(long, required = true, value_parser = ranges::above(0.0f64, 10.0))]
    radius_m: Option<f64>,
    /// The ball's colour model from a disc of the first frame: `x,y,r` in pixels.
    #[arg(long, conflicts_with = "colour")]
    patch: Option<String>,
    /// The ball's colour model from one colour: `r,g,b` (0..255).
    #[arg(long)]
    colour: Option<String>,
    /// Number of particles. Range: 1..=2000000.
    #[arg(long, default_value_t = DEFAULT_PARTICLES, value_parser = ranges::within(1usize, MAX_PARTICLES))]
    particles: usize,
    /// Share alpha of particles drawn from colour-blob detections (0: plain SIR). Range: 0..=1.
    #[arg(long, default_value_t = 0.2, value_parser = ranges::within(0.0f64, 1.0))]
    boost: f64,
    /// Gravity along the camera's y axis (down), m/s^2 (9.81 for a thrown ball filmed by a
    /// level camera). Range: -100..=100.
    #[arg(long, default_value_t = 0.0, value_parser = ranges::within(-100.0f64, 100.0))]
    gravity: f64,
    /// Height of a level floor the ball bounces on: camera-frame y (down) of the floor,
    /// metres (`generate ball` prints it). Default: no floor. Range: -1000..=1000.
    #[arg(long, value_parser = ranges::within(-1000.0f64, 1000.0))]
    floor_y: Option<f64>,
    /// Share of its speed into the floor that a bounce keeps (with --floor-y). Range: 0..=1.
    #[arg(long, default_value_t = 0.8, value_parser = ranges::within(0.0f64, 1.0))]
    restitution: f64,
    /// White acceleration noise of the motion model, m/s^2. Range: above 0, at most 1000.
    #[arg(long, default_value_t = 10.0, value_parser = ranges::above(0.0f64, 1000.0))]
    accel_sigma: f64,
    /// Frame rate, Hz. Range: above 0, at most 100000.
    #[arg(long, default_value_t = 30.0, value_parser = ranges::above(0.0f64, 1e5))]
    fps: f64,
    /// Seed of the filter. Range: any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Ground truth (truth.csv of `generate ball`): adds error.png and prints the scores.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Write no overlay PNGs (the mp4 still, when ffmpeg is there).
    #[arg(long)]
    no_overlays: bool,
    /// Also log the run for the Rerun viewer to this .rrd file: frames, up to 1000 particles
    /// (in the image and in 3D), the estimate (circle and centre), the truth with --truth,
    /// and per frame the ESS, the colour score and, with --truth, the 3D and image-centre
    /// errors (needs ocellus built with the `rerun` feature).
    #[arg(long)]
    rrd: Option<PathBuf>,
    /// Output folder: track.csv, overlays/frame_NNNNN.png (particles in yellow, the
    /// estimated circle in green, red when lost), overlays.mp4 (with ffmpeg), error.png (with
    /// --truth).
    #[arg(long, default_value = "ocellus-track")]
    out: PathBuf,
}

#[derive(Subcommand, Debug)]
enum Sub {
    /// Score a track.csv against a truth.csv: 3D RMSE (% of the mean depth), median
    /// image-centre error, lost frames, re-acquisition delay after each full occlusion.
    Eval(EvalArgs),
    /// The active stereo head: a pan-tilt head with two verging eyes keeps a generated ball in
    /// both foveas (tracker on the left eye, saccades on the main sequence, smooth pursuit,
    /// vergence from the log-polar fovea) at 60 Hz of simulated time.
    Head(HeadArgs),
    /// The accuracy study: generated sequences (thrown, bouncing, approaching; both occluders;
    /// noise) x seeds, tracked by the plain SIR and the boosted filter.
    Study(StudyArgs),
}

#[derive(Args, Debug)]
struct EvalArgs {
    /// The track (track.csv of `ocellus track`).
    track: PathBuf,
    /// The truth (truth.csv of `ocellus generate ball`).
    truth: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
struct HeadArgs {
    /// How the ball moves.
    #[arg(long, value_enum, default_value = "throw")]
    trajectory: crate::generate_ball::TrajectoryArg,
    /// Seed of the world and the filter. Range: any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Control steps (60 Hz of simulated time). Range: 2..=100000.
    #[arg(long, default_value_t = 120, value_parser = ranges::within(2usize, 100_000))]
    steps: usize,
    /// Particles of the tracker. Range: 1..=2000000.
    #[arg(long, default_value_t = 2000, value_parser = ranges::within(1usize, MAX_PARTICLES))]
    particles: usize,
    /// Output folder: gaze.csv (per step: time, pan, tilt, vergence in degrees, saccade,
    /// both foveal errors, disparity, lost), gaze.png (angles and errors over time),
    /// eyes/step_NNNNN.png (what the left and right eye saw, side by side, fovea marked).
    #[arg(long, default_value = "ocellus-head")]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct StudyArgs {
    /// Seeds, comma separated (each a world and a filter seed).
    #[arg(long, default_value = "1,2,3")]
    seeds: String,
    /// Particles. Range: 1..=2000000.
    #[arg(long, default_value_t = DEFAULT_PARTICLES, value_parser = ranges::within(1usize, MAX_PARTICLES))]
    particles: usize,
    /// Boost alpha of the boosted filter. Range: above 0, at most 1.
    #[arg(long, default_value_t = 0.2, value_parser = ranges::above(0.0f64, 1.0))]
    boost: f64,
    /// Occluders in the sequences.
    #[arg(long, value_enum, default_value = "both")]
    occlusion: crate::generate_ball::OcclusionArg,
    /// Add the static, redder distractor ball to every sequence.
    #[arg(long)]
    distractor: bool,
    /// Add the lighting change to every sequence.
    #[arg(long)]
    lighting_change: bool,
    /// Random streams per sequence: each is tracked this many times, the filter seeded by
    /// the world's seed (stream 0) and then by seeds far from every world's; the summary
    /// gives the median and mean of each stream, so that a change is judged against the
    /// spread the random stream alone makes. Range: 1..=20.
    #[arg(long, default_value_t = 1, value_parser = ranges::within(1u64, 20))]
    streams: u64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// The header of track.csv.
pub const TRACK_HEADER: &str = "frame,time_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,ess,u_px,v_px,r_px,score,lost,detections";

fn numbers<const N: usize>(s: &str, what: &str) -> Result<[f64; N]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .with_context(|| format!("{what} '{s}' is not {N} comma-separated numbers"))?;
    let a: [f64; N] = v.try_into().map_err(|_| anyhow::anyhow!("{what} '{s}' is not {N} comma-separated numbers"))?;
    if !a.iter().all(|x| x.is_finite()) {
        bail!("{what} '{s}' has a non-finite number");
    }
    Ok(a)
}

/// Runs the subcommand.
pub fn run(a: TrackArgs) -> Result<()> {
    match a.sub {
        Some(Sub::Eval(e)) => return eval(&e),
        Some(Sub::Study(s)) => return run_study(&s),
        Some(Sub::Head(h)) => return run_head_cmd(&h),
        None => {}
    }
    let (Some(input), Some(camera), Some(radius_m)) = (&a.input, &a.camera, a.radius_m) else {
        bail!("give the frames, --camera and --radius-m")
    };
    let cam = camera_file::read(camera)?;
    let patch = a.patch.as_deref().map(|s| numbers::<3>(s, "--patch")).transpose()?;
    let colour = a.colour.as_deref().map(|s| numbers::<3>(s, "--colour")).transpose()?;
    if patch.is_none() && colour.is_none() {
        bail!("give the ball's colour: --patch x,y,r (a disc of the first frame) or --colour r,g,b");
    }
    if let Some(c) = colour {
        if !c.iter().all(|v| (0.0..=255.0).contains(v)) {
            bail!("--colour {c:?}: each channel must be in 0..=255");
        }
    }
    let truth = a.truth.as_deref().map(read_truth).transpose()?;
    let mut cfg = TrackerConfig::at_fps(a.fps);
    cfg.particles = a.particles;
    cfg.boost = a.boost;
    cfg.filter.seed = a.seed;
    cfg.motion.gravity = [0.0, a.gravity, 0.0];
    cfg.motion.accel_sigma = a.accel_sigma;
    cfg.motion.floor = a.floor_y.map(|y| Floor::below(y, radius_m, a.restitution));
    crate::inputs::check_out_dir(&a.out, std::slice::from_ref(input))?;
    crate::output_files::create_dir(&a.out)?;
    if !a.no_overlays {
        crate::output_files::create_dir(&a.out.join("overlays"))?;
    }
    ocellus_io::video_writer::check_output(&a.out.join("overlays.mp4"))?;
    let mut csv = crate::output_files::create_file(&a.out.join("track.csv"))?;
    writeln!(csv, "{TRACK_HEADER}")?;
    let mut tracker: Option<BallTracker> = None;
    let mut video: Option<VideoWriter> = None;
    let mut estimates = Vec::new();
    let mut first_size: Option<(usize, usize)> = None;
    let pinhole = PinholeCamera { k: cam.intrinsics, r: nalgebra::Matrix3::identity(), t: nalgebra::Vector3::zeros() };
    let rrd = crate::rrd::open(a.rrd.as_deref(), "ocellus_track")?;
    if let Some(rec) = &rrd {
        rec.static_axes("world", true)?;
    }
    let t0 = std::time::Instant::now();
    let n = for_each_frame(input, None, |k, frame| {
        let f = frame.to_u8();
        if k == 0 {
            camera_file::check_frame_size(&cam, camera, "the first frame", f.size())?;
            let model = match (patch, colour) {
                (Some([x, y, r]), _) => ColourModel::from_patch(&f, Circle { x, y, r })?,
                (None, Some(c)) => ColourModel::from_colour(c.map(|v| v.round() as u8)),
                (None, None) => bail!("no colour model"),
            };
            tracker = Some(BallTracker::new(cfg, pinhole, cam.distortion, radius_m, model)?);
        } else if Some(f.size()) != first_size {
            bail!("frame {k} is {}x{}, unlike the first frame", f.width(), f.height());
        }
        first_size.get_or_insert(f.size());
        let Some(tr) = tracker.as_mut() else { bail!("no tracker") };
        let e = tr.process(&f)?;
        write_row(&mut csv, &e, a.fps)?;
        if let Some(rec) = &rrd {
            log_frame(rec, &f, &e, tr, truth.as_deref().and_then(|t| t.get(k)), radius_m, a.fps)?;
        }
        let over = overlay(&f, &e, tr);
        if !a.no_overlays {
            ocellus_io::write_png(a.out.join("overlays").join(format!("frame_{k:05}.png")), &over)?;
        }
        if k == 0 {
            video = VideoWriter::start(
                &a.out.join("overlays.mp4"),
                over.width(),
                over.height(),
                (a.fps.round() as u32).clamp(1, 1000),
            )?;
        }
        if let Some(v) = video.as_mut() {
            v.write(&over)?;
        }
        estimates.push(e);
        Ok(())
    })?;
    csv.flush()?;
    if let Some(v) = video {
        v.finish()?;
    }
    if let Some(rec) = rrd {
        rec.finish()?;
    }
    let secs = t0.elapsed().as_secs_f64();
    let lost = estimates.iter().filter(|e| e.lost).count();
    outln!(
        "{n} frames tracked in {secs:.2} s ({:.1} fps, {} particles, boost {}); lost in {lost}; wrote {}",
        n as f64 / secs.max(1e-9),
        a.particles,
        a.boost,
        a.out.join("track.csv").display()
    );
    if let Some(p) = &a.rrd {
        outln!("wrote {}", p.display());
    }
    if let Some(truth) = truth {
        let est: Vec<EstimateFrame> = estimates.iter().map(ocellus_sim::ball_tracking::estimate_frame).collect();
        if truth.len() != est.len() {
            bail!("the truth has {} frames, the input {}", truth.len(), est.len());
        }
        let s = score(&truth, &est)?;
        print_scores(&s)?;
        error_plot(&a.out.join("error.png"), &truth, &est)?;
        outln!("wrote {}", a.out.join("error.png").display());
    }
    Ok(())
}

fn write_row(w: &mut impl Write, e: &TrackEstimate, fps: f64) -> Result<()> {
    let (Some(p), Some(v)) = (e.position, e.velocity) else { return Ok(()) };
    let c = e.circle.map_or([0.0; 3], |c| [c.x, c.y, c.r]);
    writeln!(
        w,
        "{},{:.6},{:.6},{:.6},{:.6},{:.5},{:.5},{:.5},{:.1},{:.3},{:.3},{:.3},{:.4},{},{}",
        e.frame,
        e.frame as f64 / fps,
        p[0],
        p[1],
        p[2],
        v[0],
        v[1],
        v[2],
        e.ess,
        c[0],
        c[1],
        c[2],
        e.score,
        u8::from(e.lost),
        e.detections
    )?;
    Ok(())
}

/// One frame in the Rerun log (see `--rrd`); 3D in the camera frame (x right, y down, z
/// forward), metres.
fn log_frame(
    rec: &crate::rrd::Recorder,
    f: &Plane<[u8; 3]>,
    e: &TrackEstimate,
    tr: &BallTracker,
    truth: Option<&TruthFrame>,
    radius_m: f64,
    fps: f64,
) -> Result<()> {
    rec.at(e.frame, Some(e.frame as f64 / fps));
    rec.frame_rgb("frame", f)?;
    let ps = tr.particles();
    let step = ps.len().div_ceil(1000).max(1);
    let shown: Vec<_> = ps.iter().step_by(step).collect();
    let centres: Vec<[f64; 2]> = shown.iter().filter_map(|p| tr.model().circle(p)).map(|c| [c.x, c.y]).collect();
    rec.points_2d("frame/particles", &centres, 1.0, [255, 230, 0, 160])?;
    rec.points_3d("world/particles", &shown.iter().map(|p| p.position).collect::<Vec<_>>(), 0.003, [255, 200, 0, 160])?;
    if let Some(c) = e.circle {
        let colour = if e.lost { [230, 30, 30, 255] } else { [40, 230, 60, 255] };
        rec.circles_2d("frame/estimate", &[[c.x, c.y, c.r]], colour)?;
    }
    if let Some(p) = e.position {
        rec.points_3d("world/estimate", &[p], radius_m as f32, [40, 230, 60, 255])?;
    }
    rec.scalar("filter/ess", e.ess)?;
    rec.scalar("filter/score", e.score)?;
    if let Some(t) = truth {
        if let Some(c) = t.circle {
            rec.circles_2d("frame/truth", &[c], [60, 120, 255, 255])?;
            if let Some(ec) = e.circle {
                rec.scalar("error/centre_px", (ec.x - c[0]).hypot(ec.y - c[1]))?;
            }
        }
        rec.points_3d("world/truth", &[t.position], radius_m as f32, [60, 120, 255, 255])?;
        if let Some(p) = e.position {
            let d = (0..3).map(|i| (p[i] - t.position[i]).powi(2)).sum::<f64>().sqrt();
            rec.scalar("error/3d_m", d)?;
        }
    }
    Ok(())
}

/// The frame with up to 400 particles' centres (yellow) and the estimate's circle (green,
/// red when lost).
fn overlay(f: &Plane<[u8; 3]>, e: &TrackEstimate, tr: &BallTracker) -> Plane<[u8; 3]> {
    let mut img = f.clone();
    let ps = tr.particles();
    let step = (ps.len() / 400).max(1);
    for p in ps.iter().step_by(step) {
        if let Some(c) = tr.model().circle(p) {
            draw::dot(&mut img, [c.x, c.y], [255, 230, 0]);
        }
    }
    if let Some(c) = e.circle {
        let colour = if e.lost { [230, 30, 30] } else { [40, 230, 60] };
        draw::ring(&mut img, c.x as f32, c.y as f32, c.r as f32, colour);
        draw::ring(&mut img, c.x as f32, c.y as f32, c.r as f32 + 1.0, colour);
    }
    img
}

/// Reads truth.csv of `generate ball`.
fn read_truth(path: &Path) -> Result<Vec<TruthFrame>> {
    let rows = ocellus_io::csv::read_rows(path, 12, &format!("'{TRUTH_HEADER}'"))?;
    rows.iter()
        .enumerate()
        .map(|(k, r)| {
            if r[0] != k as f64 {
                bail!(
                    "{}: row {} is frame {}, expected frame {k} (one row per frame, in order)",
                    path.display(),
                    k + 1,
                    r[0]
                );
            }
            if !(0.0..=1.0).contains(&r[11]) {
                bail!("{}: frame {k}: visible_fraction {} is outside [0, 1]", path.display(), r[11]);
            }
            Ok(TruthFrame {
                position: [r[2], r[3], r[4]],
                circle: (r[10] > 0.0).then_some([r[8], r[9], r[10]]),
                visible_fraction: r[11],
            })
        })
        .collect()
}

/// Reads track.csv of `ocellus track` as one estimate per frame up to `frames` (frames
/// before the tracker started have none).
fn read_track(path: &Path, frames: usize) -> Result<Vec<EstimateFrame>> {
    let rows = ocellus_io::csv::read_rows(path, 15, &format!("'{TRACK_HEADER}'"))?;
    let mut out = vec![EstimateFrame { position: None, centre_px: None, lost: true }; frames];
    for (i, r) in rows.iter().enumerate() {
        let k = r[0];
        if !(k >= 0.0 && k.fract() == 0.0 && (k as usize) < frames) {
            bail!("{}: row {} names frame {k}, outside the truth's 0..{frames}", path.display(), i + 1);
        }
        out[k as usize] = EstimateFrame {
            position: Some([r[2], r[3], r[4]]),
            centre_px: (r[11] > 0.0).then_some([r[9], r[10]]),
            lost: r[13] != 0.0,
        };
    }
    Ok(out)
}

fn print_scores(s: &TrackingScores) -> Result<()> {
    outln!(
        "3D RMSE {:.4} m = {:.2} % of the mean depth {:.2} m; median image-centre error {:.2} px; lost {} of {} scored frames; re-acquired after {}",
        s.rmse_3d_m,
        s.rmse_3d_percent_of_depth,
        s.mean_depth_m,
        s.median_centre_error_px,
        s.lost_frames,
        s.scored_frames,
        delays(&s.reacquisition_delays)
    );
    Ok(())
}

fn delays(d: &[Option<usize>]) -> String {
    if d.is_empty() {
        return "no full occlusion".into();
    }
    let v: Vec<String> = d.iter().map(|x| x.map_or("never".into(), |k| format!("{k} frames"))).collect();
    v.join(", ")
}

fn eval(a: &EvalArgs) -> Result<()> {
    let truth = read_truth(&a.truth)?;
    let est = read_track(&a.track, truth.len())?;
    let s = score(&truth, &est)?;
    if a.json {
        outln!("{}", serde_json::to_string(&s)?);
    } else {
        print_scores(&s)?;
    }
    Ok(())
}

/// Image-centre and 3D errors over time.
fn error_plot(path: &Path, truth: &[TruthFrame], est: &[EstimateFrame]) -> Result<()> {
    let px: Vec<(f64, f64)> = truth
        .iter()
        .zip(est)
        .enumerate()
        .filter_map(|(k, (t, e))| {
            let (c, p) = (t.circle?, e.centre_px?);
            Some((k as f64, (p[0] - c[0]).hypot(p[1] - c[1]).min(100.0)))
        })
        .collect();
    let cm: Vec<(f64, f64)> = truth
        .iter()
        .zip(est)
        .enumerate()
        .filter_map(|(k, (t, e))| {
            let p = e.position?;
            let d = (0..3).map(|i| (p[i] - t.position[i]).powi(2)).sum::<f64>().sqrt();
            Some((k as f64, (100.0 * d).min(100.0)))
        })
        .collect();
    let hidden: Vec<(f64, f64)> =
        truth.iter().enumerate().map(|(k, t)| (k as f64, 10.0 * (1.0 - t.visible_fraction))).collect();
    plot::draw(
        path,
        &Plot {
            title: "tracking error (capped at 100)",
            x_label: "frame",
            y_label: "image-centre error (px) / 3D error (cm) / hidden x 10",
            series: &[
                Series { label: "image centre, px", points: px, color: RGBColor(30, 120, 220) },
                Series { label: "3D, cm", points: cm, color: RGBColor(220, 80, 30) },
                Series { label: "hidden share x 10", points: hidden, color: RGBColor(120, 120, 120) },
            ],
            threshold: Some((2.0, "2 px")),
            y_range: None,
        },
    )
}

fn run_study(a: &StudyArgs) -> Result<()> {
    let seeds: Vec<u64> = a
        .seeds
        .split(',')
        .map(|s| s.trim().parse::<u64>())
        .collect::<std::result::Result<_, _>>()
        .with_context(|| format!("--seeds '{}' is not a comma-separated list of integers", a.seeds))?;
    if seeds.is_empty() || seeds.len() > 100 {
        bail!("--seeds takes 1..=100 seeds");
    }
    let mut base = TrackerConfig::at_fps(30.0);
    base.particles = a.particles;
    let trajectories = [Trajectory::Throw, Trajectory::Bounce, Trajectory::Approach];
    let scene = ocellus_sim::ball_tracking::StudyScene {
        occlusion: crate::generate_ball::occlusion_of(a.occlusion),
        distractor: a.distractor,
        lighting_change: a.lighting_change,
    };
    let (background, occluder) = (photo("rocket.jpg")?, photo("gravel.png")?);
    let runs = study(&background, &occluder, &trajectories, &seeds, &[0.0, a.boost], base, scene, a.streams)?;
    if a.json {
        outln!("{}", serde_json::to_string(&serde_json::json!({ "particles": a.particles, "runs": runs }))?);
        return Ok(());
    }
    outln!("trajectory  seed  stream  filter        3D RMSE        centre  lost  re-acquired after the full occlusion");
    for r in &runs {
        let s = &r.scores;
        outln!(
            "{:<10} {:>5}  {:>6}  {:<11} {:>6.2} % depth  {:>6.2} px  {:>4}  {}",
            format!("{:?}", r.trajectory).to_lowercase(),
            r.seed,
            r.stream,
            if r.boost == 0.0 { "SIR".to_string() } else { format!("boost {}", r.boost) },
            s.rmse_3d_percent_of_depth,
            s.median_centre_error_px,
            s.lost_frames,
            delays(&s.reacquisition_delays)
        );
    }
    let summary = |label: String, pick: &dyn Fn(&ocellus_sim::ball_tracking::StudyRun) -> bool| -> Result<()> {
        let s = ocellus_sim::ball_tracking::summarize(runs.iter().filter(|r| r.boost > 0.0 && pick(r)));
        outln!(
            "boosted{label}: 3D RMSE median {:.2} %, mean {:.2} % of the depth over {} runs ({} at most {} %)",
            s.median_rmse_percent,
            s.mean_rmse_percent,
            s.runs,
            s.within_target,
            ocellus_sim::ball_tracking::TARGET_RMSE_PERCENT_OF_DEPTH
        );
        Ok(())
    };
    summary(String::new(), &|_| true)?;
    if a.streams > 1 {
        for k in 0..a.streams {
            summary(format!(", stream {k}"), &|r| r.stream == k)?;
        }
    }
    Ok(())
}

fn run_head_cmd(a: &HeadArgs) -> Result<()> {
    use ocellus_sim::stereo_head::{run_head, HeadConfig};
    use ocellus_synth::ball_world::{BallWorld, BallWorldConfig};
    let trajectory = match a.trajectory {
        crate::generate_ball::TrajectoryArg::Throw => Trajectory::Throw,
        crate::generate_ball::TrajectoryArg::Bounce => Trajectory::Bounce,
        crate::generate_ball::TrajectoryArg::Approach => Trajectory::Approach,
    };
    let mut cfg = HeadConfig::default();
    cfg.tracker.particles = a.particles;
    cfg.tracker.filter.seed = a.seed;
    let wc = BallWorldConfig { fps: cfg.control_hz, frames: a.steps, ..BallWorldConfig::new(trajectory, a.seed) };
    let world = BallWorld::new(wc, &photo("rocket.jpg")?, &photo("gravel.png")?)?;
    crate::output_files::create_dir(&a.out)?;
    crate::output_files::create_dir(&a.out.join("eyes"))?;
    let mut csv = crate::output_files::create_file(&a.out.join("gaze.csv"))?;
    writeln!(csv, "time_s,pan_deg,tilt_deg,vergence_deg,saccade,left_error_deg,right_error_deg,disparity_px,lost")?;
    let (w, h) = (cfg.eye_width, cfg.eye_height);
    // The robot's loop on one core, as a robot's controller would get.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let mut k = 0usize;
    let run = pool.install(|| {
        run_head(&world, &cfg, |s, left, right| {
            let mut both = Plane::from_fn(2 * w + 4, h, |x, y| {
                if x < w {
                    left.get(x, y)
                } else if x >= w + 4 {
                    right.get(x - w - 4, y)
                } else {
                    [0, 0, 0]
                }
            });
            for off in [0.0, (w + 4) as f64] {
                let (cx, cy) = (off + (w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
                draw::line(&mut both, [cx - 6.0, cy], [cx + 6.0, cy], [40, 230, 60]);
                draw::line(&mut both, [cx, cy - 6.0], [cx, cy + 6.0], [40, 230, 60]);
            }
            ocellus_io::write_png(a.out.join("eyes").join(format!("step_{k:05}.png")), &both)
                .map_err(|e| ocellus_sim::SimError::Stopped(e.to_string()))?;
            k += 1;
            let g = s.gaze;
            writeln!(
                csv,
                "{:.5},{:.4},{:.4},{:.4},{},{:.4},{:.4},{:.3},{}",
                s.time_s,
                g.pan.to_degrees(),
                g.tilt.to_degrees(),
                g.vergence.to_degrees(),
                u8::from(s.saccade),
                s.left_error_deg,
                s.right_error_deg,
                s.disparity_px,
                u8::from(s.lost)
            )
            .map_err(|e| ocellus_sim::SimError::Stopped(e.to_string()))
        })
    })?;
    csv.flush()?;
    let pts = |f: &dyn Fn(&ocellus_sim::stereo_head::HeadStep) -> f64| -> Vec<(f64, f64)> {
        run.steps.iter().map(|s| (s.time_s, f(s))).collect()
    };
    plot::draw(
        &a.out.join("gaze.png"),
        &Plot {
            title: "active stereo head",
            x_label: "time (s)",
            y_label: "degrees",
            series: &[
                Series { label: "pan", points: pts(&|s| s.gaze.pan.to_degrees()), color: RGBColor(30, 120, 220) },
                Series { label: "tilt", points: pts(&|s| s.gaze.tilt.to_degrees()), color: RGBColor(40, 170, 60) },
                Series {
                    label: "vergence",
                    points: pts(&|s| s.gaze.vergence.to_degrees()),
                    color: RGBColor(150, 60, 200),
                },
                Series {
                    label: "foveal error (worse eye)",
                    points: pts(&|s| s.left_error_deg.max(s.right_error_deg)),
                    color: RGBColor(220, 80, 30),
                },
            ],
            threshold: Some((2.0, "2 deg")),
            y_range: None,
        },
    )?;
    let s = run.summary();
    outln!(
        "{} steps at {} Hz of simulated time: the ball within 2 deg of both foveas in {:.0} % of the steps, within 5 deg in {:.0} % (median {:.2} deg); {} saccades; the robot's loop (tracker, vergence, control) ran at {:.0} Hz on one core ({:.1} s rendering the eyes, not counted); wrote {}",
        s.steps,
        cfg.control_hz,
        100.0 * s.within_2deg,
        100.0 * s.within_5deg,
        s.median_error_deg,
        s.saccades,
        s.control_hz,
        run.render_s,
        a.out.display()
    );
    Ok(())
}
