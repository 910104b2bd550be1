//! The ordered frame pipeline (SPEC 9.1): a source stage (decoding) on its own thread, the
//! per-frame work spread over worker threads, and the results handed to one sink, on the
//! calling thread, in source order.
//!
//! It is the CPU form of the seed's scheme of one thread per GPU and two semaphores: a fixed
//! number of *tokens* bounds the items alive anywhere in the pipeline (queued for a worker,
//! being worked on, waiting to be put back in order); the source takes a token before it reads
//! an item and the sink returns it once the item is delivered. Memory is therefore bounded by
//! the depth, whatever the length of the stream, and a slow worker holds back at most `depth`
//! items behind it.
//!
//! Stateful steps (surprise, chaos, attention) belong in the sink, which sees every item in
//! order; stateless per-item work goes to the workers, each with its own state made by
//! `init` (an engine and its buffers). The first error, in source order, stops the pipeline
//! and is returned; every item before it has been delivered to the sink.
//!
//! ```
//! use ocellus_io::pipeline::{run_ordered, PipelineConfig};
//! let mut next = 0u32;
//! let mut got = Vec::new();
//! let n = run_ordered(
//!     PipelineConfig { workers: 3, depth: 8 },
//!     move || -> Result<Option<u32>, String> { next += 1; Ok((next <= 100).then_some(next)) },
//!     || Ok(0u64), // per-worker state: items it has seen
//!     |seen, _k, v| { *seen += 1; Ok(v * v) },
//!     |k, sq| { got.push((k, sq)); Ok(()) },
//! ).unwrap();
//! assert_eq!(n, 100);
//! assert!(got.iter().enumerate().all(|(i, &(k, sq))| k == i && sq == ((i + 1) * (i + 1)) as u32));
//! ```

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver};
use std::sync::{Arc, Mutex};

/// Threads and queue depth of a pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PipelineConfig {
    /// Worker threads, at least 1.
    pub workers: usize,
    /// Items alive in the pipeline at once (read, queued, worked on or waiting for their
    /// turn), at least 1; `workers + 2` or more keeps every worker busy.
    pub depth: usize,
}

impl PipelineConfig {
    /// `workers` threads (0: one per available core) with a depth of twice that plus two.
    pub fn with_workers(workers: usize) -> Self {
        let workers = if workers == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { workers };
        Self { workers, depth: 2 * workers + 2 }
    }
}

/// Why a pipeline stopped early.
#[derive(Debug, PartialEq)]
pub enum PipelineError<E> {
    /// A stage (source, worker or sink) returned this error for the item at this index.
    Stage(E),
    /// The configuration has no worker or a depth of 0.
    Config(String),
    /// A worker or the source panicked (a bug: stages return errors).
    Panicked,
}

impl<E: std::fmt::Display> std::fmt::Display for PipelineError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Stage(e) => write!(f, "{e}"),
            Self::Config(s) => write!(f, "pipeline: {s}"),
            Self::Panicked => write!(f, "pipeline: a worker thread panicked"),
        }
    }
}

impl<E: std::fmt::Debug + std::fmt::Display> std::error::Error for PipelineError<E> {}

