//! `ocellus calibrate`: camera calibration from correspondences.

use anyhow::{bail, Context, Result};
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

type Correspondences = (Vec<[f64; 3]>, Vec<[f64; 2]>);

fn read_correspondences(path: &Path) -> Result<Correspondences> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let (mut p3, mut p2) = (Vec::new(), Vec::new());
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let v: Vec<Option<f64>> =
            line.split([',', ';', '\t', ' ']).filter(|s| !s.is_empty()).map(|s| s.parse().ok()).collect();
        if v.len() < 5 || v[..5].iter().any(Option::is_none) {
            if p3.is_empty() && n == 0 {
                continue; // header
            }
            bail!("{} line {}: expected 'X,Y,Z,u,v', got '{line}'", path.display(), n + 1);
        }
        let f: Vec<f64> = v[..5].iter().map(|x| x.unwrap_or(f64::NAN)).collect();
        p3.push([f[0], f[1], f[2]]);
        p2.push([f[3], f[4]]);
    }
    Ok((p3, p2))
}

/// Runs the subcommand.
pub fn run(a: CalibrateArgs) -> Result<()> {
    let What::Dlt(a) = a.what;
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
    println!(
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
    println!("wrote {}", a.out.display());
    Ok(())
}
