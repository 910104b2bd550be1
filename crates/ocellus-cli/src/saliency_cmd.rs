//! `ocellus saliency`: saliency maps, overlays and raw values for images and folders.

use crate::{config_file, inputs};
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_image::{convert, Plane};
use std::path::{Path, PathBuf};

/// Arguments of `ocellus saliency`.
#[derive(Args, Debug)]
pub struct SaliencyArgs {
    /// Image files (PNG, JPEG, PNM) or folders of them (read in natural order).
    #[arg(required_unless_present = "print_config")]
    pub images: Vec<PathBuf>,
    /// Parameter preset: `ace2009` (the seed's parameters) or `stb` (SaliencyToolbox defaults).
    #[arg(long, default_value = "ace2009")]
    pub preset: String,
    /// TOML file overriding any preset field (field names as printed by --print-config).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Output folder (created if missing).
    #[arg(long, default_value = "ocellus-out")]
    pub out: PathBuf,
    /// Also write each channel's conspicuity map (PNG and NPY).
    #[arg(long)]
    pub conspicuity: bool,
    /// Print the time of each pipeline stage for every image (milliseconds).
    #[arg(long)]
    pub timings: bool,
    /// Print the effective configuration as TOML and exit (no images are read).
    #[arg(long, conflicts_with_all = ["images", "conspicuity", "timings", "out"])]
    pub print_config: bool,
    /// Worker threads over the images (each with its own engine); 0: one per core. Results
    /// and the order of the printed lines do not depend on it. Range: 0..=256.
    #[arg(long, default_value_t = 0, value_parser = crate::ranges::within(0usize, 256))]
    pub workers: usize,
    /// Run the whole pipeline (pyramids, opponency, Gabor energies, then rescaling,
    /// center-surround, N(.) and combination) on the GPU through wgpu (Vulkan, Metal or DX12;
    /// a software Vulkan driver works too, slowly): `backend = "gpu"` of the configuration;
    /// only a spatial prior is applied on the CPU. The maps equal
    /// the CPU's within 1e-4 of their peak. It needs opponency at each level (the ace2009
    /// preset) and the intensity, colour and orientation channels only; 16-bit inputs are
    /// reduced to 8 bits.
    #[arg(long, conflicts_with = "print_config")]
    pub gpu: bool,
}

/// What one image produced.
pub struct SaliencyResult {
    /// Map-level size (w, h).
    pub map_size: (usize, usize),
    /// Most salient location in input pixels (x, y; integer centres), centre of the winning map cell.
    pub peak_px: [f64; 2],
}

fn write_map(out: &Path, name: &str, map: &Plane<f32>) -> Result<()> {
    let (_, mx) = map.min_max();
    let png = out.join(format!("{name}.png"));
    ocellus_io::write_png(&png, &convert::to_grey8(map, 0.0, if mx > 0.0 { mx } else { 1.0 }))?;
    let npy = out.join(format!("{name}.npy"));
    ocellus_io::npy::write_plane(&npy, map)?;
    Ok(())
}

/// Computes and writes the outputs of one image with `engine` (rebuilt when the size changes).
pub fn process_one(
    path: &Path,
    cfg: &SaliencyConfig,
    engine: &mut Option<SaliencyEngine>,
    out: &Path,
    conspicuity: bool,
) -> Result<SaliencyResult> {
    let img = crate::budget::read_image(path)?;
    let (w, h) = img.size();
    if engine.as_ref().map(|e| e.frame_size()) != Some((w, h)) {
        *engine = Some(SaliencyEngine::new(cfg.clone(), w, h).with_context(|| format!("{}", path.display()))?);
    }
    let Some(e) = engine.as_mut() else { bail!("engine missing") };
    e.process(&img).with_context(|| format!("{}", path.display()))?;
    let stem = inputs::stem(path);
    write_map(out, &format!("{stem}.saliency"), e.saliency())?;
    let mut full = Plane::default();
    e.saliency_full_size(&mut full)?;
    let ov = out.join(format!("{stem}.overlay.png"));
    ocellus_io::write_png(&ov, &ocellus_image::colormap::overlay(&img.to_u8(), &full))?;
    if conspicuity {
        let maps: Vec<(String, Plane<f32>)> =
            e.conspicuity_maps().map(|(l, m)| (l.replace(':', "-"), m.clone())).collect();
        for (label, m) in maps {
            write_map(out, &format!("{stem}.conspicuity.{label}"), &m)?;
        }
    }
    let s = e.saliency();
    let Some(peak) = ocellus_image::location::peak(s, (w, h)) else {
        bail!("{}: the saliency map is empty", path.display())
    };
    Ok(SaliencyResult { map_size: s.size(), peak_px: peak.pixel })
}

/// Runs the subcommand.
pub fn run(a: SaliencyArgs) -> Result<()> {
    let mut cfg = config_file::load(&a.preset, a.config.as_deref())?;
    if a.gpu {
        cfg.backend = ocellus_image::Backend::Gpu;
    }
    if a.print_config {
        out!("{}", config_file::to_toml(&cfg)?);
        return Ok(());
    }
    let files = inputs::collect_images(&a.images)?;
    inputs::output_stems(&files)?;
    inputs::check_out_dir(&a.out, &files)?;
    crate::output_files::create_dir(&a.out)?;
    let bar = if files.len() > 1 {
        let b = ProgressBar::new(files.len() as u64);
        b.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}").unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    } else {
        ProgressBar::hidden()
    };
    let mut failed = 0;
    // The images through the ordered pipeline: read and processed on the workers, reported
    // here in the order given. A failing image is reported and counted, the others go on.
    let mut next = files.iter();
    let r = ocellus_io::pipeline::run_ordered(
        ocellus_io::pipeline::PipelineConfig::with_workers(a.workers),
        move || -> Result<Option<&PathBuf>> { Ok(next.next()) },
        || Ok(None::<SaliencyEngine>),
        |engine, _, f| {
            let r = process_one(f, &cfg, engine, &a.out, a.conspicuity);
            let timings = engine.as_ref().map(|e| {
                let t = e.timings();
                let parts: Vec<String> =
                    t.stages().iter().map(|(n, d)| format!("{n} {:.3}", d.as_secs_f64() * 1e3)).collect();
                format!("  timings ms: {}; total {:.3}", parts.join(", "), t.total().as_secs_f64() * 1e3)
            });
            Ok((f, r, timings))
        },
        |_, (f, r, timings)| {
            bar.set_message(inputs::stem(f));
            match r {
                Ok(r) => {
                    bar.suspend(|| {
                        outln!(
                            "{}: map {}x{}, most salient at ({:.1}, {:.1}) px",
                            f.display(),
                            r.map_size.0,
                            r.map_size.1,
                            r.peak_px[0],
                            r.peak_px[1]
                        );
                        if let Some(t) = timings.filter(|_| a.timings) {
                            outln!("{t}");
                        }
                        Ok::<(), anyhow::Error>(())
                    })?;
                }
                Err(e) => {
                    failed += 1;
                    bar.suspend(|| errln!("error: {e:#}"));
                }
            }
            bar.inc(1);
            Ok(())
        },
    );
    if let Err(e) = crate::frames::pipeline_result(r) {
        bar.finish_and_clear();
        return Err(e);
    }
    bar.finish_and_clear();
    if failed < files.len() {
        outln!("wrote the maps of {} images to {}", files.len() - failed, a.out.display());
    }
    if failed > 0 {
        bail!("{failed} of {} images failed", files.len());
    }
    Ok(())
}
