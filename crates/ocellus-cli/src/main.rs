//! `ocellus`: the command-line program of the ocellus active-vision toolkit.

mod assets;
mod attend;
mod bench;
mod bench_attention;
mod bench_geometry;
mod bench_logpolar;
mod bench_odometry;
mod bench_planning;
mod calibrate_cmd;
mod calibrate_planar;
mod camera_file;
mod config_file;
mod corridor_sim;
mod demo;
mod eval;
mod frames;
mod generate;
mod generate_chessboard;
mod generate_ground;
mod inputs;
mod logpolar_cmd;
mod odometry_cmd;
mod overlay;
mod plan_cmd;
mod plot;
mod saliency_cmd;
mod stereo_cmd;
mod surprise_cmd;
mod triangulate_cmd;
mod undistort_cmd;
mod video_out;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// Fast, biologically inspired active vision: where to look, how it moved, where things are.
#[derive(Parser, Debug)]
#[command(
    name = "ocellus",
    version,
    about = "Fast, biologically inspired active vision for robots: saliency, surprise, attention and view planning (where to look); calibration, triangulation and stereo (where things are)",
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the main capabilities end to end on built-in data: saliency maps and overlays, then
    /// attention over a generated sequence.
    Demo(demo::DemoArgs),
    /// Compute bottom-up saliency maps (Itti-Koch-Niebur) for images or folders of images.
    Saliency(saliency_cmd::SaliencyArgs),
    /// Score saliency maps against human fixations (CC, SIM, KL, NSS, AUCs, IG; MIT benchmark definitions).
    Eval(eval::EvalArgs),
    /// Attention over a video or image sequence: saliency with flicker, surprise, context
    /// chaos, winner-take-all with inhibition of return on an ego-sphere; writes overlays, a
    /// video, the scanpath and per-frame context values with a plot.
    Attend(attend::AttendArgs),
    /// Bayesian surprise maps (bits) of a video or image sequence, and the per-frame maximum.
    Surprise(surprise_cmd::SurpriseArgs),
    /// Information-based view-direction planning in a simulated corridor (top-down landmarks
    /// vs bottom-up surprise, switched by the context chaos degree).
    Plan(plan_cmd::PlanArgs),
    /// Camera calibration: `dlt` from 3D-2D correspondences (K, R, t, P and errors);
    /// `chessboard` from images of a chessboard and `planar` from planar correspondences
    /// (Zhang with lens distortion; camera.toml, standard deviations, per-view errors).
    Calibrate(calibrate_cmd::CalibrateArgs),
    /// Visual odometry of a camera looking down at the floor (the seed's block matching and
    /// Kalman filter): a TUM trajectory, a plot and flow overlays; `odometry eval` scores a
    /// trajectory against ground truth.
    Odometry(odometry_cmd::OdometryArgs),
    /// Foveal vision: the anti-aliased log-polar image of a picture about a gaze point and its
    /// inverse; `logpolar register` estimates rotation and scale between two images;
    /// `logpolar vergence` the disparity at a gaze point of a stereo pair.
    Logpolar(logpolar_cmd::LogPolarArgs),
    /// Remove lens distortion from images with a calibrated camera file (same intrinsics).
    Undistort(undistort_cmd::UndistortArgs),
    /// 3D points from pixel matches in two or more calibrated cameras (camera JSON files of
    /// `ocellus calibrate dlt`); flags points behind a camera.
    Triangulate(triangulate_cmd::TriangulateArgs),
    /// Dense disparity of a rectified stereo pair by semi-global matching or block matching;
    /// depth and a point cloud with calibration; bad-2.0 against a ground-truth PFM.
    Stereo(stereo_cmd::StereoArgs),
    /// Generate ground-truth scenes and sequences from the built-in real images (`synth` is
    /// the same command).
    #[command(visible_alias = "synth")]
    Generate(generate::GenerateArgs),
    /// Print benchmark figures (median ms per frame, fps on all cores, per stage, peak memory).
    Bench(bench::BenchArgs),
}

fn main() {
    // Behave like other command-line programs when the reader of stdout goes away
    // (`ocellus ... | head`): end quietly instead of panicking on the write.
    #[cfg(unix)]
    // SAFETY: restoring the default action of SIGPIPE before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let r: Result<()> = match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Saliency(a) => saliency_cmd::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Attend(a) => attend::run(a),
        Command::Surprise(a) => surprise_cmd::run(a),
        Command::Generate(a) => generate::run(a),
        Command::Plan(a) => plan_cmd::run(a),
        Command::Stereo(a) => stereo_cmd::run(a),
        Command::Calibrate(a) => calibrate_cmd::run(a),
        Command::Triangulate(a) => triangulate_cmd::run(a),
        Command::Undistort(a) => undistort_cmd::run(a),
        Command::Odometry(a) => odometry_cmd::run(a),
        Command::Logpolar(a) => logpolar_cmd::run(a),
    };
    if let Err(e) = r {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
