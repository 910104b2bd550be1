//! `ocellus attend`: saliency, surprise, context chaos and attention over a video or image
//! sequence, with overlays, a scanpath and per-frame context values.

use crate::{config_file, frames, plot, ranges};
use anyhow::{bail, Context, Result};
use clap::Args;
use ocellus_attention::attention::{Fixation, Reason};
use ocellus_attention::stream::{FrameMaps, StreamConfig, StreamEngine, StreamFrame, StreamWorker};
use ocellus_attention::surprise::SurpriseConfig;
use ocellus_image::colormap::overlay_scaled;
use ocellus_image::convert::RgbImage;
use ocellus_image::draw;
use ocellus_image::Backend;
use ocellus_image::Plane;
use ocellus_io::video_writer::VideoWriter;
use plotters::style::RGBColor;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Arguments of `ocellus attend`.
#[derive(Args, Debug)]
pub struct AttendArgs {
    /// A video file (anything ffmpeg reads; .y4m natively) or a folder of images (natural order).
    pub input: PathBuf,
    /// CSV of the camera's pan and tilt per frame (`frame,pan_deg,tilt_deg`, degrees, positive
    /// right and down) for the ego-sphere; without it the camera is taken as still.
    #[arg(long)]
    pub pan_tilt: Option<PathBuf>,
    /// Camera angle per pixel in degrees (0.1: 64 degrees across 640 pixels). Range: above 0,
    /// at most 10.
    #[arg(long, default_value_t = 0.1, value_parser = ranges::above(0.0f32, 10.0))]
    pub deg_per_px: f32,
    /// Output folder.
    #[arg(long, default_value = "ocellus-attend")]
    pub out: PathBuf,
    #[command(flatten)]
    pub stream: StreamOptions,
    /// Do not write per-frame overlay PNGs (the video, CSVs and plot are still written).
    #[arg(long)]
    pub no_overlays: bool,
    /// Do not write overlays.mp4 (with --no-overlays no overlay is drawn at all: the
    /// fastest run, CSVs and plot only).
    #[arg(long)]
    pub no_video: bool,
    /// Frame rate of the overlay video, frames per second. Range: 1..=1000.
    #[arg(long, default_value_t = 30, value_parser = ranges::within(1u32, 1000))]
    pub fps: u32,
    /// Process at most N frames. Range: 1..=10000000.
    #[arg(long, value_parser = ranges::within(1usize, 10_000_000))]
    pub limit: Option<usize>,
    /// Worker threads for the per-frame work (saliency, and drawing and writing the
    /// overlays); 0: one per core. The results do not depend on it. Range: 0..=256.
    #[arg(long, default_value_t = 0, value_parser = ranges::within(0usize, 256))]
    pub workers: usize,
    /// Also log the run for the Rerun viewer to this .rrd file: frames, saliency, surprise
    /// and inhibition maps, fixations, the scanpath, chaos degree and surprise maximum per
    /// frame (needs ocellus built with the `rerun` feature).
    #[arg(long)]
    pub rrd: Option<PathBuf>,
}

/// Options shared by the commands that run the stream engine.
#[derive(Args, Debug, Clone)]
pub struct StreamOptions {
    /// Saliency preset (ace2009 or stb); a flicker channel is added.
    #[arg(long, default_value = "ace2009")]
    pub preset: String,
    /// TOML file overriding preset fields (as `ocellus saliency --config`).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Use the 5-model multi-timescale surprise (iLab) instead of the single model.
    #[arg(long)]
    pub surprise_chain: bool,
}

impl StreamOptions {
    /// The stream configuration, for a camera of `deg_per_px` degrees per pixel.
    pub fn config(&self, deg_per_px: f32) -> Result<StreamConfig> {
        Ok(StreamConfig {
            saliency: config_file::load(&self.preset, self.config.as_deref())?,
            surprise: if self.surprise_chain { SurpriseConfig::chain() } else { SurpriseConfig::default() },
            deg_per_px,
            ..StreamConfig::default()
        })
    }
}

impl Default for StreamOptions {
    fn default() -> Self {
        Self { preset: "ace2009".into(), config: None, surprise_chain: false }
    }
}

