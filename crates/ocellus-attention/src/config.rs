//! Parameters of the saliency pipeline and its named presets.
//!
//! Every field can be overridden from the API, from a TOML file (serde) and from the CLI.
//! Units: pixels of the pyramid level a quantity applies to; angles in degrees; sigmas of
//! the normalization as fractions of the map's larger side.

use crate::{AttentionError, Result};
use ocellus_image::{pyramid::PyramidKernel, resample::ResampleMethod, Backend};
use serde::{Deserialize, Serialize};

/// Where the intensity and colour-opponency maps are computed (SPEC 1.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpponencyStage {
    /// At the input resolution; I, RG and BY are then pyramided (SaliencyToolbox).
    Input,
    /// R, G and B are pyramided; I, RG, BY are computed at each level (the seed's GPU code).
    EachLevel,
}

/// Weights (r, g, b) of the intensity channel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IntensityWeights {
    /// (r + g + b) / 3 (Itti et al. 1998, the seed).
    Mean,
    /// Luminance 0.2989 r + 0.5870 g + 0.1140 b (GNU Octave's `rgb2gray`, SaliencyToolbox).
    Luminance,
}

impl IntensityWeights {
    /// The three weights.
    pub fn weights(self) -> [f32; 3] {
        match self {
            IntensityWeights::Mean => [1.0 / 3.0; 3],
            IntensityWeights::Luminance => [0.298_936, 0.587_043, 0.114_021],
        }
    }
}

/// How the Gabor filtering treats the map border.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GaborBorder {
    /// Edge pixels repeat outward (the seed's clamp-to-border texture).
    Clamp,
    /// Zeros outside.
    Zero,
    /// What SaliencyToolbox's `conv2PreserveEnergy` produces: zeros outside, and the top and
    /// bottom `size/2` rows of the interior columns multiplied by `sum(kernel) / partial sum`,
    /// which is 0 for a zero-mean Gabor (the left/right branch of that function never runs).
    StbCompat,
}

/// Gabor filters of the orientation channel (SPEC 1.4).
///
/// `G(x, y) = exp(-(x'^2 + gamma^2 y'^2) / (2 sigma^2)) cos(2 pi x' / lambda + psi)`,
/// `x' = x cos(theta) + y sin(theta)`, `y' = -x sin(theta) + y cos(theta)`, x right, y down,
/// on a `size` x `size` grid centred on the pixel. Each kernel has its mean removed and is
/// scaled to unit L2 norm. Response `M_theta = |I * G_0| + |I * G_{pi/2}|`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaborConfig {
    /// Side of the square kernel in pixels (odd).
    pub size: usize,
    /// Wavelength lambda in pixels.
    pub wavelength_px: f32,
    /// Envelope standard deviation in pixels.
    pub sigma_px: f32,
    /// Aspect ratio gamma. Only 1 (isotropic envelope) is supported: it makes the filter separable.
    pub gamma: f32,
    /// Orientations theta in degrees.
    pub angles_deg: Vec<f32>,
    /// Border rule.
    pub border: GaborBorder,
}

/// Constant term subtracted at each iteration of the iterative normalization.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GlobalInhibition {
    /// A constant `C_inh` (Itti & Koch 2001; the seed: 0.02).
    Constant(f32),
    /// `factor * max(map)` at each iteration (SaliencyToolbox: 0.02).
    RelativeToMax(f32),
}

/// The competition operator N(.) (SPEC 1.6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum Normalization {
    /// Iterative difference of Gaussians (Itti & Koch 2001):
    /// `M <- max(0, M + M * G_ex - M * G_inh - C_inh)`, with the Gaussians
    /// `c^2 / (2 pi s^2) exp(-(x^2 + y^2) / (2 s^2))` cut where they fall below 1 % of the
    /// peak (half-width capped at `floor(min(w, h) / 2) - 1`), truncated and renormalized at
    /// the map border.
    Iterative {
        /// Number of iterations.
        iterations: usize,
        /// Excitatory sigma as a fraction of the map's larger side.
        excitation_sigma_frac: f32,
        /// Inhibitory sigma as a fraction of the map's larger side.
        inhibition_sigma_frac: f32,
        /// Excitatory coefficient c_ex.
        c_excitation: f32,
        /// Inhibitory coefficient c_inh.
        c_inhibition: f32,
        /// The constant inhibition term.
        global_inhibition: GlobalInhibition,
    },
    /// Itti et al. 1998: multiply by `(global max - mean of the other local maxima)^2`.
    LocalMax,
    /// Only the initial rescaling.
    None,
}

