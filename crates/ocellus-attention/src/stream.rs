//! Attention over a video stream: saliency (with flicker) → surprise → context chaos →
//! attention dynamics, frame by frame, with every buffer owned and reused.
//!
//! The work splits in two: the per-frame maps ([`StreamWorker`]: saliency with flicker and the
//! chaos level's intensity), which workers may compute for different frames at once, and the
//! sequential part ([`StreamEngine::process_maps`]: surprise, chaos and attention, in frame
//! order). [`StreamEngine::process`] runs both for one frame; `ocellus attend` runs the first
//! on the threads of an `ocellus_io::pipeline` with the same results.
//!
//! ```
//! use ocellus_attention::stream::{StreamConfig, StreamEngine};
//! use ocellus_image::{convert::RgbImage, Plane};
//! let mut engine = StreamEngine::new(StreamConfig::default(), 320, 256).unwrap();
//! for k in 0..4u8 {
//!     let frame = RgbImage::U8(Plane::from_fn(320, 256, |x, y| [(x / 8) as u8 * k, (y / 8) as u8, 60]));
//!     let out = engine.process(&frame, 0.0, 0.0).unwrap();
//!     assert_eq!(out.frame, k as usize);
//!     assert_eq!(out.chaos.is_some(), k >= 2, "the chaos degree needs three frames");
//! }
//! ```

use crate::attention::{Attention, AttentionConfig, Fixation};
use crate::chaos::{ChaosConfig, ChaosDegree};
use crate::config::{ChannelConfig, ChannelKind};
use crate::egosphere::ViewGeometry;
use crate::saliency::Source;
use crate::surprise::{Surprise, SurpriseConfig};
use crate::{AttentionError, Result, SaliencyConfig, SaliencyEngine};
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Everything a stream needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamConfig {
    /// The saliency pipeline; a flicker channel is added if it has none.
    pub saliency: SaliencyConfig,
    /// Weight of the added flicker channel (0: no flicker channel).
    pub flicker_weight: f32,
    /// Surprise on the saliency map.
    pub surprise: SurpriseConfig,
    /// Context chaos degree.
    pub chaos: ChaosConfig,
    /// Intensity pyramid level the chaos degree is computed on (2: 160x120 for 640x480).
    pub chaos_level: usize,
    /// Attention dynamics.
    pub attention: AttentionConfig,
    /// Camera angle per pixel, degrees (for the ego-sphere).
    pub deg_per_px: f32,
}

impl Default for StreamConfig {
    fn default() -> Self {
        Self {
            saliency: SaliencyConfig::ace2009(),
            flicker_weight: 1.0,
            surprise: SurpriseConfig::default(),
            chaos: ChaosConfig::default(),
            chaos_level: 2,
            attention: AttentionConfig::default(),
            deg_per_px: 0.1,
        }
    }
}

/// Results of one frame (borrowed from the engine until the next frame).
#[derive(Debug)]
pub struct StreamFrame<'a> {
    /// Frame index (0-based).
    pub frame: usize,
    /// Saliency map (map level).
    pub saliency: &'a Plane<f32>,
    /// Surprise map in bits (map level).
    pub surprise: &'a Plane<f32>,
    /// Chaos degree in bits (from the third frame on).
    pub chaos: Option<f64>,
    /// `true` when the context is familiar (chaos below S, or not yet known).
    pub familiar: bool,
    /// Where attention is.
    pub fixation: Option<Fixation>,
    /// Inhibition (0..1) per map cell.
    pub inhibition: &'a Plane<f32>,
    /// Time in the saliency engine.
    pub saliency_time: Duration,
    /// Time in surprise, chaos and attention together.
    pub temporal_time: Duration,
}