/// Where the per-frame values go (in frame order): the CSVs and the plot's series.
struct Outputs {
    dir: PathBuf,
    overlays: bool,
    scanpath: crate::output_files::OutputFile,
    context: crate::output_files::OutputFile,
    chaos: Vec<(f64, f64)>,
    surprise_max: Vec<(f64, f64)>,
    recent: Vec<Fixation>,
    saccades: usize,
}

fn create(dir: &Path, name: &str) -> Result<crate::output_files::OutputFile> {
    crate::output_files::create_file(&dir.join(name))
}

/// What drawing one overlay needs, owned so that a render worker can take it.
struct RenderJob {
    frame: Arc<RgbImage>,
    saliency: Plane<f32>,
    surprise: Plane<f32>,
    inhibition: Plane<f32>,
    fixation: Option<Fixation>,
    recent: Vec<Fixation>,
}

impl Outputs {
    fn new(dir: &Path, overlays: bool) -> Result<Self> {
        crate::output_files::create_dir(dir)?;
        ocellus_io::video_writer::check_output(&dir.join("overlays.mp4"))?;
        if overlays {
            crate::output_files::create_dir(&dir.join("overlays"))?;
        }
        let mut scanpath = create(dir, "scanpath.csv")?;
        writeln!(scanpath, "frame,x,y,azimuth_deg,elevation_deg,reason")?;
        let mut context = create(dir, "context.csv")?;
        writeln!(
            context,
            "frame,chaos_bits,familiar,surprise_max_bits,fixation_x,fixation_y,reason,saliency_ms,temporal_us"
        )?;
        Ok(Self {
            dir: dir.into(),
            overlays,
            scanpath,
            context,
            chaos: Vec::new(),
            surprise_max: Vec::new(),
            recent: Vec::new(),
            saccades: 0,
        })
    }

    /// Writes frame `r`'s rows and returns what its overlay needs (when `draw`).
    fn record(&mut self, frame: Arc<RgbImage>, r: &StreamFrame, draw: bool) -> Result<Option<RenderJob>> {
        let k = r.frame;
        let smax = r.surprise.min_max().1;
        let (fx, fy, reason) = match r.fixation {
            Some(f) => (format!("{:.1}", f.x), format!("{:.1}", f.y), f.reason.as_str()),
            None => (String::new(), String::new(), ""),
        };
        let chaos = r.chaos.map(|c| format!("{c:.5}")).unwrap_or_default();
        writeln!(
            self.context,
            "{k},{chaos},{},{smax:.4},{fx},{fy},{reason},{:.3},{:.1}",
            u8::from(r.familiar),
            r.saliency_time.as_secs_f64() * 1e3,
            r.temporal_time.as_secs_f64() * 1e6
        )?;
        if let Some(c) = r.chaos {
            self.chaos.push((k as f64, c));
        }
        self.surprise_max.push((k as f64, smax as f64));
        if let Some(f) = r.fixation.filter(|f| f.saccade) {
            writeln!(
                self.scanpath,
                "{k},{:.1},{:.1},{:.3},{:.3},{}",
                f.x,
                f.y,
                f.azimuth_deg,
                f.elevation_deg,
                f.reason.as_str()
            )?;
            self.saccades += 1;
            self.recent.push(f);
            if self.recent.len() > 8 {
                self.recent.remove(0);
            }
        }
        Ok(draw.then(|| RenderJob {
            frame,
            saliency: r.saliency.clone(),
            surprise: r.surprise.clone(),
            inhibition: r.inhibition.clone(),
            fixation: r.fixation,
            recent: self.recent.clone(),
        }))
    }

    /// Flushes the CSVs and draws the plot; returns what was written (`video`: whether
    /// overlays.mp4 was).
    fn finish(mut self, threshold: f64, video: bool) -> Result<Vec<String>> {
        self.scanpath.flush()?;
        self.context.flush()?;
        let mut written = vec!["scanpath.csv".to_string(), "context.csv".into()];
        if video {
            written.push("overlays.mp4".into());
        }
        if self.overlays {
            written.push("overlays/".into());
        }
        let series = [
            plot::Series { label: "chaos degree s", points: self.chaos, color: RGBColor(200, 40, 40) },
            plot::Series { label: "max surprise", points: self.surprise_max, color: RGBColor(30, 90, 200) },
        ];
        plot::draw(
            &self.dir.join("context.png"),
            &plot::Plot {
                title: "context chaos degree and surprise per frame",
                x_label: "frame",
                y_label: "bits",
                series: &series,
                threshold: Some((threshold, "threshold S")),
                y_range: None,
            },
        )?;
        written.push("context.png".into());
        Ok(written)
    }
}

