//! The GPU backend of ocellus (SPEC 9.2): the saliency front end on any GPU that wgpu reaches
//! (Vulkan, Metal, DX12), checked in CI on Mesa's software Vulkan driver (lavapipe).
//!
//! The seed ran the whole Itti-Koch pipeline in CUDA. Here the GPU runs the per-pixel front
//! end, the stages whose cost grows with the frame: 8-bit RGB to float, the colour
//! pyramids (levels 0..8, separable [1 5 10 10 5 1]/32 low-pass and decimation, truncated
//! and renormalized kernels at the borders from the same tap rule as the CPU), intensity and
//! colour opponency at the levels the center-surround pairs read, and the Gabor energies
//! there (direct 19x19 correlation with the mean-removed unit-norm kernels). What remains
//! works on 40x30 maps (rescaling to the map level, center-surround, N(.), combination) and
//! runs on the CPU engine, fed through
//! [`SaliencyEngine::process_front_end`](ocellus_attention::SaliencyEngine::process_front_end).
//!
//! Tolerance: the GPU's levels and saliency map equal the CPU's within a relative error of
//! [`TOLERANCE`] of each plane's largest magnitude (the sums run in another order, the Gabor
//! bank is direct on the GPU and separable on the CPU, and GPUs may fuse multiply-adds).

mod context;
mod front_end;
mod saliency;

pub use context::GpuContext;
pub use front_end::GpuFrontEnd;
pub use saliency::GpuSaliencyEngine;

/// Largest difference between a GPU and a CPU plane, relative to the CPU plane's largest
/// magnitude, that the tests accept.
pub const TOLERANCE: f32 = 1e-4;

/// Errors of the GPU backend.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No GPU adapter (not even a software one) could be opened.
    #[error(
        "no GPU adapter: {0} (install a Vulkan driver, e.g. Debian's mesa-vulkan-drivers, or use the CPU backend)"
    )]
    NoAdapter(String),
    /// The adapter refused to open a device.
    #[error("the GPU adapter refused a device: {0}")]
    Device(String),
    /// The configuration asks for something the GPU front end does not do.
    #[error("not supported on the GPU backend: {0}")]
    Unsupported(String),
    /// The frame does not fit this engine or the device's limits.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// Reading results back from the device failed.
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    /// The CPU part of the pipeline failed.
    #[error(transparent)]
    Attention(#[from] ocellus_attention::AttentionError),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, GpuError>;
