//! Streaming frames from a folder, Y4M or video file through a per-frame closure, with a
//! progress bar, and camera angles per frame from a CSV.

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_image::convert::RgbImage;
use ocellus_io::video::Frames;
use std::path::Path;

/// Calls `f(k, frame)` for each frame (at most `limit`). If the source fails at frame k, the
/// frames before it have been processed; the error names frame k.
pub fn for_each_frame(
    input: &Path,
    limit: Option<usize>,
    mut f: impl FnMut(usize, &RgbImage) -> Result<()>,
) -> Result<usize> {
    let mut frames = Frames::open(input)?;
    let total = match (frames.len_hint(), limit) {
        (Some(n), Some(l)) => Some(n.min(l)),
        (n, l) => n.or(l),
    };
    let bar = match total {
        Some(n) => ProgressBar::new(n as u64).with_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} frames {per_sec} eta {eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        ),
        None => ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} {pos} frames {per_sec}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        ),
    };
    let mut k = 0;
    while limit.map_or(true, |l| k < l) {
        let frame = match frames.next_frame() {
            Ok(Some(fr)) => fr,
            Ok(None) => break,
            Err(e) => {
                bar.finish_and_clear();
                return Err(anyhow::Error::new(e)
                    .context(format!("stopped at frame {k}; the {k} frames before it were processed and written")));
            }
        };
        f(k, &frame).with_context(|| format!("frame {k}"))?;
        k += 1;
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(k)
}

/// Camera (pan, tilt) in degrees per frame, from a CSV `frame,pan_deg,tilt_deg` (a header
/// line allowed). Frames must be listed in order from 0, one row each.
pub fn read_pan_tilt(path: &Path) -> Result<Vec<(f32, f32)>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed = (f.first().and_then(|v| v.parse::<usize>().ok()), f.get(1).and_then(|v| v.parse::<f32>().ok()));
        let (Some(frame), Some(pan)) = parsed else {
            if out.is_empty() && n == 0 {
                continue; // header
            }
            bail!("{} line {}: expected 'frame,pan_deg,tilt_deg', got '{line}'", path.display(), n + 1);
        };
        let tilt = match f.get(2) {
            Some(v) => {
                v.parse::<f32>().with_context(|| format!("{} line {}: bad tilt '{v}'", path.display(), n + 1))?
            }
            None => 0.0,
        };
        if frame != out.len() {
            bail!("{} line {}: frame {frame}, expected {}", path.display(), n + 1, out.len());
        }
        if !pan.is_finite() || !tilt.is_finite() {
            bail!("{} line {}: non-finite angle", path.display(), n + 1);
        }
        out.push((pan, tilt));
    }
    Ok(out)
}
