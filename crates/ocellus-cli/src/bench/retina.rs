//! `ocellus bench retina`: the self-organizing retina's cost per gradient evaluation and per
//! solver iteration, for both of the seed's experiments at their sizes, on all threads and on
//! one, and the peak memory.

use super::timing::{median, peak_rss_mb};
use anyhow::Result;
use ocellus_retina::action::ActionKinds;
use ocellus_retina::experiment::{setup, start, ExperimentConfig, Init};
use ocellus_retina::model::Objective;
use ocellus_retina::solver::{solve, Method, SolverConfig, SolverState};
use serde_json::json;
use std::time::Instant;

/// Median seconds of one cost + gradient evaluation, and mean seconds per iteration of each
/// solver over `iters` iterations from the blob start.
fn measure(cfg: &ExperimentConfig, threads: usize, iters: usize) -> Result<serde_json::Value> {
    let sources: Vec<_> = crate::assets::IMAGES
        .iter()
        .chain(crate::assets::TEXTURES)
        .map(|(n, _)| crate::assets::decode(n).map(|i| i.to_grey()))
        .collect::<Result<_>>()?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    pool.install(|| -> Result<serde_json::Value> {
        let su = setup::<f32>(cfg, &sources)?;
        let p0 = start(&su, Init::Blobs, 1)?;
        let obj = Objective { data: &su.train, free: cfg.free(), simplicity: cfg.simplicity, smoothness: None };
        let mut t: Vec<f64> = (0..7)
            .map(|_| {
                let s = Instant::now();
                let e = obj.evaluate(&p0, true);
                std::hint::black_box(e.cost);
                s.elapsed().as_secs_f64()
            })
            .collect();
        let grad_ms = median(&mut t) * 1e3;
        let mut per_iter = serde_json::Map::new();
        for method in [Method::Pgd, Method::Adam] {
            let mut p = p0.clone();
            let mut st = SolverState::new();
            let scfg = SolverConfig { method, max_iterations: iters, tolerance: 0.0, ..SolverConfig::default() };
            let s = Instant::now();
            solve(&obj, &scfg, &mut p, &mut st, |_, _| true)?;
            let name = format!("{method:?}").to_lowercase();
            per_iter.insert(format!("ms_per_iteration_{name}"), json!(s.elapsed().as_secs_f64() * 1e3 / iters as f64));
            per_iter.insert(format!("evaluations_per_iteration_{name}"), json!(st.evaluations as f64 / iters as f64));
        }
        let mut v = json!({ "ms_per_gradient": grad_ms, "variables": cfg.variables(), "triplets": su.train.len() });
        if let Some(o) = v.as_object_mut() {
            o.extend(per_iter);
        }
        Ok(v)
    })
}

/// Runs the benchmark.
pub fn run(json_out: bool) -> Result<()> {
    let threads = rayon::current_num_threads();
    let mut figures = serde_json::Map::new();
    figures.insert("threads".into(), json!(threads));
    for (key, cfg) in [
        ("experiment1", ExperimentConfig::sensor_design(ActionKinds::RotationDilation)),
        ("experiment2", ExperimentConfig::co_development(ActionKinds::RotationDilation)),
    ] {
        figures.insert(format!("{key}_all_threads"), measure(&cfg, threads, 20)?);
        figures.insert(format!("{key}_one_thread"), measure(&cfg, 1, 5)?);
    }
    figures.insert("peak_rss_mb".into(), json!(peak_rss_mb()));
    let v = serde_json::Value::Object(figures);
    if json_out {
        outln!("{v}");
        return Ok(());
    }
    for key in ["experiment1", "experiment2"] {
        for (t, name) in [("all_threads", format!("{threads} threads")), ("one_thread", "1 thread".to_string())] {
            let e = &v[format!("{key}_{t}")];
            outln!(
                "{key} ({} variables, {} triplets), {name}: gradient {:.1} ms, PGD iteration {:.1} ms ({:.2} evaluations), Adam iteration {:.1} ms",
                e["variables"],
                e["triplets"],
                e["ms_per_gradient"].as_f64().unwrap_or(0.0),
                e["ms_per_iteration_pgd"].as_f64().unwrap_or(0.0),
                e["evaluations_per_iteration_pgd"].as_f64().unwrap_or(0.0),
                e["ms_per_iteration_adam"].as_f64().unwrap_or(0.0)
            );
        }
    }
    if let Some(m) = v["peak_rss_mb"].as_f64() {
        outln!("peak memory {m:.0} MB");
    }
    Ok(())
}
