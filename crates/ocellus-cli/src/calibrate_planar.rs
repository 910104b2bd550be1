//! `ocellus calibrate chessboard` and `ocellus calibrate planar`: Zhang calibration from
//! images of a chessboard or from given planar correspondences.

use crate::inputs::{check_out_dir, collect_images, output_stems, stem};
use crate::plot::{self, Plot, Series};
use anyhow::{bail, Context, Result};
use clap::Args;
use ocellus_geometry::camera_file::{self, CameraFile};
use ocellus_geometry::chessboard::{find_chessboard, ChessboardOptions};
use ocellus_geometry::zhang::{calibrate, project_view, PlanarCalibration, PlanarView, ZhangOptions};
use ocellus_image::draw::ring as draw_ring;
use ocellus_image::Plane;
use rayon::prelude::*;
use serde_json::json;
use std::path::{Path, PathBuf};

/// What the refinement estimates (shared by both forms).
#[derive(Args, Debug, Clone, Copy)]
pub struct ModelArgs {
    /// Hold k3 at 0 (estimate k1, k2, p1, p2 only): better when the views do not reach the
    /// image corners.
    #[arg(long)]
    fix_k3: bool,
    /// Hold the tangential p1, p2 at 0.
    #[arg(long)]
    no_tangential: bool,
    /// No distortion at all (pinhole only).
    #[arg(long)]
    no_distortion: bool,
}

impl ModelArgs {
    fn options(&self) -> ZhangOptions {
        ZhangOptions {
            radial: !self.no_distortion,
            k3: !self.fix_k3,
            tangential: !(self.no_tangential || self.no_distortion),
            ..Default::default()
        }
    }
}

/// Arguments of `ocellus calibrate chessboard`.
#[derive(Args, Debug)]
pub struct ChessboardArgs {
    /// Images of the board (files or folders), at least 3 where the board is found, all of one size.
    #[arg(required = true)]
    images: Vec<PathBuf>,
    /// Inner corners per row x per column (a board of 10x7 squares has 9x6). Range: 2..=64 each.
    #[arg(long, default_value = "9x6")]
    board: String,
    /// Side of a square, with its unit: `25mm`, `2.5cm`, `0.025m` (a bare number is mm). Range:
    /// above 0, at most 1000 m.
    /// Poses in the report are in millimetres.
    #[arg(long, default_value = "25mm")]
    square: String,
    #[command(flatten)]
    model: ModelArgs,
    /// Output folder: camera.toml, calibration.json, per_view_error.png, corners/NAME.png;
    /// for `ocellus triangulate`, board.csv (the inner corners on the board, mm, z = 0) and
    /// per view views/NAME.json (the projection matrix from the board's millimetres to
    /// undistorted pixels) and views/NAME.csv (the corners found, undistorted, in board.csv's
    /// order).
    #[arg(long, default_value = "ocellus-calibration")]
    out: PathBuf,
}

/// Arguments of `ocellus calibrate planar`.
#[derive(Args, Debug)]
pub struct PlanarArgs {
    /// CSV of `view,X,Y,u,v`: view index, point on the target plane (target units), its pixel.
    points: PathBuf,
    /// Image size `WxH` to record in the camera file. Range: 1..=65536 each.
    #[arg(long)]
    image_size: Option<String>,
    #[command(flatten)]
    model: ModelArgs,
    /// Output folder: camera.toml, calibration.json, per_view_error.png.
    #[arg(long, default_value = "ocellus-calibration")]
    out: PathBuf,
}

/// `9x6` -> (9, 6).
pub fn parse_pair(s: &str, what: &str, range: std::ops::RangeInclusive<usize>) -> Result<(usize, usize)> {
    let parts: Vec<&str> = s.split(['x', 'X']).collect();
    let (Some(a), Some(b), 2) = (parts.first(), parts.get(1), parts.len()) else {
        bail!("{what} '{s}': expected two counts like 9x6");
    };
    let a: usize = a.trim().parse().with_context(|| format!("{what} '{s}'"))?;
    let b: usize = b.trim().parse().with_context(|| format!("{what} '{s}'"))?;
    if !range.contains(&a) || !range.contains(&b) {
        bail!("{what} '{s}': each count must be in the range {}..={}", range.start(), range.end());
    }
    Ok((a, b))
}

/// Inner-corner counts of a chessboard a detector can find (per row and per column).
pub const BOARD_RANGE: std::ops::RangeInclusive<usize> = 2..=64;

/// A length with unit (`mm`, `cm`, `m`; bare numbers are mm) in millimetres.
pub fn parse_length_mm(s: &str) -> Result<f64> {
    let t = s.trim();
    let (num, scale) = if let Some(n) = t.strip_suffix("mm") {
        (n, 1.0)
    } else if let Some(n) = t.strip_suffix("cm") {
        (n, 10.0)
    } else if let Some(n) = t.strip_suffix('m') {
        (n, 1000.0)
    } else {
        (t, 1.0)
    };
    let v: f64 = num.trim().parse().with_context(|| format!("length '{s}': expected e.g. 25mm"))?;
    if !(v.is_finite() && v > 0.0 && v * scale <= 1e6) {
        bail!("length '{s}' is outside the range: above 0, at most 1000 m");
    }
    Ok(v * scale)
}

