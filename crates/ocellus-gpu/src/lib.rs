//! The GPU backend of ocellus (SPEC 9.2): compute shaders (WGSL) on any GPU that wgpu reaches
//! (Vulkan, Metal, DX12), checked in CI on Mesa's software Vulkan driver (lavapipe).
//!
//! [`GpuFrontEnd`] runs the Itti-Koch saliency pipeline on the device, in one command buffer
//! per frame:
//! - the front end, whose cost grows with the frame: 8-bit RGB to float, the colour pyramids
//!   (levels 0..8, separable low-pass and decimation with the CPU's own truncated,
//!   renormalized border taps), intensity and colour opponency at the levels the
//!   center-surround pairs read, and the Gabor energies there (direct 2D correlation with the
//!   mean-removed, unit-norm kernels);
//! - with a [`BackEndSpec`], the map-level stages on the planes where they lie: across-scale
//!   rescaling, center-surround differences with attenuated borders, N(.) (iterative
//!   difference of Gaussians, local maxima, or none) and the combination into conspicuity
//!   and saliency maps. One workgroup owns one map of the map level (40x30 for 640x480) from
//!   start to end, so N(.)'s iterations cost barriers, not dispatches.
//!
//! Only what is asked comes back: the maps (and optionally the levels) of one frame, or the
//! saliency maps of a batch of frames sent in one submission ([`GpuFrontEnd::process_batch`]).
//! The saliency engine of `ocellus-attention` selects it with `Backend::Gpu` (feature `gpu`).
//!
//! Tolerance: the GPU's planes and maps equal the CPU's within a relative error of
//! [`TOLERANCE`] of each plane's largest magnitude (sums run in another order, the Gabor bank
//! is direct here and separable on the CPU, and GPUs may fuse multiply-adds).

mod back_end;
mod context;
mod front_end;

pub use back_end::{BackEndSpec, ChannelSpec, GpuNormalization, PlaneSource};
pub use context::GpuContext;
pub use front_end::{FrontEndSpec, FrontEndTimings, GpuFrontEnd, LevelsOut, MAX_ANGLES};

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
    /// The spec asks for something the GPU front end does not do.
    #[error("not supported on the GPU backend: {0}")]
    Unsupported(String),
    /// The frame does not fit this engine or the device's limits.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// Reading results back from the device failed.
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, GpuError>;