/// Feature channels (SPEC 1.3, 1.4, 1.8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChannelKind {
    /// Intensity: one sub-feature.
    Intensity,
    /// Red-green and blue-yellow opponency: two sub-features.
    Color,
    /// Gabor orientations: one sub-feature per angle.
    Orientation,
    /// Skin chromaticity likelihood (see [`crate::channels::skin_likelihood`]): one sub-feature.
    Skin,
    /// Flicker (SPEC 1.8): `|I_t - I_(t-1)|` on each intensity pyramid level, against the
    /// previous frame given to the same engine; flat (no contribution) on the first frame.
    Flicker,
    /// A map supplied with each frame by the caller (e.g. a detector's output), by name.
    External(String),
}

impl ChannelKind {
    /// Short label.
    pub fn label(&self) -> String {
        match self {
            ChannelKind::Intensity => "intensity".into(),
            ChannelKind::Color => "color".into(),
            ChannelKind::Orientation => "orientation".into(),
            ChannelKind::Skin => "skin".into(),
            ChannelKind::Flicker => "flicker".into(),
            ChannelKind::External(n) => format!("external:{n}"),
        }
    }
}

/// One channel and its gain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelConfig {
    /// Which feature.
    pub kind: ChannelKind,
    /// Gain of its conspicuity map in the combination (top-down feature prior).
    pub weight: f32,
}

/// How conspicuity maps are weighted into the saliency map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Combination {
    /// `S = sum_c w_c C_c / sum_c w_c` (weighted mean).
    WeightedMean,
    /// SaliencyToolbox: `S = sum_c C_c * w_c / (number of sub-features of c) / (number of channels)`.
    StbPerSubfeature,
}

/// All parameters of the saliency pipeline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SaliencyConfig {
    /// Name of the preset this started from (informational).
    pub preset: String,
    /// Low-pass kernel of the dyadic pyramid.
    pub pyramid: PyramidKernel,
    /// Where intensity and opponency are computed.
    pub opponency_at: OpponencyStage,
    /// Intensity weights.
    pub intensity: IntensityWeights,
    /// Below this max(r, g, b) (in [0, 1]) the opponency values are 0.
    pub color_threshold: f32,
    /// Orientation filters.
    pub gabor: GaborConfig,
    /// Centre levels c (level 0 = input).
    pub center_levels: Vec<usize>,
    /// Surround offsets: s = c + delta.
    pub deltas: Vec<usize>,
    /// Level at which feature, conspicuity and saliency maps live.
    pub map_level: usize,
    /// How centre and surround levels are brought to the map level.
    pub across_scale: ResampleMethod,
    /// Width of a linear ramp that attenuates feature-map borders, as a fraction of the
    /// map's larger side (rounded to pixels); 0 disables it.
    pub border_ramp_frac: f32,
    /// The competition operator N(.).
    pub normalization: Normalization,
    /// Range feature maps are scaled to before N(.) (`[0, r]`).
    pub feature_range: f32,
    /// A map whose max - min is at most this (in its own units; intensities are in [0, 1])
    /// is flat: it has no contrast, and scaling it would stretch float rounding noise of the
    /// pyramid (about 1e-7) to the full range. Real contrast is far above the default 1e-5.
    #[serde(default = "default_flat_tolerance")]
    pub flat_tolerance: f32,
    /// Flicker below this absolute intensity change (intensities in [0, 1]) counts as sensor
    /// noise: the flicker channel uses `max(|I_t - I_(t-1)| - t, 0)` on each level. Without it,
    /// N(.) would stretch the noise of a still scene to full range. Default 0.02 (5 grey
    /// levels; sensor noise of 2 grey levels is far below it on levels >= 2).
    #[serde(default = "default_flicker_threshold")]
    pub flicker_threshold: f32,
    /// Channels and gains.
    pub channels: Vec<ChannelConfig>,
    /// Conspicuity combination rule.
    pub combination: Combination,
    /// If set, the combined map goes through N(.) once more after scaling to `[0, r]`.
    pub final_range: Option<f32>,
    /// Kernel build to run.
    pub backend: Backend,
}

impl Default for SaliencyConfig {
    fn default() -> Self {
        Self::ace2009()
    }
}

fn default_flat_tolerance() -> f32 {
    1e-5
}

fn default_flicker_threshold() -> f32 {
    0.02
}

fn standard_channels() -> Vec<ChannelConfig> {
    [ChannelKind::Intensity, ChannelKind::Color, ChannelKind::Orientation]
        .into_iter()
        .map(|kind| ChannelConfig { kind, weight: 1.0 })
        .collect()
}

