//! The camera file shared by the geometry subcommands: intrinsics, distortion and the image
//! size, as TOML or JSON (chosen by the extension; `calibrate dlt`'s JSON reads too).

use anyhow::{bail, Context, Result};
use ocellus_geometry::camera::Intrinsics;
use ocellus_geometry::distortion::Distortion;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A calibrated camera as stored on disk.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CameraFile {
    /// Image size (width, height) the calibration is for, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_size: Option<[usize; 2]>,
    /// Intrinsics, pixels.
    pub intrinsics: Intrinsics,
    /// Lens distortion (zero when absent).
    #[serde(default)]
    pub distortion: Distortion,
    /// Height of the camera above the floor, metres (ground-facing cameras, odometry).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_m: Option<f64>,
    /// Camera position to the right of the robot's rotation centre, metres (odometry).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount_right_m: Option<f64>,
    /// Camera position ahead of the robot's rotation centre, metres (odometry).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount_forward_m: Option<f64>,
}

fn is_toml(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

/// Reads a camera file (`.toml`, otherwise JSON).
pub fn read(path: &Path) -> Result<CameraFile> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read camera file {}", path.display()))?;
    let cam: CameraFile = if is_toml(path) {
        toml::from_str(&text).with_context(|| format!("{} is not a camera TOML file", path.display()))?
    } else {
        serde_json::from_str(&text).with_context(|| format!("{} is not a camera JSON file", path.display()))?
    };
    let k = &cam.intrinsics;
    let d = &cam.distortion;
    let finite = [k.fx, k.fy, k.cx, k.cy, k.skew, d.k1, d.k2, d.k3, d.p1, d.p2].iter().all(|v| v.is_finite());
    if !finite || k.fx <= 0.0 || k.fy <= 0.0 {
        bail!("{}: focal lengths must be positive and every value finite", path.display());
    }
    Ok(cam)
}

/// Writes a camera file (`.toml`, otherwise JSON).
pub fn write(path: &Path, cam: &CameraFile) -> Result<()> {
    let text = if is_toml(path) { toml::to_string(cam)? } else { serde_json::to_string_pretty(cam)? };
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}
