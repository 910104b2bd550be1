//! `ocellus bench tracking`: one SIR step of the 3D ball tracker on a 640x480 frame (moving
//! the particles, binning the region their circles read, weighing every particle by the
//! colour likelihood, resampling; and once with the whole frame binned first) for
//! 10^2..10^5 particles on one thread and on all, and resampling 10^6 particles with each
//! scheme.

use super::timing::median;
use anyhow::Result;
use nalgebra::{Matrix3, Vector3};
use ocellus_estimation::particle_filter::{FilterConfig, ParticleFilter};
use ocellus_estimation::resampling::Resampler;
use ocellus_geometry::camera::{Intrinsics, PinholeCamera};
use ocellus_geometry::distortion::Distortion;
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;
use ocellus_tracking::ball::{project_ball, BallFrame, BallModel, BallState};
use ocellus_tracking::binning::BinnedFrame;
use ocellus_tracking::colour::{Circle, ColourModel};
use ocellus_tracking::motion::MotionModel;
use ocellus_tracking::tracker::TrackerConfig;
use serde_json::json;
use std::time::Instant;

/// The built-in astronaut photo stretched to 640x480 with an orange ball (5 cm at 2 m).
fn scene() -> Result<(Plane<[u8; 3]>, BallModel, Vector3<f64>)> {
    let photo = crate::assets::decode("astronaut.png")?.to_u8();
    let k = Intrinsics { fx: 600.0, fy: 600.0, cx: 319.5, cy: 239.5, skew: 0.0 };
    let camera = PinholeCamera { k, r: Matrix3::identity(), t: Vector3::zeros() };
    let distortion = Distortion { k1: -0.12, k2: 0.02, k3: 0.0, p1: 0.0, p2: 0.0 };
    let ball = Vector3::new(0.2, -0.1, 2.0);
    let c = project_ball(&camera, &distortion, &ball, 0.05).ok_or_else(|| anyhow::anyhow!("ball out of view"))?;
    let (pw, ph) = photo.size();
    let frame = Plane::from_fn(640, 480, |x, y| {
        if (x as f64 - c.x).powi(2) + (y as f64 - c.y).powi(2) <= c.r * c.r {
            [245, 120, 25]
        } else {
            photo.get(x * pw / 640, y * ph / 480)
        }
    });
    let colour = ColourModel::from_patch(&frame, Circle { r: 0.8 * c.r, ..c })?;
    let model = BallModel {
        camera,
        distortion,
        radius_m: 0.05,
        motion: MotionModel::at_fps(30.0),
        colour,
        boost: 0.0,
        detection_velocity_sigma_mps: [3.0, 0.5],
        evidence_score: TrackerConfig::at_fps(30.0).evidence_score,
        cut_sigma_px: 0.0,
    };
    Ok((frame, model, ball))
}

/// Median milliseconds of one SIR step (binning included) with `n` particles on `pool`:
/// as the plain tracker does it (particles moved first, then only the region their circles
/// read is binned), or with the whole frame binned first (`whole_frame`).
fn sir_step_ms(
    pool: &rayon::ThreadPool,
    n: usize,
    frame: &Plane<[u8; 3]>,
    model: &BallModel,
    ball: &Vector3<f64>,
    whole_frame: bool,
) -> Result<f64> {
    pool.install(|| -> Result<f64> {
        let mut pf = cloud(n, ball)?;
        let mut obs = BallFrame::default();
        let reps = (200_000 / n).clamp(5, 200);
        let mut t = Vec::with_capacity(reps);
        for _ in 0..reps {
            let s = Instant::now();
            if whole_frame {
                obs.binned.update(frame);
                pf.propose(model, &obs);
                model.weigh(&mut pf, &obs)?;
            } else {
                model.step_in_region(&mut pf, frame, &mut obs)?;
            }
            t.push(s.elapsed().as_secs_f64() * 1e3);
        }
        Ok(median(&mut t))
    })
}

/// `n` particles about `ball` (metres), resampled every step.
fn cloud(n: usize, ball: &Vector3<f64>) -> Result<ParticleFilter<BallState>> {
    let mut rng = SplitMix64::new(1);
    let particles: Vec<BallState> = (0..n)
        .map(|_| BallState {
            position: [ball.x + 0.03 * rng.normal(), ball.y + 0.03 * rng.normal(), ball.z + 0.1 * rng.normal()],
            velocity: [0.3 * rng.normal(), 0.3 * rng.normal(), 0.3 * rng.normal()],
        })
        .collect();
    let cfg = FilterConfig { resample_below: 1.0, ..FilterConfig::default() };
    Ok(ParticleFilter::new(cfg, particles)?)
}

/// Rounds of [`speedup`].
const SPEEDUP_ROUNDS: usize = 15;

/// Timed steps per side of a round of [`speedup`], after one untimed.
const SPEEDUP_BLOCK: usize = 8;