/// An image and its corners (or why none were found).
type Detection = (Plane<[u8; 3]>, std::result::Result<Vec<[f64; 2]>, String>);

fn grey(img: &ocellus_image::convert::RgbImage) -> Plane<f32> {
    img.to_grey()
}

/// Runs `calibrate chessboard`.
pub fn run_chessboard(a: ChessboardArgs) -> Result<()> {
    let (cols, rows) = parse_pair(&a.board, "--board", BOARD_RANGE)?;
    let square = parse_length_mm(&a.square)?;
    let files = collect_images(&a.images)?;
    output_stems(&files)?;
    check_out_dir(&a.out, &files)?;
    check_out_dir(&a.out.join("corners"), &files)?;
    crate::output_files::create_dir(&a.out.join("corners"))?;
    let object: Vec<[f64; 2]> =
        (0..rows).flat_map(|r| (0..cols).map(move |c| [c as f64 * square, r as f64 * square])).collect();
    let detections: Vec<Result<Detection>> = files
        .par_iter()
        .map(|f| {
            let img = crate::budget::read_image(f)?;
            let found =
                find_chessboard(&grey(&img), cols, rows, &ChessboardOptions::default()).map_err(|e| e.to_string());
            Ok((img.to_u8(), found))
        })
        .collect();
    let mut size = None;
    let (mut views, mut used, mut pictures) = (Vec::new(), Vec::new(), Vec::new());
    for (f, d) in files.iter().zip(detections) {
        let (img, found) = d.with_context(|| format!("cannot read {}", f.display()))?;
        match size {
            None => size = Some(img.size()),
            Some(s) if s != img.size() => {
                bail!(
                    "{} is {}x{}, the first image {}x{}: calibrate one camera mode at a time",
                    f.display(),
                    img.width(),
                    img.height(),
                    s.0,
                    s.1
                )
            }
            _ => {}
        }
        match found {
            Ok(corners) => {
                outln!("{}: {} corners", f.display(), corners.len());
                views.push(PlanarView { object: object.clone(), image: corners });
                used.push(f.clone());
                pictures.push(img);
            }
            Err(e) => outln!("{}: skipped ({e})", f.display()),
        }
    }
    if views.len() < 3 {
        bail!("the board was found in {} of {} images; calibration needs at least 3", views.len(), files.len());
    }
    let cal = calibrate(&views, &a.model.options())?;
    for ((f, img), (view, pose)) in used.iter().zip(pictures).zip(views.iter().zip(&cal.poses)) {
        let mut img = img;
        let reproj = project_view(&cal.intrinsics, &cal.distortion, pose, &view.object).unwrap_or_default();
        for (p, q) in view.image.iter().zip(&reproj) {
            draw_ring(&mut img, p[0] as f32, p[1] as f32, 5.0, [0, 220, 0]);
            draw_ring(&mut img, q[0] as f32, q[1] as f32, 1.5, [255, 0, 0]);
        }
        ocellus_io::write_png(a.out.join("corners").join(format!("{}.png", stem(f))), &img)?;
    }
    write_views(&a.out, &used, &views, &cal)?;
    let names: Vec<String> = used.iter().map(|f| f.display().to_string()).collect();
    report(&a.out, &cal, size, &names, "chessboard", square)
}

