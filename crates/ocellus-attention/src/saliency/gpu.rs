//! The saliency engine on the GPU backend (`Backend::Gpu`, feature `gpu` of this crate): the
//! device pipeline built from the configuration, and frames and batches run through it.

#[cfg(feature = "gpu")]
use super::Source;
#[cfg(feature = "gpu")]
use super::StageTimings;
use super::{FeatureMap, SaliencyEngine, SubFeature};
#[cfg(feature = "gpu")]
use crate::center_surround::ramp_width;
use crate::config::SaliencyConfig;
#[cfg(feature = "gpu")]
use crate::config::{ChannelKind, Combination, OpponencyStage};
use crate::normalize::Normalizer;
use crate::{AttentionError, Result};
use ocellus_image::convert::RgbImage;
use ocellus_image::resample::Resampler;
use ocellus_image::Plane;
#[cfg(feature = "gpu")]
use std::time::Instant;

#[cfg(feature = "gpu")]
pub(super) type GpuFront = ocellus_gpu::GpuFrontEnd;
/// Without the `gpu` feature there is no GPU front end.
#[cfg(not(feature = "gpu"))]
#[derive(Debug)]
pub(super) enum GpuFront {}

/// What [`gpu_front`] needs of the engine besides its configuration.
#[cfg_attr(not(feature = "gpu"), allow(dead_code))]
pub(super) struct GpuParts<'a> {
    pub(super) sizes: &'a [(usize, usize)],
    pub(super) used: &'a [usize],
    pub(super) subs: &'a [SubFeature],
    pub(super) features: &'a [FeatureMap],
    pub(super) resamplers: &'a [Option<Resampler>],
    pub(super) normalizer: &'a Normalizer,
}

