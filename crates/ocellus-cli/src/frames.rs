//! Streaming frames from a folder, Y4M or video file through a per-frame closure, with a
//! progress bar, and camera angles per frame from a CSV.

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_image::convert::RgbImage;
use std::path::Path;

/// Calls `f(k, frame)` for each frame (at most `limit`). If the source fails at frame k, the
/// frames before it have been processed; the error names frame k.
pub fn for_each_frame(
    input: &Path,
    limit: Option<usize>,
    mut f: impl FnMut(usize, &RgbImage) -> Result<()>,
) -> Result<usize> {
    let mut frames = crate::budget::open_frames(input)?;
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
    let rows = ocellus_io::csv::read_rows(path, 3, "'frame,pan_deg,tilt_deg'")?;
    rows.iter()
        .enumerate()
        .map(|(k, r)| {
            if r[0] != k as f64 {
                bail!("{}: row {} is frame {}, expected frame {k}", path.display(), k + 1, r[0]);
            }
            Ok((r[1] as f32, r[2] as f32))
        })
        .collect()
}
