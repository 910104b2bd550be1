//! `ocellus bench saliency`: per-preset milliseconds per frame on one core, with the stage
//! breakdown, and frames per second on all cores.

use super::timing::{median, peak_rss_mb};
use super::BenchArgs;
use anyhow::Result;
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_image::convert::{merge_rgb8, split_rgb8, RgbImage};
use ocellus_image::resample::{resize, ResampleMethod};
use ocellus_image::Backend;
use serde_json::json;
use std::time::{Duration, Instant};

fn frames(a: &BenchArgs) -> Result<Vec<RgbImage>> {
    let (width, height) = a.size();
    // Decoded as every command decodes (format checks, memory budget); resized bilinearly
    // channel by channel (the content only has to be real photographs).
    let decoded: Vec<RgbImage> = match &a.image {
        Some(p) => vec![crate::budget::read_image(p)?],
        None => crate::assets::IMAGES.iter().map(|(n, _)| crate::assets::decode(n)).collect::<Result<_>>()?,
    };
    let (w, h) = (width as usize, height as usize);
    decoded
        .iter()
        .map(|d| {
            let [r, g, b] = split_rgb8(&d.to_u8()).map(|c| resize(Backend::Auto, &c, w, h, ResampleMethod::Bilinear));
            Ok(RgbImage::U8(merge_rgb8([&r?, &g?, &b?])))
        })
        .collect()
}

fn bench_preset(cfg: &SaliencyConfig, frames: &[RgbImage], n: usize) -> Result<serde_json::Value> {
    let (w, h) = frames[0].size();
    let mut e = SaliencyEngine::new(cfg.clone(), w, h)?;
    for f in frames.iter().cycle().take(20) {
        e.process(f)?;
    }
    let mut total = Vec::with_capacity(n);
    let mut stages: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(n)).collect();
    #[cfg_attr(not(feature = "gpu"), allow(unused_mut))]
    let mut gpu_phases: [Vec<f64>; 3] = Default::default();
    for f in frames.iter().cycle().take(n) {
        let t = Instant::now();
        e.process(f)?;
        total.push(t.elapsed().as_secs_f64() * 1e3);
        for (k, (_, d)) in e.timings().stages().iter().enumerate() {
            stages[k].push(d.as_secs_f64() * 1e3);
        }
        #[cfg(feature = "gpu")]
        if let Some(t) = e.gpu_timings() {
            for (k, d) in [t.upload, t.gpu, t.readback].iter().enumerate() {
                gpu_phases[k].push(d.as_secs_f64() * 1e3);
            }
        }
    }
    let mean_ms = total.iter().sum::<f64>() / total.len() as f64;
    let ms = median(&mut total);
    let names = e.timings().stages().map(|s| s.0);
    let stage_ms: serde_json::Map<String, serde_json::Value> =
        names.iter().zip(stages.iter_mut()).map(|(n, v)| (n.to_string(), json!(median(v)))).collect();

    // Throughput with 1 thread and with all threads, same harness, alternated three times
    // so that both see the same machine load; medians.
    // On the GPU backend the engines share one device: throughput is the single engine's.
    let threads = rayon::current_num_threads();
    let (fps_1, fps_all) = if cfg.backend == Backend::Gpu {
        (1e3 / ms, 1e3 / ms)
    } else {
        let (mut one, mut all) = (Vec::new(), Vec::new());
        for _ in 0..3 {
            one.push(throughput(cfg, frames, 1, n)?);
            all.push(throughput(cfg, frames, threads, n.max(threads * 100))?);
        }
        (median(&mut one), median(&mut all))
    };
    let mut phases = serde_json::Map::new();
    if !gpu_phases[0].is_empty() {
        for (name, v) in ["upload", "gpu", "readback"].iter().zip(gpu_phases.iter_mut()) {
            phases.insert(name.to_string(), json!(median(v)));
        }
    }
    let mut figures = json!({
        "ms_per_frame_1thread": ms,
        "ms_per_frame_1thread_mean": mean_ms,
        "fps_1thread": fps_1,
        "threads": threads,
        "fps_all_threads": fps_all,
        "speedup_all_threads": fps_all / fps_1,
        "stage_ms_1thread": stage_ms,
        "frames_timed": n,
    });
    if !phases.is_empty() {
        figures["gpu_phase_ms"] = serde_json::Value::Object(phases);
    }
    if cfg.backend == Backend::Gpu {
        // The whole frame is one GPU round trip: its phases replace the CPU's stages.
        if let Some(m) = figures.as_object_mut() {
            m.remove("stage_ms_1thread");
        }
        gpu_figures(cfg, frames, n, &mut figures)?;
    }
    Ok(figures)
}

