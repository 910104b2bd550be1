//! `ocellus stereo`: dense disparity of a rectified pair (block matching or SGM), depth and a
//! point cloud.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use ocellus_geometry::block_matching::{bad_pixels, block_match, BlockMatching};
use ocellus_geometry::sgm::{Sgm, SgmMatcher, SgmPaths};
use ocellus_geometry::stereo::{depth_and_points, ParallelStereo};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `ocellus stereo`.
#[derive(Args, Debug)]
pub struct StereoArgs {
    /// Left image of a rectified pair.
    pub left: PathBuf,
    /// Right image (same size; left pixel (x, y) with disparity d matches right (x - d, y)).
    pub right: PathBuf,
    /// Matching method: `bm` block matching (SAD on x-Sobel, the seed's method) or `sgm`
    /// semi-global matching (census costs, 8 paths by default).
    #[arg(long, value_enum, default_value = "sgm")]
    pub method: Method,
    /// Disparities searched: 0..N pixels. Range: 1..=256.
    #[arg(long, default_value_t = 64, value_parser = crate::ranges::within(1usize, 256))]
    pub max_disp: usize,
    /// Odd block size of `bm`, pixels [default: 9]. Range: odd, 3..=63.
    #[arg(long, value_parser = crate::ranges::within(3usize, 63))]
    pub block: Option<usize>,
    /// Uniqueness margin (default 0.15 for bm, 0.05 for sgm: the best cost must beat every
    /// non-adjacent disparity by this fraction). Range: 0..=0.99.
    #[arg(long, value_parser = crate::ranges::within(0.0f32, 0.99))]
    pub uniqueness: Option<f32>,
    /// Paths of `sgm` [default: 8]. Range: 4 or 8.
    #[arg(long, value_parser = crate::ranges::within(4u8, 8))]
    pub paths: Option<u8>,
    /// Penalties P1 and P2 of `sgm` (census bits) [default: 10 120]. Range: 1..=1000 each,
    /// P1 <= P2.
    #[arg(long, num_args = 2, value_names = ["P1", "P2"], value_parser = crate::ranges::within(1u16, 1000))]
    pub penalties: Vec<u16>,
    /// 3x3 median of the `sgm` disparities.
    #[arg(long)]
    pub median: bool,
    /// Ground-truth disparity (PFM, inf where unknown): prints bad-2.0 and density.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Focal length in pixels (with --baseline: depth map and point cloud). Range: above 0,
    /// at most 1000000.
    #[arg(long, value_parser = crate::ranges::above(0.0f64, 1e6))]
    pub focal_px: Option<f64>,
    /// Baseline, in the unit wanted for depths (e.g. mm). Range: above 0, at most 1e9.
    #[arg(long, value_parser = crate::ranges::above(0.0f64, 1e9))]
    pub baseline: Option<f64>,
    /// Principal point x offset between the cameras (Middlebury doffs), pixels [default: 0];
    /// with --focal-px and --baseline. Range: -100000..=100000.
    #[arg(long, value_parser = crate::ranges::within(-1e5f64, 1e5))]
    pub doffs: Option<f64>,
    /// Principal point `X,Y` of the left camera, pixels (pixel centres at integers), for the
    /// point cloud [default: the image centre]; with --focal-px and --baseline.
    #[arg(long, value_parser = crate::ranges::point)]
    pub principal_point: Option<[f64; 2]>,
    /// Output folder: disparity.png, disparity.pfm, and depth.pfm, points.ply with calibration.
    #[arg(long, default_value = "ocellus-stereo")]
    pub out: PathBuf,
}

/// Dense matching method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// Block matching (SAD).
    Bm,
    /// Semi-global matching.
    Sgm,
}