/// The per-frame maps of one frame, as a [`StreamWorker`] computes them.
#[derive(Clone, Debug, Default)]
pub struct FrameMaps {
    /// Frame index (0-based).
    pub frame: usize,
    /// Saliency map (map level), flicker included.
    pub saliency: Plane<f32>,
    /// The intensity pyramid level the chaos degree reads (`chaos_level`).
    pub chaos_grey: Plane<f32>,
    /// Time in the saliency engine.
    pub saliency_time: Duration,
}

/// The per-frame half of the stream: saliency with flicker, and the chaos level's intensity.
/// A worker may be given any frame; it primes its flicker memory from the previous frame
/// when that is not the one it saw last, so its maps equal a sequential run's.
#[derive(Debug)]
pub struct StreamWorker {
    saliency: SaliencyEngine,
    chaos_level: usize,
    last: Option<usize>,
}

impl StreamWorker {
    /// The worker of `cfg` for `width` x `height` frames (a flicker channel added as
    /// [`StreamEngine::new`] does).
    pub fn new(cfg: &StreamConfig, width: usize, height: usize) -> Result<Self> {
        let mut sal = cfg.saliency.clone();
        let has_flicker = sal.channels.iter().any(|c| c.kind == ChannelKind::Flicker);
        if !has_flicker && cfg.flicker_weight > 0.0 {
            sal.channels.push(ChannelConfig { kind: ChannelKind::Flicker, weight: cfg.flicker_weight });
        }
        let saliency = SaliencyEngine::new(sal, width, height)?;
        if cfg.chaos_level >= saliency.level_sizes().len() {
            return Err(AttentionError::InvalidConfig(format!(
                "chaos_level {} but the pyramid has levels 0..{}",
                cfg.chaos_level,
                saliency.level_sizes().len() - 1
            )));
        }
        Ok(Self { saliency, chaos_level: cfg.chaos_level, last: None })
    }

    /// The saliency engine (its maps of the last frame, timings, configuration).
    pub fn saliency_engine(&self) -> &SaliencyEngine {
        &self.saliency
    }

    /// The maps of frame `k` of a stream into `out`. `prev` is frame `k - 1`: needed (an
    /// error without it) when this worker's last frame was not `k - 1`; frame 0 has no
    /// flicker.
    pub fn process_into(
        &mut self,
        k: usize,
        frame: &RgbImage,
        prev: Option<&RgbImage>,
        out: &mut FrameMaps,
    ) -> Result<()> {
        let follows = k > 0 && self.last == Some(k - 1);
        if !follows {
            self.saliency.reset_temporal();
            if k > 0 {
                let p = prev.ok_or_else(|| {
                    AttentionError::InvalidInput(format!("frame {k}: the previous frame is needed for flicker"))
                })?;
                self.saliency.prime_temporal(p)?;
            }
        }
        // Whatever happens next, the flicker memory is no longer that of frame k - 1.
        self.last = None;
        let t0 = Instant::now();
        self.saliency.process(frame)?;
        let saliency_time = t0.elapsed();
        let level = self.chaos_level;
        let grey = self.saliency.level(Source::Intensity, level).ok_or_else(|| {
            AttentionError::InvalidConfig(format!("intensity level {level} is not computed (chaos_level)"))
        })?;
        out.frame = k;
        out.saliency.clone_from(self.saliency.saliency());
        out.chaos_grey.clone_from(grey);
        out.saliency_time = saliency_time;
        self.last = Some(k);
        Ok(())
    }

    /// [`process_into`](Self::process_into) into new maps.
    pub fn process(&mut self, k: usize, frame: &RgbImage, prev: Option<&RgbImage>) -> Result<FrameMaps> {
        let mut out = FrameMaps::default();
        self.process_into(k, frame, prev, &mut out)?;
        Ok(out)
    }
}

/// The stream engine.
#[derive(Debug)]
pub struct StreamEngine {
    worker: StreamWorker,
    maps: FrameMaps,
    surprise: Surprise,
    chaos: ChaosDegree,
    attention: Attention,
    frame: usize,
}

