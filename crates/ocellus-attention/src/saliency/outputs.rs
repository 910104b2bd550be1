//! What the engine exposes after a frame: the saliency map, conspicuity and feature maps with
//! their sub-features and scale pairs, per-stage timings, and the map at the input size.

use super::{SaliencyEngine, Source};
use crate::center_surround::ScalePair;
use crate::Result;
use ocellus_image::resample::{ResampleMethod, Resampler};
use ocellus_image::Plane;
use std::time::Duration;

/// One sub-feature: a pyramid whose center-surround maps are normalized together.
#[derive(Clone, Debug)]
pub struct SubFeature {
    /// Index of its channel in `config.channels`.
    pub channel: usize,
    /// What it is computed from.
    pub source: Source,
    /// Readable name (e.g. "orientation 45").
    pub label: String,
}

/// A center-surround feature map (before normalization), at the map level.
#[derive(Clone, Debug, Default)]
pub struct FeatureMap {
    /// Index into [`SaliencyEngine::subfeatures`].
    pub subfeature: usize,
    /// Centre level.
    pub center: usize,
    /// Surround level.
    pub surround: usize,
    /// `|C(c) - S(s)|` (border-attenuated when configured).
    pub map: Plane<f32>,
}

/// Wall time per stage of the last frame (SPEC 1.9, the seed's Table 4.1 stages).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimings {
    /// u8 to float, colour and intensity maps, Gaussian pyramids.
    pub pyramid: Duration,
    /// Gabor filtering.
    pub orientation: Duration,
    /// Bringing levels to the map level.
    pub rescale: Duration,
    /// |c - s| and border ramp.
    pub center_surround: Duration,
    /// N(.) on feature, sub-feature and channel maps.
    pub normalization: Duration,
    /// Sums, weights, final map.
    pub combination: Duration,
}

impl StageTimings {
    /// Stage names and durations, in pipeline order.
    pub fn stages(&self) -> [(&'static str, Duration); 6] {
        [
            ("pyramid_and_colour", self.pyramid),
            ("orientation", self.orientation),
            ("rescale", self.rescale),
            ("center_surround", self.center_surround),
            ("normalization", self.normalization),
            ("combination", self.combination),
        ]
    }

    /// Sum of all stages.
    pub fn total(&self) -> Duration {
        self.stages().iter().map(|s| s.1).sum()
    }
}

impl SaliencyEngine {
    /// The saliency map of the last frame, at the map level.
    pub fn saliency(&self) -> &Plane<f32> {
        &self.saliency
    }

    /// Conspicuity map of channel `i` (order of `config.channels`), after weighting.
    pub fn conspicuity(&self, i: usize) -> Option<&Plane<f32>> {
        self.conspicuity.get(i)
    }

    /// All conspicuity maps with their channel labels.
    pub fn conspicuity_maps(&self) -> impl Iterator<Item = (String, &Plane<f32>)> {
        self.cfg.channels.iter().map(|c| c.kind.label()).zip(self.conspicuity.iter())
    }

    /// The center-surround feature maps (before normalization) of the last frame:
    /// 42 for the standard channels (6 intensity, 12 colour, 24 orientation).
    pub fn feature_maps(&self) -> &[FeatureMap] {
        &self.features
    }

    /// The sub-features, indexed by [`FeatureMap::subfeature`].
    pub fn subfeatures(&self) -> &[SubFeature] {
        &self.subs
    }

    /// The center-surround level pairs.
    pub fn scale_pairs(&self) -> &[ScalePair] {
        &self.pairs
    }

    /// Per-stage timings of the last frame.
    pub fn timings(&self) -> StageTimings {
        self.timings
    }

    /// The saliency map resampled (bilinear, pixel centres aligned) to the input size.
    pub fn saliency_full_size(&mut self, out: &mut Plane<f32>) -> Result<()> {
        if self.upsampler.is_none() {
            self.upsampler =
                Some(Resampler::new(ResampleMethod::Bilinear, self.map_size(), (self.width, self.height))?);
        }
        if let Some(up) = &self.upsampler {
            up.apply_with(self.backend, &self.saliency, out, &mut self.resample_row)?;
        }
        Ok(())
    }
}