/// The GPU's end-to-end milliseconds per frame (upload, the whole pipeline, readback) with
/// only the map-level outputs read back (no pyramid levels), and in batches of 8 and 64
/// frames (one submission, only the saliency maps read back); medians over `n` frames.
fn gpu_figures(cfg: &SaliencyConfig, frames: &[RgbImage], n: usize, figures: &mut serde_json::Value) -> Result<()> {
    let (w, h) = frames[0].size();
    let mut e = SaliencyEngine::new(cfg.clone(), w, h)?;
    e.set_gpu_level_readback(false);
    for f in frames.iter().take(3) {
        e.process(f)?;
    }
    let mut t: Vec<f64> = frames
        .iter()
        .cycle()
        .take(n)
        .map(|f| {
            let s = Instant::now();
            e.process(f).map(|_| s.elapsed().as_secs_f64() * 1e3)
        })
        .collect::<std::result::Result<_, _>>()?;
    figures["ms_per_frame_maps_only"] = json!(median(&mut t));
    let mut out = Vec::new();
    for batch in [8usize, 64] {
        let group: Vec<RgbImage> = frames.iter().cycle().take(batch).cloned().collect();
        e.process_batch(&group, &mut out)?;
        let (mut per_frame, mut phases): (Vec<f64>, [Vec<f64>; 3]) = (Vec::new(), Default::default());
        for _ in 0..(n / batch).max(1) {
            let s = Instant::now();
            e.process_batch(&group, &mut out)?;
            per_frame.push(s.elapsed().as_secs_f64() * 1e3 / batch as f64);
            #[cfg(feature = "gpu")]
            if let Some(t) = e.gpu_timings() {
                for (k, d) in [t.upload, t.gpu, t.readback].iter().enumerate() {
                    phases[k].push(d.as_secs_f64() * 1e3 / batch as f64);
                }
            }
        }
        figures[format!("ms_per_frame_batch_{batch}")] = json!(median(&mut per_frame));
        if !phases[0].is_empty() {
            // Per frame: the GPU phase alone is the batch's time without upload and readback.
            let m: serde_json::Map<String, serde_json::Value> = ["upload", "gpu", "readback"]
                .iter()
                .zip(phases.iter_mut())
                .map(|(name, v)| (name.to_string(), json!(median(v))))
                .collect();
            figures[format!("gpu_phase_ms_per_frame_batch_{batch}")] = serde_json::Value::Object(m);
        }
    }
    Ok(())
}

/// Frames per second of `threads` engines (one per thread, built and warmed up before the
/// clock starts) sharing `n` frames: thread t takes frames t, t + T, ..., as a pipeline that
/// spreads frames over workers would.
fn throughput(cfg: &SaliencyConfig, frames: &[RgbImage], threads: usize, n: usize) -> Result<f64> {
    let (w, h) = frames[0].size();
    let barrier = std::sync::Barrier::new(threads + 1);
    let elapsed = std::thread::scope(|scope| -> Result<Duration> {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let barrier = &barrier;
                scope.spawn(move || -> Result<()> {
                    let engine = SaliencyEngine::new(cfg.clone(), w, h);
                    let warm = engine.and_then(|mut e| {
                        for f in frames.iter().cycle().take(10) {
                            e.process(f)?;
                        }
                        Ok(e)
                    });
                    // Reach the barrier whatever happened, so the timer thread never waits forever.
                    barrier.wait();
                    let mut e = warm?;
                    for i in (t..n).step_by(threads) {
                        e.process(&frames[i % frames.len()])?;
                    }
                    Ok(())
                })
            })
            .collect();
        barrier.wait();
        let t0 = Instant::now();
        for h in handles {
            h.join().map_err(|_| anyhow::anyhow!("benchmark thread panicked"))??;
        }
        Ok(t0.elapsed())
    })?;
    Ok(n as f64 / elapsed.as_secs_f64())
}

/// The device the front end runs on: the GPU adapter, or the CPU's model name.
fn device(backend: Backend) -> Result<String> {
    #[cfg(feature = "gpu")]
    if backend == Backend::Gpu {
        return Ok(ocellus_gpu::GpuContext::shared()?.describe());
    }
    let _ = backend;
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpuinfo.lines().find_map(|l| l.strip_prefix("model name")?.split_once(':').map(|(_, m)| m.trim()));
    Ok(model.unwrap_or("cpu").to_string())
}

