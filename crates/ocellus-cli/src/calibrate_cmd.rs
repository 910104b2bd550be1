//! `ocellus calibrate`: camera calibration from 3D-2D correspondences (DLT); the planar forms
//! are in `calibrate_planar`.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use ocellus_geometry::dlt::{decompose, dlt, dlt_linear, reprojection};
use serde_json::json;
use std::path::{Path, PathBuf};

/// Arguments of `ocellus calibrate`.
#[derive(Args, Debug)]
pub struct CalibrateArgs {
    #[command(subcommand)]
    what: What,
}

#[derive(Subcommand, Debug)]
enum What {
    /// The 3x4 projection matrix from 3D-2D correspondences (DLT), decomposed into K, R, t.
    Dlt(DltArgs),
    /// Zhang calibration with lens distortion from images of a chessboard: detects the inner
    /// corners (sub-pixel), calibrates, and writes camera.toml, calibration.json (standard
    /// deviations, per-view errors and poses), per_view_error.png and corner overlays.
    Chessboard(crate::calibrate_planar::ChessboardArgs),
    /// Zhang calibration from given correspondences on a planar target (CSV `view,X,Y,u,v`).
    Planar(crate::calibrate_planar::PlanarArgs),
}

#[derive(Args, Debug)]
struct DltArgs {
    /// CSV of correspondences `X,Y,Z,u,v` (world units of your choice; pixels, x right, y down,
    /// pixel centres at integers); a header line and `#` comments are allowed. At least 6 rows,
    /// not all on one plane.
    points: PathBuf,
    /// Use the seed's linear form (p34 = 1) instead of the normalized SVD form.
    #[arg(long)]
    linear: bool,
    /// Write the camera (K, R, t, P, errors) as JSON here.
    #[arg(long, default_value = "camera.json")]
    out: PathBuf,
}

/// 3D points and their pixels.
type Correspondences = (Vec<[f64; 3]>, Vec<[f64; 2]>);

fn read_correspondences(path: &Path) -> Result<Correspondences> {
    let rows = ocellus_io::csv::read_rows(path, 5, "'X,Y,Z,u,v'")?;
    Ok(rows.iter().map(|r| ([r[0], r[1], r[2]], [r[3], r[4]])).unzip())
}

/// Runs the subcommand.
pub fn run(a: CalibrateArgs) -> Result<()> {
    match a.what {
        What::Dlt(a) => run_dlt(a),
        What::Chessboard(a) => crate::calibrate_planar::run_chessboard(a),
        What::Planar(a) => crate::calibrate_planar::run_planar(a),
    }
}

fn run_dlt(a: DltArgs) -> Result<()> {
    let (p3, p2) = read_correspondences(&a.points)?;
    let p = if a.linear { dlt_linear(&p3, &p2)? } else { dlt(&p3, &p2)? };
    let err = reprojection(&p, &p3, &p2);
    let cam = decompose(&p)?;
    let rows = |m: &dyn Fn(usize, usize) -> f64, r: usize, c: usize| -> Vec<Vec<f64>> {
        (0..r).map(|i| (0..c).map(|j| m(i, j)).collect()).collect()
    };
    let doc = json!({
        "method": if a.linear { "dlt_linear_p34_1" } else { "dlt_normalized_svd" },
        "points": p3.len(),
        "intrinsics": cam.k,
        "rotation_world_to_camera": rows(&|i, j| cam.r[(i, j)], 3, 3),
        "translation_world_to_camera": [cam.t.x, cam.t.y, cam.t.z],
        "projection_matrix": rows(&|i, j| p[(i, j)], 3, 4),
        "reprojection_rms_px": err.rms_px,
        "reprojection_max_px": err.per_point.iter().cloned().fold(0.0f64, f64::max),
        "seed_error_e": err.seed_e,
    });
    std::fs::write(&a.out, serde_json::to_string_pretty(&doc)?)
        .with_context(|| format!("cannot write {}", a.out.display()))?;
    outln!(
        "{} points: fx {:.3} fy {:.3} cx {:.3} cy {:.3} skew {:.4} px; reprojection RMS {:.4} px; camera centre ({:.4}, {:.4}, {:.4})",
        p3.len(),
        cam.k.fx,
        cam.k.fy,
        cam.k.cx,
        cam.k.cy,
        cam.k.skew,
        err.rms_px,
        cam.centre().x,
        cam.centre().y,
        cam.centre().z
    );
    outln!("wrote {}", a.out.display());
    Ok(())
}
