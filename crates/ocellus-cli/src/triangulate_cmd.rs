//! `ocellus triangulate`: 3D points from pixel matches in calibrated views.

use anyhow::{bail, Context, Result};
use clap::Args;
use nalgebra::{Matrix3x4, Vector3, Vector4};
use ocellus_geometry::triangulate::{n_view, two_view_seed};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus triangulate`.
#[derive(Args, Debug)]
pub struct TriangulateArgs {
    /// Camera files written by `ocellus calibrate dlt` (their `projection_matrix`), two or more.
    #[arg(long = "camera", required = true, num_args = 1)]
    pub cameras: Vec<PathBuf>,
    /// CSV of matches: per line the pixel (u, v) in each camera, in the order of --camera.
    pub matches: PathBuf,
    /// Use the seed's 4x3 least squares (two cameras only) instead of the homogeneous form.
    #[arg(long)]
    pub seed_form: bool,
    /// The true points, `X,Y,Z` per line in the order of the matches (e.g. board.csv of
    /// `calibrate chessboard`): prints the RMS 3D error (world units).
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Output CSV: X, Y, Z, in front of every camera (1/0), RMS reprojection error (pixels).
    #[arg(long, default_value = "points.csv")]
    pub out: PathBuf,
}

fn read_camera(path: &Path) -> Result<Matrix3x4<f64>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let rows =
        v["projection_matrix"].as_array().with_context(|| format!("{}: no projection_matrix", path.display()))?;
    let mut p = Matrix3x4::zeros();
    if rows.len() != 3 {
        bail!("{}: projection_matrix must have 3 rows", path.display());
    }
    for (i, r) in rows.iter().enumerate() {
        let r = r
            .as_array()
            .filter(|r| r.len() == 4)
            .with_context(|| format!("{}: rows need 4 numbers", path.display()))?;
        for (j, x) in r.iter().enumerate() {
            p[(i, j)] =
                x.as_f64().filter(|x| x.is_finite()).with_context(|| format!("{}: bad number", path.display()))?;
        }
    }
    Ok(p)
}

/// Runs the subcommand.
pub fn run(a: TriangulateArgs) -> Result<()> {
    if a.cameras.len() < 2 {
        bail!("triangulation needs at least two --camera files");
    }
    if a.seed_form && a.cameras.len() != 2 {
        bail!("--seed-form works with exactly two cameras");
    }
    let ps: Vec<Matrix3x4<f64>> = a.cameras.iter().map(|c| read_camera(c)).collect::<Result<_>>()?;
    ocellus_geometry::triangulate::check_rig(&ps).context("the --camera files cannot triangulate")?;
    let rows = ocellus_io::csv::read_rows(&a.matches, 2 * ps.len(), "a pixel 'u,v' per camera")?;
    let truth = match &a.truth {
        Some(path) => {
            let t = ocellus_io::csv::read_rows(path, 3, "'X,Y,Z'")?;
            if t.len() != rows.len() {
                bail!("{} has {} points for {} matches", path.display(), t.len(), rows.len());
            }
            Some(t)
        }
        None => None,
    };
    let mut points = Vec::with_capacity(rows.len());
    let mut out = crate::output_files::create_file(&a.out)?;
    writeln!(out, "x,y,z,in_front,rms_px")?;
    let (mut n, mut behind) = (0usize, 0usize);
    for (i, row) in rows.iter().enumerate() {
        let px: Vec<[f64; 2]> = row.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let t = if a.seed_form {
            two_view_seed(&ps[0], px[0], &ps[1], px[1])
        } else {
            let views: Vec<_> = ps.iter().zip(&px).map(|(p, x)| (p, *x)).collect();
            n_view(&views)
        }
        .with_context(|| format!("{} row {}", a.matches.display(), i + 1))?;
        let x = Vector4::new(t.point.x, t.point.y, t.point.z, 1.0);
        let sq: f64 = ps
            .iter()
            .zip(&px)
            .map(|(p, q)| {
                let h = p * x;
                (h.x / h.z - q[0]).powi(2) + (h.y / h.z - q[1]).powi(2)
            })
            .sum();
        let rms = (sq / ps.len() as f64).sqrt();
        writeln!(out, "{},{},{},{},{rms:.6}", t.point.x, t.point.y, t.point.z, u8::from(t.in_front))?;
        points.push(t.point);
        n += 1;
        behind += usize::from(!t.in_front);
    }
    out.flush()?;
    outln!("{n} points triangulated from {} cameras ({behind} behind a camera); wrote {}", ps.len(), a.out.display());
    if n > 0 && behind == n {
        bail!(
            "every point lies behind a camera (column in_front is 0 for all {n}): the matches or the cameras are wrong"
        );
    }
    if behind > 0 {
        errln!("warning: {behind} of {n} points lie behind a camera (in_front = 0 in {})", a.out.display());
    }
    if let Some(t) = truth {
        let t: Vec<Vector3<f64>> = t.iter().map(|r| Vector3::new(r[0], r[1], r[2])).collect();
        let e = ocellus_geometry::triangulate::rms_distance(&points, &t)?;
        outln!("RMS 3D error against the truth: {e:.4} (world units), over {n} points");
    }
    Ok(())
}