/// Runs `source` on its own thread until it returns `Ok(None)`, `work` on
/// `cfg.workers` threads (each with the state `init` made), and `sink(index, result)` on the
/// calling thread in source order. Returns the number of items delivered.
///
/// `work` gets the item's index (from 0) so that per-item state can be keyed on it; with
/// deterministic `work`, the sink sees the same values in the same order at any number of
/// workers.
pub fn run_ordered<T, S, U, E>(
    cfg: PipelineConfig,
    mut source: impl FnMut() -> Result<Option<T>, E> + Send,
    init: impl Fn() -> Result<S, E> + Sync,
    work: impl Fn(&mut S, usize, T) -> Result<U, E> + Sync,
    mut sink: impl FnMut(usize, U) -> Result<(), E>,
) -> Result<usize, PipelineError<E>>
where
    T: Send,
    U: Send,
    E: Send,
{
    if cfg.workers == 0 || cfg.depth == 0 {
        return Err(PipelineError::Config(format!(
            "{} workers and depth {}: both must be at least 1",
            cfg.workers, cfg.depth
        )));
    }
    let stop = AtomicBool::new(false);
    // Tokens: the source takes one per item, the sink gives it back on delivery.
    let (token_tx, token_rx) = sync_channel::<()>(cfg.depth);
    for _ in 0..cfg.depth {
        // Cannot fail: the channel holds `depth` and the receiver is alive.
        let _ = token_tx.send(());
    }
    // Source to workers: items or the source's error, by index.
    let (job_tx, job_rx) = sync_channel::<(usize, Result<T, E>)>(cfg.depth);
    let job_rx = Arc::new(Mutex::new(job_rx));
    // Workers to sink.
    let (done_tx, done_rx) = sync_channel::<(usize, Result<U, E>)>(cfg.depth);
    std::thread::scope(|scope| {
        let stop = &stop;
        let source_thread = scope.spawn(move || {
            let mut k = 0;
            while token_rx.recv().is_ok() && !stop.load(Ordering::Relaxed) {
                let item = match source() {
                    Ok(Some(t)) => Ok(t),
                    Ok(None) => break,
                    Err(e) => Err(e),
                };
                let failed = item.is_err();
                if job_tx.send((k, item)).is_err() || failed {
                    break;
                }
                k += 1;
            }
        });
        let mut workers = Vec::with_capacity(cfg.workers);
        for _ in 0..cfg.workers {
            let (job_rx, done_tx, init, work) = (Arc::clone(&job_rx), done_tx.clone(), &init, &work);
            workers.push(scope.spawn(move || {
                let mut state = None;
                loop {
                    let next = match job_rx.lock() {
                        Ok(rx) => rx.recv(),
                        Err(_) => return,
                    };
                    let Ok((k, item)) = next else { return };
                    let out = match item {
                        Err(e) => Err(e),
                        // Nobody will look at it; skip the work.
                        Ok(_) if stop.load(Ordering::Relaxed) => return,
                        Ok(t) => {
                            let s = match state.take() {
                                Some(s) => Ok(s),
                                None => init(),
                            };
                            s.and_then(|mut s| {
                                let r = work(&mut s, k, t);
                                state = Some(s);
                                r
                            })
                        }
                    };
                    if done_tx.send((k, out)).is_err() {
                        return;
                    }
                }
            }));
        }
        // Only the workers hold the job queue and the result senders now: when they are gone,
        // a source blocked on a full queue and the sink's loop both see it.
        drop(job_rx);
        drop(done_tx);
        let delivered = deliver(done_rx, &token_tx, &mut sink);
        if delivered.is_err() {
            stop.store(true, Ordering::Relaxed);
        }
        // Let the source and the workers see the end: no more tokens, no more results read.
        drop(token_tx);
        let panicked = source_thread.join().is_err() | workers.into_iter().fold(false, |p, w| w.join().is_err() | p);
        match delivered {
            Err(e) => Err(PipelineError::Stage(e)),
            Ok(_) if panicked => Err(PipelineError::Panicked),
            Ok(n) => Ok(n),
        }
    })
}

