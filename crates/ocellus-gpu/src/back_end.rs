//! The map-level stages of the saliency pipeline on the GPU (SPEC 1.5-1.7): across-scale
//! rescaling, center-surround differences, N(.) and the combination, reading the front end's
//! planes where they lie on the device (shaders/back_end.wgsl).

use crate::front_end::Pass;
use crate::{GpuContext, GpuError, Result};
use ocellus_image::preserving::preserving_factors;
use wgpu::util::DeviceExt;

/// Which front-end plane a sub-feature reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneSource {
    /// Intensity.
    Intensity,
    /// Red-green opponency.
    RedGreen,
    /// Blue-yellow opponency.
    BlueYellow,
    /// The Gabor energy of the angle with this index.
    Orientation(usize),
}

/// The competition operator N(.) (SPEC 1.6), as `ocellus-attention`'s `Normalizer` runs it.
#[derive(Clone, Debug, PartialEq)]
pub enum GpuNormalization {
    /// Clamp at 0 (and rescale where asked) only.
    None,
    /// Iterative difference of Gaussians: `iterations` times
    /// `M <- max(0, M + M * excitation - M * inhibition - C)`, each filter the separable,
    /// energy-preserving (zero border, renormalized) filter of its odd-length 1D kernel.
    Iterative {
        /// 1D excitatory kernel (peak included, odd length).
        excitation: Vec<f32>,
        /// 1D inhibitory kernel (odd length).
        inhibition: Vec<f32>,
        /// Number of iterations.
        iterations: usize,
        /// The constant C, or its factor of the map's maximum when `relative_to_max`.
        global_inhibition: f32,
        /// Whether C is `global_inhibition` times the map's current maximum.
        relative_to_max: bool,
    },
    /// The local-maxima rule of Itti et al. 1998.
    LocalMax,
}

/// One channel of the combination: its sub-features and its weight.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelSpec {
    /// Index of its first sub-feature; its sub-features are consecutive.
    pub first_subfeature: usize,
    /// How many sub-features it has (N(.) is applied to their sum when more than one).
    pub subfeatures: usize,
    /// Factor of its conspicuity map in the saliency map.
    pub weight: f32,
}

/// What the map-level stages compute, in plain terms; `ocellus-attention` fills it from its
/// configuration.
#[derive(Clone, Debug)]
pub struct BackEndSpec {
    /// Size (width, height) of every map of the map level.
    pub map_size: (usize, usize),
    /// The across-scale resampling of each used level (in the front end's `used_levels`
    /// order) to the map level: per axis (x, then y) and output index, (i0, i1, weight of
    /// i1), as `ocellus_image::resample::Resampler::tables`.
    pub rescale: Vec<[Vec<(usize, usize, f32)>; 2]>,
    /// The plane each sub-feature reads.
    pub subfeatures: Vec<PlaneSource>,
    /// Feature maps as (sub-feature, center level, surround level), grouped by sub-feature
    /// (each sub-feature's maps consecutive, sub-features in order).
    pub features: Vec<(usize, usize, usize)>,
    /// The channels, in order, covering the sub-features in order.
    pub channels: Vec<ChannelSpec>,
    /// Width of the linear border ramp of the center-surround maps, pixels.
    pub border_ramp: usize,
    /// N(.).
    pub normalization: GpuNormalization,
    /// Range feature maps are scaled to before N(.).
    pub feature_range: f32,
    /// Maps whose range is at most this are flat (set to half the range).
    pub flat_tolerance: f32,
    /// Range of the final saliency map (rescaled with N(.)), if any.
    pub final_range: Option<f32>,
}

/// The map-level stages on the device: their passes, and the buffer of their maps (feature
/// maps, sub-feature sums, conspicuity maps, saliency map, each `map_size`, in that order;
/// then the normalized feature maps, which are not read back).
pub(crate) struct BackEnd {
    pub(crate) passes: Vec<Pass>,
    pub(crate) maps: wgpu::Buffer,
    /// Number of maps in `maps`.
    pub(crate) n_maps: usize,
    /// Offset (floats) of the saliency map in `maps`.
    pub(crate) saliency_at: usize,
    pub(crate) map_size: (usize, usize),
}

/// Offsets (floats) of a used level's planes in the front end's plane buffer: intensity,
/// red-green, blue-yellow, first Gabor plane (the angles follow, one plane apart).
pub(crate) type LevelOffsets = [u64; 4];

