//! Closed-loop experiments: simulations in which what the robot sees depends on where it
//! chose to look. Each runs the library's engines (saliency, surprise, chaos, planning,
//! estimation) on frames rendered from real imagery by `ocellus-synth`, so that the CLI, the
//! tests and the examples all run the same loop.
//!
//! - [`ball_tracking`]: generated ball worlds tracked by the plain and the boosted particle
//!   filter, scored against the truth (SPEC 7).
//! - [`stereo_head`]: an active stereo head keeping a tracked ball in both foveas (saccades on
//!   the main sequence, smooth pursuit, vergence from the log-polar fovea).
//! - [`corridor_experiment`]: the seed's corridor (SPEC 2.6): information-based view
//!   planning switching from landmarks to a suddenly appearing person.
//!
//! ```
//! use ocellus_sim::corridor_experiment::{corridor, run, CorridorImages, RunConfig};
//! use ocellus_sim::SimError;
//! let images = CorridorImages::load(|n| ocellus_io::read_image(ocellus_testdata::asset(n))).unwrap();
//! let world = corridor(&images)?;
//! let cfg = RunConfig { steps: 2, ..Default::default() };
//! let records = run(&cfg, &world, |_, _| Ok::<(), SimError>(()))?;
//! // Without an event the planner looks where landmarks are.
//! assert!(records.iter().all(|r| r.decision.v == 1.0));
//! # Ok::<(), SimError>(())
//! ```

pub mod ball_tracking;
pub mod corridor_experiment;
pub mod stereo_head;

/// Errors of the simulations.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// An engine of the attention crate failed (saliency, surprise, chaos, planning).
    #[error(transparent)]
    Attention(#[from] ocellus_attention::AttentionError),
    /// The position belief's update failed.
    #[error(transparent)]
    Estimation(#[from] ocellus_estimation::EstimationError),
    /// The scene generator failed.
    #[error(transparent)]
    Synth(#[from] ocellus_synth::SynthError),
    /// The vergence measurement failed.
    #[error(transparent)]
    Fovea(#[from] ocellus_fovea::FoveaError),
    /// The tracker failed.
    #[error(transparent)]
    Tracking(#[from] ocellus_tracking::TrackingError),
    /// The evaluation failed.
    #[error(transparent)]
    Eval(#[from] ocellus_eval::EvalError),
    /// A parameter is out of range.
    #[error("invalid simulation parameter: {0}")]
    InvalidConfig(String),
    /// The callback given to a run reported an error; the run stopped there.
    #[error("stopped by the step callback: {0}")]
    Stopped(String),
}

/// Result of the simulations.
pub type Result<T> = std::result::Result<T, SimError>;
