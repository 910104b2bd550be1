//! `ocellus stereo`: dense disparity of a rectified pair, depth and a point cloud.

use crate::overlay;
use anyhow::{bail, Context, Result};
use clap::Args;
use ocellus_geometry::block_matching::{bad_pixels, block_match, BlockMatching};
use ocellus_geometry::stereo::ParallelStereo;
use ocellus_image::convert::{to_image_rgb8, RgbImage};
use ocellus_image::Plane;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `ocellus stereo`.
#[derive(Args, Debug)]
pub struct StereoArgs {
    /// Left image of a rectified pair.
    pub left: PathBuf,
    /// Right image (same size; left pixel (x, y) with disparity d matches right (x - d, y)).
    pub right: PathBuf,
    /// Disparities searched: 0..N pixels.
    #[arg(long, default_value_t = 64)]
    pub max_disp: usize,
    /// Odd block size, pixels.
    #[arg(long, default_value_t = 9)]
    pub block: usize,
    /// Uniqueness margin (0.15: the best cost must beat non-adjacent disparities by 15 %).
    #[arg(long, default_value_t = 0.15)]
    pub uniqueness: f32,
    /// Ground-truth disparity (PFM, inf where unknown): prints bad-2.0 and density.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Focal length in pixels (with --baseline: depth map and point cloud).
    #[arg(long)]
    pub focal_px: Option<f64>,
    /// Baseline, in the unit wanted for depths (e.g. mm).
    #[arg(long)]
    pub baseline: Option<f64>,
    /// Principal point x offset between the cameras (Middlebury doffs), pixels.
    #[arg(long, default_value_t = 0.0)]
    pub doffs: f64,
    /// Output folder: disparity.png, disparity.pfm, and depth.pfm, points.ply with calibration.
    #[arg(long, default_value = "ocellus-stereo")]
    pub out: PathBuf,
}

/// Disparity as a heat map (0..max), invalid pixels black.
fn disparity_image(d: &Plane<f32>, max: f32) -> Plane<[u8; 3]> {
    Plane::from_fn(d.width(), d.height(), |x, y| {
        let v = d.get(x, y);
        if v.is_finite() {
            overlay::heat_color(v / max)
        } else {
            [0, 0, 0]
        }
    })
}

fn write_cloud(
    path: &Path,
    disp: &Plane<f32>,
    colour: &RgbImage,
    rig: &ParallelStereo,
    doffs: f64,
) -> Result<(usize, Plane<f32>)> {
    let (w, h) = disp.size();
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let mut depth = Plane::from_fn(w, h, |_, _| f32::NAN);
    let mut pts = Vec::new();
    let px = colour.to_u8();
    for y in 0..h {
        for x in 0..w {
            let d = disp.get(x, y);
            if !d.is_finite() {
                continue;
            }
            // Zero total disparity is infinite depth: left out, not divided by.
            if let Ok(p) = rig.point(x as f64, y as f64, d as f64 + doffs, cx, cy) {
                depth.set(x, y, p[2] as f32);
                pts.push(([p[0] as f32, p[1] as f32, p[2] as f32], px.get(x, y)));
            }
        }
    }
    ocellus_io::ply::write(path, &pts)?;
    Ok((pts.len(), depth))
}

/// Runs the subcommand.
pub fn run(a: StereoArgs) -> Result<()> {
    let (li, ri) = (ocellus_io::read_image(&a.left)?, ocellus_io::read_image(&a.right)?);
    if li.size() != ri.size() {
        bail!("the images differ in size: {:?} and {:?}", li.size(), ri.size());
    }
    let p = BlockMatching {
        max_disparity: a.max_disp,
        block: a.block,
        uniqueness: a.uniqueness,
        ..BlockMatching::default()
    };
    let (l, r) = (li.to_luma8(), ri.to_luma8());
    let t = Instant::now();
    let disp = block_match(&l, &r, &p)?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    std::fs::create_dir_all(&a.out).with_context(|| format!("cannot create {}", a.out.display()))?;
    ocellus_io::write_png(a.out.join("disparity.png"), &to_image_rgb8(&disparity_image(&disp, a.max_disp as f32)))?;
    ocellus_io::pfm::write(a.out.join("disparity.pfm"), &disp)?;
    let valid = disp.to_vec().iter().filter(|v| v.is_finite()).count();
    println!(
        "block matching {}x{}, {} disparities, block {}: {ms:.1} ms, {:.1} % of pixels with a disparity",
        l.width(),
        l.height(),
        a.max_disp,
        a.block,
        100.0 * valid as f64 / (l.width() * l.height()) as f64
    );
    let mut written = vec!["disparity.png", "disparity.pfm"];
    if let Some(tp) = &a.truth {
        let truth = ocellus_io::pfm::read(tp)?;
        let (bad, density) = bad_pixels(&disp, &truth, 2.0)?;
        println!("against {}: bad-2.0 {:.2} %, density {:.2} %", tp.display(), bad * 100.0, density * 100.0);
    }
    match (a.focal_px, a.baseline) {
        (Some(f), Some(b)) => {
            let rig = ParallelStereo { baseline: b, focal_px: f };
            let (n, depth) = write_cloud(&a.out.join("points.ply"), &disp, &li, &rig, a.doffs)?;
            ocellus_io::pfm::write(a.out.join("depth.pfm"), &depth)?;
            println!("{n} points (units of the baseline, left camera frame)");
            written.extend(["depth.pfm", "points.ply"]);
        }
        (None, None) => {}
        _ => bail!("--focal-px and --baseline go together"),
    }
    println!("wrote {} in {}", written.join(", "), a.out.display());
    Ok(())
}
