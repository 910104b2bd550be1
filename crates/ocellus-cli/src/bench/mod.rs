//! `ocellus bench`: the figures the issues ask for, printed as a table or one JSON object.

mod attention;
mod geometry;
mod logpolar;
mod odometry;
mod planning;
mod retina;
mod saliency;
mod timing;
mod tracking;

use crate::ranges;
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use ocellus_image::Backend;
use serde_json::json;
use std::path::PathBuf;

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
    /// Particle filters: one SIR step of the 3D ball tracker on a 640x480 frame for 10^2..10^5
    /// particles, and resampling 10^6 particles with each scheme.
    Tracking,
    /// The self-organizing retina: ms per gradient evaluation and per solver iteration for
    /// both of the seed's experiments at their sizes, all threads and one; peak memory.
    Retina,
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
    /// 100 decisions; saliency on the gpu backend: 50]. Saliency, attention and planning only. Range: 1..=100000.
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
    /// Kernel build: auto, scalar, sse41, avx2 or avx512 (an unavailable one falls back to the best
    /// below it), or gpu (saliency only: the whole pipeline on the GPU, the ace2009 preset by
    /// default) [default: auto]. Not for attention (it times the `attend` command).
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
            Target::Attention => &["--frames"],
            Target::Planning => &["--frames", "--backend"],
            Target::Geometry | Target::Odometry | Target::Logpolar => &["--backend"],
            Target::Tracking | Target::Retina => &[],
        };
        let unused: Vec<&str> = given.iter().filter(|(n, g)| *g && !used.contains(n)).map(|(n, _)| *n).collect();
        if !unused.is_empty() {
            let name = format!("{:?}", self.target).to_lowercase();
            let takes = if used.is_empty() { "no options besides --json".to_string() } else { used.join(", ") };
            bail!("bench {name} does not use {} (it takes {takes})", unused.join(", "));
        }
        Ok(())
    }

    pub(crate) fn size(&self) -> (u32, u32) {
        (self.width.unwrap_or(640), self.height.unwrap_or(480))
    }
}

/// Runs the subcommand.
pub fn run(a: BenchArgs) -> Result<()> {
    a.reject_unused()?;
    let backend_name = a.backend.as_deref().unwrap_or("auto");
    let backend: Backend = serde_json::from_value(json!(backend_name))
        .map_err(|_| anyhow::anyhow!("unknown backend '{backend_name}' (auto, scalar, sse41, avx2, avx512, gpu)"))?;
    if backend == Backend::Gpu && !matches!(a.target, Target::Saliency) {
        bail!("--backend gpu is for bench saliency only (the other pipelines have no GPU path)");
    }
    let n = a.frames.unwrap_or(if backend == Backend::Gpu { 50 } else { 300 });
    match a.target {
        Target::Attention => return attention::run(a.json, n),
        Target::Planning => return planning::run(a.json, backend, n.max(100)),
        Target::Geometry => return geometry::run(a.json, backend, 5),
        Target::Odometry => return odometry::run(a.json, backend),
        Target::Logpolar => return logpolar::run(a.json, backend),
        Target::Tracking => return tracking::run(a.json),
        Target::Retina => return retina::run(a.json),
        Target::Saliency => {}
    }
    saliency::run(&a, backend, n)
}
