//! `ocellus demo`: every capability end to end on built-in and generated data, and one HTML
//! page of it all (`ocellus-demo/index.html`).
//!
//! Each part runs the very `ocellus` command lines its section shows (through
//! [`crate::run_args`], in the demo's folder, so they can be pasted there as they are), keeps
//! what they printed, picks the key figures from it and sets them beside the seed's or an
//! anchor's figure. Each part writes its `section.json`; the page is then built from the
//! folder exactly as `ocellus report` builds it.

use crate::{assets, out};
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_report::scan::{report_from_dir, write_report, Layout, LAYOUT_FILE};
use ocellus_report::{Figure, Picture, Section, SECTION_FILE};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `ocellus demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output folder (created if missing): one subfolder per part, inputs/, and index.html.
    #[arg(long, default_value = "ocellus-demo")]
    pub out: PathBuf,
    /// Shorter sequences and a shorter retina run (about a sixth of the time).
    #[arg(long)]
    pub quick: bool,
}

/// One part of the demo as it runs: the commands it ran and what they printed.
struct Part {
    section: Section,
    started: Instant,
}

impl Part {
    fn new(id: &str, title: &str, about: &str) -> Self {
        let mut section = Section::new(id, title);
        section.about = about.into();
        Self { section, started: Instant::now() }
    }

    /// Runs `ocellus ARGS` (words split on spaces), keeping the command and its output;
    /// returns the output.
    fn run(&mut self, args: &str) -> Result<String> {
        let words: Vec<String> = args.split_whitespace().map(String::from).collect();
        self.section.commands.push(format!("ocellus {args}"));
        let (r, text) = out::captured(|| crate::run_args(&words));
        self.section.log.push_str(&format!("$ ocellus {args}\n{text}"));
        r.with_context(|| format!("demo part '{}': ocellus {args}", self.section.id))?;
        Ok(text)
    }

    fn figure(&mut self, label: &str, value: Option<String>, reference: &str) {
        // A figure the output did not hold is left out, not shown as a guess.
        if let Some(v) = value {
            self.section.figures.push(Figure::new(label, &v).beside(reference));
        }
    }

    fn picture(&mut self, path: &str, caption: &str) {
        self.section.pictures.push(Picture::new(path, caption));
    }

    fn files(&mut self, paths: &[&str]) {
        self.section.files.extend(paths.iter().map(|p| p.to_string()));
    }

    /// Writes the section into its folder.
    fn finish(mut self) -> Result<f64> {
        let t = self.started.elapsed().as_secs_f64();
        self.section.seconds = Some(t);
        let dir = PathBuf::from(&self.section.id);
        crate::output_files::create_dir(&dir)?;
        let f = dir.join(SECTION_FILE);
        std::fs::write(&f, serde_json::to_string_pretty(&self.section)?)
            .with_context(|| format!("cannot write {}", f.display()))?;
        Ok(t)
    }
}

/// The first number after `key` in `text` (the rest of that line), e.g. `bad-2.0 13.78 %`.
fn number_after(text: &str, key: &str) -> Option<f64> {
    let rest = &text[text.find(key)? + key.len()..];
    let line = rest.lines().next()?;
    line.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .filter(|w| w.chars().any(|c| c.is_ascii_digit()))
        .find_map(|w| w.parse::<f64>().ok())
}

/// Every number after `key` in `text`, one per occurrence.
fn numbers_after(text: &str, key: &str) -> Vec<f64> {
    text.match_indices(key).filter_map(|(i, _)| number_after(&text[i..], key)).collect()
}

fn fmt(v: Option<f64>, digits: usize, unit: &str) -> Option<String> {
    v.map(|v| format!("{v:.digits$}{unit}"))
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then(|| v[v.len() / 2])
}

/// The tokens of the row of `step` in a `plan corridor` table.
fn plan_row(text: &str, step: usize) -> Option<Vec<String>> {
    text.lines()
        .map(|l| l.split_whitespace().map(String::from).collect::<Vec<_>>())
        .find(|t| t.len() >= 7 && t[0] == step.to_string() && t[5] == "->")
}

/// Runs the demo (see the module doc).
pub fn run(a: DemoArgs) -> Result<()> {
    crate::output_files::create_dir(&a.out)?;
    let started = Instant::now();
    let home = std::env::current_dir().context("cannot read the current folder")?;
    std::env::set_current_dir(&a.out).with_context(|| format!("cannot enter {}", a.out.display()))?;
    let r = run_parts(a.quick);
    std::env::set_current_dir(&home).context("cannot return to the starting folder")?;
    let order = r?;
    let layout = Layout {
        title: "ocellus: what it does and how well".into(),
        intro: format!(
            "Every capability of ocellus run end to end on built-in and generated data by \"ocellus demo{}\" \
             ({:.0} s on this machine). Each section gives the commands that reproduce it in this folder, \
             its key figures beside the seed's or an anchor's, pictures and the data files.",
            if a.quick { " --quick" } else { "" },
            started.elapsed().as_secs_f64()
        ),
        order,
    };
    let lf = a.out.join(LAYOUT_FILE);
    std::fs::write(&lf, serde_json::to_string_pretty(&layout)?)
        .with_context(|| format!("cannot write {}", lf.display()))?;
    let report = report_from_dir(&a.out, &layout.title)?;
    let page = write_report(&a.out, &report)?;
    let size: u64 = std::fs::metadata(&page).map(|m| m.len()).unwrap_or(0);
    outln!(
        "demo done in {:.1} s: {} sections, page {} ({:.0} kB), open it in a browser",
        started.elapsed().as_secs_f64(),
        report.sections.len(),
        page.display(),
        size as f64 / 1e3
    );
    Ok(())
}

type PartFn = fn(&mut Part, bool) -> Result<()>;

/// Runs every part in the current folder; returns their folder names in order.
fn run_parts(quick: bool) -> Result<Vec<String>> {
    write_inputs()?;
    let parts: [(&str, &str, &str, PartFn); 10] = [
        ("saliency", "Where to look: bottom-up saliency", "The Itti-Koch-Niebur saliency map (SPEC 1) of the four built-in photographs with both presets: ace2009 (the seed's parameters) and stb (SaliencyToolbox's). Overlays mark the most salient point; the conspicuity maps show what each channel found.", saliency),
        ("eval", "How well it predicts where people look", "The saliency map scored against human fixation density maps of MIT1003 images with the MIT benchmark's definitions (CC, SIM, KL), beside the centre-prior baseline. The repository ships four of the images; the README's table has the 100-image figures.", eval),
        ("attention", "Attention over time: surprise, context and saccades", "A generated 30-frame sequence over a real photo in which an object appears at frame 15: Bayesian surprise, the context chaos degree, winner-take-all with habituation and inhibition of return on an ego-sphere (SPEC 2.1, 2.2, 3).", attention),
        ("plan", "Where to look next: information-based view planning", "The seed's corridor experiment (SPEC 2.6): a robot drives past four landmarks and picks a pan angle every 0.5 m by top-down information gain; when a person appears at step 5 the chaos degree jumps and bottom-up surprise wins.", plan),
        ("calibration", "Where things are: calibration, undistortion, triangulation", "Twelve generated views of a 9x6 chessboard over real photographs through a camera with lens distortion; Zhang's planar calibration refined by Levenberg-Marquardt (SPEC 5.3), then the views undistorted, and the board rebuilt in 3D by triangulating its corners from two calibrated views (SPEC 5.5).", calibration),
        ("stereo", "Stereo depth: semi-global matching", "The Middlebury 2014 motorcycle pair (downsampled 4x): census costs aggregated along 8 paths, sub-pixel disparity, left-right check (SPEC 5.6), scored against the ground truth, with depth and a point cloud from the calibration.", stereo),
        ("odometry", "How it moved: ground-facing visual odometry", "A generated floor sequence seen by a downward camera (SPEC 6): the seed's block matching and Kalman filter, and the robust mode fused with wheel encoders, each scored against the true trajectory.", odometry),
        ("logpolar", "Foveal vision: the log-polar retina", "The anti-aliased log-polar image of a photo about a gaze point and its inverse (SPEC 4.1), rotation and scale between two images by log-polar phase correlation, and vergence at the fovea of a stereo pair (SPEC 4.3).", logpolar),
        ("tracking", "Where did it go: 3D ball tracking and an active head", "A ball thrown across a real photo behind a pillar and a panel, tracked in 3D by the boosted particle filter (SPEC 7); then a simulated pan-tilt head with two verging eyes keeps it in both foveas with saccades and smooth pursuit.", tracking),
        ("retina", "What should my retina be: the self-organizing retina", "A short run of the seed's first experiment at reduced size (SPEC 8): receptive fields, motor fields and predictors learned from rotation and dilation of real image patches.", retina),
    ];
    let bar_style = ProgressStyle::with_template("{spinner} {prefix:>12} {msg} [{elapsed}]")
        .unwrap_or_else(|_| ProgressStyle::default_spinner());
    let mut order = Vec::new();
    for (i, (id, title, about, f)) in parts.into_iter().enumerate() {
        let bar = ProgressBar::new_spinner().with_style(bar_style.clone()).with_prefix(id.to_string());
        bar.set_message(format!("{}/{}: {title}", i + 1, parts.len()));
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        let mut part = Part::new(id, title, about);
        let r = f(&mut part, quick);
        bar.finish_and_clear();
        r?;
        let t = part.finish()?;
        outln!("  {:>2}/{} {id:<12} {t:>6.1} s  {title}", i + 1, parts.len());
        order.push(id.to_string());
    }
    Ok(order)
}

/// Writes the built-in images and the demo's data into `inputs/`, with a section that links
/// them (the other sections show them).
fn write_inputs() -> Result<()> {
    let mut s = Section::new("inputs", "The inputs");
    s.about = "What the demo ran on, written from the program itself: the built-in photographs (see \
               assets/LICENSES.md in the repository), the Middlebury 2014 motorcycle pair and four \
               MIT1003 images with their fixation maps (testdata/LICENSES.md)."
        .into();
    for (name, bytes) in assets::IMAGES.iter().chain(assets::DEMO_DATA) {
        let p = Path::new("inputs").join(name);
        if let Some(d) = p.parent() {
            crate::output_files::create_dir(d)?;
        }
        std::fs::write(&p, bytes).with_context(|| format!("cannot write {}", p.display()))?;
        s.files.push(format!("inputs/{name}"));
    }
    let f = Path::new("inputs").join(SECTION_FILE);
    std::fs::write(&f, serde_json::to_string_pretty(&s)?).with_context(|| format!("cannot write {}", f.display()))?;
    Ok(())
}

const IMAGES: &str = "inputs/astronaut.png inputs/chelsea.png inputs/coffee.png inputs/rocket.jpg";

fn saliency(p: &mut Part, _quick: bool) -> Result<()> {
    let ace = p.run(&format!("saliency {IMAGES} --preset ace2009 --conspicuity --timings --out saliency/ace2009"))?;
    let stb = p.run(&format!("saliency {IMAGES} --preset stb --timings --out saliency/stb"))?;
    p.figure(
        "ace2009 per built-in photo (median of 4, 451x300 to 640x427 px; first-run buffers included)",
        fmt(median(numbers_after(&ace, "total ")), 2, " ms"),
        "seed: iLab C++ 51.34 ms on one core, CUDA 10.61 ms on one GeForce 8800 GTX (Table 4.1)",
    );
    p.figure("stb preset, median of 4 images", fmt(median(numbers_after(&stb, "total ")), 2, " ms"), "");
    for n in ["astronaut", "chelsea", "coffee", "rocket"] {
        p.picture(&format!("saliency/ace2009/{n}.overlay.png"), &format!("{n}: ace2009, the most salient point"));
    }
    p.picture("saliency/ace2009/chelsea.saliency.png", "chelsea: ace2009 saliency map");
    p.picture("saliency/stb/chelsea.overlay.png", "chelsea: stb preset");
    p.files(&["saliency/ace2009/chelsea.saliency.npy", "saliency/stb/chelsea.saliency.npy"]);
    Ok(())
}

fn eval(p: &mut Part, _quick: bool) -> Result<()> {
    let args = "--stimuli inputs/mit1003/stimuli --fixations inputs/mit1003/fixation_maps";
    crate::output_files::create_dir(Path::new("eval"))?;
    let ours = p.run(&format!("eval {args} --model ocellus:ace2009 --center-prior --json eval/ocellus.json"))?;
    let centre = p.run(&format!("eval {args} --model centre --json eval/centre.json"))?;
    for (m, full) in [("CC", "0.4573 (centre baseline 0.3791)"), ("SIM", "0.3907 (0.3067)"), ("KL", "1.241 (1.553)")] {
        p.figure(
            &format!(
                "{m}, 4 images (centre baseline {})",
                fmt(number_after(&centre, &format!("{m} ")), 4, "").unwrap_or_default()
            ),
            fmt(number_after(&ours, &format!("{m} ")), 4, ""),
            &format!("100 MIT1003 images, cross-validated, README: {full}"),
        );
    }
    for n in ["p1010764", "p1010800"] {
        p.picture(&format!("inputs/mit1003/stimuli/i05june05_static_street_boston_{n}.jpg"), &format!("{n}: stimulus"));
        p.picture(
            &format!("inputs/mit1003/fixation_maps/i05june05_static_street_boston_{n}.jpg"),
            &format!("{n}: human fixation density"),
        );
    }
    p.files(&["eval/ocellus.json", "eval/centre.json"]);
    Ok(())
}

fn attention(p: &mut Part, _quick: bool) -> Result<()> {
    p.run("generate attention --scenario sudden --frames 30 --event-frame 15 --out attention/sequence")?;
    let o =
        p.run("attend attention/sequence/frames --pan-tilt attention/sequence/pan_tilt.csv --out attention/attend")?;
    p.figure("saccades over 30 frames", fmt(number_after(&o, "frames, "), 0, ""), "");
    let chaos = std::fs::read_to_string("attention/attend/context.csv")
        .ok()
        .and_then(|t| t.lines().filter_map(|l| l.split(',').nth(1)?.parse::<f64>().ok()).reduce(f64::max));
    p.figure(
        "largest context chaos degree (object appears at frame 15)",
        fmt(chaos, 3, " bits"),
        "seed: static floor 0.0526, crowd 0.0473, fast car 1.1761, sudden person large; familiar below S = 1.0",
    );
    p.picture("attention/attend/context.png", "chaos degree and surprise per frame");
    p.picture("attention/attend/overlays/frame_00015.png", "frame 15: the object appears");
    p.picture("attention/attend/overlays/frame_00016.png", "frame 16: attention moves to it");
    p.files(&["attention/attend/scanpath.csv", "attention/attend/context.csv", "attention/attend/overlays.mp4"]);
    Ok(())
}

fn plan(p: &mut Part, _quick: bool) -> Result<()> {
    let calm = p.run("plan corridor --out plan/no-event")?;
    let event = p.run("plan corridor --event --out plan/event")?;
    let pan = |t: &str| plan_row(t, 5).map(|r| format!("{} deg", r[6]));
    p.figure("pan chosen at step 5, no event", pan(&calm), "seed: 50 deg");
    p.figure("pan chosen at step 5, a person appears", pan(&event), "seed: 10 deg");
    p.figure(
        "chaos degree at step 5 with the event",
        plan_row(&event, 5).map(|r| format!("{} bits", r[2])),
        "seed: above S = 1.0",
    );
    p.picture("plan/event/angles.png", "chosen pan per step, with the event");
    p.picture("plan/event/gains_step5.png", "information gains at step 5, with the event");
    p.picture("plan/no-event/angles.png", "chosen pan per step, no event");
    p.files(&["plan/event/steps.csv", "plan/no-event/steps.csv"]);
    Ok(())
}

fn calibration(p: &mut Part, _quick: bool) -> Result<()> {
    p.run("generate chessboard --views 12 --seed 1 --out calibration/boards")?;
    let c = p.run("calibrate chessboard calibration/boards --board 9x6 --square 25mm --out calibration/calib")?;
    p.run("undistort calibration/boards --camera calibration/calib/camera.toml --out calibration/undistorted")?;
    p.figure(
        "RMS reprojection error, 12 views",
        fmt(number_after(&c, "RMS reprojection error "), 4, " px"),
        "cv2.calibrateCamera on the same kind of views: see `ocellus bench geometry`",
    );
    let truth = std::fs::read_to_string("calibration/boards/camera_truth.toml").ok();
    let fx_truth = truth.as_deref().and_then(|t| number_after(t, "fx = "));
    p.figure("fx", fmt(number_after(&c, "fx "), 2, " px"), &fmt(fx_truth, 2, " px (truth)").unwrap_or_default());
    p.figure(
        "k1",
        fmt(number_after(&c, "k1 "), 4, ""),
        &fmt(truth.as_deref().and_then(|t| number_after(t, "k1 = ")), 4, " (truth)").unwrap_or_default(),
    );
    // Two views rebuild the board: their corners (undistorted) side by side, as `paste -d,`
    // would join them, triangulated with the two views' projection matrices.
    let views = ["view_00", "view_06"];
    let matches = "calibration/matches.csv";
    let join = format!(
        "paste -d, calibration/calib/views/{}.csv calibration/calib/views/{}.csv > {matches}",
        views[0], views[1]
    );
    paste_csv(&views.map(|v| format!("calibration/calib/views/{v}.csv")), Path::new(matches))?;
    p.section.commands.push(join.clone());
    p.section.log.push_str(&format!("$ {join}\n"));
    let t = p.run(&format!(
        "triangulate --camera calibration/calib/views/{}.json --camera calibration/calib/views/{}.json {matches} \
         --truth calibration/calib/board.csv --out calibration/board_points.csv",
        views[0], views[1]
    ))?;
    p.figure(
        "board corners triangulated from 2 views, RMS 3D error",
        fmt(number_after(&t, "against the truth: "), 3, " mm"),
        "squares of 25 mm",
    );
    p.picture("calibration/boards/view_00.png", "a generated view");
    p.picture("calibration/undistorted/view_00.png", "the same view undistorted");
    p.picture("calibration/calib/per_view_error.png", "reprojection error per view");
    p.files(&[
        "calibration/calib/camera.toml",
        "calibration/calib/calibration.json",
        "calibration/boards/camera_truth.toml",
        "calibration/board_points.csv",
    ]);
    Ok(())
}

/// Joins CSV files line by line with commas, as `paste -d,` does (equal line counts).
fn paste_csv(inputs: &[String], out: &Path) -> Result<()> {
    let texts: Vec<String> = inputs
        .iter()
        .map(|f| std::fs::read_to_string(f).with_context(|| format!("cannot read {f}")))
        .collect::<Result<_>>()?;
    let lines: Vec<Vec<&str>> = texts.iter().map(|t| t.lines().collect()).collect();
    if lines.windows(2).any(|w| w[0].len() != w[1].len()) {
        bail!("{} do not have equal line counts", inputs.join(" and "));
    }
    let n = lines.first().map_or(0, Vec::len);
    let joined: String = (0..n).map(|i| lines.iter().map(|l| l[i]).collect::<Vec<_>>().join(",") + "\n").collect();
    std::fs::write(out, joined).with_context(|| format!("cannot write {}", out.display()))
}

fn stereo(p: &mut Part, _quick: bool) -> Result<()> {
    let o = p.run(
        "stereo inputs/motorcycle_left.png inputs/motorcycle_right.png --truth inputs/motorcycle_disp.pfm \
         --focal-px 994.978 --baseline 193.001 --doffs 31.086 --principal-point 311.193,254.877 --out stereo/sgm",
    )?;
    p.figure(
        "bad-2.0 (pixels off by more than 2 px)",
        fmt(number_after(&o, "bad-2.0 "), 2, " %"),
        "cv2.StereoSGBM block 3: 18.1 %, cv2.StereoBM: 27.0 % (README)",
    );
    p.figure("SGM time, 741x500, 64 disparities", fmt(number_after(&o, "64 disparities: "), 1, " ms"), "");
    p.picture("inputs/motorcycle_left.png", "left image");
    p.picture("stereo/sgm/disparity.png", "disparity");
    p.files(&["stereo/sgm/disparity.pfm", "stereo/sgm/points.ply", "stereo/sgm/depth.pfm"]);
    Ok(())
}

fn odometry(p: &mut Part, quick: bool) -> Result<()> {
    let frames = if quick { 60 } else { 200 };
    p.run(&format!("synth ground --texture mosaic --seed 1 --frames {frames} --out odometry/ground"))?;
    let cam = "--camera odometry/ground/camera.toml";
    let robust = p.run(&format!(
        "odometry odometry/ground/frames {cam} --encoders odometry/ground/encoders.csv --out odometry/robust"
    ))?;
    let er = p.run(
        "odometry eval odometry/robust/trajectory.tum odometry/ground/groundtruth.tum --plot odometry/robust/eval.png",
    )?;
    p.run(&format!("odometry odometry/ground/frames {cam} --mode seed --out odometry/seed"))?;
    let es = p.run(
        "odometry eval odometry/seed/trajectory.tum odometry/ground/groundtruth.tum --plot odometry/seed/eval.png",
    )?;
    p.figure(
        "final drift, robust mode with encoders",
        fmt(number_after(&er, "final drift "), 4, " % of the path"),
        &fmt(number_after(&es, "final drift "), 4, " % with the seed's method").unwrap_or_default(),
    );
    p.figure(
        "trajectory ATE RMSE, robust",
        fmt(number_after(&er, "ATE RMSE "), 3, " mm"),
        &fmt(number_after(&es, "ATE RMSE "), 3, " mm with the seed's method").unwrap_or_default(),
    );
    p.figure(
        "frames per second, decoding included",
        fmt(number_after(&robust, " s ("), 0, " fps"),
        "seed: 200 Hz on a 2008 quad core",
    );
    p.picture("odometry/robust/eval.png", "robust mode against the truth");
    p.picture("odometry/seed/eval.png", "the seed's method against the truth");
    p.picture("odometry/robust/flow_00001.png", "block-matching flow on frame 1");
    p.files(&[
        "odometry/robust/trajectory.tum",
        "odometry/seed/trajectory.tum",
        "odometry/ground/groundtruth.tum",
        "odometry/ground/encoders.csv",
    ]);
    Ok(())
}

fn logpolar(p: &mut Part, _quick: bool) -> Result<()> {
    let m = p.run("logpolar inputs/chelsea.png --fovea 170,130 --out logpolar/chelsea")?;
    let r = p.run("logpolar register inputs/motorcycle_left.png inputs/motorcycle_right.png --mode spectrum")?;
    let v = p.run("logpolar vergence inputs/motorcycle_left.png inputs/motorcycle_right.png --gaze 310,240")?;
    p.figure("compression of the log-polar image", fmt(number_after(&m, "compression "), 1, "x"), "");
    p.figure("rotation between the stereo pair (none)", fmt(number_after(&r, "rotation "), 3, " deg"), "truth: 0 deg");
    p.figure("scale between the stereo pair (none)", fmt(number_after(&r, "scale "), 4, ""), "truth: 1");
    p.figure("vergence disparity at the fovea", fmt(number_after(&v, "disparity "), 2, " px"), "");
    p.picture("inputs/chelsea.png", "the photo (gaze at 170, 130)");
    p.picture("logpolar/chelsea/cortex.png", "cortical image: rings x sectors");
    p.picture("logpolar/chelsea/inverse.png", "inverse map: what the retina keeps");
    p.files(&["logpolar/chelsea/logpolar.json"]);
    Ok(())
}

fn tracking(p: &mut Part, quick: bool) -> Result<()> {
    let frames = if quick { 45 } else { 60 };
    p.run(&format!(
        "generate ball --trajectory throw --seed 1 --occlusion both --frames {frames} --out tracking/ball"
    ))?;
    let truth = std::fs::read_to_string("tracking/ball/truth.csv").context("cannot read tracking/ball/truth.csv")?;
    // The model patch a user would click: 0.8 of the ball's radius on the first frame.
    let first: Vec<f64> = truth.lines().nth(1).unwrap_or("").split(',').filter_map(|v| v.parse().ok()).collect();
    if first.len() < 12 {
        bail!("tracking/ball/truth.csv has no first frame");
    }
    let (u, v, r) = (first[8], first[9], first[10]);
    let floor = number_after(&p.section.log, "--floor-y ").unwrap_or(0.55);
    let t = p.run(&format!(
        "track tracking/ball/frames --camera tracking/ball/camera.toml --radius-m 0.05 --patch {u:.1},{v:.1},{:.1} \
         --gravity 9.81 --floor-y {floor} --truth tracking/ball/truth.csv --out tracking/track",
        0.8 * r
    ))?;
    let steps = if quick { 60 } else { 120 };
    let h = p.run(&format!("track head --trajectory throw --seed 1 --steps {steps} --out tracking/head"))?;
    p.figure(
        "3D RMSE (10-frame full occlusion and a pillar)",
        fmt(number_after(&t, "= "), 2, " % of the depth"),
        "issue target: 2 %",
    );
    p.figure(
        "median image-centre error",
        fmt(number_after(&t, "median image-centre error "), 2, " px"),
        "CamShift on the same frames: see the README's table",
    );
    p.figure("steps with the ball within 2 deg of both foveas", fmt(number_after(&h, "both foveas in "), 0, " %"), "");
    p.figure(
        "robot loop rate on one core",
        fmt(number_after(&h, "control) ran at "), 0, " Hz"),
        "lecture's challenge: 50 Hz (stereo head), 60 Hz (iCub)",
    );
    p.picture("tracking/track/error.png", "tracking error over time");
    p.picture("tracking/track/overlays/frame_00020.png", "frame 20: particles and the estimate");
    p.picture("tracking/head/gaze.png", "the head's gaze angles");
    p.files(&[
        "tracking/track/track.csv",
        "tracking/ball/truth.csv",
        "tracking/head/gaze.csv",
        "tracking/track/overlays.mp4",
    ]);
    Ok(())
}

fn retina(p: &mut Part, quick: bool) -> Result<()> {
    let limit = if quick { 3 } else { 20 };
    let o = p.run(&format!("retina learn --experiment 1 --small --actions rotation-dilation --time-limit {limit} --out retina/rotation-dilation"))?;
    p.figure(
        "fovea index of the learned layout",
        fmt(number_after(&o, "fovea index "), 3, ""),
        "above 0: denser at the centre (the seed: a fovea emerges)",
    );
    p.figure(
        "held-out prediction error per pixel",
        fmt(number_after(&o, "learned "), 6, ""),
        &fmt(number_after(&o, "identity "), 6, " predicting no change").unwrap_or_default(),
    );
    p.picture("retina/rotation-dilation/layout.png", "learned receptive-field layout");
    p.picture("retina/rotation-dilation/fields.png", "receptive fields");
    p.picture("retina/rotation-dilation/cost.png", "cost over iterations");
    p.files(&["retina/rotation-dilation/retina.json", "retina/rotation-dilation/S.npy"]);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_are_read_from_what_the_commands_print() {
        let t = "against x.pfm: bad-2.0 13.78 %, density 91.84 %\n  timings ms: a 1; total 1.857\n  total 2.5\n";
        assert_eq!(number_after(t, "bad-2.0 "), Some(13.78));
        assert_eq!(numbers_after(t, "total "), [1.857, 2.5]);
        assert_eq!(number_after(t, "missing "), None);
        assert_eq!(number_after("rotation -0.062 deg", "rotation "), Some(-0.062));
        let plan =
            "step  x(m)  chaos(bits)  v  pan -> chosen (deg)\n   5   2.5        1.324  0    20 ->     10          3\n";
        assert_eq!(plan_row(plan, 5).map(|r| r[6].clone()).as_deref(), Some("10"));
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
    }
}