impl BackEnd {
    /// Builds the passes of `spec` reading `planes` (levels at `used` with `offsets`).
    pub(crate) fn new(
        ctx: &GpuContext,
        spec: &BackEndSpec,
        sizes: &[(usize, usize)],
        used: &[usize],
        offsets: &[LevelOffsets],
        n_angles: usize,
        [planes, energies]: [&wgpu::Buffer; 2],
        energies_at: usize,
    ) -> Result<Self> {
        let bad = |m: String| Err(GpuError::InvalidInput(m));
        let (mw, mh) = spec.map_size;
        let n = mw * mh;
        if n == 0 {
            return bad("empty map level".into());
        }
        if spec.rescale.len() != used.len() {
            return bad(format!("{} rescale tables for {} used levels", spec.rescale.len(), used.len()));
        }
        let ns = spec.subfeatures.len();
        if let Some(PlaneSource::Orientation(a)) =
            spec.subfeatures.iter().find(|s| matches!(s, PlaneSource::Orientation(a) if *a >= n_angles))
        {
            return bad(format!("orientation {a} of {n_angles} angles"));
        }
        let level_index = |l: usize| used.iter().position(|&u| u == l);
        // Sub-feature ranges of the feature list.
        let mut sub_ranges = vec![(0usize, 0usize); ns];
        for (f, &(s, c, su)) in spec.features.iter().enumerate() {
            if s >= ns || level_index(c).is_none() || level_index(su).is_none() {
                return bad(format!("feature map {f}: sub-feature {s}, levels {c}/{su} not computed"));
            }
            let r = &mut sub_ranges[s];
            if r.1 == 0 {
                *r = (f, 1);
            } else if r.0 + r.1 == f {
                r.1 += 1;
            } else {
                return bad("feature maps must be grouped by sub-feature".into());
            }
        }
        let mut next = 0;
        for c in &spec.channels {
            if c.first_subfeature != next || c.subfeatures == 0 || !c.weight.is_finite() {
                return bad("channels must cover the sub-features in order, with finite weights".into());
            }
            next += c.subfeatures;
        }
        if next != ns {
            return bad(format!("channels cover {next} of {ns} sub-features"));
        }
        for [xs, ys] in &spec.rescale {
            if xs.len() != mw || ys.len() != mh {
                return bad("a rescale table does not match the map size".into());
            }
        }

        // The tables, one u32 buffer.
        let mut t: Vec<u32> = Vec::new();
        let f = |v: f32| v.to_bits();
        let mut axis_at = Vec::new();
        for (li, [xs, ys]) in spec.rescale.iter().enumerate() {
            let (sw, sh) = sizes[used[li]];
            if xs.iter().any(|e| e.0.max(e.1) >= sw) || ys.iter().any(|e| e.0.max(e.1) >= sh) {
                return bad(format!("rescale table of level {} points outside it", used[li]));
            }
            let at = t.len();
            for &(i0, i1, w) in xs.iter().chain(ys) {
                t.extend([i0 as u32, i1 as u32, f(w)]);
            }
            axis_at.push((at, at + 3 * mw));
        }
        // (buffer: 0 the opponency planes, 1 the Gabor energies; offset in it).
        let plane_offset = |s: PlaneSource, li: usize| -> (u32, u64) {
            let o = offsets[li];
            match s {
                PlaneSource::Intensity => (0, o[0]),
                PlaneSource::RedGreen => (0, o[1]),
                PlaneSource::BlueYellow => (0, o[2]),
                PlaneSource::Orientation(a) => {
                    (1, o[3] - energies_at as u64 + (a * sizes[used[li]].0 * sizes[used[li]].1) as u64)
                }
            }
        };
        let rescaled_at = |s: usize, li: usize| ((s * used.len() + li) * n) as u32;
        let rescale_jobs = t.len();
        for (s, &src) in spec.subfeatures.iter().enumerate() {
            for (li, &l) in used.iter().enumerate() {
                let (xs, ys) = axis_at[li];
                let (buffer, at) = plane_offset(src, li);
                t.extend([at as u32, sizes[l].0 as u32, buffer, rescaled_at(s, li), xs as u32, ys as u32]);
            }
        }
        let feature_jobs = t.len();
        for &(s, c, su) in &spec.features {
            // Checked above: both levels are used.
            let (ci, si) = (level_index(c).unwrap_or(0), level_index(su).unwrap_or(0));
            t.extend([rescaled_at(s, ci), rescaled_at(s, si)]);
        }
        let sub_jobs = t.len();
        for &(first, count) in &sub_ranges {
            t.extend([first as u32, count as u32]);
        }
        let channel_jobs = t.len();
        for c in &spec.channels {
            t.extend([c.first_subfeature as u32, c.subfeatures as u32, f(c.weight), u32::from(c.subfeatures > 1)]);
        }
        let (mut kind, mut iterations, mut relative, mut inhibition) = (0u32, 0u32, 0u32, 0f32);
        let (mut ex, mut inh) = ([0u32; 4], [0u32; 4]);
        match &spec.normalization {
            GpuNormalization::None => {}
            GpuNormalization::LocalMax => kind = 2,
            GpuNormalization::Iterative {
                excitation,
                inhibition: k_in,
                iterations: it,
                global_inhibition,
                relative_to_max,
            } => {
                kind = 1;
                iterations = *it as u32;
                relative = u32::from(*relative_to_max);
                inhibition = *global_inhibition;
                for (k, out) in [(excitation, &mut ex), (k_in, &mut inh)] {
                    if k.is_empty() || k.len().is_multiple_of(2) || k.iter().sum::<f32>() <= 0.0 {
                        return bad("N(.) kernels need an odd length and a positive sum".into());
                    }
                    let at = t.len() as u32;
                    t.extend(k.iter().map(|&v| f(v)));
                    let fx = t.len() as u32;
                    t.extend(preserving_factors(k, mw).into_iter().map(f));
                    let fy = t.len() as u32;
                    t.extend(preserving_factors(k, mh).into_iter().map(f));
                    *out = [k.len() as u32, at, fx, fy];
                }
            }
        }
        let nf = spec.features.len();
        let nc = spec.channels.len();
        let (subs_at, consp_at, saliency_at) = (nf * n, (nf + ns) * n, (nf + ns + nc) * n);
        let n_maps = nf + ns + nc + 1;
        let params: [u32; 32] = [
            mw as u32,
            mh as u32,
            (ns * used.len()) as u32,
            nf as u32,
            ns as u32,
            nc as u32,
            kind,
            iterations,
            relative,
            f(inhibition),
            f(spec.feature_range),
            f(spec.flat_tolerance),
            f(spec.final_range.unwrap_or(0.0)),
            spec.border_ramp as u32,
            ex[0],
            inh[0],
            ex[1],
            inh[1],
            ex[2],
            ex[3],
            inh[2],
            inh[3],
            rescale_jobs as u32,
            feature_jobs as u32,
            sub_jobs as u32,
            channel_jobs as u32,
            subs_at as u32,
            consp_at as u32,
            saliency_at as u32,
            (n_maps * n) as u32,
            0,
            0,
        ];
        let workgroups = nf.max(ns).max(1);
        let limits = ctx.limits();
        let scratch_bytes = 16 * (workgroups * n) as u64;
        let most = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if scratch_bytes > most || 4 * (ns * used.len() * n) as u64 > most || 4 * ((n_maps + nf) * n) as u64 > most {
            return bad(format!("maps of {mw}x{mh} need more buffer space than this device binds ({most} bytes)"));
        }
        if workgroups.max(ns * used.len()) as u64 > u64::from(limits.max_compute_workgroups_per_dimension) {
            return bad("more maps than this device runs workgroups in one dispatch".into());
        }

        let device = &ctx.device;
        let init = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let storage = |floats: usize, label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 4 * floats.max(1) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let params = init("back-end params", bytemuck::cast_slice(&params), wgpu::BufferUsages::UNIFORM);
        let tables = init("back-end tables", bytemuck::cast_slice(&t), wgpu::BufferUsages::STORAGE);
        let rescaled = storage(ns * used.len() * n, "rescaled levels");
        let maps = storage((n_maps + nf) * n, "maps");
        let scratch = storage(4 * workgroups * n, "N(.) scratch");

        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let rw = wgpu::BufferBindingType::Storage { read_only: false };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("back end"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, ro),
                entry(2, ro),
                entry(3, rw),
                entry(4, rw),
                entry(5, rw),
                entry(6, ro),
            ],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("back end"),
            layout: &layout,
            entries: &[&params, planes, &tables, &rescaled, &maps, &scratch, energies]
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
                .collect::<Vec<_>>(),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("back end"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("back end"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/back_end.wgsl").into()),
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let mut passes = Vec::new();
        for (entry, groups) in
            [("rescale", ns * used.len()), ("features", nf), ("subfeatures", ns), ("combine", usize::from(nc > 0))]
        {
            if groups > 0 {
                passes.push(Pass {
                    pipeline: pipeline(entry),
                    bind_group: bind_group.clone(),
                    groups: [groups as u32, 1, 1],
                });
            }
        }
        Ok(Self { passes, maps, n_maps, saliency_at, map_size: spec.map_size })
    }
}