impl SaliencyConfig {
    /// The seed's parameters (seed 001 section 4; SPEC 1): 6-tap [1 5 10 10 5 1]/32 pyramid,
    /// 19x19 Gabor (lambda 7, sigma 7/3, clamped border), centres 2-4, deltas 3-4, map level 4,
    /// bilinear across-scale, iterative DoG normalization (3 iterations, C_inh = 0.02),
    /// equal weights. The seed does not say how feature-map borders are treated; like iLab's
    /// toolkit and the SaliencyToolbox we attenuate them with a linear ramp of max(w, h) / 20
    /// map pixels, because otherwise the frame edge produces false maxima (SPEC 1.6).
    pub fn ace2009() -> Self {
        Self {
            preset: "ace2009".into(),
            pyramid: PyramidKernel::itti(),
            opponency_at: OpponencyStage::EachLevel,
            intensity: IntensityWeights::Mean,
            color_threshold: 0.1,
            gabor: GaborConfig {
                size: 19,
                wavelength_px: 7.0,
                sigma_px: 7.0 / 3.0,
                gamma: 1.0,
                angles_deg: vec![0.0, 45.0, 90.0, 135.0],
                border: GaborBorder::Clamp,
            },
            center_levels: vec![2, 3, 4],
            deltas: vec![3, 4],
            map_level: 4,
            across_scale: ResampleMethod::Bilinear,
            border_ramp_frac: 1.0 / 20.0,
            normalization: Normalization::Iterative {
                iterations: 3,
                excitation_sigma_frac: 0.02,
                inhibition_sigma_frac: 0.25,
                c_excitation: 0.5,
                c_inhibition: 1.5,
                global_inhibition: GlobalInhibition::Constant(0.02),
            },
            feature_range: 10.0,
            flat_tolerance: default_flat_tolerance(),
            flicker_threshold: default_flicker_threshold(),
            channels: standard_channels(),
            combination: Combination::WeightedMean,
            final_range: None,
            backend: Backend::Auto,
        }
    }

    /// SaliencyToolbox 2.x `defaultSaliencyParams` (Walther & Koch 2006), as listed in
    /// `testdata/reference/README.md`: 7-tap pyramid, luminance intensity at the input,
    /// 9x9 Gabor (sigma 2.3333), nearest-neighbour across scale, border ramp of max/20,
    /// global inhibition 0.02 max, per-sub-feature weighting, final N to [0, 2].
    ///
    /// It reproduces the toolbox's output (correlation 1.0000 with maps it computed), quirks
    /// included: its zero-padded Gabor filters see the frame edge as an oriented edge, so a
    /// flat image gets a non-flat orientation map near the border, as in the toolbox.
    pub fn stb() -> Self {
        let mut c = Self::ace2009();
        c.preset = "stb".into();
        c.pyramid = PyramidKernel::stb();
        c.opponency_at = OpponencyStage::Input;
        c.intensity = IntensityWeights::Luminance;
        c.gabor.size = 9;
        c.gabor.sigma_px = 2.3333;
        c.gabor.border = GaborBorder::StbCompat;
        c.across_scale = ResampleMethod::Nearest;
        if let Normalization::Iterative { global_inhibition, .. } = &mut c.normalization {
            *global_inhibition = GlobalInhibition::RelativeToMax(0.02);
        }
        c.combination = Combination::StbPerSubfeature;
        c.final_range = Some(2.0);
        c
    }

