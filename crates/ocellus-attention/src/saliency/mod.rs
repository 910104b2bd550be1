//! The saliency engine: input frame to saliency map (SPEC 1), with every intermediate kept.
//!
//! Build once per frame size with [`SaliencyEngine::new`]; [`SaliencyEngine::process`]
//! reuses all buffers, so steady state allocates nothing.
//!
//! Channels are a list ([`crate::config::ChannelKind`]); each yields sub-features ([`Source`])
//! whose pyramids go through the same center-surround and N(.) machinery. A new channel,
//! such as flicker |I_t - I_{t-1}| for video, is one more `ChannelKind` and `Source` (plus
//! the previous frame's intensity pyramid kept in the engine), not a new pipeline.

use crate::center_surround::{abs_difference, attenuate_borders, ramp_width, scale_pairs, ScalePair};
use crate::channels::{opponent_from_planes, opponent_planes, skin_plane, split_rgb};
use crate::combine::{add_into, add_lane, copy_lane, interleave, scale};
use crate::config::{ChannelKind, Combination, OpponencyStage, SaliencyConfig};
use crate::gabor::GaborBank;
use crate::normalize::Normalizer;
use crate::{AttentionError, Result};
use ocellus_image::convert::RgbImage;
use ocellus_image::preserving::Lanes;
use ocellus_image::pyramid::{level_sizes, pyr_down, pyr_down_rgb8, PyrScratch};
use ocellus_image::resample::{ResampleMethod, Resampler};
use ocellus_image::{Backend, Plane};
use std::time::{Duration, Instant};

/// The fewest maps that N(.) takes as one batch of eight SIMD lanes: a batch costs
/// the same however few lanes it fills, about four single maps with the AVX2 kernels on 40x30
/// maps (AMD EPYC, Zen 3: 71 against 18 us, the fastest of 600 timings of ten calls each).
/// The 42 maps of the standard channels go as five batches and two single maps.
const LANES_FROM: usize = 3;

mod gpu;
mod outputs;
use gpu::{gpu_front, GpuFront, GpuParts};
pub use outputs::{FeatureMap, StageTimings, SubFeature};

/// Where a sub-feature's pyramid comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Intensity.
    Intensity,
    /// Red-green opponency.
    RedGreen,
    /// Blue-yellow opponency.
    BlueYellow,
    /// Gabor energy at the orientation with this index in `gabor.angles_deg`.
    Orientation(usize),
    /// Skin likelihood.
    Skin,
    /// `|I_t - I_(t-1)|` of the intensity pyramid.
    Flicker,
    /// The n-th external map.
    External(usize),
}

/// The Gaussian pyramids of one frame, levels 0..=max_level; levels a source does not need
/// stay empty.
#[derive(Debug)]
struct Pyramids {
    /// R, G, B (when opponency is computed at each level).
    rgb: [Vec<Plane<f32>>; 3],
    /// Intensity, red-green, blue-yellow.
    opp: [Vec<Plane<f32>>; 3],
    /// Gabor energy, per level then per angle.
    ori: Vec<Vec<Plane<f32>>>,
    skin: Vec<Plane<f32>>,
    flicker: Vec<Plane<f32>>,
    /// The previous frame's intensity levels (for flicker); empty before the first frame.
    prev_intensity: Vec<Plane<f32>>,
    external: Vec<Vec<Plane<f32>>>,
}

impl Pyramids {
    /// Level `level` of `source`'s pyramid.
    fn get(&self, source: Source, level: usize) -> Option<&Plane<f32>> {
        match source {
            Source::Intensity => self.opp[0].get(level),
            Source::RedGreen => self.opp[1].get(level),
            Source::BlueYellow => self.opp[2].get(level),
            Source::Orientation(a) => self.ori.get(level).and_then(|v| v.get(a)),
            Source::Skin => self.skin.get(level),
            Source::Flicker => self.flicker.get(level),
            Source::External(k) => self.external.get(k).and_then(|v| v.get(level)),
        }
    }
}

