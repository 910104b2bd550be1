//! `ocellus retina summary`: the fovea index of several `retina learn` runs, each and pooled per
//! experiment, action set and action factor, with 95 % confidence intervals.

use anyhow::{Context, Result};
use clap::Args;
use ocellus_retina::layout::{correlation_ci95, pooled_correlation, Pooled};
use serde_json::json;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus retina summary`.
#[derive(Args, Debug)]
pub(crate) struct SummaryArgs {
    /// Output folders of `ocellus retina learn` (each holds a retina.json).
    #[arg(required = true, num_args = 1..)]
    runs: Vec<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

/// `[lo, hi]` with three decimals.
pub(crate) fn interval(ci: [f64; 2]) -> String {
    format!("[{:.3}, {:.3}]", ci[0], ci[1])
}

/// What an interval says about a correlation.
fn verdict(ci: [f64; 2]) -> &'static str {
    if ci[0] > 0.0 {
        "positive"
    } else if ci[1] < 0.0 {
        "negative"
    } else {
        "not told apart from 0"
    }
}

/// The figures of one `retina learn` run that `retina summary` pools.
struct RunFigures {
    dir: PathBuf,
    group: (u64, String, f64),
    seed: u64,
    index: (f64, usize),
    interior: (f64, usize),
    over_random_s: Option<f64>,
}

fn read_run(dir: &Path) -> Result<RunFigures> {
    let f = dir.join("retina.json");
    let text = std::fs::read_to_string(&f).with_context(|| format!("cannot read {}", f.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).with_context(|| format!("{} is not JSON", f.display()))?;
    let num = |path: &str| -> Result<f64> {
        v.pointer(path)
            .and_then(|x| x.as_f64())
            .with_context(|| format!("{} has no number at {path} (not written by `retina learn`?)", f.display()))
    };
    let count = |path: &str| -> Result<usize> {
        v.pointer(path)
            .and_then(|x| x.as_array().map(|a| a.len()).or_else(|| x.as_u64().map(|n| n as usize)))
            .with_context(|| format!("{} has no {path} (not written by `retina learn`?)", f.display()))
    };
    let actions = v
        .pointer("/config/actions")
        .and_then(|x| x.as_str())
        .with_context(|| format!("{} has no /config/actions", f.display()))?
        .to_string();
    Ok(RunFigures {
        dir: dir.to_path_buf(),
        group: (num("/experiment")? as u64, actions, num("/config/action_scale")?),
        seed: num("/config/seed")? as u64,
        index: (num("/layout/fovea_index")?, count("/layout/fields")?),
        interior: (num("/layout/fovea_index_interior")?, count("/layout/interior_fields")?),
        over_random_s: v.pointer("/improvement_over_random_s").and_then(|x| x.as_f64()),
    })
}

/// Runs `ocellus retina summary`.
pub(crate) fn run(a: SummaryArgs) -> Result<()> {
    let runs = a.runs.iter().map(|d| read_run(d)).collect::<Result<Vec<_>>>()?;
    let mut groups: Vec<(u64, String, f64)> = Vec::new();
    for r in &runs {
        if !groups.contains(&r.group) {
            groups.push(r.group.clone());
        }
    }
    let ci = |p: (f64, usize)| correlation_ci95(p.0, p.1);
    let pool = |g: &(u64, String, f64), pick: fn(&RunFigures) -> (f64, usize)| -> Option<Pooled> {
        pooled_correlation(&runs.iter().filter(|r| &r.group == g).map(pick).collect::<Vec<_>>())
    };
    let pooled: Vec<(Option<Pooled>, Option<Pooled>)> =
        groups.iter().map(|g| (pool(g, |r| r.index), pool(g, |r| r.interior))).collect();
    if a.json {
        let out = json!({
            "runs": runs.iter().map(|r| json!({
                "dir": r.dir.display().to_string(),
                "experiment": r.group.0,
                "actions": r.group.1,
                "action_scale": r.group.2,
                "seed": r.seed,
                "fovea_index": r.index.0,
                "fields": r.index.1,
                "fovea_index_ci95": ci(r.index),
                "fovea_index_interior": r.interior.0,
                "interior_fields": r.interior.1,
                "fovea_index_interior_ci95": ci(r.interior),
                "improvement_over_random_s": r.over_random_s,
            })).collect::<Vec<_>>(),
            "pooled": groups.iter().zip(&pooled).map(|(g, (p, q))| json!({
                "experiment": g.0,
                "actions": g.1,
                "action_scale": g.2,
                "fovea_index": p,
                "fovea_index_interior": q,
            })).collect::<Vec<_>>(),
        });
        outln!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    for r in &runs {
        outln!(
            "{}: experiment {}, {} x{}, seed {}: fovea index {:.3} {} over {} fields, interior {:.3} {} over {}{}",
            r.dir.display(),
            r.group.0,
            r.group.1,
            r.group.2,
            r.seed,
            r.index.0,
            interval(ci(r.index)),
            r.index.1,
            r.interior.0,
            interval(ci(r.interior)),
            r.interior.1,
            r.over_random_s.map(|x| format!(", {x:.2}x better than random S")).unwrap_or_default()
        );
    }
    let describe = |p: &Option<Pooled>| match p {
        Some(p) => format!("{:.3} {} over {} fields: {}", p.r, interval(p.ci95), p.pairs, verdict(p.ci95)),
        None => "too few fields".to_string(),
    };
    for (g, (p, q)) in groups.iter().zip(&pooled) {
        let n = runs.iter().filter(|r| &r.group == g).count();
        outln!("pooled, experiment {}, {} x{} ({n} runs): fovea index {}", g.0, g.1, g.2, describe(p));
        outln!("    interior fields: {}", describe(q));
    }
    Ok(())
}
