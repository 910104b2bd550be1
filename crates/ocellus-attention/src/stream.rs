//! Attention over a video stream: saliency (with flicker) → surprise → context chaos →
//! attention dynamics, frame by frame, with every buffer owned and reused.
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

/// The stream engine.
#[derive(Debug)]
pub struct StreamEngine {
    saliency: SaliencyEngine,
    surprise: Surprise,
    chaos: ChaosDegree,
    chaos_level: usize,
    attention: Attention,
    frame: usize,
}

impl StreamEngine {
    /// Validates everything and allocates for `width` x `height` frames.
    pub fn new(cfg: StreamConfig, width: usize, height: usize) -> Result<Self> {
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
        let (mw, mh) = saliency.map_size();
        let view = ViewGeometry { width, height, deg_per_px: cfg.deg_per_px };
        Ok(Self {
            surprise: Surprise::new(cfg.surprise, mw, mh)?,
            chaos: ChaosDegree::new(cfg.chaos)?,
            chaos_level: cfg.chaos_level,
            attention: Attention::new(cfg.attention, view)?,
            saliency,
            frame: 0,
        })
    }

    /// The saliency engine (its maps of the last frame, timings, configuration).
    pub fn saliency_engine(&self) -> &SaliencyEngine {
        &self.saliency
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

    /// Forgets the previous frames of flicker, surprise and chaos, as after a jump of the
    /// camera (a new burst); attention's memory (habituation, inhibition, ego-sphere) and the
    /// frame count stay.
    pub fn reset_temporal(&mut self) {
        self.saliency.reset_temporal();
        self.surprise.reset();
        self.chaos.reset();
    }

    /// Processes one frame seen by a camera at (`pan_deg`, `tilt_deg`).
    pub fn process(&mut self, frame: &RgbImage, pan_deg: f32, tilt_deg: f32) -> Result<StreamFrame<'_>> {
        let t0 = Instant::now();
        self.saliency.process(frame)?;
        let t1 = Instant::now();
        let level = self.chaos_level;
        let grey = self.saliency.level(Source::Intensity, level).ok_or_else(|| {
            AttentionError::InvalidConfig(format!("intensity level {level} is not computed (chaos_level)"))
        })?;
        let chaos = self.chaos.update(grey)?;
        let surprise = self.surprise.update(self.saliency.saliency())?;
        let fixation = self.attention.step(self.saliency.saliency(), Some(surprise), pan_deg, tilt_deg)?;
        let t2 = Instant::now();
        let k = self.frame;
        self.frame += 1;
        Ok(StreamFrame {
            frame: k,
            saliency: self.saliency.saliency(),
            surprise: self.surprise.map(),
            // Not yet known counts as familiar.
            familiar: chaos.map_or(true, |s| self.chaos.is_familiar(s)),
            chaos,
            fixation,
            inhibition: self.attention.inhibition_map(),
            saliency_time: t1 - t0,
            temporal_time: t2 - t1,
        })
    }
}