/// Computes saliency maps for frames of one size.
#[derive(Debug)]
pub struct SaliencyEngine {
    cfg: SaliencyConfig,
    backend: Backend,
    width: usize,
    height: usize,
    sizes: Vec<(usize, usize)>,
    pairs: Vec<ScalePair>,
    used_levels: Vec<usize>,
    subs: Vec<SubFeature>,
    n_external: usize,
    pyr: Pyramids,
    pyr_scratch: PyrScratch,
    gabor: Option<GaborBank>,
    resamplers: Vec<Option<Resampler>>,
    external_resamplers: Vec<Option<Resampler>>,
    rescaled: Vec<Vec<Plane<f32>>>,
    features: Vec<FeatureMap>,
    normalizer: Normalizer,
    lanes: Plane<Lanes>,
    /// One feature map under N(.) when its batch is too small for the lanes (see
    /// `LANES_FROM`).
    single: Plane<f32>,
    sub_sums: Vec<Plane<f32>>,
    resample_row: Vec<f32>,
    conspicuity: Vec<Plane<f32>>,
    saliency: Plane<f32>,
    prior: Option<Plane<f32>>,
    upsampler: Option<Resampler>,
    timings: StageTimings,
    /// The pipeline on the GPU (`Backend::Gpu`).
    gpu: Option<GpuFront>,
    /// Whether the GPU pipeline reads back the pyramid levels too.
    gpu_levels: bool,
}

fn empty_pyr(n: usize) -> Vec<Plane<f32>> {
    (0..n).map(|_| Plane::default()).collect()
}