/// Runs the subcommand.
pub fn run(a: StereoArgs) -> Result<()> {
    // Checked before the matching, which takes a while.
    match (a.focal_px, a.baseline) {
        (Some(_), Some(_)) => {}
        (None, None) if a.doffs.is_some() || a.principal_point.is_some() => {
            bail!("--doffs and --principal-point are used with --focal-px and --baseline (the depth map)")
        }
        (None, None) => {}
        _ => bail!("--focal-px and --baseline go together"),
    }
    let (li, ri) = (crate::budget::read_image(&a.left)?, crate::budget::read_image(&a.right)?);
    if li.size() != ri.size() {
        bail!("the images differ in size: {:?} and {:?}", li.size(), ri.size());
    }
    let (l, r) = (li.to_luma8(), ri.to_luma8());
    let sgm_only = [("--paths", a.paths.is_some()), ("--penalties", !a.penalties.is_empty()), ("--median", a.median)];
    match a.method {
        Method::Bm => {
            if let Some((flag, _)) = sgm_only.iter().find(|f| f.1) {
                bail!("{flag} is an option of --method sgm; block matching does not use it");
            }
        }
        Method::Sgm if a.block.is_some() => bail!("--block is an option of --method bm; SGM does not use it"),
        Method::Sgm => {}
    }
    let block = a.block.unwrap_or(9);
    let (disp, ms, what) = match a.method {
        Method::Bm => {
            let p = BlockMatching {
                max_disparity: a.max_disp,
                block,
                uniqueness: a.uniqueness.unwrap_or(0.15),
                ..BlockMatching::default()
            };
            let t = Instant::now();
            let disp = block_match(&l, &r, &p)?;
            (disp, t.elapsed().as_secs_f64() * 1e3, format!("block matching (block {block})"))
        }
        Method::Sgm => {
            let n_paths = a.paths.unwrap_or(8);
            let paths = match n_paths {
                8 => SgmPaths::Eight,
                4 => SgmPaths::Four,
                n => bail!("--paths {n}: SGM uses 4 or 8 paths"),
            };
            let [p1, p2] = match a.penalties[..] {
                [p1, p2] => [p1, p2],
                _ => [10, 120],
            };
            if p1 > p2 {
                bail!("--penalties {p1} {p2}: P1 must not exceed P2");
            }
            // The cost volume: a byte of census cost and two of aggregated cost per pixel and disparity.
            let need = (l.width() * l.height()) as u64 * (3 * a.max_disp as u64 + 16);
            crate::budget::check(
                &format!("SGM at {}x{} with {} disparities", l.width(), l.height(), a.max_disp),
                need,
            )?;
            let p = Sgm {
                max_disparity: a.max_disp,
                paths,
                p1,
                p2,
                uniqueness: a.uniqueness.unwrap_or(0.05),
                median: a.median,
                ..Sgm::default()
            };
            let mut m = SgmMatcher::new(p, l.width(), l.height())?;
            let t = Instant::now();
            let disp = m.compute(&l, &r)?.clone();
            (disp, t.elapsed().as_secs_f64() * 1e3, format!("SGM ({n_paths} paths, P1 {p1}, P2 {p2})"))
        }
    };
    crate::output_files::create_dir(&a.out)?;
    ocellus_io::write_png(a.out.join("disparity.png"), &ocellus_image::colormap::heat_map(&disp, a.max_disp as f32))?;
    ocellus_io::pfm::write(a.out.join("disparity.pfm"), &disp)?;
    let valid = disp.to_vec().iter().filter(|v| v.is_finite()).count();
    outln!(
        "{what} {}x{}, {} disparities: {ms:.1} ms (first run, buffers included), {:.1} % of pixels with a disparity",
        l.width(),
        l.height(),
        a.max_disp,
        100.0 * valid as f64 / (l.width() * l.height()) as f64
    );
    let mut written = vec!["disparity.png", "disparity.pfm"];
    if let Some(tp) = &a.truth {
        let truth = ocellus_io::pfm::read(tp)?;
        let (bad, density) = bad_pixels(&disp, &truth, 2.0).with_context(|| format!("--truth {}", tp.display()))?;
        outln!("against {}: bad-2.0 {:.2} %, density {:.2} %", tp.display(), bad * 100.0, density * 100.0);
    }
    if let (Some(f), Some(b)) = (a.focal_px, a.baseline) {
        let rig = ParallelStereo { baseline: b, focal_px: f };
        let (w, h) = disp.size();
        let centre = a.principal_point.unwrap_or([(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0]);
        let (depth, cloud) = depth_and_points(&disp, &rig, centre, a.doffs.unwrap_or(0.0))?;
        let colour = li.to_u8();
        let pts: Vec<([f32; 3], [u8; 3])> = cloud.iter().map(|p| (p.xyz, colour.get(p.pixel.0, p.pixel.1))).collect();
        ocellus_io::ply::write(a.out.join("points.ply"), &pts)?;
        ocellus_io::pfm::write(a.out.join("depth.pfm"), &depth)?;
        outln!(
            "{} points (units of the baseline, left camera frame, principal point ({:.1}, {:.1}) px)",
            pts.len(),
            centre[0],
            centre[1]
        );
        written.extend(["depth.pfm", "points.ply"]);
    }
    outln!("wrote {} in {}", written.join(", "), a.out.display());
    Ok(())
}