/// Frame `r` in the Rerun log: the frame, its maps, where attention is, the recent scanpath
/// (before this frame's saccade) and the context values.
fn log_frame(rec: &crate::rrd::Recorder, frame: &RgbImage, r: &StreamFrame, recent: &[Fixation]) -> Result<()> {
    rec.at(r.frame, None);
    match frame {
        RgbImage::U8(p) => rec.frame_rgb("frame", p)?,
        other => rec.frame_rgb("frame", &other.to_u8())?,
    }
    rec.map("maps/saliency", r.saliency)?;
    rec.map("maps/surprise_bits", r.surprise)?;
    rec.map("maps/inhibition", r.inhibition)?;
    if let Some(f) = r.fixation {
        // Salient places green, surprising ones red.
        let colour = match f.reason {
            Reason::Salient => [40, 220, 80, 255],
            Reason::Surprising => [255, 60, 40, 255],
        };
        rec.points_2d("frame/fixation", &[[f64::from(f.x), f64::from(f.y)]], 8.0, colour)?;
        let mut path: Vec<[f64; 2]> = recent.iter().map(|p| [f64::from(p.x), f64::from(p.y)]).collect();
        if f.saccade {
            path.push([f64::from(f.x), f64::from(f.y)]);
        }
        rec.strip_2d("frame/scanpath", &path, [255, 220, 0, 255])?;
    }
    if let Some(c) = r.chaos {
        rec.scalar("context/chaos_bits", c)?;
    }
    rec.scalar("context/surprise_max_bits", f64::from(r.surprise.min_max().1))?;
    Ok(())
}

/// The overlay image: [frame with fixations | saliency] over [surprise | inhibition], each
/// panel at half the frame size (even sizes, for video).
fn composite(r: &RenderJob) -> Result<Plane<[u8; 3]>> {
    let px = r.frame.to_u8();
    let mut half = draw::half_size(&px);
    let (w, h) = (half.width() & !1, half.height() & !1);
    half = Plane::from_fn(w.max(2), h.max(2), |x, y| half.get(x.min(half.width() - 1), y.min(half.height() - 1)));
    let sal = overlay_scaled(Backend::Auto, &half, &r.saliency, 0.0)?;
    // Surprise on a fixed scale up to 10 bits, so quiet frames look quiet.
    let sur = overlay_scaled(Backend::Auto, &half, &r.surprise, 10.0)?;
    let inh = overlay_scaled(Backend::Auto, &half, &r.inhibition, 1.0)?;
    let mut view = half.clone();
    for f in &r.recent {
        draw::ring(&mut view, (f.x - 0.5) / 2.0, (f.y - 0.5) / 2.0, 6.0, [255, 255, 255]);
    }
    if let Some(f) = r.fixation {
        let color = match f.reason {
            Reason::Salient => [40, 230, 60],
            Reason::Surprising => [250, 40, 40],
        };
        draw::ring(&mut view, (f.x - 0.5) / 2.0, (f.y - 0.5) / 2.0, 14.0, color);
    }
    Ok(draw::grid2x2([&view, &sal, &sur, &inh]))
}

/// The stream of `input` (at most `limit` frames) on `workers` threads (0: one per core):
/// saliency on the workers (`StreamWorker`), then `f(k, engine, maps, frame)` here in frame
/// order with one `StreamEngine` (made for the first frame's size) for the sequential part.
pub fn stream_frames(
    input: &Path,
    limit: Option<usize>,
    workers: usize,
    cfg: &StreamConfig,
    mut f: impl FnMut(usize, &mut StreamEngine, FrameMaps, Arc<RgbImage>) -> Result<()>,
) -> Result<usize> {
    let mut engine: Option<StreamEngine> = None;
    frames::for_each_frame_parallel(
        input,
        limit,
        workers,
        |w, h| Ok(StreamWorker::new(cfg, w, h)?),
        |worker, k, pair| Ok((worker.process(k, &pair.cur, pair.prev.as_deref())?, pair.cur)),
        |k, (maps, frame)| {
            let (w, h) = frame.size();
            let e = match engine.as_mut() {
                Some(e) => e,
                None => engine.insert(StreamEngine::new(cfg.clone(), w, h)?),
            };
            f(k, e, maps, frame)
        },
    )
}

