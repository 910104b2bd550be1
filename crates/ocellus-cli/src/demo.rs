//! `ocellus demo`: the main capabilities end to end on the built-in images.

use crate::attend::{self, AttendArgs, StreamOptions};
use crate::{assets, generate, inputs, logpolar_cmd, saliency_cmd};
use anyhow::{Context, Result};
use clap::Args;
use ocellus_attention::SaliencyConfig;
use ocellus_fovea::logpolar::{LogPolarConfig, LogPolarMap};
use ocellus_synth::attention_scenes::{Scenario, SceneConfig};
use std::path::PathBuf;

/// Arguments of `ocellus demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output folder (created if missing).
    #[arg(long, default_value = "ocellus-demo")]
    pub out: PathBuf,
}

/// Runs the demo: saliency maps, conspicuity maps and overlays with both presets, log-polar
/// images fixating each image's most salient point, then attention over a generated sequence.
pub fn run(a: DemoArgs) -> Result<()> {
    let dir = a.out;
    crate::output_files::create_dir(&dir)?;
    let src = dir.join("inputs");
    crate::output_files::create_dir(&src)?;
    outln!("ocellus demo: bottom-up saliency (Itti-Koch-Niebur) on {} built-in images", assets::IMAGES.len());
    let mut peaks = Vec::new();
    for preset in SaliencyConfig::PRESETS {
        let cfg = SaliencyConfig::preset(preset)?;
        let out = dir.join(preset);
        crate::output_files::create_dir(&out)?;
        let mut engine = None;
        for (name, bytes) in assets::IMAGES {
            let path = src.join(name);
            std::fs::write(&path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
            let r = saliency_cmd::process_one(&path, &cfg, &mut engine, &out, true)?;
            let t = engine.as_ref().map(|e| e.timings().total().as_secs_f64() * 1e3).unwrap_or(0.0);
            if *preset == SaliencyConfig::PRESETS[0] {
                peaks.push((path.clone(), r.peak_px));
            }
            outln!(
                "  {preset:>8} {:<10} map {}x{}, most salient at ({:.0}, {:.0}) px, {:.2} ms, {} files",
                inputs::stem(&path),
                r.map_size.0,
                r.map_size.1,
                r.peak_px[0],
                r.peak_px[1],
                t,
                r.files.len()
            );
        }
    }
    outln!("wrote maps, conspicuity maps and overlays to {}", dir.display());

    // Foveal vision: each image seen through the log-polar retina fixating its most salient
    // point (where to look, then look there).
    outln!("ocellus demo: log-polar images fixating the most salient point of each image");
    let fov = dir.join("logpolar");
    crate::output_files::create_dir(&fov)?;
    for (path, [px, py]) in &peaks {
        let img = crate::budget::read_image(path)?.to_u8();
        let (w, h) = img.size();
        let cfg = LogPolarConfig { centre: [*px, *py], ..LogPolarConfig::for_image(w, h) };
        let map = LogPolarMap::new(&cfg, w, h)?;
        let stem = inputs::stem(path);
        let (c, i) = (fov.join(format!("{stem}.cortex.png")), fov.join(format!("{stem}.inverse.png")));
        logpolar_cmd::write_foveated(&map, &img, &c, &i)?;
        outln!(
            "  {stem:<10} gaze ({px:.0}, {py:.0}) px: {} rows x {} sectors, compression {:.1}x",
            map.rows(),
            map.sectors(),
            map.compression_ratio()
        );
    }
    outln!("wrote cortical images and their inverses to {}", fov.display());

    // Attention over time: a generated sequence in which an object appears at frame 15.
    outln!("ocellus demo: surprise, context chaos and attention on a generated 30-frame sequence");
    let seq = dir.join("sequence");
    let cfg = SceneConfig::new(Scenario::SuddenObject);
    let event = cfg.event_frame;
    generate::write_sequence(cfg, &seq, false)?;
    let args = AttendArgs {
        input: seq.join("frames"),
        pan_tilt: Some(seq.join("pan_tilt.csv")),
        deg_per_px: 0.1,
        out: dir.join("attend"),
        stream: StreamOptions::default(),
        no_overlays: false,
        fps: 30,
        limit: None,
        no_video: false,
        workers: 0,
    };
    let (n, saccades, written) = attend::run_quiet(args)?;
    outln!(
        "  {n} frames, object appears at frame {event}; {saccades} saccades; wrote {} to {}",
        written.join(", "),
        dir.join("attend").display()
    );
    Ok(())
}