/// The SIR step of `n` particles on one thread and on `threads`, timed in alternating
/// blocks: each of [`SPEEDUP_ROUNDS`] rounds runs [`SPEEDUP_BLOCK`] steps (after one untimed)
/// of one filter on one thread, then as many of an identical filter on `threads` (both
/// filters go through the same particles, as the result does not depend on the thread
/// count). Returns the median milliseconds on `threads` and the median of the rounds'
/// ratios of block medians (one thread over `threads`). Alternating rounds put a burst of
/// load from elsewhere on both sides of a round, not on all of one side, as when the sides
/// were timed one after the other; blocks, not single steps, because a pool left idle puts
/// its threads to sleep, and waking them cost up to 2 ms a step on this 2-vCPU VM when the
/// sides took turns step by step (the speed-up then read 1.3-1.9x).
fn speedup(
    n: usize,
    threads: usize,
    frame: &Plane<[u8; 3]>,
    model: &BallModel,
    ball: &Vector3<f64>,
) -> Result<(f64, f64)> {
    let one_pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let all_pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let (mut a, mut b) = (cloud(n, ball)?, cloud(n, ball)?);
    let (mut oa, mut ob) = (BallFrame::default(), BallFrame::default());
    let block = |pool: &rayon::ThreadPool, pf: &mut ParticleFilter<BallState>, obs: &mut BallFrame| {
        pool.install(|| -> Result<f64> {
            model.step_in_region(pf, frame, obs)?;
            let mut t = (0..SPEEDUP_BLOCK)
                .map(|_| -> Result<f64> {
                    let s = Instant::now();
                    model.step_in_region(pf, frame, obs)?;
                    Ok(s.elapsed().as_secs_f64() * 1e3)
                })
                .collect::<Result<Vec<f64>>>()?;
            Ok(median(&mut t))
        })
    };
    let (mut alls, mut ratios) = (Vec::new(), Vec::new());
    for _ in 0..SPEEDUP_ROUNDS {
        let t1 = block(&one_pool, &mut a, &mut oa)?;
        let t2 = block(&all_pool, &mut b, &mut ob)?;
        alls.push(t2);
        ratios.push(t1 / t2);
    }
    Ok((median(&mut alls), median(&mut ratios)))
}

/// Runs the benchmark.
pub fn run(json_out: bool) -> Result<()> {
    let n = 1_000_000;
    let mut rng = SplitMix64::new(5);
    // Uneven weights, as after a sharp likelihood: a few heavy particles among many light.
    let raw: Vec<f64> = (0..n).map(|_| rng.unit().powi(6)).collect();
    let s: f64 = raw.iter().sum();
    let w: Vec<f64> = raw.iter().map(|v| v / s).collect();
    let mut out = Vec::with_capacity(n);
    let mut figures = serde_json::Map::new();
    let (frame, model, ball) = scene()?;
    let threads = rayon::current_num_threads();
    figures.insert("threads".into(), json!(threads));
    let mut frame_bin = BinnedFrame::default();
    // Binning and the steps run on the pool: the one-thread figures on a pool of one.
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let mut tb: Vec<f64> = one_thread.install(|| {
        (0..20)
            .map(|_| {
                let s = Instant::now();
                frame_bin.update(&frame);
                s.elapsed().as_secs_f64() * 1e3
            })
            .collect()
    });
    figures.insert("ms_bin_frame_640x480".into(), json!(median(&mut tb)));
    for (p, key) in [(100, "1e2"), (1000, "1e3"), (10_000, "1e4"), (100_000, "1e5")] {
        figures.insert(
            format!("ms_sir_step_{key}_1thread"),
            json!(sir_step_ms(&one_thread, p, &frame, &model, &ball, false)?),
        );
    }
    figures.insert(
        "ms_sir_step_1e3_whole_frame_1thread".into(),
        json!(sir_step_ms(&one_thread, 1000, &frame, &model, &ball, true)?),
    );
    // Its thread is not left beside the two pools of the speed-up.
    drop(one_thread);
    let (all, ratio) = speedup(10_000, threads, &frame, &model, &ball)?;
    figures.insert("ms_sir_step_1e4_all_threads".into(), json!(all));
    figures.insert("speedup_all_threads_1e4".into(), json!(ratio));
    figures.insert("particles_resampled".into(), json!(n));
    for (name, r) in [
        ("systematic", Resampler::Systematic),
        ("stratified", Resampler::Stratified),
        ("multinomial", Resampler::Multinomial),
        ("residual", Resampler::Residual),
    ] {
        let mut t: Vec<f64> = (0..11)
            .map(|_| -> Result<f64> {
                let s = Instant::now();
                r.resample(&w, &mut rng, &mut out)?;
                Ok(s.elapsed().as_secs_f64() * 1e3)
            })
            .collect::<Result<_>>()?;
        figures.insert(format!("ms_resample_{name}_1e6"), json!(median(&mut t)));
    }
    let v = serde_json::Value::Object(figures);
    if json_out {
        outln!("{v}");
        return Ok(());
    }
    outln!(
        "one SIR step of the ball tracker on a 640x480 frame, binning the particles' region (the whole frame: {:.2} ms), one thread:",
        v["ms_bin_frame_640x480"].as_f64().unwrap_or(0.0)
    );
    for key in ["1e2", "1e3", "1e4", "1e5"] {
        outln!("  {key:>4} particles  {:.3} ms", v[format!("ms_sir_step_{key}_1thread")].as_f64().unwrap_or(0.0));
    }
    outln!(
        "   1e3 particles, the whole frame binned first: {:.3} ms",
        v["ms_sir_step_1e3_whole_frame_1thread"].as_f64().unwrap_or(0.0)
    );
    outln!(
        "  1e4 particles on {threads} threads: {:.3} ms ({:.2}x)",
        v["ms_sir_step_1e4_all_threads"].as_f64().unwrap_or(0.0),
        v["speedup_all_threads_1e4"].as_f64().unwrap_or(0.0)
    );
    outln!("resampling {n} particles on one thread (median of 11):");
    for name in ["systematic", "stratified", "multinomial", "residual"] {
        outln!("  {name:<12} {:.2} ms", v[format!("ms_resample_{name}_1e6")].as_f64().unwrap_or(0.0));
    }
    Ok(())
}
