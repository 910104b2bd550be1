//! `ocellus bench planning`: the cost of one view-direction decision (19 candidate pans, a
//! 40x30 surprise map, 4 landmarks), one thread.

use super::timing::median;
use anyhow::Result;
use nalgebra::{Matrix2, Vector2};
use ocellus_attention::planning::{PlannerConfig, ViewPlanner};
use ocellus_estimation::bearing::Landmark;
use ocellus_image::rng::SplitMix64;
use ocellus_image::{Backend, Plane};
use serde_json::json;
use std::time::Instant;

/// Runs the benchmark: `n` decisions, alternating a calm and an eventful surprise map.
pub fn run(json_out: bool, backend: Backend, n: usize) -> Result<()> {
    let landmarks = [(3.0, 2.5), (5.5, 0.0), (9.0, 2.5), (11.0, 0.0)].map(|(x, y)| Landmark { x, y }).to_vec();
    let mut planner = ViewPlanner::new(PlannerConfig { backend, ..PlannerConfig::default() }, landmarks)?;
    // Weak background surprise everywhere (every cell takes part), and a surprising region.
    let mut rng = SplitMix64::new(3);
    let calm = Plane::from_fn(40, 30, |_, _| (0.3 * rng.unit()) as f32);
    let mut event = calm.clone();
    for y in 10..20 {
        for x in 26..33 {
            event.set(x, y, 20.0 + (x + y) as f32 * 0.1);
        }
    }
    let (mu, cov) = (Vector2::new(2.5, 1.25), Matrix2::new(0.004, 0.0005, 0.0005, 0.003));
    let mut times = Vec::with_capacity(n);
    let mut checksum = 0.0;
    for i in 0..n + 50 {
        let (map, s) = if i % 2 == 0 { (&calm, 0.1) } else { (&event, 2.0) };
        let t = Instant::now();
        let d = planner.decide(&mu, &cov, 0.0, 20.0, map, s)?;
        let us = t.elapsed().as_secs_f64() * 1e6;
        checksum += d.pan_deg;
        if i >= 50 {
            times.push(us);
        }
    }
    let v = json!({
        "backend": backend.name(),
        "us_per_decision_1thread": median(&mut times),
        "candidates": planner.config().candidates_deg.len(),
        "surprise_map": [40, 30],
        "decisions_timed": n,
        "checksum_pan_deg": checksum,
    });
    if json_out {
        outln!("{v}");
    } else {
        outln!(
            "view planning: {:.1} us per decision (median of {n}, 19 candidates, 40x30 surprise map, 4 landmarks, 1 thread)",
            v["us_per_decision_1thread"].as_f64().unwrap_or(f64::NAN)
        );
    }
    Ok(())
}
