//! `ocellus surprise`: Bayesian surprise maps of a video or image sequence, through the
//! ordered frame pipeline (saliency on workers, surprise in order, maps written on workers).

use crate::attend::{stream_frames, StreamOptions};
use crate::frames;
use anyhow::{bail, Result};
use clap::Args;
use ocellus_image::colormap::overlay_scaled;
use ocellus_image::convert::RgbImage;
use ocellus_image::draw::half_size;
use ocellus_image::Plane;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

/// Arguments of `ocellus surprise`.
#[derive(Args, Debug)]
pub struct SurpriseArgs {
    /// A video file (anything ffmpeg reads; .y4m natively) or a folder of images.
    pub input: PathBuf,
    /// Output folder: surprise/frame_NNNNN.png (and .npy with --npy), surprise.csv.
    #[arg(long, default_value = "ocellus-surprise")]
    pub out: PathBuf,
    #[command(flatten)]
    pub stream: StreamOptions,
    /// Also write each surprise map (bits, map level) as NumPy .npy.
    #[arg(long)]
    pub npy: bool,
    /// Process at most N frames. Range: 1..=10000000.
    #[arg(long, value_parser = crate::ranges::within(1usize, 10_000_000))]
    pub limit: Option<usize>,
    /// Worker threads for saliency and for writing the maps; 0: one per core. The results do
    /// not depend on it. Range: 0..=256.
    #[arg(long, default_value_t = 0, value_parser = crate::ranges::within(0usize, 256))]
    pub workers: usize,
}

/// Runs the subcommand.
pub fn run(a: SurpriseArgs) -> Result<()> {
    let cfg = a.stream.config(0.1)?;
    let maps = a.out.join("surprise");
    for d in [&a.out, &maps] {
        crate::inputs::check_out_dir(d, std::slice::from_ref(&a.input))?;
    }
    crate::output_files::create_dir(&maps)?;
    let csv_path = a.out.join("surprise.csv");
    let mut csv = crate::output_files::create_file(&csv_path)?;
    writeln!(csv, "frame,surprise_max_bits,x,y,chaos_bits")?;
    let mut peak = (0.0f32, 0usize);
    // Saliency on the workers, surprise in frame order here, the maps written by the writers.
    let (result, written) = frames::with_ordered_writer(
        a.workers,
        |k, (frame, m): (Arc<RgbImage>, Plane<f32>)| -> Result<()> {
            let img = overlay_scaled(ocellus_image::Backend::Auto, &half_size(&frame.to_u8()), &m, 10.0)?;
            ocellus_io::write_png(maps.join(format!("frame_{k:05}.png")), &img)?;
            if a.npy {
                ocellus_io::npy::write_plane(maps.join(format!("frame_{k:05}.npy")), &m)?;
            }
            Ok(())
        },
        |_, ()| Ok(()),
        |jobs| {
            stream_frames(&a.input, a.limit, a.workers, &cfg, |k, e, maps, frame| {
                let (w, h) = frame.size();
                let r = e.process_maps(maps, 0.0, 0.0)?;
                let m = r.surprise;
                let Some(p) = ocellus_image::location::peak(m, (w, h)) else { bail!("frame {k}: empty surprise map") };
                let (best, [px, py]) = (p.value, p.pixel);
                let chaos = r.chaos.map(|c| format!("{c:.5}")).unwrap_or_default();
                writeln!(csv, "{k},{best:.4},{px:.1},{py:.1},{chaos}")?;
                if best > peak.0 {
                    peak = (best, k);
                }
                if jobs.send((frame, m.clone())).is_err() {
                    bail!("the map writer stopped");
                }
                Ok(())
            })
        },
    );
    csv.flush()?;
    // The writers' own error first: the stream stops with "writer stopped" after it.
    written?;
    let n = result?;
    outln!(
        "{n} frames; largest surprise {:.2} bits at frame {}; wrote surprise/ and surprise.csv in {}",
        peak.0,
        peak.1,
        a.out.display()
    );
    Ok(())
}
