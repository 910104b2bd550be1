//! The camera file: intrinsics, lens distortion, the image size it was calibrated at, and the
//! mounting of a ground-facing camera, as TOML or JSON (chosen by the extension; the JSON that
//! `ocellus calibrate dlt` writes reads too).
//!
//! ```toml
//! image_size = [640, 480]
//! height_m = 0.3
//! [intrinsics]
//! fx = 600.0
//! fy = 600.0
//! cx = 319.5
//! cy = 239.5
//! skew = 0.0
//! [distortion]
//! k1 = -0.2
//! ```
//!
//! Every key is checked: a misspelt one (`distorsion`) is an error naming it, never silently a
//! camera without distortion. Values must be finite, focal lengths positive.

use crate::camera::Intrinsics;
use crate::distortion::Distortion;
use crate::{GeometryError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A calibrated camera as stored on disk.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

/// The top-level keys of a camera file.
pub const KEYS: [&str; 6] = ["image_size", "intrinsics", "distortion", "height_m", "mount_right_m", "mount_forward_m"];

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

/// Image sides a camera file may record, pixels.
pub const IMAGE_SIDE_RANGE: std::ops::RangeInclusive<usize> = 1..=65_536;

fn bad(path: &Path, reason: impl Into<String>) -> GeometryError {
    GeometryError::CameraFile { path: path.into(), reason: reason.into() }
}

fn is_toml(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

fn check_keys<'a>(path: &Path, keys: impl Iterator<Item = &'a String>) -> Result<()> {
    for k in keys {
        if !KEYS.contains(&k.as_str()) && !DLT_KEYS.contains(&k.as_str()) {
            return Err(bad(path, format!("unknown key '{k}' (a camera file has {})", KEYS.join(", "))));
        }
    }
    Ok(())
}

/// Reads a camera file (`.toml`, otherwise JSON).
pub fn read(path: &Path) -> Result<CameraFile> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(path, format!("cannot read the camera file: {e}")))?;
    if is_toml(path) {
        parse_toml(&text, path)
    } else {
        parse_json(&text, path)
    }
}

/// Parses camera TOML; `path` only names the source in errors.
pub fn parse_toml(text: &str, path: &Path) -> Result<CameraFile> {
    let v: toml::Table = toml::from_str(text).map_err(|e| bad(path, format!("not a camera TOML file: {e}")))?;
    check_keys(path, v.keys())?;
    let cam: CameraFile = v.try_into().map_err(|e| bad(path, format!("not a camera TOML file: {e}")))?;
    validate(&cam, path)?;
    Ok(cam)
}

/// Parses camera JSON; `path` only names the source in errors.
pub fn parse_json(text: &str, path: &Path) -> Result<CameraFile> {
    let v: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(text).map_err(|e| bad(path, format!("not a camera JSON file: {e}")))?;
    check_keys(path, v.keys())?;
    let cam: CameraFile = serde_json::from_value(serde_json::Value::Object(v))
        .map_err(|e| bad(path, format!("not a camera JSON file: {e}")))?;
    validate(&cam, path)?;
    Ok(cam)
}

fn validate(cam: &CameraFile, path: &Path) -> Result<()> {
    let k = &cam.intrinsics;
    let d = &cam.distortion;
    let finite = [k.fx, k.fy, k.cx, k.cy, k.skew, d.k1, d.k2, d.k3, d.p1, d.p2].iter().all(|v| v.is_finite());
    if !finite || k.fx <= 0.0 || k.fy <= 0.0 {
        return Err(bad(path, "focal lengths must be positive and every value finite"));
    }
    if let Some([w, h]) = cam.image_size {
        if !IMAGE_SIDE_RANGE.contains(&w) || !IMAGE_SIDE_RANGE.contains(&h) {
            return Err(bad(path, format!("image_size {w}x{h} is outside the range 1..=65536 per side")));
        }
    }
    for (name, v) in
        [("height_m", cam.height_m), ("mount_right_m", cam.mount_right_m), ("mount_forward_m", cam.mount_forward_m)]
    {
        if v.is_some_and(|v| !v.is_finite()) {
            return Err(bad(path, format!("{name} must be finite")));
        }
    }
    Ok(())
}

/// Writes a camera file (`.toml`, otherwise JSON).
pub fn write(path: &Path, cam: &CameraFile) -> Result<()> {
    let text = if is_toml(path) {
        toml::to_string(cam).map_err(|e| bad(path, e.to_string()))?
    } else {
        serde_json::to_string_pretty(cam).map_err(|e| bad(path, e.to_string()))?
    };
    std::fs::write(path, text).map_err(|e| bad(path, format!("cannot write: {e}")))
}

/// Refuses frames of another size than the camera was calibrated for: its intrinsics would
/// put the principal point and the distortion in the wrong place. `what` names the frames.
pub fn check_frame_size(cam: &CameraFile, camera_path: &Path, what: &str, size: (usize, usize)) -> Result<()> {
    match cam.image_size {
        Some([w, h]) if (w, h) != size => {
            Err(bad(camera_path, format!("{what} is {}x{}, but the camera is calibrated for {w}x{h}", size.0, size.1)))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "[intrinsics]\nfx = 600.0\nfy = 600.0\ncx = 320.0\ncy = 240.0\nskew = 0.0\n";

    #[test]
    fn unknown_keys_are_named() {
        let p = Path::new("c.toml");
        assert_eq!(parse_toml(GOOD, p).unwrap().intrinsics.fx, 600.0);
        for (text, key) in [
            (format!("distorsion = 1\n{GOOD}"), "distorsion"),
            (format!("{GOOD}foo = 2\n"), "foo"),
            (GOOD.replace("skew", "skw"), "skw"),
            (format!("{GOOD}[distortion]\nk4 = 0.1\n"), "k4"),
        ] {
            let e = parse_toml(&text, p).unwrap_err().to_string();
            assert!(e.contains(key), "{text}: {e}");
        }
        assert!(parse_toml(&GOOD.replace("600.0\nfy", "nan\nfy"), p).is_err());
        assert!(parse_toml(&format!("image_size = [0, 480]\n{GOOD}"), p).is_err());
    }

    #[test]
    fn toml_and_json_round_trip_and_frame_size() {
        let cam = parse_toml(&format!("image_size = [640, 480]\nheight_m = 0.3\n{GOOD}"), Path::new("c.toml")).unwrap();
        let json = serde_json::to_string(&cam).unwrap();
        assert_eq!(parse_json(&json, Path::new("c.json")).unwrap(), cam);
        let toml_text = toml::to_string(&cam).unwrap();
        assert_eq!(parse_toml(&toml_text, Path::new("c.toml")).unwrap(), cam);
        assert!(check_frame_size(&cam, Path::new("c.toml"), "frame", (640, 480)).is_ok());
        let e = check_frame_size(&cam, Path::new("c.toml"), "frame", (320, 240)).unwrap_err().to_string();
        assert!(e.contains("320x240") && e.contains("640x480"), "{e}");
    }
}
