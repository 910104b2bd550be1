//! `ocellus bench attention`: the per-frame cost of surprise, chaos and attention on top of
//! saliency, and end-to-end frames per second of `ocellus attend` from video files (1 and 2
//! workers, with and without overlay PNGs), with its peak memory after 10^3 and 10^4 frames.

use super::timing::{median, peak_rss_mb};
use crate::attend::{self, AttendArgs, StreamOptions};
use crate::generate::scene;
use anyhow::Result;
use ocellus_attention::attention::Attention;
use ocellus_attention::chaos::ChaosDegree;
use ocellus_attention::egosphere::ViewGeometry;
use ocellus_attention::saliency::Source;
use ocellus_attention::stream::{StreamConfig, StreamEngine};
use ocellus_attention::surprise::Surprise;
use ocellus_image::convert::RgbImage;
use ocellus_io::video::Frames;
use ocellus_io::y4m::Y4mWriter;
use ocellus_synth::attention_scenes::{Scenario, SceneConfig};
use serde_json::json;
use std::path::Path;
use std::time::Instant;

/// Frames of the benchmark sequence (an object appears at the middle one).
const SEQUENCE: usize = 48;

fn us(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e6
}

/// Median microseconds per frame of surprise, chaos, attention and the three together, on
/// one thread, over `n` frames (the sequence cycled), maps precomputed.
fn temporal_costs(frames: &[RgbImage], n: usize) -> Result<serde_json::Value> {
    let cfg = StreamConfig::default();
    let (w, h) = frames[0].size();
    // Saliency maps and chaos levels of each frame, from a real stream (flicker included).
    let mut stream = StreamEngine::new(cfg.clone(), w, h)?;
    let mut maps = Vec::new();
    for f in frames {
        stream.process(f, 0.0, 0.0)?;
        let e = stream.saliency_engine();
        let grey = e.level(Source::Intensity, cfg.chaos_level).cloned().unwrap_or_default();
        maps.push((e.saliency().clone(), grey));
    }
    let (mw, mh) = maps[0].0.size();
    let mut surprise = Surprise::new(cfg.surprise.clone(), mw, mh)?;
    let mut chaos = ChaosDegree::new(cfg.chaos.clone())?;
    let mut attention = Attention::new(cfg.attention.clone(), ViewGeometry { width: w, height: h, deg_per_px: 0.1 })?;
    let (mut ts, mut tc, mut ta, mut total) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, (s, g)) in maps.iter().cycle().take(n + 20).enumerate() {
        let t0 = Instant::now();
        chaos.update(g)?;
        let c = us(t0);
        let t1 = Instant::now();
        let sur = surprise.update(s)?;
        let su = us(t1);
        let t2 = Instant::now();
        attention.step(s, Some(sur), 0.0, 0.0)?;
        let a = us(t2);
        if i >= 20 {
            tc.push(c);
            ts.push(su);
            ta.push(a);
            total.push(c + su + a);
        }
    }
    Ok(json!({
        "us_per_frame_surprise_chaos_attention_1thread": median(&mut total),
        "us_surprise": median(&mut ts),
        "us_chaos": median(&mut tc),
        "us_attention": median(&mut ta),
        "map_size": [mw, mh],
        "frames_timed": n,
    }))
}

/// Frames per second of decode + the whole stream engine, no outputs.
fn analysis_fps(video: &Path) -> Result<f64> {
    let t = Instant::now();
    let mut engine: Option<StreamEngine> = None;
    let mut n = 0;
    for f in Frames::open(video)? {
        let f = f?;
        let (w, h) = f.size();
        let e = match engine.as_mut() {
            Some(e) => e,
            None => engine.insert(StreamEngine::new(StreamConfig::default(), w, h)?),
        };
        e.process(&f, 0.0, 0.0)?;
        n += 1;
    }
    Ok(n as f64 / t.elapsed().as_secs_f64())
}

/// Frames per second of the `ocellus attend` command itself (all outputs written) over a
/// video of `frames` frames, and its peak resident memory in MiB (the high-water mark is
/// reset first where Linux allows).
fn attend_fps(video: &Path, out: &Path, overlays: bool, workers: usize, frames: usize) -> Result<(f64, Option<f64>)> {
    let args = AttendArgs {
        input: video.into(),
        pan_tilt: None,
        deg_per_px: 0.1,
        out: out.into(),
        stream: StreamOptions::default(),
        no_overlays: !overlays,
        no_video: !overlays,
        fps: 30,
        limit: None,
        workers,
        rrd: None,
    };
    // "5" resets the peak resident set size of this process (Linux 4.0 and later).
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    let t = Instant::now();
    let (n, _, _) = attend::run_quiet(args)?;
    let fps = n as f64 / t.elapsed().as_secs_f64();
    if n != frames {
        anyhow::bail!("attend read {n} frames of {}, expected {frames}", video.display());
    }
    let _ = std::fs::remove_dir_all(out);
    Ok((fps, peak_rss_mb()))
}