/// The sink side: puts results back in order and hands them on; returns a token per item.
fn deliver<U, E>(
    done_rx: Receiver<(usize, Result<U, E>)>,
    token_tx: &std::sync::mpsc::SyncSender<()>,
    sink: &mut impl FnMut(usize, U) -> Result<(), E>,
) -> Result<usize, E> {
    let mut waiting: BTreeMap<usize, Result<U, E>> = BTreeMap::new();
    let mut next = 0;
    // Ends when every worker has finished and dropped its sender.
    for (k, r) in done_rx.iter() {
        waiting.insert(k, r);
        while let Some(r) = waiting.remove(&next) {
            sink(next, r?)?;
            next += 1;
            // The source may be gone (it hit the end); tokens are then not needed.
            let _ = token_tx.send(());
        }
    }
    Ok(next)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;
    use std::time::Duration;

    /// A stream of `n` items whose work takes a pseudo-random time (so that workers finish
    /// out of order) and whose result depends on the index only.
    fn run(n: usize, workers: usize, depth: usize) -> (Vec<(usize, u64)>, usize) {
        let alive = AtomicUsize::new(0);
        let most = AtomicUsize::new(0);
        let mut k = 0u64;
        let mut got = Vec::new();
        let delivered = run_ordered(
            PipelineConfig { workers, depth },
            || -> Result<Option<u64>, String> {
                k += 1;
                let a = alive.fetch_add(1, Ordering::SeqCst) + 1;
                most.fetch_max(a, Ordering::SeqCst);
                Ok((k <= n as u64).then_some(k))
            },
            || Ok(()),
            |_, i, v| {
                std::thread::sleep(Duration::from_micros((v * 7919 % 13) * 50));
                Ok(v.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ i as u64)
            },
            |i, v| {
                alive.fetch_sub(1, Ordering::SeqCst);
                got.push((i, v));
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(delivered, n);
        (got, most.load(Ordering::SeqCst))
    }

    #[test]
    fn results_come_in_order_and_equal_at_any_worker_count() {
        let (one, _) = run(200, 1, 3);
        assert!(one.iter().enumerate().all(|(i, &(k, _))| i == k));
        for workers in [2, 3, 8] {
            let (many, most) = run(200, workers, workers + 2);
            assert_eq!(many, one, "{workers} workers");
            // The source read ahead at most `depth` items (+1: the end-of-stream call).
            assert!(most <= workers + 2 + 1, "{most} alive with depth {}", workers + 2);
        }
    }

    #[test]
    fn the_first_error_in_order_stops_it_after_the_items_before() {
        for workers in [1, 4] {
            let mut k = 0;
            let mut got = Vec::new();
            let r = run_ordered(
                PipelineConfig { workers, depth: 6 },
                || -> Result<Option<usize>, String> {
                    k += 1;
                    Ok(Some(k - 1))
                },
                || Ok(()),
                |_, i, v| if i == 37 || i == 50 { Err(format!("bad item {v}")) } else { Ok(v) },
                |i, v| {
                    got.push((i, v));
                    Ok(())
                },
            );
            assert_eq!(r, Err(PipelineError::Stage("bad item 37".to_string())));
            assert_eq!(got, (0..37).map(|i| (i, i)).collect::<Vec<_>>());
        }
        // A source error and a sink error end it the same way.
        let mut k = 0;
        let r = run_ordered(
            PipelineConfig::with_workers(2),
            || -> Result<Option<usize>, String> {
                k += 1;
                if k > 5 {
                    Err("decode failed".into())
                } else {
                    Ok(Some(k))
                }
            },
            || Ok(()),
            |_, _, v| Ok(v),
            |_, _| Ok(()),
        );
        assert_eq!(r, Err(PipelineError::Stage("decode failed".to_string())));
        let r = run_ordered(
            PipelineConfig::with_workers(2),
            || -> Result<Option<usize>, String> { Ok(Some(1)) },
            || Ok(()),
            |_, _, v| Ok(v),
            |i, _| if i == 3 { Err("disk full".to_string()) } else { Ok(()) },
        );
        assert_eq!(r, Err(PipelineError::Stage("disk full".to_string())));
        let bad = run_ordered(
            PipelineConfig { workers: 0, depth: 1 },
            || -> Result<Option<usize>, String> { Ok(None) },
            || Ok(()),
            |_, _, v| Ok(v),
            |_, _| Ok(()),
        );
        assert!(matches!(bad, Err(PipelineError::Config(_))));
    }

    #[test]
    fn an_empty_stream_and_a_failing_worker_state() {
        let r = run_ordered(
            PipelineConfig::with_workers(3),
            || -> Result<Option<u8>, String> { Ok(None) },
            || Ok(()),
            |_, _, v| Ok(v),
            |_, _| Ok(()),
        );
        assert_eq!(r, Ok(0));
        let mut k = 0;
        let r = run_ordered(
            PipelineConfig::with_workers(2),
            || -> Result<Option<u8>, String> {
                k += 1;
                Ok((k < 10).then_some(k))
            },
            || -> Result<(), String> { Err("no engine for this size".into()) },
            |_, _, v| Ok(v),
            |_, _| Ok(()),
        );
        assert_eq!(r, Err(PipelineError::Stage("no engine for this size".to_string())));
    }
}