/// The largest difference between `cfg`'s maps and the scalar CPU's over `frames`, relative
/// to the CPU map's peak.
fn max_rel_diff_vs_cpu(cfg: &SaliencyConfig, frames: &[RgbImage]) -> Result<f64> {
    let (w, h) = frames[0].size();
    let mut this = SaliencyEngine::new(cfg.clone(), w, h)?;
    let mut reference = SaliencyEngine::new(SaliencyConfig { backend: Backend::Scalar, ..cfg.clone() }, w, h)?;
    let mut worst = 0.0f64;
    for f in frames {
        let a = this.process(f)?.clone();
        let b = reference.process(f)?;
        let peak = b.as_slice().iter().fold(0.0f32, |m, v| m.max(v.abs())).max(1e-12);
        let diff = a.as_slice().iter().zip(b.as_slice()).fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
        worst = worst.max(f64::from(diff / peak));
    }
    Ok(worst)
}

/// Runs `ocellus bench saliency` with `backend`'s kernels, `n` frames per preset.
pub fn run(a: &BenchArgs, backend: Backend, n: usize) -> Result<()> {
    let (width, height) = a.size();
    let frames = frames(a)?;
    let presets = if a.preset.is_empty() && backend == Backend::Gpu {
        // The GPU front end does the ace2009 preset (opponency at each level).
        vec!["ace2009".to_string()]
    } else if a.preset.is_empty() {
        SaliencyConfig::PRESETS.iter().map(|s| s.to_string()).collect()
    } else {
        a.preset.clone()
    };
    let mut out = serde_json::Map::new();
    out.insert("frame_width".into(), json!(width));
    out.insert("frame_height".into(), json!(height));
    out.insert("threads".into(), json!(rayon::current_num_threads()));
    out.insert("backend".into(), json!(backend.name()));
    out.insert("device".into(), json!(device(backend)?));
    for p in &presets {
        let mut cfg = SaliencyConfig::preset(p)?;
        cfg.backend = backend;
        let mut figures = bench_preset(&cfg, &frames, n)?;
        if backend == Backend::Gpu {
            figures["max_rel_diff_vs_cpu"] = json!(max_rel_diff_vs_cpu(&cfg, &frames)?);
        }
        out.insert(p.clone(), figures);
    }
    out.insert("peak_rss_mb".into(), json!(peak_rss_mb()));
    let v = serde_json::Value::Object(out);
    if a.json {
        outln!("{v}");
        return Ok(());
    }
    outln!(
        "saliency benchmark: {}x{}, backend {} on {}, {} threads",
        width,
        height,
        backend.name(),
        v["device"].as_str().unwrap_or("?"),
        rayon::current_num_threads()
    );
    for p in &presets {
        let r = &v[p];
        outln!(
            "{p:>8}: {:.3} ms/frame on 1 thread (median of {}), {:.0} fps on all threads ({:.2}x)",
            r["ms_per_frame_1thread"].as_f64().unwrap_or(0.0),
            n,
            r["fps_all_threads"].as_f64().unwrap_or(0.0),
            r["speedup_all_threads"].as_f64().unwrap_or(0.0)
        );
        if let Some(ph) = r["gpu_phase_ms"].as_object() {
            let parts: Vec<String> = ph.iter().map(|(k, v)| format!("{k} {:.3}", v.as_f64().unwrap_or(0.0))).collect();
            outln!("          GPU phases ms: {}", parts.join(", "));
            for key in ["ms_per_frame_maps_only", "ms_per_frame_batch_8", "ms_per_frame_batch_64"] {
                outln!("          {key:<24} {:.3}", r[key].as_f64().unwrap_or(0.0));
            }
        }
        if let Some(d) = r["max_rel_diff_vs_cpu"].as_f64() {
            outln!("          largest difference from the scalar CPU map: {d:.2e} of its peak");
        }
        if let Some(st) = r["stage_ms_1thread"].as_object() {
            for (k, ms) in st {
                outln!("          {k:<20} {:.3} ms", ms.as_f64().unwrap_or(0.0));
            }
        }
    }
    if let Some(m) = v["peak_rss_mb"].as_f64() {
        outln!("peak resident memory: {m:.1} MiB");
    }
    Ok(())
}