/// Runs the subcommand.
pub fn run(a: AttendArgs) -> Result<()> {
    let out = a.out.clone();
    let (n, saccades, written) = run_quiet(a)?;
    outln!("{n} frames, {saccades} saccades; wrote {} in {}", written.join(", "), out.display());
    Ok(())
}

/// Runs the subcommand without the summary line: (frames, saccades, files written).
///
/// Three stages run at once: decoding; saliency on `workers` threads
/// (`ocellus_attention::stream::StreamWorker`, through the ordered pipeline); then, in
/// frame order, surprise, chaos and attention with the CSV rows; and the overlays drawn and
/// written on `workers` threads, fed to the video in order. Bounded queues between them
/// keep the memory fixed whatever the length of the stream.
pub fn run_quiet(a: AttendArgs) -> Result<(usize, usize, Vec<String>)> {
    let cfg = a.stream.config(a.deg_per_px)?;
    let rrd = crate::rrd::open(a.rrd.as_deref(), "ocellus_attend")?;
    let pan_tilt = a.pan_tilt.as_deref().map(frames::read_pan_tilt).transpose()?;
    for d in [a.out.clone(), a.out.join("overlays")] {
        crate::inputs::check_out_dir(&d, std::slice::from_ref(&a.input))?;
    }
    let mut out = Outputs::new(&a.out, !a.no_overlays)?;
    let threshold = cfg.chaos.threshold;
    let png_dir = (!a.no_overlays).then(|| a.out.join("overlays"));
    let workers = a.workers;
    let draw = png_dir.is_some() || !a.no_video;
    let mut video: Option<VideoWriter> = None;
    let (result, rendered) = frames::with_ordered_writer(
        workers,
        // Each job's overlay, drawn and written on the writer threads.
        |k, job: RenderJob| -> Result<Plane<[u8; 3]>> {
            let img = composite(&job)?;
            if let Some(d) = &png_dir {
                ocellus_io::write_png(d.join(format!("frame_{k:05}.png")), &img)?;
            }
            Ok(img)
        },
        // Then fed to the video in frame order.
        |k, img| {
            if k == 0 && !a.no_video {
                video = VideoWriter::start(&a.out.join("overlays.mp4"), img.width(), img.height(), a.fps)?;
                if video.is_none() {
                    errln!("note: ffmpeg not found; no overlays.mp4 (scripts/setup.sh installs it)");
                }
            }
            if let Some(v) = video.as_mut() {
                v.write(&img)?;
            }
            Ok(())
        },
        |jobs| {
            stream_frames(&a.input, a.limit, workers, &cfg, |k, e, maps, frame| {
                let (pan, tilt) = match &pan_tilt {
                    Some(v) => *v.get(k).with_context(|| format!("the pan-tilt CSV has no row for frame {k}"))?,
                    None => (0.0, 0.0),
                };
                let r = e.process_maps(maps, pan, tilt)?;
                if let Some(rec) = &rrd {
                    log_frame(rec, &frame, &r, &out.recent)?;
                }
                let job = out.record(frame, &r, draw)?;
                if job.is_some_and(|j| jobs.send(j).is_err()) {
                    bail!("the overlay writer stopped");
                }
                Ok(())
            })
        },
    );
    let wrote_video = video.is_some();
    let logged = rrd.map_or(Ok(()), crate::rrd::Recorder::finish);
    let rendered = rendered.and_then(|()| video.take().map_or(Ok(()), |v| Ok(v.finish()?)));
    // Whatever happened, what was processed is written out.
    let saccades = out.saccades;
    let mut written = out.finish(threshold, wrote_video && rendered.is_ok())?;
    logged?;
    if let Some(p) = &a.rrd {
        written.push(p.display().to_string());
    }
    // A writer that failed first makes the stream stop with "writer stopped": its own error
    // is the one to report.
    rendered?;
    let n = result?;
    Ok((n, saccades, written))
}
