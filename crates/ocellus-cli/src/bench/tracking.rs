//! `ocellus bench tracking`: the particle-filter figures that exist so far: resampling 10^6
//! particles with each scheme on one core (the colour-likelihood step of issue 16 is not
//! built yet, so no per-frame figure is printed).

use super::timing::median;
use anyhow::Result;
use ocellus_estimation::resampling::Resampler;
use ocellus_image::rng::SplitMix64;
use serde_json::json;
use std::time::Instant;

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
    figures.insert("particles".into(), json!(n));
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
    outln!("resampling {n} particles on one thread (median of 11):");
    for name in ["systematic", "stratified", "multinomial", "residual"] {
        outln!("  {name:<12} {:.2} ms", v[format!("ms_resample_{name}_1e6")].as_f64().unwrap_or(0.0));
    }
    Ok(())
}
