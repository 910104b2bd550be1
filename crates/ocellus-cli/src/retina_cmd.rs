//! `ocellus retina learn`: the self-organizing retina (SPEC 8) on the built-in images; writes
//! the learned S, M, P, the pictures, the cost curves, the figures and checkpoints.

use crate::output_files::create_dir;
use crate::plot::{draw, Plot, Series};
use crate::ranges;
use crate::retina_summary::interval;
use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_image::Plane;
use ocellus_retina::action::{Action, ActionKinds, MotorCode};
use ocellus_retina::experiment::{setup, start, ExperimentConfig, Init, MotorSpace, Setup};
use ocellus_retina::layout::{measure, Layout};
use ocellus_retina::model::{Free, Objective, Params};
use ocellus_retina::picture;
use ocellus_retina::solver::{solve, Method, SolverConfig, SolverState, Stop};
use plotters::style::RGBColor;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus retina`.
#[derive(Args, Debug)]
pub struct RetinaArgs {
    #[command(subcommand)]
    sub: Sub,
}

#[derive(Subcommand, Debug)]
enum Sub {
    /// Learn receptive fields, motor fields and predictors from sensorimotor experience
    /// rendered from the built-in photographs and textures (one of the seed's two
    /// experiments), and measure the layout (does a fovea emerge?).
    Learn(LearnArgs),
    /// Pool the fovea index of several `retina learn` runs (e.g. seeds 1-3) per experiment,
    /// action set and action factor, with 95 % confidence intervals: is the index told apart
    /// from 0 (a fovea, or its opposite), or not?
    Summary(crate::retina_summary::SummaryArgs),
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
enum ActionsArg {
    Translation,
    RotationDilation,
    All,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
enum MotorSpaceArg {
    /// Each fixed motor field is a cell of a grid tiling the 2D motor space (60: 10 x 6), its
    /// triplets' actions drawn anywhere inside it.
    Cells,
    /// Each fixed motor field is one exact action value on the two axes.
    Values,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
enum SolverArg {
    /// PGD for experiment 1, Adam for experiment 2 (the one that reached the lower cost there).
    Auto,
    /// Spectral projected gradient descent with a nonmonotone line search.
    Pgd,
    /// Adam with projection onto >= 0.
    Adam,
    /// Both from the same start; the run with the lower final cost is the one written, both
    /// cost curves are plotted (PGD checkpoints and resumes).
    Both,
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
enum InitArg {
    /// Gaussian blobs at random centres with random widths (no size-eccentricity relation).
    Blobs,
    /// Every entry uniform random.
    Uniform,
}

/// Arguments of `ocellus retina learn`.
#[derive(Args, Debug)]
struct LearnArgs {
    /// 1: sensor design (60 fixed motor fields, 4080 triplets, 2877 pixels, 48 receptive
    /// fields); 2: co-development (225 motor cells, 16 motor fields and 16 receptive fields
    /// learned, 481 pixels, 22,500 triplets). Range: 1..=2.
    #[arg(long, value_parser = ranges::within(1u8, 2))]
    experiment: u8,
    /// Actions: shifts, rotations and dilations, or all four (experiment 1 only) [default:
    /// rotation-dilation].
    #[arg(long, value_enum, default_value = "rotation-dilation")]
    actions: ActionsArg,
    /// Experiment 1: what each fixed motor field stands for [default: cells; values with
    /// `--actions all`, which has no 2D motor space to tile].
    #[arg(long, value_enum)]
    motor_space: Option<MotorSpaceArg>,
    /// Solver.
    #[arg(long, value_enum, default_value = "auto")]
    solver: SolverArg,
    /// Starting point of S and P.
    #[arg(long, value_enum, default_value = "blobs")]
    init: InitArg,
    /// Most iterations. Range: 1..=1000000.
    #[arg(long, default_value_t = 5000, value_parser = ranges::within(1usize, 1_000_000))]
    iterations: usize,
    /// Most seconds of solving per solver run. Range: 1..=86400.
    #[arg(long, default_value_t = 600.0, value_parser = ranges::within(1.0f64, 86400.0))]
    time_limit: f64,
    /// Converged when the cost fell by less than this share over 50 iterations. Range: 0..=1.
    #[arg(long, default_value_t = 1e-3, value_parser = ranges::within(0.0f64, 1.0))]
    tolerance: f64,
    /// Adam's step as a share of each block's initial mean entry. Range: 1e-6..=1.
    #[arg(long, default_value_t = 0.01, value_parser = ranges::within(1e-6f64, 1.0))]
    learning_rate: f64,
    /// Weight lambda of the simplicity term lambda (mean S + mean P + mean M). Range: 0..=10.
    #[arg(long, default_value_t = ocellus_retina::experiment::DEFAULT_SIMPLICITY, value_parser = ranges::within(0.0f64, 10.0))]
    simplicity: f64,
    /// Seed of the experience (gaze points, images, random actions) and of the start. Range:
    /// any 64-bit unsigned integer.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Gaussian blur of the source images before sampling (the eye's optics), sigma in
    /// pixels. Range: 0..=50.
    #[arg(long, default_value_t = ocellus_retina::experiment::DEFAULT_BLUR_PX, value_parser = ranges::within(0.0f64, 50.0))]
    blur: f64,
    /// Factor on the largest actions (shifts of half the disc radius, rotations of 30
    /// degrees, dilations by e^0.3) [default, experiment 1 with cells: 5 for rotation +
    /// dilation (rotations up to 150 degrees, dilations up to e^1.5), 1.5 for translation
    /// (shifts up to 0.75 radii: on average as much of the view stays in view, 64 % against
    /// 66 %); 1 otherwise]. Range: 0.05..=5.
    #[arg(long, value_parser = ranges::within(0.05f64, 5.0))]
    action_scale: Option<f64>,
    /// Experiment 2: weight of the motor fields' smoothness (the mean squared difference of
    /// neighbouring motor cells) in the cost. Range: 0..=100.
    #[arg(long, default_value_t = 0.0, value_parser = ranges::within(0.0f64, 100.0))]
    motor_smoothness: f64,
    /// Also learn the baseline with a random fixed S (only P, and M in experiment 2); on by
    /// default, `--baseline false` skips it.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    baseline: bool,
    /// Experiment 1 reduced (481 pixels, 16 fields, 20 motor fields x 24 triplets), for a
    /// quick look.
    #[arg(long)]
    small: bool,
    /// More source images (a folder of PNG/JPEG/PNM, read as grey) beside the built-in ones.
    #[arg(long)]
    images: Option<PathBuf>,
    /// Continue from OUT/checkpoint (same experiment, actions, seed and solver).
    #[arg(long)]
    resume: bool,
    /// Write a checkpoint every this many iterations. Range: 1..=1000000.
    #[arg(long, default_value_t = 100, value_parser = ranges::within(1usize, 1_000_000))]
    checkpoint_every: usize,
    /// Output folder: S.npy (fields x pixels), M.npy, P.npy (motor fields x fields x
    /// fields), disc.npy (the pixels' x, y offsets), fields.png, layout.png, predictors.png,
    /// flow_*.png (canonical predictors as flows), motor_fields.png (experiment 2), cost.png,
    /// retina.json (the figures), checkpoint/.
    #[arg(long, default_value = "ocellus-retina")]
    out: PathBuf,
}

/// Runs `ocellus retina`.
pub fn run(a: RetinaArgs) -> Result<()> {
    match a.sub {
        Sub::Learn(l) => learn(l),
        Sub::Summary(s) => crate::retina_summary::run(s),
    }
}

/// The built-in photographs and textures, grey, plus any images of `extra`.
fn sources(extra: Option<&Path>) -> Result<Vec<Plane<f32>>> {
    let mut v = Vec::new();
    for (name, _) in crate::assets::IMAGES.iter().chain(crate::assets::TEXTURES) {
        v.push(crate::assets::decode(name)?.to_grey());
    }
    if let Some(dir) = extra {
        let files = crate::inputs::collect_images(&[dir.to_path_buf()])?;
        for f in files {
            v.push(ocellus_io::read_image(&f)?.to_grey());
        }
    }
    Ok(v)
}

fn kinds(a: ActionsArg) -> ActionKinds {
    match a {
        ActionsArg::Translation => ActionKinds::Translation,
        ActionsArg::RotationDilation => ActionKinds::RotationDilation,
        ActionsArg::All => ActionKinds::All,
    }
}

/// One solver run's outcome.
struct Run {
    method: Method,
    params: Params<f32>,
    state: SolverState,
    stop: Stop,
}

fn learn(a: LearnArgs) -> Result<()> {
    let actions = kinds(a.actions);
    let mut cfg = match (a.experiment, a.small) {
        (1, false) => ExperimentConfig::sensor_design(actions),
        (1, true) => ExperimentConfig::sensor_design_small(actions),
        (2, false) => ExperimentConfig::co_development(actions),
        _ => bail!("--small reduces experiment 1 only"),
    };
    cfg.seed = a.seed;
    cfg.simplicity = a.simplicity;
    cfg.blur_px = a.blur;
    cfg.motor_smoothness = a.motor_smoothness;
    match (a.motor_space, cfg.experiment) {
        (Some(MotorSpaceArg::Cells), 1) => cfg.motor_space = MotorSpace::Cells,
        (Some(MotorSpaceArg::Values), 1) => {
            cfg.motor_space = MotorSpace::Values;
            cfg.action_scale = 1.0;
        }
        (Some(_), _) => bail!("--motor-space is for experiment 1 (experiment 2 learns its motor fields)"),
        (None, _) => {}
    }
    if let Some(k) = a.action_scale {
        cfg.action_scale = k;
    }
    cfg.validate()?;
    let src = sources(a.images.as_deref())?;
    outln!(
        "experiment {}: {} pixels, {} receptive fields, {} motor fields over {} motor cells{}, {} actions; {} variables",
        cfg.experiment,
        cfg.pixels,
        cfg.fields,
        cfg.motor_fields,
        cfg.shape().motor_cells,
        if cfg.experiment == 1 { format!(" (as {})", cfg.motor_space.name()) } else { String::new() },
        actions.name(),
        cfg.variables()
    );
    let su: Setup<f32> = setup(&cfg, &src)?;
    outln!(
        "{} training and {} held-out triplets from {} images (disc radius {:.2} px)",
        su.train.len(),
        su.heldout.len(),
        src.len(),
        su.disc.radius()
    );
    // How much of the view an action keeps on average (2D motor spaces only).
    let kept = su.ranges.mean_kept_share(cfg.actions, su.disc.radius()).ok();
    if let Some(k) = kept {
        outln!("an action keeps {:.0} % of the view in view on average", 100.0 * k);
    }
    create_dir(&a.out)?;
    let ckpt = a.out.join("checkpoint");
    create_dir(&ckpt)?;
    let init = match a.init {
        InitArg::Blobs => Init::Blobs,
        InitArg::Uniform => Init::Uniform,
    };
    let p0 = start(&su, init, a.seed)?;
    let layout0 = measure(&su.disc, &p0.s, cfg.fields)?;
    let scfg = |method| SolverConfig {
        method,
        max_iterations: a.iterations,
        time_limit_s: a.time_limit,
        tolerance: a.tolerance,
        window: 50,
        learning_rate: a.learning_rate,
    };
    let obj = Objective { data: &su.train, free: cfg.free(), simplicity: cfg.simplicity, smoothness: cfg.smoothness() };
    let methods: Vec<Method> = match a.solver {
        SolverArg::Auto if cfg.experiment == 2 => vec![Method::Adam],
        SolverArg::Auto | SolverArg::Pgd => vec![Method::Pgd],
        SolverArg::Adam => vec![Method::Adam],
        SolverArg::Both => vec![Method::Pgd, Method::Adam],
    };
    let mut runs = Vec::new();
    for (i, &method) in methods.iter().enumerate() {
        // Only the first (written) run checkpoints and resumes.
        let dir = (i == 0).then_some(ckpt.as_path());
        let (mut params, mut state) = match (a.resume && i == 0, dir) {
            (true, Some(d)) => load_checkpoint(d, &cfg, method)?,
            _ => (p0.clone(), SolverState::new()),
        };
        let stop = run_solver(&obj, &scfg(method), &mut params, &mut state, dir, &cfg, a.checkpoint_every, "")?;
        let last = state.history.last().map(|r| (r.cost, r.mse, r.seconds)).unwrap_or_default();
        outln!(
            "{:?}: {:?} after {} iterations ({} evaluations, {:.1} s), cost {:.6}, mse {:.6}",
            method,
            stop,
            state.iteration,
            state.evaluations,
            last.2,
            last.0,
            last.1
        );
        runs.push(Run { method, params, state, stop });
    }
    // The written result: the run with the lower final cost.
    let final_cost = |r: &Run| r.state.history.last().map_or(f64::INFINITY, |h| h.cost);
    let best = (0..runs.len()).min_by(|&a, &b| final_cost(&runs[a]).total_cmp(&final_cost(&runs[b]))).unwrap_or(0);
    let main = &runs[best];
    let held = Objective { data: &su.heldout, free: cfg.free(), simplicity: 0.0, smoothness: None };
    let mse_learned = held.evaluate(&main.params, false).mse;
    let mse_identity = su.heldout.identity_mse();
    let baseline = if a.baseline {
        let mut p = start(&su, Init::Uniform, a.seed ^ 0xBA5E)?;
        let free = Free { s: false, ..cfg.free() };
        let bobj = Objective { data: &su.train, free, simplicity: cfg.simplicity, smoothness: cfg.smoothness() };
        let mut st = SolverState::new();
        let stop =
            run_solver(&bobj, &scfg(main.method), &mut p, &mut st, None, &cfg, a.checkpoint_every, "random S: ")?;
        let mse = Objective { data: &su.heldout, free, simplicity: 0.0, smoothness: None }.evaluate(&p, false).mse;
        Some((mse, stop, st))
    } else {
        None
    };
    let layout = measure(&su.disc, &main.params.s, cfg.fields)?;
    let density = |l: &ocellus_retina::layout::Layout| {
        l.density_ratio.map(|d| format!("{d:.2}")).unwrap_or_else(|| "none outside".into())
    };
    outln!(
        "held-out mse per pixel: learned {:.6}, identity {:.6}{}",
        mse_learned,
        mse_identity,
        baseline.as_ref().map(|b| format!(", random fixed S {:.6}", b.0)).unwrap_or_default()
    );
    outln!(
        "layout: {} live fields ({} dead), fovea index {:.3} (95 % interval {}; start {:.3}), over the {} interior fields {:.3} ({}; start {:.3}), slope {:.2} px^2/px, areas centre {:.1} / periphery {:.1} px^2, density ratio {} (start {})",
        layout.fields.len(),
        layout.dead,
        layout.fovea_index,
        interval(layout.fovea_index_ci95),
        layout0.fovea_index,
        layout.interior_fields,
        layout.fovea_index_interior,
        interval(layout.fovea_index_interior_ci95),
        layout0.fovea_index_interior,
        layout.slope_px2_per_px,
        layout.mean_area_centre_px,
        layout.mean_area_periphery_px,
        density(&layout),
        density(&layout0)
    );
    write_outputs(&a.out, &su, &runs, best, &layout)?;
    let figures = json!({
        "experiment": cfg.experiment,
        "config": cfg,
        "variables": cfg.variables(),
        "triplets_train": su.train.len(),
        "triplets_heldout": su.heldout.len(),
        "images": src.len(),
        "disc_radius_px": su.disc.radius(),
        "init": format!("{:?}", init).to_lowercase(),
        "convergence": "relative cost decrease over 50 iterations below the tolerance",
        "tolerance": a.tolerance,
        "runs": runs.iter().map(|r| {
            let last = r.state.history.last();
            json!({
                "solver": r.method,
                "stop": r.stop,
                "iterations": r.state.iteration,
                "evaluations": r.state.evaluations,
                "seconds": last.map(|x| x.seconds),
                "cost": last.map(|x| x.cost),
                "mse_train": last.map(|x| x.mse),
                "mse_heldout": held.evaluate(&r.params, false).mse,
            })
        }).collect::<Vec<_>>(),
        "solver_written": main.method,
        "mse_heldout_learned": mse_learned,
        "mse_heldout_identity": mse_identity,
        "mse_heldout_random_s": baseline.as_ref().map(|b| b.0),
        "random_s_stop": baseline.as_ref().map(|b| b.1),
        "random_s_iterations": baseline.as_ref().map(|b| b.2.iteration),
        "improvement_over_identity": mse_identity / mse_learned,
        "improvement_over_random_s": baseline.as_ref().map(|b| b.0 / mse_learned),
        "fovea_index": layout.fovea_index,
        "fovea_index_start": layout0.fovea_index,
        "fovea_index_interior": layout.fovea_index_interior,
        "fovea_index_interior_start": layout0.fovea_index_interior,
        "density_ratio_start": layout0.density_ratio,
        "kept_share_mean": kept,
        "layout": layout,
    });
    let f = a.out.join("retina.json");
    std::fs::write(&f, serde_json::to_string_pretty(&figures)?)
        .with_context(|| format!("cannot write {}", f.display()))?;
    outln!("wrote {}", a.out.display());
    Ok(())
}

/// Runs one solver with a progress bar, checkpointing into `ckpt` when given.
fn run_solver(
    obj: &Objective<f32>,
    scfg: &SolverConfig,
    params: &mut Params<f32>,
    state: &mut SolverState,
    ckpt: Option<&Path>,
    cfg: &ExperimentConfig,
    every: usize,
    label: &str,
) -> Result<Stop> {
    let bar = ProgressBar::new(scfg.max_iterations as u64).with_style(
        ProgressStyle::with_template("{prefix}{bar:30} {pos}/{len} it {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_prefix(format!("{label}{:?} ", scfg.method));
    bar.set_position(state.iteration as u64);
    let mut failed = None;
    let stop = solve(obj, scfg, params, state, |p, st| {
        bar.set_position(st.iteration as u64);
        if let Some(r) = st.history.last() {
            bar.set_message(format!("cost {:.6} mse {:.6}", r.cost, r.mse));
        }
        if let Some(d) = ckpt {
            if st.iteration % every == 0 {
                if let Err(e) = save_checkpoint(d, cfg, scfg.method, p, st) {
                    failed = Some(e);
                    return false;
                }
            }
        }
        true
    })?;
    bar.finish_and_clear();
    if let Some(e) = failed {
        return Err(e);
    }
    if let Some(d) = ckpt {
        save_checkpoint(d, cfg, scfg.method, params, state)?;
    }
    Ok(stop)
}

fn f32s(v: &[f32]) -> Vec<f32> {
    v.to_vec()
}

/// Writes the parameters and the solver state so that `--resume` continues the run.
fn save_checkpoint(
    dir: &Path,
    cfg: &ExperimentConfig,
    method: Method,
    p: &Params<f32>,
    st: &SolverState,
) -> Result<()> {
    let sh = p.shape;
    ocellus_io::npy::write_f32(dir.join("S.npy"), &[sh.fields, sh.pixels], &f32s(&p.s))?;
    ocellus_io::npy::write_f32(dir.join("M.npy"), &[sh.motor_fields, sh.motor_cells], &f32s(&p.m))?;
    ocellus_io::npy::write_f32(dir.join("P.npy"), &[sh.motor_fields, sh.fields, sh.fields], &f32s(&p.p))?;
    let total = st.adam_m.len();
    ocellus_io::npy::write_f64(dir.join("adam_m.npy"), &[total], &st.adam_m)?;
    ocellus_io::npy::write_f64(dir.join("adam_v.npy"), &[total], &st.adam_v)?;
    let mut light = st.clone();
    light.adam_m.clear();
    light.adam_v.clear();
    let j = json!({ "config": cfg, "solver": method, "state": light });
    // Written last and renamed into place: a checkpoint is whole or absent.
    let tmp = dir.join("state.json.tmp");
    std::fs::write(&tmp, serde_json::to_string(&j)?).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, dir.join("state.json")).with_context(|| format!("cannot write {}", dir.display()))?;
    Ok(())
}

fn load_checkpoint(dir: &Path, cfg: &ExperimentConfig, method: Method) -> Result<(Params<f32>, SolverState)> {
    let f = dir.join("state.json");
    let text =
        std::fs::read_to_string(&f).with_context(|| format!("no checkpoint to resume: cannot read {}", f.display()))?;
    let j: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not a checkpoint", f.display()))?;
    let saved: ExperimentConfig = serde_json::from_value(j["config"].clone()).context("checkpoint config")?;
    let saved_method: Method = serde_json::from_value(j["solver"].clone()).context("checkpoint solver")?;
    if saved != *cfg || saved_method != method {
        bail!(
            "the checkpoint in {} is of another run ({:?} experiment {} {} seed {}); resume with the same options or use another --out",
            dir.display(),
            saved_method,
            saved.experiment,
            saved.actions.name(),
            saved.seed
        );
    }
    let mut state: SolverState = serde_json::from_value(j["state"].clone()).context("checkpoint state")?;
    let read = |name: &str, want: usize| -> Result<Vec<f64>> {
        let a = ocellus_io::npy::read(dir.join(name))?;
        if a.data.len() != want {
            bail!("{} holds {} values, the run needs {want}", dir.join(name).display(), a.data.len());
        }
        Ok(a.data)
    };
    let sh = cfg.shape();
    let [ns, nm, np] = sh.sizes();
    let to32 = |v: Vec<f64>| v.into_iter().map(|x| x as f32).collect::<Vec<f32>>();
    let params =
        Params { shape: sh, s: to32(read("S.npy", ns)?), m: to32(read("M.npy", nm)?), p: to32(read("P.npy", np)?) };
    params.validate()?;
    let adam = ocellus_io::npy::read(dir.join("adam_m.npy"))?.data;
    if !adam.is_empty() {
        state.adam_m = read("adam_m.npy", ns + nm + np)?;
        state.adam_v = read("adam_v.npy", ns + nm + np)?;
    }
    Ok((params, state))
}

/// The canonical actions shown as predictor flows: the largest zoom-out and rotate-right (or
/// shift-right and shift-down) of the action set.
fn canonical(su: &Setup<f32>) -> Vec<(&'static str, Action)> {
    let r = su.ranges;
    match su.config.actions {
        ActionKinds::Translation => vec![
            ("shift_right", Action::Shift { dx: r.shift_px, dy: 0.0 }),
            ("shift_down", Action::Shift { dx: 0.0, dy: r.shift_px }),
        ],
        _ => vec![
            ("zoom_out", Action::RotateDilate { theta: 0.0, s: -r.log_scale }),
            ("rotate_right", Action::RotateDilate { theta: r.rotation_rad, s: 0.0 }),
        ],
    }
}

fn write_outputs(out: &Path, su: &Setup<f32>, runs: &[Run], best: usize, layout: &Layout) -> Result<()> {
    let p = &runs[best].params;
    let sh = p.shape;
    ocellus_io::npy::write_f32(out.join("S.npy"), &[sh.fields, sh.pixels], &p.s)?;
    ocellus_io::npy::write_f32(out.join("M.npy"), &[sh.motor_fields, sh.motor_cells], &p.m)?;
    ocellus_io::npy::write_f32(out.join("P.npy"), &[sh.motor_fields, sh.fields, sh.fields], &p.p)?;
    let offs: Vec<f32> = su.disc.offsets().iter().flat_map(|o| [o[0] as f32, o[1] as f32]).collect();
    ocellus_io::npy::write_f32(out.join("disc.npy"), &[sh.pixels, 2], &offs)?;
    let scale = if sh.pixels > 1000 { 4 } else { 8 };
    ocellus_io::write_png(out.join("fields.png"), &picture::receptive_fields(&su.disc, &p.s, sh.fields, scale)?)?;
    ocellus_io::write_png(out.join("layout.png"), &picture::layout_contours(&su.disc, &p.s, layout, 2 * scale)?)?;
    ocellus_io::write_png(
        out.join("predictors.png"),
        &picture::predictor_matrices(&p.p, sh.motor_fields, sh.fields, 4)?,
    )?;
    if let MotorCode::Grid { cells, .. } = su.code {
        ocellus_io::write_png(out.join("motor_fields.png"), &picture::motor_fields(&p.m, sh.motor_fields, cells, 8)?)?;
    }
    let mut q = vec![0.0; su.code.len()];
    for (name, action) in canonical(su) {
        // The discrete values of experiment 1 hold the extremes exactly; the grid holds any.
        if su.code.encode(&action, &mut q).is_err() {
            continue;
        }
        let rr = sh.fields * sh.fields;
        let mut pq = vec![0.0f32; rr];
        for k in 0..sh.motor_fields {
            let a: f64 = (0..sh.motor_cells).map(|j| p.m[k * sh.motor_cells + j] as f64 * q[j]).sum();
            for (o, &v) in pq.iter_mut().zip(&p.p[k * rr..(k + 1) * rr]) {
                *o += (a * v as f64) as f32;
            }
        }
        ocellus_io::write_png(
            out.join(format!("flow_{name}.png")),
            &picture::predictor_flow(&su.disc, layout, &pq, sh.fields, 2 * scale)?,
        )?;
    }
    let colours = [RGBColor(30, 90, 200), RGBColor(220, 80, 20)];
    let lowest =
        runs.iter().filter_map(|r| r.state.history.last().map(|h| h.cost)).fold(f64::INFINITY, f64::min).max(1e-12);
    let series: Vec<Series> = runs
        .iter()
        .zip(colours)
        .map(|(r, color)| Series {
            label: if r.method == Method::Pgd { "PGD (spectral, line search)" } else { "Adam + projection" },
            // At most about 300 markers per curve: thousands of iterations would draw a rope.
            points: {
                let step = (r.state.history.len() / 300).max(1);
                r.state.history.iter().step_by(step).map(|h| (h.seconds, h.cost)).collect()
            },
            color,
        })
        .collect();
    draw(
        &out.join("cost.png"),
        &Plot {
            title: "cost per solver",
            x_label: "seconds",
            y_label: "cost",
            series: &series,
            threshold: None,
            // The first iterations fall by an order of magnitude; show the part that differs.
            y_range: Some((0.0, 4.0 * lowest)),
        },
    )?;
    Ok(())
}
