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

/// The top-level keys of a camera file.
const KEYS: [&str; 6] = ["image_size", "intrinsics", "distortion", "height_m", "mount_right_m", "mount_forward_m"];

/// The further keys of the JSON `ocellus calibrate dlt` writes, which reads as a camera file.
const DLT_KEYS: [&str; 8] = [
    "method",
    "points",
    "rotation_world_to_camera",
    "translation_world_to_camera",
    "projection_matrix",
    "reprojection_rms_px",
    "reprojection_max_px",
    "seed_error_e",
];

/// Refuses a key the file format does not have, so a misspelt `distorsion` is not silently a
/// camera without distortion. (The nested tables refuse theirs through serde.)
fn check_keys<'a>(path: &Path, keys: impl Iterator<Item = &'a String>) -> Result<()> {
    for k in keys {
        if !KEYS.contains(&k.as_str()) && !DLT_KEYS.contains(&k.as_str()) {
            bail!("{}: unknown key '{k}' (a camera file has {})", path.display(), KEYS.join(", "));
        }
    }
    Ok(())
}

/// Reads a camera file (`.toml`, otherwise JSON).
pub fn read(path: &Path) -> Result<CameraFile> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read camera file {}", path.display()))?;
    let cam: CameraFile = if is_toml(path) {
        let v: toml::Table =
            toml::from_str(&text).with_context(|| format!("{} is not a camera TOML file", path.display()))?;
        check_keys(path, v.keys())?;
        v.try_into().with_context(|| format!("{} is not a camera TOML file", path.display()))?
    } else {
        let v: serde_json::Map<String, serde_json::Value> =
            serde_json::from_str(&text).with_context(|| format!("{} is not a camera JSON file", path.display()))?;
        check_keys(path, v.keys())?;
        serde_json::from_value(serde_json::Value::Object(v))
            .with_context(|| format!("{} is not a camera JSON file", path.display()))?
    };
    let k = &cam.intrinsics;
    let d = &cam.distortion;
    let finite = [k.fx, k.fy, k.cx, k.cy, k.skew, d.k1, d.k2, d.k3, d.p1, d.p2].iter().all(|v| v.is_finite());
    if !finite || k.fx <= 0.0 || k.fy <= 0.0 {
        bail!("{}: focal lengths must be positive and every value finite", path.display());
    }
    if let Some([w, h]) = cam.image_size {
        if !(1..=65_536).contains(&w) || !(1..=65_536).contains(&h) {
            bail!("{}: image_size {w}x{h} is outside the range 1..=65536 per side", path.display());
        }
    }
    for (name, v) in
        [("height_m", cam.height_m), ("mount_right_m", cam.mount_right_m), ("mount_forward_m", cam.mount_forward_m)]
    {
        if v.is_some_and(|v| !v.is_finite()) {
            bail!("{}: {name} must be finite", path.display());
        }
    }
    Ok(cam)
}

/// Refuses frames of another size than the camera was calibrated for: its intrinsics would
/// put the principal point and the distortion in the wrong place.
pub fn check_frame_size(cam: &CameraFile, camera_path: &Path, what: &str, size: (usize, usize)) -> Result<()> {
    if let Some([w, h]) = cam.image_size {
        if (w, h) != size {
            bail!(
                "{what} is {}x{}, but the camera file {} is calibrated for {w}x{h}",
                size.0,
                size.1,
                camera_path.display()
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_keys_are_named() {
        let dir = std::env::temp_dir().join(format!("ocellus-camfile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = "[intrinsics]\nfx = 600.0\nfy = 600.0\ncx = 320.0\ncy = 240.0\nskew = 0.0\n";
        let f = dir.join("c.toml");
        std::fs::write(&f, good).unwrap();
        assert_eq!(read(&f).unwrap().intrinsics.fx, 600.0);
        for (text, key) in [
            (format!("distorsion = 1\n{good}"), "distorsion"),
            (format!("{good}foo = 2\n"), "foo"),
            (good.replace("skew", "skw"), "skw"),
            (format!("{good}[distortion]\nk4 = 0.1\n"), "k4"),
        ] {
            std::fs::write(&f, &text).unwrap();
            let e = format!("{:#}", read(&f).unwrap_err());
            assert!(e.contains(key), "{text}: {e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// Writes a camera file (`.toml`, otherwise JSON).
pub fn write(path: &Path, cam: &CameraFile) -> Result<()> {
    let text = if is_toml(path) { toml::to_string(cam)? } else { serde_json::to_string_pretty(cam)? };
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}