    /// A preset by name: `ace2009` or `stb`.
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "ace2009" => Ok(Self::ace2009()),
            "stb" => Ok(Self::stb()),
            other => Err(AttentionError::InvalidConfig(format!("unknown preset '{other}' (known: ace2009, stb)"))),
        }
    }

    /// Names of the presets.
    pub const PRESETS: &'static [&'static str] = &["ace2009", "stb"];

    /// Highest pyramid level the configuration needs.
    pub fn max_level(&self) -> usize {
        let c = self.center_levels.iter().copied().max().unwrap_or(0);
        let d = self.deltas.iter().copied().max().unwrap_or(0);
        (c + d).max(self.map_level)
    }

    /// Lowest pyramid level the configuration needs.
    pub fn min_level(&self) -> usize {
        self.center_levels.iter().copied().min().unwrap_or(0).min(self.map_level)
    }

    /// This configuration with every `kind` channel replaced by one of `weight` (none for a
    /// weight of 0), checked: e.g. the skin channel of the evaluation mode.
    pub fn with_channel_weight(&self, kind: ChannelKind, weight: f32) -> Result<SaliencyConfig> {
        if !weight.is_finite() || weight < 0.0 {
            return Err(AttentionError::InvalidConfig(format!("{kind:?} channel weight must be >= 0, got {weight}")));
        }
        let mut c = self.clone();
        c.channels.retain(|ch| ch.kind != kind);
        if weight > 0.0 {
            c.channels.push(ChannelConfig { kind, weight });
        }
        c.validate()?;
        Ok(c)
    }

    /// Checks every parameter; the message names the offending one.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(AttentionError::InvalidConfig(m));
        self.pyramid.validate().map_err(|e| AttentionError::InvalidConfig(format!("pyramid: {e}")))?;
        if self.center_levels.is_empty() || self.deltas.is_empty() {
            return bad("center_levels and deltas must not be empty".into());
        }
        if self.deltas.contains(&0) {
            return bad("deltas must be >= 1 (surround coarser than centre)".into());
        }
        if self.max_level() > 16 {
            return bad(format!("pyramid level {} is too deep (at most 16)", self.max_level()));
        }
        let g = &self.gabor;
        if g.size == 0 || g.size.is_multiple_of(2) || g.size > 99 {
            return bad(format!("gabor.size = {}: must be odd, 1..=99", g.size));
        }
        if !(g.wavelength_px.is_finite() && g.wavelength_px > 0.0 && g.sigma_px.is_finite() && g.sigma_px > 0.0) {
            return bad(format!("gabor wavelength {} and sigma {} must be positive", g.wavelength_px, g.sigma_px));
        }
        if (g.gamma - 1.0).abs() > 1e-6 {
            return bad(format!("gabor.gamma = {}: only 1 (isotropic envelope) is supported", g.gamma));
        }
        if g.angles_deg.iter().any(|a| !a.is_finite()) {
            return bad("gabor angles must be finite".into());
        }
        if !(self.color_threshold.is_finite() && (0.0..=1.0).contains(&self.color_threshold)) {
            return bad(format!("color_threshold = {}: must be in [0, 1]", self.color_threshold));
        }
        if !(self.border_ramp_frac.is_finite() && (0.0..=0.5).contains(&self.border_ramp_frac)) {
            return bad(format!("border_ramp_frac = {}: must be in [0, 0.5]", self.border_ramp_frac));
        }
        if !(self.feature_range.is_finite() && self.feature_range > 0.0) {
            return bad(format!("feature_range = {}: must be positive", self.feature_range));
        }
        if !(self.flicker_threshold.is_finite() && self.flicker_threshold >= 0.0) {
            return bad(format!("flicker_threshold = {}: must be finite and >= 0", self.flicker_threshold));
        }
        if !(self.flat_tolerance.is_finite() && self.flat_tolerance >= 0.0) {
            return bad(format!("flat_tolerance = {}: must be finite and >= 0", self.flat_tolerance));
        }
        if let Some(r) = self.final_range {
            if !(r.is_finite() && r > 0.0) {
                return bad(format!("final_range = {r}: must be positive"));
            }
        }
        if let Normalization::Iterative {
            iterations,
            excitation_sigma_frac,
            inhibition_sigma_frac,
            c_excitation,
            c_inhibition,
            global_inhibition,
        } = &self.normalization
        {
            let gi = match global_inhibition {
                GlobalInhibition::Constant(v) | GlobalInhibition::RelativeToMax(v) => *v,
            };
            let vals = [*excitation_sigma_frac, *inhibition_sigma_frac, *c_excitation, *c_inhibition, gi];
            if vals.iter().any(|v| !v.is_finite() || *v < 0.0)
                || *excitation_sigma_frac <= 0.0
                || *inhibition_sigma_frac <= 0.0
            {
                return bad("normalization sigmas must be positive and coefficients non-negative".into());
            }
            if *iterations > 100 {
                return bad(format!("normalization.iterations = {iterations}: at most 100"));
            }
        }
        if self.channels.is_empty() {
            return bad("at least one channel is needed".into());
        }
        if self.channels.iter().any(|c| !c.weight.is_finite() || c.weight < 0.0) {
            return bad("channel weights must be finite and non-negative".into());
        }
        if self.combination == Combination::WeightedMean && self.channels.iter().map(|c| c.weight).sum::<f32>() <= 0.0 {
            return bad("channel weights sum to 0".into());
        }
        if self.channels.iter().any(|c| c.kind == ChannelKind::Orientation) && g.angles_deg.is_empty() {
            return bad("the orientation channel needs at least one angle".into());
        }
        Ok(())
    }
}
