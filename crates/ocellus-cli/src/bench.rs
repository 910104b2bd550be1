//! `ocellus bench`: the figures the issues ask for, printed as a table or one JSON object.

use crate::{assets, ranges};
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_image::{convert::RgbImage, Backend, Plane};
use serde_json::json;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What to benchmark.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Target {
    /// The saliency pipeline (SPEC 1): per-preset ms/frame on one core, fps on all cores.
    Saliency,
    /// Surprise, chaos and attention per frame on top of saliency (640x480, one core), and
    /// end-to-end fps of `ocellus attend` from video files, decode included.
    Attention,
    /// One view-direction decision: 19 candidate pans, a 40x30 surprise map (microseconds).
    Planning,
    /// DLT and Zhang calibration, triangulation of 100k points, block matching and SGM at 741x500.
    Geometry,
    /// Visual odometry per 640x480 frame on one core (seed mode), on generated floor frames.
    Odometry,
    /// The log-polar map, 640x480 grey and RGB to 128 rings x 128 sectors on one core, and
    /// the table construction.
    Logpolar,
}

/// Arguments of `ocellus bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// What to measure.
    pub target: Target,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Frames timed on one thread (the median is reported) [default: 300; planning: at least
    /// 100 decisions]. Saliency, attention and planning only. Range: 1..=100000.
    #[arg(long, value_parser = ranges::within(1usize, 100_000))]
    pub frames: Option<usize>,
    /// Frame width in pixels (the built-in images are resized to it) [default: 640].
    /// Saliency only. Range: 32..=8192.
    #[arg(long, value_parser = ranges::within(32u32, 8192))]
    pub width: Option<u32>,
    /// Frame height in pixels [default: 480]. Saliency only. Range: 32..=8192.
    #[arg(long, value_parser = ranges::within(32u32, 8192))]
    pub height: Option<u32>,
    /// Use this image (resized) instead of the built-in ones. Saliency only.
    #[arg(long)]
    pub image: Option<PathBuf>,
    /// Presets to measure (default: ace2009 and stb). Saliency only.
    #[arg(long, value_delimiter = ',')]
    pub preset: Vec<String>,
    /// Kernel build: auto, scalar or avx2 [default: auto]. Saliency only.
    #[arg(long)]
    pub backend: Option<String>,
}

impl BenchArgs {
    /// Refuses the options `target` does not use, so that no figure is printed for a setting
    /// that was silently ignored.
    fn reject_unused(&self) -> Result<()> {
        let given = [
            ("--frames", self.frames.is_some()),
            ("--width", self.width.is_some()),
            ("--height", self.height.is_some()),
            ("--image", self.image.is_some()),
            ("--preset", !self.preset.is_empty()),
            ("--backend", self.backend.is_some()),
        ];
        let used: &[&str] = match self.target {
            Target::Saliency => &["--frames", "--width", "--height", "--image", "--preset", "--backend"],
            Target::Attention | Target::Planning => &["--frames"],
            Target::Geometry | Target::Odometry | Target::Logpolar => &[],
        };
        let unused: Vec<&str> = given.iter().filter(|(n, g)| *g && !used.contains(n)).map(|(n, _)| *n).collect();
        if !unused.is_empty() {
            let name = format!("{:?}", self.target).to_lowercase();
            let takes = if used.is_empty() { "no options besides --json".to_string() } else { used.join(", ") };
            bail!("bench {name} does not use {} (it takes {takes})", unused.join(", "));
        }
        Ok(())
    }

    fn size(&self) -> (u32, u32) {
        (self.width.unwrap_or(640), self.height.unwrap_or(480))
    }
}

fn frames(a: &BenchArgs) -> Result<Vec<RgbImage>> {
    let (width, height) = a.size();
    // Decoded as every command decodes (format checks, memory budget); resized by `image`.
    let decoded: Vec<RgbImage> = match &a.image {
        Some(p) => vec![crate::budget::read_image(p)?],
        None => assets::IMAGES
            .iter()
            .map(|(n, b)| ocellus_io::decode_image(b, std::path::Path::new(n)))
            .collect::<std::result::Result<_, _>>()?,
    };
    decoded
        .iter()
        .map(|d| {
            let rgb = ocellus_image::convert::to_image_rgb8(&d.to_u8());
            let r = image::imageops::resize(&rgb, width, height, image::imageops::FilterType::Triangle);
            let data = r.pixels().map(|p| p.0).collect();
            Ok(RgbImage::U8(Plane::from_vec(width as usize, height as usize, data)?))
        })
        .collect()
}

