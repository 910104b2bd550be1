//! `ocellus`: the command-line program of the ocellus active-vision toolkit.

#[macro_use]
mod out;

mod assets;
mod attend;
mod bench;
mod budget;
mod calibrate_cmd;
mod calibrate_planar;

mod config_file;
mod demo;
mod eval;
mod frames;
mod generate;
mod generate_ball;
mod generate_chessboard;
mod generate_ground;
mod inputs;
mod logpolar_cmd;
mod odometry_cmd;
mod output_files;
mod plan_cmd;
mod plot;
mod ranges;
mod report_cmd;
mod retina_cmd;
mod retina_summary;
mod rrd;
mod saliency_cmd;
mod stereo_cmd;
mod surprise_cmd;
mod track_cmd;
mod triangulate_cmd;
mod undistort_cmd;

use anyhow::Result;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

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
    /// Run every capability end to end on built-in and generated data and write one HTML
    /// report (ocellus-demo/index.html).
    Demo(demo::DemoArgs),
    /// Build the HTML report (DIR/index.html) of the outputs in a folder: a section per
    /// subfolder.
    Report(report_cmd::ReportArgs),
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
    /// Where did it go: the 3D ball tracker (particle filter with a colour likelihood, boosted
    /// by colour-blob detections) on frames; `track eval` scores a track against truth;
    /// `track study` prints the accuracy figures on generated sequences.
    Track(track_cmd::TrackArgs),
    /// What should my retina be: learn receptive fields, motor fields and predictors from
    /// self-induced image changes (the self-organizing retina, the seed's two experiments).
    Retina(retina_cmd::RetinaArgs),
    /// Print benchmark figures (median ms per frame, fps on all cores, per stage, peak memory).
    Bench(bench::BenchArgs),
}

/// The command tree, with negative numbers read as values everywhere (`--blur -1` reaches the
/// range check in `ranges` instead of being taken for an unknown flag).
fn command() -> clap::Command {
    fn negative_numbers(c: clap::Command) -> clap::Command {
        c.allow_negative_numbers(true).mut_subcommands(negative_numbers)
    }
    negative_numbers(Cli::command())
}

fn main() {
    // SIGPIPE stays ignored (Rust's default): a closed stdout or a dead ffmpeg then shows up
    // as a write error that is reported (see `out`), not as a silent death by signal.
    let cli = match Cli::from_arg_matches(&command().get_matches()) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    let r = dispatch(cli.command);
    let r = r.and_then(|()| Ok(out::flush_stdout()?));
    if let Err(e) = r {
        let stdout = e.chain().find_map(|c| c.downcast_ref::<out::StdoutError>());
        if stdout.is_some_and(out::StdoutError::is_broken_pipe) {
            // The reader took what it wanted (`| head -1`): end quietly, with the status a
            // shell gives a program stopped by SIGPIPE.
            std::process::exit(141);
        }
        errln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// Runs one command line, `args` without the program name (`["stereo", "l.png", ...]`),
/// as `main` would: the demo runs its parts through the very commands it shows.
pub fn run_args(args: &[String]) -> Result<()> {
    let argv = std::iter::once("ocellus".to_string()).chain(args.iter().cloned());
    let matches = command().try_get_matches_from(argv)?;
    dispatch(Cli::from_arg_matches(&matches)?.command)
}

fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Demo(a) => demo::run(a),
        Command::Report(a) => report_cmd::run(a),
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
        Command::Track(a) => track_cmd::run(a),
        Command::Retina(a) => retina_cmd::run(a),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every numeric option states its range in `--help`, so the one check in `ranges` and
    /// what the user reads cannot drift apart unnoticed.
    #[test]
    fn every_numeric_option_states_its_range() {
        use clap::builder::ValueParser;
        let numeric = [
            ValueParser::from(clap::value_parser!(f64)).type_id(),
            ValueParser::from(clap::value_parser!(f32)).type_id(),
            ValueParser::from(clap::value_parser!(u8)).type_id(),
            ValueParser::from(clap::value_parser!(u16)).type_id(),
            ValueParser::from(clap::value_parser!(u32)).type_id(),
            ValueParser::from(clap::value_parser!(u64)).type_id(),
            ValueParser::from(clap::value_parser!(usize)).type_id(),
            ValueParser::from(clap::value_parser!(i64)).type_id(),
        ];
        fn walk<T: PartialEq>(
            c: &clap::Command,
            path: &str,
            numeric: &[T],
            id: &dyn Fn(&clap::Arg) -> T,
            missing: &mut Vec<String>,
        ) {
            for a in c.get_arguments() {
                let help = a.get_long_help().or(a.get_help()).map(|h| h.to_string()).unwrap_or_default();
                if numeric.contains(&id(a)) && !help.contains("Range") {
                    missing.push(format!("{path} --{}", a.get_id()));
                }
            }
            for s in c.get_subcommands() {
                walk(s, &format!("{path} {}", s.get_name()), numeric, id, missing);
            }
        }
        let mut missing = Vec::new();
        walk(&command(), "ocellus", &numeric, &|a| a.get_value_parser().type_id(), &mut missing);
        assert!(missing.is_empty(), "numeric options without a stated range: {missing:?}");
        // The walk does see numeric options.
        let bench = command()
            .find_subcommand("bench")
            .and_then(|b| b.get_arguments().find(|a| a.get_id() == "frames").cloned());
        assert!(bench.is_some_and(|a| numeric.contains(&a.get_value_parser().type_id())));
    }

    #[test]
    fn command_tree_is_consistent() {
        command().debug_assert();
    }
}