impl SaliencyEngine {
    /// Validates `cfg` and allocates everything for `width` x `height` frames.
    pub fn new(cfg: SaliencyConfig, width: usize, height: usize) -> Result<Self> {
        cfg.validate()?;
        let max_level = cfg.max_level();
        let min_side = 1usize << max_level;
        if width < min_side || height < min_side {
            return Err(AttentionError::TooSmall { width, height, levels: max_level + 1, min_side });
        }
        let sizes = level_sizes(width, height, max_level + 1);
        let pairs = scale_pairs(&cfg.center_levels, &cfg.deltas);
        let mut used_levels: Vec<usize> = pairs.iter().flat_map(|p| [p.center, p.surround]).collect();
        used_levels.sort_unstable();
        used_levels.dedup();

        let mut subs = Vec::new();
        let mut n_external = 0;
        for (ci, ch) in cfg.channels.iter().enumerate() {
            let mut push = |source, label: String| subs.push(SubFeature { channel: ci, source, label });
            match &ch.kind {
                ChannelKind::Intensity => push(Source::Intensity, "intensity".into()),
                ChannelKind::Color => {
                    push(Source::RedGreen, "red-green".into());
                    push(Source::BlueYellow, "blue-yellow".into());
                }
                ChannelKind::Orientation => {
                    for (a, deg) in cfg.gabor.angles_deg.iter().enumerate() {
                        push(Source::Orientation(a), format!("orientation {deg}"));
                    }
                }
                ChannelKind::Skin => push(Source::Skin, "skin".into()),
                ChannelKind::Flicker => push(Source::Flicker, "flicker".into()),
                ChannelKind::External(name) => {
                    push(Source::External(n_external), format!("external {name}"));
                    n_external += 1;
                }
            }
        }
        let has = |k: &ChannelKind| cfg.channels.iter().any(|c| &c.kind == k);
        let n = max_level + 1;
        let map_size = sizes[cfg.map_level];
        let mut resamplers = Vec::with_capacity(n);
        for (l, &s) in sizes.iter().enumerate() {
            resamplers.push(if used_levels.contains(&l) {
                Some(Resampler::new(cfg.across_scale, s, map_size)?)
            } else {
                None
            });
        }
        let gabor = has(&ChannelKind::Orientation).then(|| GaborBank::new(&cfg.gabor));
        let n_angles = cfg.gabor.angles_deg.len();
        let normalizer = Normalizer::new(&cfg.normalization, map_size.0, map_size.1, cfg.flat_tolerance)?;
        let features = pairs
            .iter()
            .flat_map(|p| (0..subs.len()).map(move |s| (s, *p)))
            .map(|(s, p)| FeatureMap {
                subfeature: s,
                center: p.center,
                surround: p.surround,
                map: Plane::new(map_size.0, map_size.1),
            })
            .collect::<Vec<_>>();
        // Order feature maps by sub-feature, then pair, for readable listings.
        let mut features = features;
        features.sort_by_key(|f| (f.subfeature, f.center, f.surround));
        let gpu = if cfg.backend == Backend::Gpu {
            let parts = GpuParts {
                sizes: &sizes,
                used: &used_levels,
                subs: &subs,
                features: &features,
                resamplers: &resamplers,
                normalizer: &normalizer,
            };
            Some(gpu_front(&cfg, &parts)?)
        } else {
            None
        };
        Ok(Self {
            gpu,
            gpu_levels: true,
            backend: cfg.backend.resolve(),
            width,
            height,
            sizes,
            pyr: Pyramids {
                rgb: [empty_pyr(n), empty_pyr(n), empty_pyr(n)],
                opp: [empty_pyr(n), empty_pyr(n), empty_pyr(n)],
                ori: (0..n).map(|_| empty_pyr(n_angles)).collect(),
                skin: empty_pyr(n),
                flicker: empty_pyr(n),
                prev_intensity: empty_pyr(n),
                external: (0..n_external).map(|_| empty_pyr(n)).collect(),
            },
            pyr_scratch: PyrScratch::default(),
            gabor,
            resamplers,
            external_resamplers: vec![None; n_external],
            rescaled: (0..subs.len()).map(|_| empty_pyr(n)).collect(),
            features,
            normalizer,
            lanes: Plane::new(map_size.0, map_size.1),
            single: Plane::new(map_size.0, map_size.1),
            resample_row: Vec::with_capacity(width),
            sub_sums: (0..subs.len()).map(|_| Plane::new(map_size.0, map_size.1)).collect(),
            conspicuity: (0..cfg.channels.len()).map(|_| Plane::new(map_size.0, map_size.1)).collect(),
            saliency: Plane::new(map_size.0, map_size.1),
            prior: None,
            upsampler: None,
            timings: StageTimings::default(),
            pairs,
            used_levels,
            subs,
            n_external,
            cfg,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SaliencyConfig {
        &self.cfg
    }

    /// Frame size (width, height) this engine was built for.
    pub fn frame_size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Size (width, height) of every pyramid level, level 0 first.
    pub fn level_sizes(&self) -> &[(usize, usize)] {
        &self.sizes
    }

    /// Size (width, height) of the feature, conspicuity and saliency maps.
    pub fn map_size(&self) -> (usize, usize) {
        self.sizes[self.cfg.map_level]
    }

    /// The backend that runs the CPU's kernels (a concrete CPU backend, also when the front
    /// end runs on the GPU).
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The phases of the last frame's GPU front end (upload, GPU work, readback); `None` on
    /// the CPU backends.
    #[cfg(feature = "gpu")]
    pub fn gpu_timings(&self) -> Option<ocellus_gpu::FrontEndTimings> {
        self.gpu.as_ref().map(|g| g.timings())
    }

    /// Whether the pipeline runs on the GPU (`Backend::Gpu`): the front end (pyramids,
    /// opponency, Gabor energies) and the map-level stages (rescaling, center-surround,
    /// N(.), combination), all on the device; only the spatial prior is applied on the CPU.
    pub fn on_gpu(&self) -> bool {
        self.gpu.is_some()
    }

    /// On the GPU backend, whether each frame also reads back the pyramid levels the
    /// center-surround pairs use (the opponency planes and Gabor energies behind
    /// [`Self::level`]; on by default). Off, only the map-level outputs (feature,
    /// conspicuity and saliency maps) come back, and [`Self::level`] keeps the last levels
    /// read. No effect on the CPU backends.
    pub fn set_gpu_level_readback(&mut self, on: bool) {
        self.gpu_levels = on;
    }

    /// Sets a spatial prior (top-down location bias, SPEC 1.8): the final saliency map is
    /// multiplied by it after resampling it (bilinear) to the map size. Values should be
    /// in [0, 1]; non-finite or negative values are an error.
    pub fn set_spatial_prior(&mut self, prior: Option<&Plane<f32>>) -> Result<()> {
        self.prior = match prior {
            None => None,
            Some(p) => {
                if p.is_empty() || !p.all_finite() || p.min_max().0 < 0.0 {
                    return Err(AttentionError::InvalidInput(
                        "spatial prior must be non-empty, finite and non-negative".into(),
                    ));
                }
                let (w, h) = self.map_size();
                let mut out = Plane::default();
                Resampler::new(ResampleMethod::Bilinear, p.size(), (w, h))?.apply(self.backend, p, &mut out)?;
                Some(out)
            }
        };
        Ok(())
    }

    /// Computes the saliency map of `frame`; returns it at the map level.
    ///
    /// ```
    /// use ocellus_attention::{SaliencyConfig, SaliencyEngine};
    /// use ocellus_image::{convert::RgbImage, Plane};
    /// // A dark frame with one bright red square centred near (200, 70).
    /// let frame = RgbImage::U8(Plane::from_fn(320, 256, |x, y| {
    ///     if (184..216).contains(&x) && (54..86).contains(&y) { [250, 30, 30] } else { [40, 40, 40] }
    /// }));
    /// let mut engine = SaliencyEngine::new(SaliencyConfig::ace2009(), 320, 256)?;
    /// let map = engine.process(&frame)?;
    /// assert_eq!(map.size(), (20, 16)); // 1/16 of the frame per side
    /// let (cx, cy, _) = map.argmax().unwrap();
    /// // The winning cell covers the square: cells are 16 px, the square spans cells 11..=13, 3..=5.
    /// assert!((11..=13).contains(&cx) && (3..=5).contains(&cy), "peak at cell ({cx}, {cy})");
    /// # Ok::<(), ocellus_attention::AttentionError>(())
    /// ```
    pub fn process(&mut self, frame: &RgbImage) -> Result<&Plane<f32>> {
        self.process_with_maps(frame, &[])
    }

    /// Like [`process`](Self::process), with one map per `External` channel (in channel
    /// order), each of any size (resampled to pyramid level `min(center_levels)`).
    pub fn process_with_maps(&mut self, frame: &RgbImage, external: &[&Plane<f32>]) -> Result<&Plane<f32>> {
        let (w, h) = frame.size();
        ocellus_image::check::same_size("frame (against the engine's)", (w, h), (self.width, self.height))?;
        if external.len() != self.n_external {
            return Err(AttentionError::InvalidInput(format!(
                "{} external maps given, the configuration has {} external channels",
                external.len(),
                self.n_external
            )));
        }
        for m in external {
            if m.is_empty() || !m.all_finite() {
                return Err(AttentionError::InvalidInput(format!(
                    "external map of {}x{} is empty or has non-finite values",
                    m.width(),
                    m.height()
                )));
            }
        }
        if self.gpu.is_some() {
            self.run_gpu(frame)?;
            return Ok(&self.saliency);
        }
        let t0 = Instant::now();
        self.build_pyramids(frame, external)?;
        let t1 = Instant::now();
        self.build_orientations()?;
        let t2 = Instant::now();
        self.rescale()?;
        let t3 = Instant::now();
        self.center_surround();
        let t4 = Instant::now();
        let (norm, comb) = self.normalize_and_combine()?;
        self.timings = StageTimings {
            pyramid: t1 - t0,
            orientation: t2 - t1,
            rescale: t3 - t2,
            center_surround: t4 - t3,
            normalization: norm,
            combination: comb,
        };
        Ok(&self.saliency)
    }

    fn max_level(&self) -> usize {
        self.sizes.len() - 1
    }

    fn pyramid_up(
        backend: Backend,
        pyr: &mut [Plane<f32>],
        from: usize,
        to: usize,
        k: &ocellus_image::pyramid::PyramidKernel,
        s: &mut PyrScratch,
    ) -> Result<()> {
        for l in from..to {
            let (lo, hi) = pyr.split_at_mut(l + 1);
            pyr_down(backend, &lo[l], &mut hi[0], k, s)?;
        }
        Ok(())
    }

    fn build_pyramids(&mut self, frame: &RgbImage, external: &[&Plane<f32>]) -> Result<()> {
        let (b, top) = (self.backend, self.max_level());
        let cfg = &self.cfg;
        let needs = |k: ChannelKind| cfg.channels.iter().any(|c| c.kind == k);
        let need_i = needs(ChannelKind::Intensity) || needs(ChannelKind::Orientation) || needs(ChannelKind::Flicker);
        let need_c = needs(ChannelKind::Color);
        let weights = cfg.intensity.weights();
        if need_i || need_c {
            match cfg.opponency_at {
                OpponencyStage::Input => {
                    let [i, rg, by] = &mut self.pyr.opp;
                    opponent_planes(b, frame, weights, cfg.color_threshold, [&mut i[0], &mut rg[0], &mut by[0]]);
                    for (k, p) in self.pyr.opp.iter_mut().enumerate() {
                        if (k == 0 && need_i) || (k > 0 && need_c) {
                            Self::pyramid_up(b, p, 0, top, &cfg.pyramid, &mut self.pyr_scratch)?;
                        }
                    }
                }
                OpponencyStage::EachLevel => {
                    let [r, g, bl] = &mut self.pyr.rgb;
                    let first = match frame {
                        // 8-bit input: conversion fused into the first level (no full-size floats).
                        RgbImage::U8(p) if top >= 1 && self.used_levels.first().is_some_and(|&l| l >= 1) => {
                            pyr_down_rgb8(
                                b,
                                p,
                                [&mut r[1], &mut g[1], &mut bl[1]],
                                &cfg.pyramid,
                                &mut self.pyr_scratch,
                            )?;
                            1
                        }
                        _ => {
                            split_rgb(b, frame, [&mut r[0], &mut g[0], &mut bl[0]]);
                            0
                        }
                    };
                    for p in self.pyr.rgb.iter_mut() {
                        Self::pyramid_up(b, p, first, top, &cfg.pyramid, &mut self.pyr_scratch)?;
                    }
                    for &l in &self.used_levels {
                        let [i, rg, by] = &mut self.pyr.opp;
                        opponent_from_planes(
                            b,
                            [&self.pyr.rgb[0][l], &self.pyr.rgb[1][l], &self.pyr.rgb[2][l]],
                            weights,
                            cfg.color_threshold,
                            [&mut i[l], &mut rg[l], &mut by[l]],
                        );
                    }
                }
            }
        }
        if needs(ChannelKind::Skin) {
            skin_plane(frame, cfg.color_threshold, &mut self.pyr.skin[0]);
            Self::pyramid_up(b, &mut self.pyr.skin, 0, top, &cfg.pyramid, &mut self.pyr_scratch)?;
        }
        let need_flicker = needs(ChannelKind::Flicker);
        let base = self.used_levels.first().copied().unwrap_or(0);
        for (k, m) in external.iter().enumerate() {
            // Maps may change size between frames; the resampler follows the map's size.
            if self.external_resamplers[k].as_ref().map(|r| r.src_size()) != Some(m.size()) {
                self.external_resamplers[k] =
                    Some(Resampler::new(ResampleMethod::Bilinear, m.size(), self.sizes[base])?);
            }
            if let Some(rs) = &self.external_resamplers[k] {
                rs.apply_with(b, m, &mut self.pyr.external[k][base], &mut self.resample_row)?;
            }
            Self::pyramid_up(b, &mut self.pyr.external[k], base, top, &cfg.pyramid, &mut self.pyr_scratch)?;
        }
        if need_flicker {
            self.flicker_levels();
        }
        Ok(())
    }

    /// Flicker at the used levels: `max(|I_t - I_(t-1)| - threshold, 0)`, zero on the first
    /// frame (or after a size change); then keeps this frame's intensity for the next.
    fn flicker_levels(&mut self) {
        let p = &mut self.pyr;
        let t = self.cfg.flicker_threshold;
        for &l in &self.used_levels {
            let (cur, prev, out) = (&p.opp[0][l], &mut p.prev_intensity[l], &mut p.flicker[l]);
            out.resize(cur.width(), cur.height());
            if prev.size() == cur.size() {
                for y in 0..cur.height() {
                    let (c, q) = (cur.row(y), prev.row(y));
                    for (x, o) in out.row_mut(y).iter_mut().enumerate() {
                        *o = ((c[x] - q[x]).abs() - t).max(0.0);
                    }
                }
            } else {
                out.fill(0.0);
            }
            prev.resize(cur.width(), cur.height());
            prev.copy_from(cur);
        }
    }

    /// Makes `frame` the previous frame of the flicker channel, computing only its pyramids:
    /// an engine that next processes frame k of a stream, having last processed some frame
    /// other than k - 1 (a worker of a parallel pipeline), primes with frame k - 1 and then
    /// gives exactly the maps of a sequential run. Nothing to do without a flicker channel.
    pub fn prime_temporal(&mut self, frame: &RgbImage) -> Result<()> {
        if !self.cfg.channels.iter().any(|c| c.kind == ChannelKind::Flicker) {
            return Ok(());
        }
        ocellus_image::check::same_size("frame (against the engine's)", frame.size(), (self.width, self.height))?;
        self.build_pyramids(frame, &[])
    }

    /// Forgets the previous frame, so that the next frame has no flicker (e.g. after a cut).
    pub fn reset_temporal(&mut self) {
        for p in &mut self.pyr.prev_intensity {
            p.resize(0, 0);
        }
    }

    fn build_orientations(&mut self) -> Result<()> {
        let Some(g) = self.gabor.as_mut() else { return Ok(()) };
        for &l in &self.used_levels {
            g.filter(self.backend, &self.pyr.opp[0][l], &mut self.pyr.ori[l])?;
        }
        Ok(())
    }

    /// The pyramid levels the center-surround pairs read, ascending (2..=8 for the default
    /// pairs).
    pub fn used_levels(&self) -> &[usize] {
        &self.used_levels
    }

    /// A pyramid level of a source (empty if that level is not computed).
    pub fn level(&self, source: Source, level: usize) -> Option<&Plane<f32>> {
        self.pyr.get(source, level).filter(|p| !p.is_empty())
    }

    fn rescale(&mut self) -> Result<()> {
        for s in 0..self.subs.len() {
            let src = self.subs[s].source;
            for &l in &self.used_levels {
                let Some(plane) = self.pyr.get(src, l) else { continue };
                if let Some(r) = &self.resamplers[l] {
                    r.apply_with(self.backend, plane, &mut self.rescaled[s][l], &mut self.resample_row)?;
                }
            }
        }
        Ok(())
    }

    fn center_surround(&mut self) {
        let (w, h) = self.map_size();
        let ramp = ramp_width(w, h, self.cfg.border_ramp_frac);
        for f in self.features.iter_mut() {
            let r = &self.rescaled[f.subfeature];
            abs_difference(&r[f.center], &r[f.surround], &mut f.map);
            attenuate_borders(&mut f.map, ramp);
        }
    }

    /// N(.) on the feature maps, then on the sub-feature sums: eight at a time in SIMD lanes,
    /// the last few of each (fewer than [`LANES_FROM`]) one by one. Each lane gets the treatment of a single map (equal within
    /// rounding, tested in `ocellus-image`), but a batch costs the same however few lanes it
    /// fills.
    fn normalize_and_combine(&mut self) -> Result<(Duration, Duration)> {
        let b = self.backend;
        let t_start = Instant::now();
        let n_channels = self.cfg.channels.len();
        let range = self.cfg.feature_range;
        // Feature maps: N with rescaling, eight at a time, summed per sub-feature.
        for s in self.sub_sums.iter_mut() {
            s.fill(0.0);
        }
        let t = Instant::now();
        // Eight maps per batch, one per SIMD lane (see Normalizer::apply_lanes).
        let nf = self.features.len();
        for start in (0..nf).step_by(8) {
            if nf - start < LANES_FROM {
                for f in &self.features[start..] {
                    self.single.copy_from(&f.map);
                    self.normalizer.apply(b, &mut self.single, Some(range))?;
                    add_into(&mut self.sub_sums[f.subfeature], &self.single);
                }
                break;
            }
            let maps: [Option<&Plane<f32>>; 8] = std::array::from_fn(|l| self.features.get(start + l).map(|f| &f.map));
            interleave(&maps, &mut self.lanes);
            self.normalizer.apply_lanes(b, &mut self.lanes, Some(range))?;
            for (l, f) in self.features[start..nf.min(start + 8)].iter().enumerate() {
                add_lane(&mut self.sub_sums[f.subfeature], &self.lanes, l);
            }
        }
        // Sub-feature sums: N without rescaling, in place.
        let ns = self.sub_sums.len();
        for start in (0..ns).step_by(8) {
            if ns - start < LANES_FROM {
                for m in &mut self.sub_sums[start..] {
                    self.normalizer.apply(b, m, None)?;
                }
                break;
            }
            let maps: [Option<&Plane<f32>>; 8] = std::array::from_fn(|l| self.sub_sums.get(start + l));
            interleave(&maps, &mut self.lanes);
            self.normalizer.apply_lanes(b, &mut self.lanes, None)?;
            for (l, m) in self.sub_sums[start..ns.min(start + 8)].iter_mut().enumerate() {
                copy_lane(m, &self.lanes, l);
            }
        }
        let mut t_norm = t.elapsed();
        let weight_sum: f32 = self.cfg.channels.iter().map(|c| c.weight).sum();
        for ci in 0..n_channels {
            let cm = &mut self.conspicuity[ci];
            cm.fill(0.0);
            let mut n_sub = 0usize;
            for (s, sub) in self.subs.iter().enumerate() {
                if sub.channel == ci {
                    n_sub += 1;
                    add_into(cm, &self.sub_sums[s]);
                }
            }
            if n_sub > 1 {
                let t = Instant::now();
                self.normalizer.apply(b, cm, None)?;
                t_norm += t.elapsed();
            }
            let ch = &self.cfg.channels[ci];
            let factor = match self.cfg.combination {
                Combination::WeightedMean => ch.weight / weight_sum,
                Combination::StbPerSubfeature => ch.weight / n_sub.max(1) as f32 / n_channels as f32,
            };
            scale(cm, factor);
        }
        self.saliency.fill(0.0);
        for cm in &self.conspicuity {
            add_into(&mut self.saliency, cm);
        }
        if let Some(r) = self.cfg.final_range {
            let t = Instant::now();
            self.normalizer.apply(b, &mut self.saliency, Some(r))?;
            t_norm += t.elapsed();
        }
        self.apply_prior();
        Ok((t_norm, t_start.elapsed().saturating_sub(t_norm)))
    }

    /// Multiplies the saliency map by the spatial prior, if one is set.
    fn apply_prior(&mut self) {
        if let Some(p) = &self.prior {
            for y in 0..p.height() {
                let pr = p.row(y);
                self.saliency.row_mut(y).iter_mut().zip(pr).for_each(|(v, q)| *v *= q);
            }
        }
    }
}
