//! `ocellus odometry`: visual odometry of a ground-facing camera, and `ocellus odometry eval`:
//! a trajectory against ground truth.

use crate::frames::for_each_frame;
use crate::plot::{self, Plot, Series};
use crate::ranges;
use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use ocellus_eval::trajectory::{self, PlanarPose};
use ocellus_geometry::camera_file;
use ocellus_geometry::distortion::{remap_bilinear, undistort_maps};
use ocellus_image::{draw, Plane};
use ocellus_io::tum::TumPose;
use ocellus_odometry::fusion::{encoder_motion, EncoderReading, Fusion, FusionConfig};
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use plotters::style::RGBColor;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus odometry`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct OdometryArgs {
    #[command(subcommand)]
    eval: Option<Eval>,
    /// Frames from a camera looking straight down: an image folder, a Y4M file or a video.
    #[arg(required = true)]
    input: Option<PathBuf>,
    /// Camera file (TOML/JSON): intrinsics, distortion (frames are undistorted first), and
    /// `height_m`, `mount_right_m`, `mount_forward_m` unless given below.
    #[arg(long, required = true)]
    camera: Option<PathBuf>,
    /// Camera height above the floor, metres (overrides the camera file). Range: above 0, at
    /// most 1000.
    #[arg(long, value_parser = ranges::above(0.0f64, 1000.0))]
    height_m: Option<f64>,
    /// Camera position ahead of the rotation centre, metres (overrides the camera file).
    /// Range: -100..=100.
    #[arg(long, value_parser = ranges::within(-100.0f64, 100.0))]
    mount_forward_m: Option<f64>,
    /// Camera position right of the rotation centre, metres (overrides the camera file).
    /// Range: -100..=100.
    #[arg(long, value_parser = ranges::within(-100.0f64, 100.0))]
    mount_right_m: Option<f64>,
    /// Estimator: `robust` (sub-pixel flow with per-window uncertainty, a robust fit over all
    /// windows) or `seed` (the seed's integer SAD groups and filter).
    #[arg(long, value_enum, default_value = "robust")]
    mode: Mode,
    /// Robust mode: how much of its offset from the calibrated camera height the height
    /// followed through the image's scale change loses per frame (0: pure integration; 1: the
    /// height stays at the calibrated value, the seed's assumption). Range: 0..=1.
    #[arg(long, default_value_t = 0.002, value_parser = ranges::within(0.0f64, 1.0))]
    height_pull: f64,
    /// Robust mode: window, frames, of the running noise and power of the image's scale
    /// change; each change is shrunk by their ratio (the Wiener gain) before the height
    /// follows it, so a floor whose height is constant does not integrate noise (0: every
    /// change followed whole). Range: 0 or 1..=1000000.
    #[arg(long, default_value_t = 32.0, value_parser = ranges::within(0.0f64, 1e6))]
    height_noise_frames: f64,
    /// Robust mode: the brightness ratio between frames as a smooth field over the image,
    /// fitted through the windows' own gains (against vignetting: a floor point moving toward a
    /// darker corner changes brightness, which one gain for the whole frame reads as flow);
    /// `--gain-field false` keeps one global gain.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    gain_field: bool,
    /// Robust mode: sigma of the Gaussian both frames are smoothed by before Lucas-Kanade,
    /// pixels (below 0.3: not smoothed). Range: 0..=5.
    #[arg(long, default_value_t = ocellus_odometry::spline::DEFAULT_SMOOTH_SIGMA_PX, value_parser = ranges::within(0.0f32, 5.0))]
    smooth_sigma_px: f32,
    /// Frame rate, Hz (timestamps of the trajectory). Range: above 0, at most 1000000.
    #[arg(long, default_value_t = 200.0, value_parser = ranges::above(0.0f64, 1e6))]
    rate_hz: f64,
    /// Wheel encoders to fuse: CSV `time_s,forward_m,yaw_rad` (a header allowed), one reading
    /// per interval ending at time_s (e.g. `encoders.csv` of `synth ground`).
    #[arg(long)]
    encoders: Option<PathBuf>,
    /// Encoder rate, Hz. Range: above 0, at most 1000000.
    #[arg(long, default_value_t = 30.0, value_parser = ranges::above(0.0f64, 1e6))]
    encoder_rate_hz: f64,
    /// Output folder: trajectory.tum (fused with the encoders when given; then also
    /// trajectory_vision.tum), trajectory.png, flow_NNNNN.png for a few frames.
    #[arg(long, default_value = "ocellus-odometry")]
    out: PathBuf,
    /// Ground truth to show beside the estimate: a TUM trajectory of the rotation centre
    /// (e.g. groundtruth.tum of `generate ground`); drawn in trajectory.png and, with --rrd,
    /// logged with the drift per frame.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Also log the run for the Rerun viewer to this .rrd file: the undistorted frames, the
    /// flow vectors (drawn 5x long), the estimated and true poses per frame and both whole
    /// trajectories, and the drift per frame with --truth (needs ocellus built with the
    /// `rerun` feature).
    #[arg(long)]
    rrd: Option<PathBuf>,
}

/// Estimator choice.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Mode {
    /// The seed's method (SPEC 6.2-6.3).
    Seed,
    /// Beyond the seed: sub-pixel, aperture-aware, robust over all windows.
    Robust,
}

#[derive(Subcommand, Debug)]
enum Eval {
    /// Compare a trajectory with ground truth (TUM files): final drift in % of the path
    /// length, final heading error, ATE RMSE and RPE per frame (no alignment: both start at
    /// the same pose, as odometry does), and a plot of both.
    Eval(EvalArgs),
}

#[derive(Args, Debug)]
struct EvalArgs {
    /// Estimated trajectory (TUM).
    estimate: PathBuf,
    /// Ground truth (TUM).
    truth: PathBuf,
    /// Largest timestamp difference when pairing poses, seconds. Range: above 0, at most 10.
    #[arg(long, default_value_t = 0.001, value_parser = ranges::above(0.0f64, 10.0))]
    max_dt: f64,
    /// Plot of both trajectories.
    #[arg(long, default_value = "trajectories.png")]
    plot: PathBuf,
}

/// Runs the subcommand.
pub fn run(a: OdometryArgs) -> Result<()> {
    if let Some(Eval::Eval(e)) = a.eval {
        return eval(&e);
    }
    let (Some(input), Some(camera)) = (&a.input, &a.camera) else { bail!("give the frames and --camera") };
    let cam = camera_file::read(camera)?;
    let height = a.height_m.or(cam.height_m).context("the camera height: --height-m or height_m in the camera file")?;
    let mount = Mount {
        right_m: a.mount_right_m.or(cam.mount_right_m).unwrap_or(0.0),
        forward_m: a.mount_forward_m.or(cam.mount_forward_m).unwrap_or(0.0),
    };
    let focal = 0.5 * (cam.intrinsics.fx + cam.intrinsics.fy);
    let mut cfg = match a.mode {
        Mode::Seed => OdometryConfig::seed(height, focal, mount),
        Mode::Robust => OdometryConfig::robust(height, focal, mount),
    };
    cfg.robust.height_pull = a.height_pull;
    cfg.robust.height_noise_frames = a.height_noise_frames;
    cfg.robust.gain_field = a.gain_field;
    cfg.robust.smooth_sigma_px = a.smooth_sigma_px;
    let mut vo = VisualOdometry::new(cfg)?;
    let readings: Option<Vec<EncoderReading>> = match &a.encoders {
        Some(p) => {
            let rows = ocellus_io::csv::read_rows(p, 3, "'time_s,forward_m,yaw_rad'")?;
            let r: Vec<EncoderReading> =
                rows.iter().map(|r| EncoderReading { time_s: r[0], forward_m: r[1], yaw_rad: r[2] }).collect();
            if r.windows(2).any(|w| w[1].time_s <= w[0].time_s) {
                bail!("{}: encoder times must increase", p.display());
            }
            Some(r)
        }
        None => None,
    };
    if !(a.encoder_rate_hz > 0.0 && a.rate_hz > 0.0) {
        bail!("--rate-hz and --encoder-rate-hz must be positive");
    }
    let truth = a.truth.as_deref().map(ocellus_io::tum::read).transpose()?;
    let rrd = crate::rrd::open(a.rrd.as_deref(), "ocellus_odometry")?;
    if let Some(rec) = &rrd {
        rec.static_axes("world", false)?;
    }
    let mut truth_path = (0.0f64, None::<[f64; 2]>);
    let mut fusion = Fusion::new(FusionConfig { encoder_rate_hz: a.encoder_rate_hz, ..Default::default() }, mount);
    let mut vision_poses = Vec::new();
    crate::inputs::check_out_dir(&a.out, std::slice::from_ref(input))?;
    crate::output_files::create_dir(&a.out)?;
    let d = cam.distortion;
    let distorted = [d.k1, d.k2, d.k3, d.p1, d.p2].iter().any(|v| *v != 0.0);
    let mut maps: Option<(Plane<f32>, Plane<f32>)> = None;
    let mut poses = Vec::new();
    let mut failures = 0usize;
    let t0 = std::time::Instant::now();
    let n = for_each_frame(input, None, |k, frame| {
        if k == 0 {
            camera_file::check_frame_size(&cam, camera, "the first frame", frame.size())?;
        }
        let mut grey = frame.to_luma8();
        if distorted {
            let (mx, my) = maps.get_or_insert_with(|| undistort_maps(&cam.intrinsics, &d, grey.width(), grey.height()));
            let f = remap_bilinear(&grey.map(|v| v as f32), mx, my, 0.0)?;
            grey = f.map(|v| v.round().clamp(0.0, 255.0) as u8);
        }
        let step = vo.step(&grey)?;
        if step.failure.is_some() {
            failures += 1;
        }
        if k > 0 && k % 50 == 1 {
            write_flow(&a.out.join(format!("flow_{k:05}.png")), &grey, &step.flows)?;
        }
        let t = k as f64 / a.rate_hz;
        let p = step.pose;
        vision_poses.push(TumPose::planar(t, p.x, p.y, p.theta));
        if let Some(r) = &readings {
            if k > 0 {
                fusion.step(&step, encoder_motion(r, a.encoder_rate_hz, t - 1.0 / a.rate_hz, t));
            }
            let f = fusion.pose();
            poses.push(TumPose::planar(t, f.x, f.y, f.theta));
        } else {
            poses.push(TumPose::planar(t, p.x, p.y, p.theta));
        }
        if let Some(rec) = &rrd {
            let est = poses.last().map_or([0.0; 3], |p| p.position);
            let truth_now = truth.as_deref().and_then(|g| pose_at(g, t, 0.5 / a.rate_hz));
            log_step(rec, k, t, &grey, &step.flows, est, truth_now, &mut truth_path)?;
        }
        Ok(())
    })?;
    if let Some(rec) = rrd {
        let floor = |p: &TumPose| [p.position[0], -p.position[1], 0.0];
        rec.static_strip_3d("world/estimate/path", &poses.iter().map(floor).collect::<Vec<_>>(), [230, 50, 40, 255])?;
        if let Some(g) = &truth {
            rec.static_strip_3d("world/truth/path", &g.iter().map(floor).collect::<Vec<_>>(), [40, 40, 40, 255])?;
        }
        rec.finish()?;
    }
    let secs = t0.elapsed().as_secs_f64();
    ocellus_io::tum::write(a.out.join("trajectory.tum"), &poses)?;
    let mut runs: Vec<(&str, &[TumPose], RGBColor)> = Vec::new();
    if let Some(g) = &truth {
        runs.push(("ground truth", g, RGBColor(30, 30, 30)));
    }
    if readings.is_some() {
        ocellus_io::tum::write(a.out.join("trajectory_vision.tum"), &vision_poses)?;
        runs.push(("fused", &poses, RGBColor(200, 40, 40)));
        runs.push(("vision", &vision_poses, RGBColor(40, 90, 200)));
        outln!(
            "encoders: {} frames with slipping wheels ignored, {} bridged by the wheels",
            fusion.rejected,
            fusion.bridged
        );
    } else {
        runs.push(("estimate", &poses, RGBColor(200, 40, 40)));
    }
    plot_trajectories(&a.out.join("trajectory.png"), &runs)?;
    let last = poses.last().context("no frames")?;
    outln!(
        "{n} frames in {secs:.2} s ({:.0} fps, decoding included); {failures} without texture; final pose ({:.4}, {:.4}) m, {:.2} deg",
        n as f64 / secs.max(1e-9),
        last.position[0],
        last.position[1],
        last.yaw().to_degrees()
    );
    outln!("wrote trajectory.tum, trajectory.png and flow overlays in {}", a.out.display());
    if let Some(p) = &a.rrd {
        outln!("wrote {}", p.display());
    }
    Ok(())
}

/// The pose of `poses` (in time order) within `tol` seconds of `t`.
fn pose_at(poses: &[TumPose], t: f64, tol: f64) -> Option<[f64; 3]> {
    let i = poses.partition_point(|p| p.time_s < t - tol);
    poses.get(i).filter(|p| (p.time_s - t).abs() <= tol).map(|p| p.position)
}

/// One frame in the Rerun log: the frame with its flow, the poses on the floor (x right, y
/// forward, as trajectory.png draws them), and the drift (distance between the estimate and
/// the truth over the true path so far, percent) once the path is 1 cm long.
#[allow(clippy::too_many_arguments)]
fn log_step(
    rec: &crate::rrd::Recorder,
    k: usize,
    t: f64,
    grey: &Plane<u8>,
    flows: &[ocellus_odometry::sad_flow::FlowPoint],
    est: [f64; 3],
    truth: Option<[f64; 3]>,
    path: &mut (f64, Option<[f64; 2]>),
) -> Result<()> {
    rec.at(k, Some(t));
    rec.frame_grey("camera", grey)?;
    let (w, h) = grey.size();
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let origins: Vec<[f64; 2]> = flows.iter().map(|f| [f.u + cx, f.v + cy]).collect();
    let vectors: Vec<[f64; 2]> = flows.iter().map(|f| [5.0 * f.du, 5.0 * f.dv]).collect();
    rec.arrows_2d("camera/flow_x5", &origins, &vectors, [0, 230, 0, 255])?;
    rec.points_3d("world/estimate", &[[est[0], -est[1], 0.0]], 0.004, [230, 50, 40, 255])?;
    if let Some(g) = truth {
        rec.points_3d("world/truth", &[[g[0], -g[1], 0.0]], 0.004, [40, 40, 40, 255])?;
        if let Some(last) = path.1 {
            path.0 += (g[0] - last[0]).hypot(g[1] - last[1]);
        }
        path.1 = Some([g[0], g[1]]);
        if path.0 >= 0.01 {
            rec.scalar("error/drift_percent", 100.0 * (est[0] - g[0]).hypot(est[1] - g[1]) / path.0)?;
        }
    }
    Ok(())
}

/// The frame with its flow vectors drawn 5x longer (green) from their group centres (red).
fn write_flow(path: &Path, grey: &Plane<u8>, flows: &[ocellus_odometry::sad_flow::FlowPoint]) -> Result<()> {
    let (w, h) = grey.size();
    let mut img = grey.map(|v| [v, v, v]);
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    for f in flows {
        let (x0, y0) = (f.u + cx, f.v + cy);
        draw::line(&mut img, [x0, y0], [x0 + 5.0 * f.du, y0 + 5.0 * f.dv], [0, 230, 0]);
        draw::dot(&mut img, [x0, y0], [230, 0, 0]);
    }
    Ok(ocellus_io::write_png(path, &img)?)
}

fn plot_trajectories(path: &Path, runs: &[(&str, &[TumPose], RGBColor)]) -> Result<()> {
    let series: Vec<Series> = runs
        .iter()
        .map(|(label, poses, color)| Series {
            label,
            // x right, y up in the plot: the floor's y points down.
            points: poses.iter().map(|p| (p.position[0], -p.position[1])).collect(),
            color: *color,
        })
        .collect();
    plot::draw(
        path,
        &Plot {
            title: "Trajectory (rotation centre)",
            x_label: "x, m",
            y_label: "-y, m",
            series: &series,
            threshold: None,
            y_range: None,
        },
    )
}

fn eval(a: &EvalArgs) -> Result<()> {
    let est = ocellus_io::tum::read(&a.estimate)?;
    let gt = ocellus_io::tum::read(&a.truth)?;
    let planar = |p: &TumPose| PlanarPose::new(p.time_s, p.position[0], p.position[1], p.yaw());
    let (est_p, gt_p): (Vec<PlanarPose>, Vec<PlanarPose>) =
        (est.iter().map(planar).collect(), gt.iter().map(planar).collect());
    // Paired once: the errors and the plot use the same pairs.
    let index_pairs = trajectory::pair_by_time(&est_p, &gt_p, a.max_dt);
    let planar_pairs: Vec<(PlanarPose, PlanarPose)> = index_pairs.iter().map(|&(i, j)| (est_p[i], gt_p[j])).collect();
    let e = trajectory::errors_of_pairs(&planar_pairs)?;
    outln!("{} poses paired, path {:.4} m", e.pairs, e.path_m);
    outln!(
        "final drift {:.4} % of the path, final heading error {:.4} deg",
        e.final_drift_percent,
        e.final_heading_deg
    );
    outln!(
        "ATE RMSE {:.3} mm ({:.3} mm after a rigid alignment), RPE per frame RMSE {:.4} mm",
        e.ate_rmse_m * 1e3,
        e.ate_aligned_rmse_m * 1e3,
        e.rpe_rmse_m * 1e3
    );
    let pairs: Vec<(TumPose, TumPose)> = index_pairs.into_iter().map(|(i, j)| (est[i], gt[j])).collect();
    let (e, g): (Vec<TumPose>, Vec<TumPose>) = pairs.into_iter().unzip();
    plot_trajectories(&a.plot, &[("ground truth", &g, RGBColor(30, 30, 30)), ("estimate", &e, RGBColor(200, 40, 40))])?;
    outln!("wrote {}", a.plot.display());
    Ok(())
}