impl StreamEngine {
    /// Validates everything and allocates for `width` x `height` frames.
    pub fn new(cfg: StreamConfig, width: usize, height: usize) -> Result<Self> {
        let worker = StreamWorker::new(&cfg, width, height)?;
        let (mw, mh) = worker.saliency.map_size();
        let view = ViewGeometry { width, height, deg_per_px: cfg.deg_per_px };
        Ok(Self {
            surprise: Surprise::new(cfg.surprise, mw, mh)?,
            chaos: ChaosDegree::new(cfg.chaos)?,
            attention: Attention::new(cfg.attention, view)?,
            worker,
            maps: FrameMaps::default(),
            frame: 0,
        })
    }

    /// The saliency engine of [`process`](Self::process) (its maps of the last frame it
    /// processed, timings, configuration).
    pub fn saliency_engine(&self) -> &SaliencyEngine {
        &self.worker.saliency
    }

    /// The attention state (inhibition, habituation, ego-sphere).
    pub fn attention(&self) -> &Attention {
        &self.attention
    }

    /// The chaos tracker (for its threshold).
    pub fn chaos(&self) -> &ChaosDegree {
        &self.chaos
    }

    /// The surprise map of the last frame, bits (map level).
    pub fn surprise_map(&self) -> &Plane<f32> {
        self.surprise.map()
    }

    /// Frames processed so far (the index the next frame gets).
    pub fn frames(&self) -> usize {
        self.frame
    }

    /// Forgets the previous frames of flicker, surprise and chaos, as after a jump of the
    /// camera (a new burst); attention's memory (habituation, inhibition, ego-sphere) and the
    /// frame count stay.
    pub fn reset_temporal(&mut self) {
        self.worker.saliency.reset_temporal();
        self.surprise.reset();
        self.chaos.reset();
    }

    /// Processes one frame seen by a camera at (`pan_deg`, `tilt_deg`).
    pub fn process(&mut self, frame: &RgbImage, pan_deg: f32, tilt_deg: f32) -> Result<StreamFrame<'_>> {
        let k = self.frame;
        // Every frame of this engine goes through its own worker in order, so the worker's
        // flicker memory is that of the frame before (or empty after reset_temporal).
        self.worker.last = k.checked_sub(1);
        let mut maps = std::mem::take(&mut self.maps);
        let r = self.worker.process_into(k, frame, None, &mut maps);
        self.maps = maps;
        r?;
        self.sequential(pan_deg, tilt_deg)
    }

    /// The sequential half for the next frame, from maps a [`StreamWorker`] computed for it
    /// (`maps.frame` must be [`frames`](Self::frames)): surprise, chaos and attention.
    pub fn process_maps(&mut self, maps: FrameMaps, pan_deg: f32, tilt_deg: f32) -> Result<StreamFrame<'_>> {
        if maps.frame != self.frame {
            return Err(AttentionError::InvalidInput(format!(
                "maps of frame {} given where frame {} is next",
                maps.frame, self.frame
            )));
        }
        self.maps = maps;
        self.sequential(pan_deg, tilt_deg)
    }

    fn sequential(&mut self, pan_deg: f32, tilt_deg: f32) -> Result<StreamFrame<'_>> {
        let t1 = Instant::now();
        let chaos = self.chaos.update(&self.maps.chaos_grey)?;
        let surprise = self.surprise.update(&self.maps.saliency)?;
        let fixation = self.attention.step(&self.maps.saliency, Some(surprise), pan_deg, tilt_deg)?;
        let t2 = Instant::now();
        let k = self.frame;
        self.frame += 1;
        Ok(StreamFrame {
            frame: k,
            saliency: &self.maps.saliency,
            surprise: self.surprise.map(),
            // Not yet known counts as familiar.
            familiar: chaos.is_none_or(|s| self.chaos.is_familiar(s)),
            chaos,
            fixation,
            inhibition: self.attention.inhibition_map(),
            saliency_time: self.maps.saliency_time,
            temporal_time: t2 - t1,
        })
    }
}