/// `src` looped into a video of `loops` copies (`sequence` frames each), without
/// re-encoding.
fn looped(src: &Path, dst: &Path, loops: usize) -> Result<()> {
    let st = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-stream_loop"])
        .arg((loops - 1).to_string())
        .arg("-i")
        .arg(src)
        .args(["-c", "copy"])
        .arg(dst)
        .status()?;
    if !st.success() {
        anyhow::bail!("ffmpeg could not loop {}", src.display());
    }
    Ok(())
}

fn has_ffmpeg() -> bool {
    std::process::Command::new("ffmpeg").arg("-version").output().is_ok_and(|o| o.status.success())
}

/// Runs the benchmark; prints a table or one JSON object.
pub fn run(json_out: bool, n: usize) -> Result<()> {
    let cfg = SceneConfig { frames: SEQUENCE, event_frame: SEQUENCE / 2, ..SceneConfig::new(Scenario::SuddenObject) };
    let g = scene(cfg)?;
    let frames: Vec<RgbImage> = (0..SEQUENCE).map(|k| g.frame(k).map(|f| f.0)).collect::<Result<_, _>>()?;
    let temporal = temporal_costs(&frames, n)?;
    let dir = std::env::temp_dir().join(format!("ocellus-bench-attention-{}", std::process::id()));
    crate::output_files::create_dir(&dir)?;
    let y4m = dir.join("sequence.y4m");
    let mut w = Y4mWriter::new(std::io::BufWriter::new(std::fs::File::create(&y4m)?), 640, 480, (30, 1))?;
    frames.iter().try_for_each(|f| w.write_frame(f))?;
    w.finish()?;
    let mut e2e = serde_json::Map::new();
    e2e.insert("fps_analysis_from_y4m".into(), json!(analysis_fps(&y4m)?));
    if has_ffmpeg() {
        let mp4 = dir.join("sequence.mp4");
        let st = std::process::Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-i"])
            .arg(&y4m)
            .args(["-c:v", "mpeg4", "-q:v", "3"])
            .arg(&mp4)
            .status()?;
        if st.success() {
            e2e.insert("fps_analysis_from_mp4".into(), json!(analysis_fps(&mp4)?));
            // About 10^3 frames: 21 loops of the sequence.
            let (loops_k, loops_10k) = (21, 209);
            let long = dir.join("long.mp4");
            looped(&mp4, &long, loops_k)?;
            let n = loops_k * SEQUENCE;
            e2e.insert("attend_frames".into(), json!(n));
            for workers in [1, 2] {
                for overlays in [false, true] {
                    let (fps, _) = attend_fps(&long, &dir.join("a"), overlays, workers, n)?;
                    let key = format!(
                        "fps_attend_mp4_{}_{workers}_workers",
                        if overlays { "with_overlays" } else { "no_overlays" }
                    );
                    e2e.insert(key, json!(fps));
                }
            }
            // Memory is bounded by the queues: the same peak after 10^3 and 10^4 frames.
            let (_, rss_k) = attend_fps(&long, &dir.join("a"), false, 2, n)?;
            let longer = dir.join("longer.mp4");
            looped(&mp4, &longer, loops_10k)?;
            let (fps_10k, rss_10k) = attend_fps(&longer, &dir.join("a"), false, 2, loops_10k * SEQUENCE)?;
            e2e.insert("peak_rss_mb_attend_1e3_frames".into(), json!(rss_k));
            e2e.insert("peak_rss_mb_attend_1e4_frames".into(), json!(rss_10k));
            e2e.insert("attend_long_frames".into(), json!(loops_10k * SEQUENCE));
            e2e.insert("fps_attend_mp4_no_overlays_2_workers_1e4_frames".into(), json!(fps_10k));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    let v = json!({
        "frame_width": 640,
        "frame_height": 480,
        "temporal": temporal,
        "end_to_end": e2e,
        "peak_rss_mb": peak_rss_mb(),
    });
    if json_out {
        outln!("{v}");
        return Ok(());
    }
    let t = &v["temporal"];
    let f = |k: &str| t[k].as_f64().unwrap_or(f64::NAN);
    outln!("attention benchmark, 640x480, median over {n} frames on 1 thread (maps precomputed):");
    outln!(
        "  surprise + chaos + attention: {:.1} us/frame (surprise {:.1}, chaos {:.1}, attention {:.1})",
        f("us_per_frame_surprise_chaos_attention_1thread"),
        f("us_surprise"),
        f("us_chaos"),
        f("us_attention")
    );
    outln!("end to end (decode and writing included):");
    for (k, val) in e2e {
        outln!("  {k:<48} {:.1}", val.as_f64().unwrap_or(f64::NAN));
    }
    if let Some(m) = v["peak_rss_mb"].as_f64() {
        outln!("peak resident memory: {m:.1} MiB");
    }
    Ok(())
}
