//! `ocellus undistort`: removes lens distortion from images with a calibrated camera.

use crate::inputs::{check_out_dir, collect_images, output_stems};
use anyhow::{Context, Result};
use clap::Args;
use ocellus_geometry::camera_file;
use ocellus_geometry::distortion::{remap_bilinear, undistort_maps};
use ocellus_image::convert::{merge_rgb8, split_rgb8};
use ocellus_image::Plane;
use std::path::PathBuf;

/// Arguments of `ocellus undistort`.
#[derive(Args, Debug)]
pub struct UndistortArgs {
    /// Images or folders of images, all of the camera's size.
    #[arg(required = true)]
    images: Vec<PathBuf>,
    /// Camera file (TOML or JSON with `intrinsics` and `distortion`, e.g. from
    /// `ocellus calibrate chessboard`).
    #[arg(long)]
    camera: PathBuf,
    /// Output folder: NAME.png per input, undistorted with the same intrinsics (pixels
    /// without a source are black).
    #[arg(long, default_value = "ocellus-undistorted")]
    out: PathBuf,
}

/// Image size and the x, y remap tables built for it.
type RemapTables = ((usize, usize), Plane<f32>, Plane<f32>);

/// Runs the subcommand.
pub fn run(a: UndistortArgs) -> Result<()> {
    let cam = camera_file::read(&a.camera)?;
    let files = collect_images(&a.images)?;
    let stems = output_stems(&files)?;
    check_out_dir(&a.out, &files)?;
    crate::output_files::create_dir(&a.out)?;
    // Remap tables for the current image size.
    let mut maps: Option<RemapTables> = None;
    for (f, name) in files.iter().zip(&stems) {
        let img = crate::budget::read_image(f).with_context(|| format!("cannot read {}", f.display()))?.to_u8();
        let size = img.size();
        camera_file::check_frame_size(&cam, &a.camera, &f.display().to_string(), size)?;
        if maps.as_ref().map(|m| m.0) != Some(size) {
            maps = None;
        }
        let (_, mx, my) = maps.get_or_insert_with(|| {
            let (mx, my) = undistort_maps(&cam.intrinsics, &cam.distortion, size.0, size.1);
            (size, mx, my)
        });
        let [r, g, b] = split_rgb8(&img).map(|c| remap_bilinear(&c, &*mx, &*my, 0.0));
        let out = merge_rgb8([&r?, &g?, &b?]);
        let path = a.out.join(format!("{name}.png"));
        ocellus_io::write_png(&path, &out)?;
    }
    outln!("{} images undistorted into {}", files.len(), a.out.display());
    Ok(())
}