/// The GPU pipeline for `cfg` (see [`SaliencyEngine::new`]): the front end, and the
/// map-level stages reading its planes on the device.
#[cfg(feature = "gpu")]
pub(super) fn gpu_front(cfg: &SaliencyConfig, parts: &GpuParts) -> Result<GpuFront> {
    use crate::config::{GlobalInhibition, Normalization};
    use ocellus_gpu::{BackEndSpec, ChannelSpec, GpuNormalization, PlaneSource};
    let GpuParts { sizes, used, subs, features, resamplers, normalizer } = *parts;
    let unsupported = |what: String| Err(AttentionError::Gpu(format!("not supported on the GPU backend: {what}")));
    if cfg.opponency_at != OpponencyStage::EachLevel {
        return unsupported(format!(
            "opponency at {:?} (the GPU front end computes it at each level, as the ace2009 preset)",
            cfg.opponency_at
        ));
    }
    if let Some(c) = cfg
        .channels
        .iter()
        .find(|c| !matches!(c.kind, ChannelKind::Intensity | ChannelKind::Color | ChannelKind::Orientation))
    {
        return unsupported(format!("channel {:?} (intensity, colour and orientation only)", c.kind));
    }
    let with_ori = cfg.channels.iter().any(|c| c.kind == ChannelKind::Orientation);
    if with_ori && cfg.gabor.border != crate::config::GaborBorder::Clamp {
        return unsupported(format!("Gabor border {:?} (clamp only)", cfg.gabor.border));
    }
    let gabor = if with_ori {
        let psi = std::f64::consts::FRAC_PI_2;
        cfg.gabor
            .angles_deg
            .iter()
            .map(|&a| [crate::gabor::kernel_2d(&cfg.gabor, a, 0.0), crate::gabor::kernel_2d(&cfg.gabor, a, psi)])
            .collect()
    } else {
        Vec::new()
    };
    let map_size = sizes[cfg.map_level];
    let subfeatures = subs
        .iter()
        .map(|s| match s.source {
            Source::Intensity => Ok(PlaneSource::Intensity),
            Source::RedGreen => Ok(PlaneSource::RedGreen),
            Source::BlueYellow => Ok(PlaneSource::BlueYellow),
            Source::Orientation(a) => Ok(PlaneSource::Orientation(a)),
            other => Err(AttentionError::Gpu(format!("not supported on the GPU backend: sub-feature {other:?}"))),
        })
        .collect::<Result<Vec<_>>>()?;
    let rescale = used
        .iter()
        .map(|&l| match &resamplers[l] {
            Some(r) => Ok(r.tables().map(<[_]>::to_vec)),
            None => Err(AttentionError::Gpu(format!("no across-scale resampling of level {l}"))),
        })
        .collect::<Result<Vec<_>>>()?;
    let n_channels = cfg.channels.len();
    let weight_sum: f32 = cfg.channels.iter().map(|c| c.weight).sum();
    let mut channels = Vec::with_capacity(n_channels);
    for (ci, ch) in cfg.channels.iter().enumerate() {
        let first = subs.iter().position(|s| s.channel == ci).unwrap_or(subs.len());
        let count = subs.iter().filter(|s| s.channel == ci).count();
        let weight = match cfg.combination {
            Combination::WeightedMean => ch.weight / weight_sum,
            Combination::StbPerSubfeature => ch.weight / count.max(1) as f32 / n_channels as f32,
        };
        channels.push(ChannelSpec { first_subfeature: first, subfeatures: count, weight });
    }
    let normalization = match (&cfg.normalization, normalizer.kernels()) {
        (Normalization::Iterative { iterations, global_inhibition, .. }, Some([ex, inh])) => {
            let (g, relative) = match *global_inhibition {
                GlobalInhibition::Constant(c) => (c, false),
                GlobalInhibition::RelativeToMax(f) => (f, true),
            };
            GpuNormalization::Iterative {
                excitation: ex.to_vec(),
                inhibition: inh.to_vec(),
                iterations: *iterations,
                global_inhibition: g,
                relative_to_max: relative,
            }
        }
        (Normalization::LocalMax, _) => GpuNormalization::LocalMax,
        _ => GpuNormalization::None,
    };
    let back_end = BackEndSpec {
        map_size,
        rescale,
        subfeatures,
        features: features.iter().map(|f| (f.subfeature, f.center, f.surround)).collect(),
        channels,
        border_ramp: ramp_width(map_size.0, map_size.1, cfg.border_ramp_frac),
        normalization,
        feature_range: cfg.feature_range,
        flat_tolerance: cfg.flat_tolerance,
        final_range: cfg.final_range,
    };
    let spec = ocellus_gpu::FrontEndSpec {
        level_sizes: sizes.to_vec(),
        used_levels: used.to_vec(),
        pyramid: cfg.pyramid.clone(),
        intensity_weights: cfg.intensity.weights(),
        color_threshold: cfg.color_threshold,
        gabor,
        gabor_size: cfg.gabor.size,
        back_end: Some(back_end),
    };
    let gpu_err = |e: ocellus_gpu::GpuError| AttentionError::Gpu(e.to_string());
    let ctx = ocellus_gpu::GpuContext::shared().map_err(gpu_err)?;
    ocellus_gpu::GpuFrontEnd::new(&ctx, &spec).map_err(gpu_err)
}

#[cfg(not(feature = "gpu"))]
pub(super) fn gpu_front(_: &SaliencyConfig, _: &GpuParts) -> Result<GpuFront> {
    Err(AttentionError::Gpu(
        "this build has no GPU backend (build ocellus-attention with its `gpu` feature; ocellus-cli enables it by default)"
            .into(),
    ))
}

