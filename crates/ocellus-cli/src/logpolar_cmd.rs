//! `ocellus logpolar`: the log-polar (foveal) image of a picture and its inverse;
//! `logpolar register A B`: rotation and scale between two images; `logpolar vergence L R`:
//! disparity at a gaze point of a stereo pair.

use crate::frames::for_each_frame_parallel;
use crate::ranges;
use anyhow::{bail, Result};
use clap::{Args, Subcommand, ValueEnum};
use ocellus_fovea::logpolar::{Fields, LogPolarConfig, LogPolarMap, Scratch};
use ocellus_fovea::register::{register, Mode, RegisterOptions};
use ocellus_fovea::vergence::{vergence, VergenceOptions};
use ocellus_image::convert::merge_rgb8;
use ocellus_image::Plane;
use ocellus_io::video_writer::VideoWriter;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus logpolar`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct LogPolarArgs {
    #[command(subcommand)]
    sub: Option<Sub>,
    /// Input image (PNG, JPEG, PNM; colour is kept), or a folder of images, a Y4M file or a
    /// video (every frame through the same map).
    #[arg(required = true)]
    image: Option<PathBuf>,
    /// Log rings between the fovea radius and the outer radius. Range: 1..=4096.
    #[arg(long, default_value_t = 128, value_parser = ranges::within(1usize, 4096))]
    rings: usize,
    /// Sectors over the full turn. Range: 4..=4096.
    #[arg(long, default_value_t = 128, value_parser = ranges::within(4usize, 4096))]
    sectors: usize,
    /// Gaze point `X,Y` in pixels (pixel centres at integers) [default: the image centre].
    #[arg(long, value_parser = ranges::point)]
    fovea: Option<[f64; 2]>,
    /// Fovea radius rho_0, pixels [default: outer radius / 60, at least 2]. Range: 0.5..=100000,
    /// and below the outer radius.
    #[arg(long, value_parser = ranges::within(0.5f64, 1e5))]
    fovea_radius: Option<f64>,
    /// Outer radius rho_max, pixels [default: half the image's smaller side]. Range: 2..=100000.
    #[arg(long, value_parser = ranges::within(2.0f64, 1e5))]
    max_radius: Option<f64>,
    /// Receptive fields: `pyramid` (fast, one bilinear read of the box-pyramid level as large
    /// as the cell) or `area` (the exact mean over each cell's annular sector).
    #[arg(long, value_enum, default_value = "pyramid")]
    fields: FieldsArg,
    /// Output folder: cortex.png (sectors across, rings down; fovea rings on top),
    /// inverse.png (the cortical image mapped back for display), logpolar.json (geometry and
    /// compression ratio). For a stream: cortex/NNNNN.png, and cortex.mp4 and inverse.mp4
    /// when ffmpeg is installed.
    #[arg(long, default_value = "ocellus-logpolar")]
    out: PathBuf,
    /// Worker threads for a stream (sampling and writing each frame); 0: one per core. The
    /// results do not depend on it. Range: 0..=256.
    #[arg(long, default_value_t = 0, value_parser = ranges::within(0usize, 256))]
    workers: usize,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum FieldsArg {
    Pyramid,
    Area,
}

#[derive(Subcommand, Debug)]
enum Sub {
    /// Rotation (degrees, clockwise on the screen) and scale of image B relative to image A,
    /// by phase correlation of their log-polar images.
    Register(RegisterArgs),
    /// Horizontal disparity (x_left - x_right, pixels) at a gaze point of a rectified stereo
    /// pair, from the log-polar images around it.
    Vergence(VergenceArgs),
}

#[derive(Args, Debug)]
struct RegisterArgs {
    /// Reference image.
    a: PathBuf,
    /// Rotated and scaled image (same size).
    b: PathBuf,
    /// `direct`: rotation and scale about the image centres; `spectrum`: of the magnitude
    /// spectra (Fourier-Mellin), so B may also be translated (the translation is printed).
    #[arg(long, value_enum, default_value = "direct")]
    mode: ModeArg,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum ModeArg {
    Direct,
    Spectrum,
}

#[derive(Args, Debug)]
struct VergenceArgs {
    /// Left image.
    left: PathBuf,
    /// Right image (rectified with the left).
    right: PathBuf,
    /// Gaze point `X,Y` in the left image, pixels.
    #[arg(long, value_parser = ranges::point)]
    gaze: [f64; 2],
    /// Largest disparity searched, pixels. Range: 1..=1024.
    #[arg(long, default_value_t = 64, value_parser = ranges::within(1i64, 1024))]
    max_disparity: i64,
    /// Outer radius of the compared field, pixels. Range: 4..=1000.
    #[arg(long, default_value_t = 24.0, value_parser = ranges::within(4.0f64, 1000.0))]
    radius: f64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

fn grey_f32(path: &Path) -> Result<Plane<f32>> {
    Ok(crate::budget::read_image(path)?.to_grey())
}

/// Runs the subcommand.
pub fn run(a: LogPolarArgs) -> Result<()> {
    match a.sub {
        Some(Sub::Register(r)) => return run_register(&r),
        Some(Sub::Vergence(v)) => return run_vergence(&v),
        None => {}
    }
    let Some(path) = &a.image else { bail!("give an image") };
    if path.is_dir() || !ocellus_io::is_image_path(path) {
        return run_stream(&a, path);
    }
    let img = crate::budget::read_image(path)?;
    let (w, h) = img.size();
    let cfg = config(&a, w, h);
    let t = std::time::Instant::now();
    let map = LogPolarMap::new(&cfg, w, h)?;
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    crate::inputs::check_out_dir(&a.out, std::slice::from_ref(path))?;
    crate::output_files::create_dir(&a.out)?;
    let t = std::time::Instant::now();
    write_foveated(&map, &img.to_u8(), &a.out.join("cortex.png"), &a.out.join("inverse.png"))?;
    let sample_us = t.elapsed().as_secs_f64() * 1e6;
    let info = serde_json::json!({
        "image": [w, h],
        "config": cfg,
        "ring_ratio": cfg.ring_ratio(),
        "cortex_rows": map.rows(),
        "cortex_columns": map.sectors(),
        "fovea_rows": cfg.fovea_rings,
        "compression_ratio": map.compression_ratio(),
        "table_entries": map.table_entries(),
        "table_build_ms": build_ms,
        "rgb_sample_and_write_us": sample_us,
    });
    std::fs::write(a.out.join("logpolar.json"), serde_json::to_string_pretty(&info)?)?;
    outln!(
        "{w}x{h} -> {} rows ({} fovea + {} log rings, ratio {:.5}) x {} sectors: compression {:.1}x; wrote cortex.png, inverse.png, logpolar.json in {}",
        map.rows(),
        cfg.fovea_rings,
        cfg.rings,
        cfg.ring_ratio(),
        map.sectors(),
        map.compression_ratio(),
        a.out.display()
    );
    Ok(())
}

/// The map's parameters for a `w` x `h` input from the options.
fn config(a: &LogPolarArgs, w: usize, h: usize) -> LogPolarConfig {
    let mut cfg = LogPolarConfig { rings: a.rings, sectors: a.sectors, ..LogPolarConfig::for_image(w, h) };
    if let Some(c) = a.fovea {
        cfg.centre = c;
    }
    if let Some(r) = a.max_radius {
        cfg.max_radius = r;
    }
    cfg.fovea_radius = a.fovea_radius.unwrap_or((cfg.max_radius / 60.0).max(2.0).min(cfg.max_radius / 2.0));
    cfg.fovea_rings = cfg.fovea_radius.round().max(1.0) as usize;
    cfg.fields = match a.fields {
        FieldsArg::Pyramid => Fields::Pyramid,
        FieldsArg::Area => Fields::Area,
    };
    cfg
}

/// A folder of images, a Y4M file or a video: every frame through one map (built from the
/// first frame's size); the cortical frames as PNG files, and as videos with their inverses
/// when ffmpeg is installed.
fn run_stream(a: &LogPolarArgs, input: &Path) -> Result<()> {
    let cortex_dir = a.out.join("cortex");
    for d in [&a.out, &cortex_dir] {
        crate::inputs::check_out_dir(d, &[input.to_path_buf()])?;
    }
    crate::output_files::create_dir(&cortex_dir)?;
    for v in ["cortex.mp4", "inverse.mp4"] {
        ocellus_io::video_writer::check_output(&a.out.join(v))?;
    }
    // Sampling, the cortical PNG and the inverse image on the workers (each with its own map,
    // built for the first frame it gets); the two videos fed here in frame order.
    let mut videos: Option<(Option<VideoWriter>, Option<VideoWriter>)> = None;
    let mut map0: Option<LogPolarMap> = None;
    let mut spent = Vec::new();
    let even = |p: &Plane<[u8; 3]>| {
        let (pw, ph) = p.size();
        Plane::from_fn(pw + pw % 2, ph + ph % 2, |x, y| p.get(x.min(pw - 1), y.min(ph - 1)))
    };
    let r = for_each_frame_parallel(
        input,
        None,
        a.workers,
        |w, h| Ok((LogPolarMap::new(&config(a, w, h), w, h)?, Scratch::default(), <[Plane<f32>; 3]>::default())),
        |(map, scratch, out), k, pair| {
            let rgb = pair.cur.to_u8();
            let (w, h) = rgb.size();
            if (w, h) != map.image_size() {
                bail!("frame is {w}x{h}, the first frame was {:?}", map.image_size());
            }
            let t = std::time::Instant::now();
            map.sample_rgb_into(&rgb, scratch, out)?;
            let us = t.elapsed().as_secs_f64() * 1e6;
            let [r, g, b] = &*out;
            let cortex = merge_rgb8([r, g, b]);
            ocellus_io::write_png(cortex_dir.join(format!("{k:05}.png")), &cortex)?;
            let inverse = merge_rgb8([&map.inverse(r)?, &map.inverse(g)?, &map.inverse(b)?]);
            Ok((us, even(&cortex), even(&inverse), (k == 0).then(|| map.clone())))
        },
        |_, (us, cortex, inverse, first)| {
            spent.push(us);
            if let Some(m) = first {
                map0 = Some(m);
            }
            if videos.is_none() {
                let (iw, ih) = inverse.size();
                videos = Some((
                    VideoWriter::start(&a.out.join("cortex.mp4"), cortex.width(), cortex.height(), 30)?,
                    VideoWriter::start(&a.out.join("inverse.mp4"), iw, ih, 30)?,
                ));
            }
            if let Some((Some(c), Some(i))) = videos.as_mut() {
                c.write(&cortex)?;
                i.write(&inverse)?;
            }
            Ok(())
        },
    );
    let (cortex_video, inverse_video) = videos.unwrap_or((None, None));
    let has_videos = cortex_video.is_some();
    for v in [cortex_video, inverse_video].into_iter().flatten() {
        v.finish()?;
    }
    let n = r?;
    let Some(map) = map0 else { bail!("{} has no frames", input.display()) };
    spent.sort_by(f64::total_cmp);
    let median_us = spent.get(spent.len() / 2).copied().unwrap_or(0.0);
    let info = serde_json::json!({
        "frames": n,
        "image": map.image_size(),
        "config": map.config(),
        "cortex_rows": map.rows(),
        "cortex_columns": map.sectors(),
        "compression_ratio": map.compression_ratio(),
        "median_rgb_sample_us": median_us,
    });
    std::fs::write(a.out.join("logpolar.json"), serde_json::to_string_pretty(&info)?)?;
    outln!(
        "{n} frames -> {} rows x {} sectors, {median_us:.0} us per frame (median, sampling only); wrote cortex/NNNNN.png{}, logpolar.json in {}",
        map.rows(),
        map.sectors(),
        if has_videos { ", cortex.mp4, inverse.mp4" } else { " (no ffmpeg: no videos)" },
        a.out.display()
    );
    Ok(())
}

/// Writes the cortical image of `rgb` under `map` and its inverse as PNG files.
pub fn write_foveated(map: &LogPolarMap, rgb: &Plane<[u8; 3]>, cortex_png: &Path, inverse_png: &Path) -> Result<()> {
    let [r, g, b] = map.sample_rgb(rgb)?;
    ocellus_io::write_png(cortex_png, &merge_rgb8([&r, &g, &b]))?;
    let (ir, ig, ib) = (map.inverse(&r)?, map.inverse(&g)?, map.inverse(&b)?);
    ocellus_io::write_png(inverse_png, &merge_rgb8([&ir, &ig, &ib]))?;
    Ok(())
}

fn run_register(r: &RegisterArgs) -> Result<()> {
    let (a, b) = (grey_f32(&r.a)?, grey_f32(&r.b)?);
    let mode = match r.mode {
        ModeArg::Direct => Mode::Direct,
        ModeArg::Spectrum => Mode::Spectrum,
    };
    let est = register(&a, &b, &RegisterOptions { mode, ..Default::default() })?;
    if r.json {
        outln!("{}", serde_json::to_string(&est)?);
    } else {
        outln!("rotation {:.3} deg, scale {:.5}", est.angle_deg, est.scale);
        if mode == Mode::Spectrum {
            outln!("translation {:.2}, {:.2} px", est.translation[0], est.translation[1]);
        }
        outln!("peak {:.3}", est.peak);
    }
    Ok(())
}

fn run_vergence(v: &VergenceArgs) -> Result<()> {
    let l = crate::budget::read_image(&v.left)?.to_luma8();
    let r = crate::budget::read_image(&v.right)?.to_luma8();
    let opts = VergenceOptions { max_disparity: v.max_disparity, max_radius: v.radius, ..Default::default() };
    let est = vergence(&l, &r, v.gaze, &opts)?;
    if v.json {
        outln!("{}", serde_json::to_string(&est)?);
    } else {
        outln!("disparity {:.2} px (correlation {:.3})", est.disparity_px, est.score);
    }
    Ok(())
}