/// Median (sorts `v`); 0 for an empty slice.
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

/// Peak resident memory of this process in MiB (Linux `VmHWM`), if known.
pub fn peak_rss_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn bench_preset(cfg: &SaliencyConfig, frames: &[RgbImage], n: usize) -> Result<serde_json::Value> {
    let (w, h) = frames[0].size();
    let mut e = SaliencyEngine::new(cfg.clone(), w, h)?;
    for f in frames.iter().cycle().take(20) {
        e.process(f)?;
    }
    let mut total = Vec::with_capacity(n);
    let mut stages: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(n)).collect();
    for f in frames.iter().cycle().take(n) {
        let t = Instant::now();
        e.process(f)?;
        total.push(t.elapsed().as_secs_f64() * 1e3);
        for (k, (_, d)) in e.timings().stages().iter().enumerate() {
            stages[k].push(d.as_secs_f64() * 1e3);
        }
    }
    let mean_ms = total.iter().sum::<f64>() / total.len() as f64;
    let ms = median(&mut total);
    let names = e.timings().stages().map(|s| s.0);
    let stage_ms: serde_json::Map<String, serde_json::Value> =
        names.iter().zip(stages.iter_mut()).map(|(n, v)| (n.to_string(), json!(median(v)))).collect();

    // Throughput with 1 thread and with all threads, same harness, alternated three times
    // so that both see the same machine load; medians.
    let threads = rayon::current_num_threads();
    let (mut one, mut all) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        one.push(throughput(cfg, frames, 1, n)?);
        all.push(throughput(cfg, frames, threads, n.max(threads * 100))?);
    }
    let (fps_1, fps_all) = (median(&mut one), median(&mut all));
    Ok(json!({
        "ms_per_frame_1thread": ms,
        "ms_per_frame_1thread_mean": mean_ms,
        "fps_1thread": fps_1,
        "threads": threads,
        "fps_all_threads": fps_all,
        "speedup_all_threads": fps_all / fps_1,
        "stage_ms_1thread": stage_ms,
        "frames_timed": n,
    }))
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

/// Runs the subcommand.
pub fn run(a: BenchArgs) -> Result<()> {
    a.reject_unused()?;
    let n = a.frames.unwrap_or(300);
    match a.target {
        Target::Attention => return crate::bench_attention::run(a.json, n),
        Target::Planning => return crate::bench_planning::run(a.json, n.max(100)),
        Target::Geometry => return crate::bench_geometry::run(a.json, 5),
        Target::Odometry => return crate::bench_odometry::run(a.json),
        Target::Logpolar => return crate::bench_logpolar::run(a.json),
        Target::Saliency => {}
    }
    let backend_name = a.backend.as_deref().unwrap_or("auto");
    let backend: Backend = serde_json::from_value(json!(backend_name))
        .map_err(|_| anyhow::anyhow!("unknown backend '{backend_name}' (auto, scalar, avx2)"))?;
    let (width, height) = a.size();
    let frames = frames(&a)?;
    let presets = if a.preset.is_empty() {
        SaliencyConfig::PRESETS.iter().map(|s| s.to_string()).collect()
    } else {
        a.preset.clone()
    };
    let mut out = serde_json::Map::new();
    out.insert("frame_width".into(), json!(width));
    out.insert("frame_height".into(), json!(height));
    out.insert("threads".into(), json!(rayon::current_num_threads()));
    out.insert("backend".into(), json!(backend.name()));
    for p in &presets {
        let mut cfg = SaliencyConfig::preset(p)?;
        cfg.backend = backend;
        out.insert(p.clone(), bench_preset(&cfg, &frames, n)?);
    }
    out.insert("peak_rss_mb".into(), json!(peak_rss_mb()));
    let v = serde_json::Value::Object(out);
    if a.json {
        outln!("{v}");
        return Ok(());
    }
    outln!(
        "saliency benchmark: {}x{}, backend {}, {} threads",
        width,
        height,
        backend.name(),
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