/// board.csv and, per view, its projection matrix (board mm to undistorted pixels) and its
/// corners undistorted: what `ocellus triangulate` reads to rebuild the board from two views.
fn write_views(out: &Path, files: &[PathBuf], views: &[PlanarView], cal: &PlanarCalibration) -> Result<()> {
    use std::io::Write;
    let dir = out.join("views");
    crate::output_files::create_dir(&dir)?;
    if let Some(v) = views.first() {
        let mut f = crate::output_files::create_file(&out.join("board.csv"))?;
        writeln!(f, "x_mm,y_mm,z_mm")?;
        for p in &v.object {
            writeln!(f, "{},{},0", p[0], p[1])?;
        }
        f.flush()?;
    }
    for ((file, view), pose) in files.iter().zip(views).zip(&cal.poses) {
        let camera = ocellus_geometry::camera::PinholeCamera { k: cal.intrinsics, r: pose.r, t: pose.t };
        let p = camera.projection_matrix();
        let doc = json!({
            "view": file.display().to_string(),
            "projection_matrix": (0..3).map(|i| (0..4).map(|j| p[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        });
        let name = dir.join(format!("{}.json", stem(file)));
        std::fs::write(&name, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("cannot write {}", name.display()))?;
        let mut f = crate::output_files::create_file(&dir.join(format!("{}.csv", stem(file))))?;
        writeln!(f, "u,v")?;
        for q in &view.image {
            let (u, v) = cal
                .distortion
                .undistort_pixel(&cal.intrinsics, q[0], q[1])
                .with_context(|| format!("{}: a corner cannot be undistorted", file.display()))?;
            writeln!(f, "{u:.4},{v:.4}")?;
        }
        f.flush()?;
    }
    Ok(())
}

/// Runs `calibrate planar`.
pub fn run_planar(a: PlanarArgs) -> Result<()> {
    let rows = ocellus_io::csv::read_rows(&a.points, 5, "'view,X,Y,u,v'")?;
    let size =
        a.image_size.as_deref().map(|s| parse_pair(s, "--image-size", camera_file::IMAGE_SIDE_RANGE)).transpose()?;
    let mut ids: Vec<i64> = Vec::new();
    let mut views: Vec<PlanarView> = Vec::new();
    for r in &rows {
        if r[0].fract() != 0.0 {
            bail!("{}: view index {} is not an integer", a.points.display(), r[0]);
        }
        let id = r[0] as i64;
        let i = match ids.iter().position(|&v| v == id) {
            Some(i) => i,
            None => {
                ids.push(id);
                views.push(PlanarView { object: Vec::new(), image: Vec::new() });
                ids.len() - 1
            }
        };
        views[i].object.push([r[1], r[2]]);
        views[i].image.push([r[3], r[4]]);
    }
    crate::output_files::create_dir(&a.out)?;
    let cal = calibrate(&views, &a.model.options())?;
    let names: Vec<String> = ids.iter().map(|i| format!("view {i}")).collect();
    report(&a.out, &cal, size, &names, "planar_points", f64::NAN)
}

fn report(
    out: &Path,
    cal: &PlanarCalibration,
    size: Option<(usize, usize)>,
    names: &[String],
    source: &str,
    square_mm: f64,
) -> Result<()> {
    let cam = CameraFile {
        image_size: size.map(|s| [s.0, s.1]),
        intrinsics: cal.intrinsics,
        distortion: cal.distortion,
        height_m: None,
        mount_right_m: None,
        mount_forward_m: None,
    };
    camera_file::write(&out.join("camera.toml"), &cam)?;
    let sd = &cal.std_dev;
    let views: Vec<_> = names
        .iter()
        .zip(&cal.per_view_rms_px)
        .zip(&cal.poses)
        .map(|((n, e), p)| {
            json!({
                "view": n,
                "rms_px": e,
                "rotation_target_to_camera": (0..3).map(|i| (0..3).map(|j| p.r[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
                "translation_target_to_camera": [p.t.x, p.t.y, p.t.z],
            })
        })
        .collect();
    let doc = json!({
        "source": source,
        "square_mm": if square_mm.is_finite() { json!(square_mm) } else { json!(null) },
        "image_size": cam.image_size,
        "intrinsics": cal.intrinsics,
        "distortion": cal.distortion,
        "std_dev": {"fx": sd[0], "fy": sd[1], "cx": sd[2], "cy": sd[3], "k1": sd[4], "k2": sd[5], "p1": sd[6], "p2": sd[7], "k3": sd[8]},
        "closed_form_intrinsics": cal.closed_form,
        "rms_px": cal.rms_px,
        "iterations": cal.iterations,
        "views": views,
    });
    std::fs::write(out.join("calibration.json"), serde_json::to_string_pretty(&doc)?)
        .with_context(|| format!("cannot write {}", out.join("calibration.json").display()))?;
    let points: Vec<(f64, f64)> = cal.per_view_rms_px.iter().enumerate().map(|(i, e)| (i as f64, *e)).collect();
    plot::draw(
        &out.join("per_view_error.png"),
        &Plot {
            title: "Reprojection error per view",
            x_label: "view (order of calibration.json)",
            y_label: "RMS error, px",
            series: &[Series { label: "per view", points, color: plotters::style::RGBColor(200, 40, 40) }],
            threshold: Some((cal.rms_px, "overall")),
            y_range: None,
        },
    )?;
    let k = &cal.intrinsics;
    let d = &cal.distortion;
    outln!("views {}, RMS reprojection error {:.4} px, {} iterations", names.len(), cal.rms_px, cal.iterations);
    outln!(
        "fx {:.3} ± {:.3}  fy {:.3} ± {:.3}  cx {:.3} ± {:.3}  cy {:.3} ± {:.3} px",
        k.fx,
        sd[0],
        k.fy,
        sd[1],
        k.cx,
        sd[2],
        k.cy,
        sd[3]
    );
    outln!(
        "k1 {:.5} ± {:.5}  k2 {:.5} ± {:.5}  p1 {:.6} ± {:.6}  p2 {:.6} ± {:.6}  k3 {:.5} ± {:.5}",
        d.k1,
        sd[4],
        d.k2,
        sd[5],
        d.p1,
        sd[6],
        d.p2,
        sd[7],
        d.k3,
        sd[8]
    );
    outln!("wrote {}/camera.toml, calibration.json, per_view_error.png", out.display());
    if source == "chessboard" {
        outln!("wrote {}/board.csv and views/NAME.json, views/NAME.csv for triangulate", out.display());
    }
    Ok(())
}
