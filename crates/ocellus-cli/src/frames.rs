//! Streaming frames from a folder, Y4M or video file through a per-frame closure, with a
//! progress bar, and camera angles per frame from a CSV.

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use ocellus_image::convert::RgbImage;
use ocellus_io::pipeline::{run_ordered, PipelineConfig, PipelineError};
use std::path::Path;
use std::sync::Arc;

/// A pipeline's outcome as an `anyhow` result: a stage's error as it was.
pub fn pipeline_result<T>(r: std::result::Result<T, PipelineError<anyhow::Error>>) -> Result<T> {
    match r {
        Ok(t) => Ok(t),
        Err(PipelineError::Stage(e)) => Err(e),
        Err(e) => Err(anyhow::anyhow!("{e}")),
    }
}

/// A frame for a pipeline worker, with the frame before it (for flicker and frame
/// differences); frames are shared, not copied.
pub struct FramePair {
    /// Frame k - 1 (`None` for frame 0).
    pub prev: Option<Arc<RgbImage>>,
    /// Frame k.
    pub cur: Arc<RgbImage>,
}

/// The frames of `input` and a progress bar for at most `limit` of them.
fn open_with_progress(input: &Path, limit: Option<usize>) -> Result<(ocellus_io::video::Frames, ProgressBar)> {
    let frames = crate::budget::open_frames(input)?;
    let total = match (frames.len_hint(), limit) {
        (Some(n), Some(l)) => Some(n.min(l)),
        (n, l) => n.or(l),
    };
    Ok((frames, progress(total)))
}

/// The progress bar of a stream of `total` frames (a spinner when unknown).
fn progress(total: Option<usize>) -> ProgressBar {
    match total {
        Some(n) => ProgressBar::new(n as u64).with_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} frames {per_sec} eta {eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        ),
        None => ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} {pos} frames {per_sec}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        ),
    }
}

/// Frames per pipeline item: a worker takes this many consecutive frames, so that a
/// stateful per-frame step (flicker needs the previous frame) restarts once per chunk.
const CHUNK: usize = 4;

/// The frames of `input` (at most `limit`) through the ordered pipeline
/// (`ocellus_io::pipeline`): decoding on its own thread, `work(state, k, frames)` on
/// `workers` threads (0: one per core), each with the state `init(width, height)` made, and
/// `sink(k, result)` here in frame order. Workers take [`CHUNK`] consecutive frames at a
/// time. As [`for_each_frame`], an error names its frame and the frames before it have been
/// through the sink.
pub fn for_each_frame_parallel<S, U: Send>(
    input: &Path,
    limit: Option<usize>,
    workers: usize,
    init: impl Fn(usize, usize) -> Result<S> + Sync,
    work: impl Fn(&mut S, usize, FramePair) -> Result<U> + Sync,
    mut sink: impl FnMut(usize, U) -> Result<()>,
) -> Result<usize> {
    let (mut frames, bar) = open_with_progress(input, limit)?;
    let mut delivered = 0;
    let mut prev: Option<Arc<RgbImage>> = None;
    let mut k = 0;
    // A read error met inside a chunk: the frames before it go first, the error next.
    let mut pending: Option<anyhow::Error> = None;
    let source = move || -> Result<Option<(usize, Vec<FramePair>)>> {
        if let Some(e) = pending.take() {
            return Err(e);
        }
        let first = k;
        let mut chunk = Vec::with_capacity(CHUNK);
        while chunk.len() < CHUNK && limit.is_none_or(|l| k < l) {
            match frames.next_frame() {
                Ok(Some(f)) => {
                    k += 1;
                    let cur = Arc::new(f);
                    chunk.push(FramePair { prev: prev.replace(cur.clone()), cur });
                }
                Ok(None) => break,
                Err(e) => {
                    let e = anyhow::Error::new(e)
                        .context(format!("stopped at frame {k}; the {k} frames before it were processed and written"));
                    if chunk.is_empty() {
                        return Err(e);
                    }
                    pending = Some(e);
                    break;
                }
            }
        }
        Ok((!chunk.is_empty()).then_some((first, chunk)))
    };
    let r = run_ordered(
        PipelineConfig::with_workers(workers),
        source,
        // Each worker makes its state from the size of the first frame it gets.
        || Ok(None::<S>),
        |state: &mut Option<S>, _, (first, chunk): (usize, Vec<FramePair>)| {
            let mut out = Vec::with_capacity(chunk.len());
            for (i, pair) in chunk.into_iter().enumerate() {
                let s = match state {
                    Some(s) => s,
                    None => {
                        let (w, h) = pair.cur.size();
                        state.insert(init(w, h)?)
                    }
                };
                match work(s, first + i, pair) {
                    Ok(u) => out.push(u),
                    // The chunk's frames before the failing one still reach the sink.
                    Err(e) => return Ok((first, out, Some(e.context(format!("frame {}", first + i))))),
                }
            }
            Ok((first, out, None))
        },
        |_, (first, out, failed): (usize, Vec<U>, Option<anyhow::Error>)| {
            for (i, u) in out.into_iter().enumerate() {
                sink(first + i, u).with_context(|| format!("frame {}", first + i))?;
                delivered += 1;
                bar.inc(1);
            }
            failed.map_or(Ok(()), Err)
        },
    );
    bar.finish_and_clear();
    pipeline_result(r).map(|_| delivered)
}

/// Runs `body` with a sender of jobs while `work(k, job)` runs on `workers` threads (0: one
/// per core) on the jobs in the order sent and `sink(k, result)`, on a thread of its own,
/// receives the results in that order (to feed a video, say). Returns what `body` returned
/// and the writers' outcome (the first error, in order). The queue is bounded: `body` waits
/// when the writers fall behind.
pub fn with_ordered_writer<J: Send, U: Send, R>(
    workers: usize,
    work: impl Fn(usize, J) -> Result<U> + Sync,
    sink: impl FnMut(usize, U) -> Result<()> + Send,
    body: impl FnOnce(&std::sync::mpsc::SyncSender<J>) -> R,
) -> (R, Result<()>) {
    std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::sync_channel::<J>(2);
        let writer = scope.spawn(|| {
            let r = run_ordered(
                PipelineConfig::with_workers(workers),
                move || Ok(rx.recv().ok()),
                || Ok(()),
                |_, k, job| work(k, job),
                sink,
            );
            pipeline_result(r).map(|_| ())
        });
        let out = body(&tx);
        // The writer ends when the queue is closed and empty.
        drop(tx);
        (out, writer.join().unwrap_or_else(|_| Err(anyhow::anyhow!("the writer thread panicked"))))
    })
}

/// Calls `f(k, frame)` for each frame (at most `limit`). If the source fails at frame k, the
/// frames before it have been processed; the error names frame k.
pub fn for_each_frame(
    input: &Path,
    limit: Option<usize>,
    mut f: impl FnMut(usize, &RgbImage) -> Result<()>,
) -> Result<usize> {
    let (mut frames, bar) = open_with_progress(input, limit)?;
    let mut k = 0;
    while limit.is_none_or(|l| k < l) {
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
