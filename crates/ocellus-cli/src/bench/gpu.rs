//! `ocellus bench gpu`: the saliency map with the GPU front end (`ocellus-gpu`), against the
//! CPU engine on the same frames.

use super::timing::median;
use super::BenchArgs;
use anyhow::{bail, Result};
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_gpu::{GpuContext, GpuSaliencyEngine};
use serde_json::json;
use std::time::Instant;

/// Runs the benchmark over `n` frames (after 5 untimed ones).
pub fn run(a: &BenchArgs, n: usize) -> Result<()> {
    let frames = super::saliency::frames(a)?;
    let Some(first) = frames.first() else { bail!("no frames to time") };
    let (w, h) = first.size();
    let ctx = GpuContext::new()?;
    let cfg = SaliencyConfig::ace2009();
    let mut gpu = GpuSaliencyEngine::new(&ctx, cfg.clone(), w, h)?;
    let mut cpu = SaliencyEngine::new(cfg, w, h)?;
    let rgb8: Vec<_> = frames.iter().map(|f| f.to_u8()).collect();
    for f in rgb8.iter().cycle().take(5) {
        gpu.process(f)?;
    }
    let (mut total, mut front, mut on_cpu) = (Vec::new(), Vec::new(), Vec::new());
    let mut worst = 0.0f32;
    for (f, img) in rgb8.iter().zip(&frames).cycle().take(n) {
        let t = Instant::now();
        let g = gpu.process(f)?.clone();
        total.push(t.elapsed().as_secs_f64() * 1e3);
        front.push(gpu.timings().0.as_secs_f64() * 1e3);
        let t = Instant::now();
        let c = cpu.process(img)?;
        on_cpu.push(t.elapsed().as_secs_f64() * 1e3);
        let peak = c.as_slice().iter().fold(0.0f32, |m, v| m.max(v.abs())).max(1e-12);
        let diff = g.as_slice().iter().zip(c.as_slice()).fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
        worst = worst.max(diff / peak);
    }
    let v = json!({
        "adapter": ctx.describe(),
        "frame_width": w,
        "frame_height": h,
        "frames_timed": n,
        "ms_per_frame_gpu": median(&mut total),
        "ms_gpu_front_end": median(&mut front),
        "ms_per_frame_cpu_1thread": median(&mut on_cpu),
        "max_rel_diff_saliency": worst,
    });
    if a.json {
        outln!("{v}");
        return Ok(());
    }
    outln!("saliency (ace2009) on the GPU: {}x{}, adapter {}", w, h, ctx.describe());
    outln!(
        "  {:.3} ms/frame end to end (front end {:.3} ms: upload, dispatches, readback), median of {n}",
        v["ms_per_frame_gpu"].as_f64().unwrap_or(0.0),
        v["ms_gpu_front_end"].as_f64().unwrap_or(0.0)
    );
    outln!(
        "  CPU engine, one thread, same frames: {:.3} ms/frame",
        v["ms_per_frame_cpu_1thread"].as_f64().unwrap_or(0.0)
    );
    outln!("  largest difference of the saliency maps: {:.2e} of the CPU map's peak", worst);
    Ok(())
}
