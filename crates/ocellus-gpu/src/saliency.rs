//! The saliency map with the GPU front end and the CPU engine's map-level stages.

use crate::{GpuContext, GpuFrontEnd, Result};
use ocellus_attention::saliency::{FrontEnd, StageTimings};
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_image::Plane;
use std::time::{Duration, Instant};

/// Computes saliency maps of 8-bit RGB frames of one size on a GPU (see the crate doc for
/// the split between GPU and CPU).
#[derive(Debug)]
pub struct GpuSaliencyEngine {
    front: GpuFrontEnd,
    cpu: SaliencyEngine,
    levels: FrontEnd,
    front_time: Duration,
}

impl GpuSaliencyEngine {
    /// Validates `cfg` (as [`SaliencyEngine::new`], plus what [`GpuFrontEnd::new`] supports)
    /// and builds everything for `width` x `height` frames on `ctx`.
    pub fn new(ctx: &GpuContext, cfg: SaliencyConfig, width: usize, height: usize) -> Result<Self> {
        let cpu = SaliencyEngine::new(cfg, width, height)?;
        let front = GpuFrontEnd::new(ctx, &cpu)?;
        Ok(Self { front, cpu, levels: FrontEnd::default(), front_time: Duration::ZERO })
    }

    /// The saliency map of `frame` at the map level (40x30 for 640x480).
    pub fn process(&mut self, frame: &Plane<[u8; 3]>) -> Result<&Plane<f32>> {
        let t = Instant::now();
        self.front.process(frame, &mut self.levels)?;
        self.front_time = t.elapsed();
        Ok(self.cpu.process_front_end(&self.levels)?)
    }

    /// The levels the GPU computed for the last frame.
    pub fn front_end(&self) -> &FrontEnd {
        &self.levels
    }

    /// The CPU engine that runs the map-level stages (its conspicuity maps, feature maps and
    /// the upsampled saliency map are those of the last frame).
    pub fn engine(&self) -> &SaliencyEngine {
        &self.cpu
    }

    /// The CPU engine, mutable (for its upsampled map, which reuses a buffer, and the spatial
    /// prior).
    pub fn engine_mut(&mut self) -> &mut SaliencyEngine {
        &mut self.cpu
    }

    /// Wall time of the last frame's GPU front end (upload, dispatches, readback), and the
    /// CPU stages' timings (whose pyramid and orientation entries read zero).
    pub fn timings(&self) -> (Duration, StageTimings) {
        (self.front_time, self.cpu.timings())
    }

    /// The device.
    pub fn context(&self) -> &GpuContext {
        self.front.context()
    }
}