impl SaliencyEngine {
    /// The saliency maps of several frames, in order, into `out` (resized to one map per
    /// frame). On the GPU backend the frames go through the device in one submission and
    /// only their saliency maps come back, which amortizes the round trip's fixed cost; the
    /// engine's other outputs (feature and conspicuity maps, levels, timings' stages) then
    /// keep the frame before the batch, and [`Self::saliency`] too. On the CPU it is
    /// [`Self::process`] frame by frame (the other outputs are the last frame's).
    pub fn process_batch(&mut self, frames: &[RgbImage], out: &mut Vec<Plane<f32>>) -> Result<()> {
        for f in frames {
            ocellus_image::check::same_size("frame (against the engine's)", f.size(), (self.width, self.height))?;
        }
        out.resize_with(frames.len(), Plane::default);
        if self.n_external > 0 {
            return Err(AttentionError::InvalidInput(format!(
                "the configuration has {} external channels: give their maps with process_with_maps",
                self.n_external
            )));
        }
        if self.gpu.is_none() {
            for (f, o) in frames.iter().zip(out.iter_mut()) {
                let m = self.process(f)?;
                o.resize(m.width(), m.height());
                o.copy_from(m);
            }
            return Ok(());
        }
        self.run_gpu_batch(frames, out)
    }

    #[cfg(feature = "gpu")]
    fn run_gpu_batch(&mut self, frames: &[RgbImage], out: &mut [Plane<f32>]) -> Result<()> {
        let Some(g) = self.gpu.as_mut() else { return Ok(()) };
        let converted: Vec<std::borrow::Cow<Plane<[u8; 3]>>> = frames
            .iter()
            .map(|f| match f {
                RgbImage::U8(p) => std::borrow::Cow::Borrowed(p),
                RgbImage::F32(_) => std::borrow::Cow::Owned(f.to_u8()),
            })
            .collect();
        let frames8: Vec<&Plane<[u8; 3]>> = converted.iter().map(|c| c.as_ref()).collect();
        g.process_batch(&frames8, out.iter_mut()).map_err(|e| AttentionError::Gpu(e.to_string()))?;
        if let Some(p) = &self.prior {
            for m in out.iter_mut() {
                for y in 0..p.height() {
                    m.row_mut(y).iter_mut().zip(p.row(y)).for_each(|(v, q)| *v *= q);
                }
            }
        }
        Ok(())
    }

    #[cfg(not(feature = "gpu"))]
    fn run_gpu_batch(&mut self, _: &[RgbImage], _: &mut [Plane<f32>]) -> Result<()> {
        match self.gpu.as_ref() {
            Some(g) => match *g {},
            None => Ok(()),
        }
    }

    /// The whole pipeline on the GPU: the maps (feature, sub-feature, conspicuity, saliency)
    /// come back from the device, and the levels too unless switched off
    /// ([`Self::set_gpu_level_readback`]); the spatial prior is applied here. The frame's
    /// whole time is reported as the pyramid stage ([`Self::gpu_timings`] splits it).
    #[cfg(feature = "gpu")]
    pub(super) fn run_gpu(&mut self, frame: &RgbImage) -> Result<()> {
        let t0 = Instant::now();
        let Some(g) = self.gpu.as_mut() else { return Ok(()) };
        let rgb8;
        let frame8 = match frame {
            RgbImage::U8(p) => p,
            RgbImage::F32(_) => {
                rgb8 = frame.to_u8();
                &rgb8
            }
        };
        let maps = self
            .features
            .iter_mut()
            .map(|f| &mut f.map)
            .chain(self.sub_sums.iter_mut())
            .chain(self.conspicuity.iter_mut())
            .chain(std::iter::once(&mut self.saliency));
        let levels = if self.gpu_levels { Some((&mut self.pyr.opp, &mut self.pyr.ori)) } else { None };
        g.process_maps(frame8, maps, levels).map_err(|e| AttentionError::Gpu(e.to_string()))?;
        self.apply_prior();
        self.timings = StageTimings { pyramid: t0.elapsed(), ..StageTimings::default() };
        Ok(())
    }

    #[cfg(not(feature = "gpu"))]
    pub(super) fn run_gpu(&mut self, _: &RgbImage) -> Result<()> {
        match self.gpu.as_ref() {
            Some(g) => match *g {},
            None => Ok(()),
        }
    }
}
