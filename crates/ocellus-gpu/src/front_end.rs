//! The saliency pipeline on the GPU: the per-pixel front end (the colour pyramids, the
//! opponency planes and the Gabor energies of the levels the center-surround pairs read) and,
//! when built with them, the map-level stages (`back_end`), in one command buffer per frame;
//! what is asked is read back through one host-visible buffer.

use crate::back_end::{BackEnd, BackEndSpec, LevelOffsets};
use crate::{GpuContext, GpuError, Result};
use ocellus_image::pyramid::PyramidKernel;
use ocellus_image::Plane;
use std::sync::mpsc;
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

mod batch;

/// Angles the Gabor shader holds at once (its accumulator array).
pub const MAX_ANGLES: usize = 8;

/// The shader programs, in the order of [`Program`].
const SHADERS: [(&str, &str, &str); 5] = [
    ("unpack", include_str!("shaders/unpack.wgsl"), "main"),
    ("pyr_vertical", include_str!("shaders/pyr_down.wgsl"), "vertical"),
    ("pyr_horizontal", include_str!("shaders/pyr_down.wgsl"), "horizontal"),
    ("opponency", include_str!("shaders/opponency.wgsl"), "main"),
    ("gabor", include_str!("shaders/gabor.wgsl"), "main"),
];

#[derive(Clone, Copy)]
enum Program {
    Unpack = 0,
    PyrVertical = 1,
    PyrHorizontal = 2,
    Opponency = 3,
    Gabor = 4,
}

/// One dispatch: its program, bindings and workgroup counts.
pub(crate) struct Pass {
    pub(crate) pipeline: wgpu::ComputePipeline,
    pub(crate) bind_group: wgpu::BindGroup,
    pub(crate) groups: [u32; 3],
}

impl Pass {
    /// Records the dispatch into `pass`.
    fn record(&self, pass: &mut wgpu::ComputePass) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups(self.groups[0], self.groups[1], self.groups[2]);
    }
}

/// What the front end computes, in plain terms; the saliency engine (`ocellus-attention`,
/// feature `gpu`) fills it from its configuration.
#[derive(Clone, Debug)]
pub struct FrontEndSpec {
    /// Size of every pyramid level (width, height), level 0 (the frame) first.
    pub level_sizes: Vec<(usize, usize)>,
    /// Levels whose opponency planes (and Gabor energies) are computed and read back.
    pub used_levels: Vec<usize>,
    /// The pyramid's low-pass kernel; its [`PyramidKernel::taps_for`] rule builds the tap
    /// tables, so borders are truncated and renormalized exactly as on the CPU.
    pub pyramid: PyramidKernel,
    /// Intensity weights of r, g, b (`I = w . (r, g, b)`).
    pub intensity_weights: [f32; 3],
    /// Opponency is 0 where max(r, g, b) is below this (values in [0, 1]).
    pub color_threshold: f32,
    /// Gabor kernels per angle, (even, odd), each `gabor_size` x `gabor_size` row-major,
    /// correlated with edge pixels repeated outward; empty: no orientation channel.
    pub gabor: Vec<[Vec<f32>; 2]>,
    /// Side of the Gabor kernels, pixels (odd).
    pub gabor_size: usize,
    /// The map-level stages (rescaling, center-surround, N(.), combination) to run on the
    /// device after the front end ([`GpuFrontEnd::process_maps`]); `None`: front end only.
    pub back_end: Option<BackEndSpec>,
}

/// The GPU saliency pipeline for frames of one size: the front end, and the map-level
/// stages when its spec has them.
pub struct GpuFrontEnd {
    ctx: GpuContext,
    width: usize,
    height: usize,
    sizes: Vec<(usize, usize)>,
    used: Vec<usize>,
    n_angles: usize,
    passes: Vec<Pass>,
    input: wgpu::Buffer,
    /// The used levels' opponency planes (see `offsets`).
    planes: wgpu::Buffer,
    /// The used levels' Gabor energies.
    energies: wgpu::Buffer,
    /// Offsets (floats) of each used level's planes in `planes` then `energies`, one after
    /// the other.
    offsets: Vec<LevelOffsets>,
    /// Bytes of `planes`, and of both.
    opp_bytes: u64,
    planes_bytes: u64,
    /// The map-level stages, when built.
    back: Option<BackEnd>,
    maps_bytes: u64,
    /// Host-visible copy of the maps (first) and the levels (after them).
    staging: wgpu::Buffer,
    bytes: Vec<u8>,
    timings: FrontEndTimings,
    /// What a batch needs to unpack each of its frames.
    unpack: batch::Unpack,
    /// The buffers of the largest batch run so far.
    batch: Option<batch::Batch>,
}

/// Where the used levels' planes are read back to: the opponency pyramids (intensity,
/// red-green, blue-yellow; indexed by level) and the Gabor energies (by level, then angle).
pub type LevelsOut<'a> = (&'a mut [Vec<Plane<f32>>; 3], &'a mut Vec<Vec<Plane<f32>>>);

/// Wall time of one frame through the front end, by phase.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrontEndTimings {
    /// Packing the frame's bytes and queueing their upload.
    pub upload: Duration,
    /// From submitting the dispatches until the results sit in the readback buffer (the
    /// upload's transfer, every shader, and the copy to host-visible memory).
    pub gpu: Duration,
    /// Copying the mapped results into the planes.
    pub readback: Duration,
}

impl std::fmt::Debug for GpuFrontEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuFrontEnd")
            .field("adapter", &self.ctx.describe())
            .field("size", &(self.width, self.height))
            .field("levels", &self.used)
            .finish_non_exhaustive()
    }
}

fn groups(n: usize, per: usize) -> u32 {
    n.div_ceil(per).max(1) as u32
}

impl GpuFrontEnd {
    /// Builds the front end of `spec` on `ctx`: pipelines, buffers and the command list of a
    /// frame. Errors for an inconsistent spec (no levels, a used level past the top, more
    /// than [`MAX_ANGLES`] angles, kernels of the wrong size) or a frame whose buffers exceed
    /// the device's limits.
    pub fn new(ctx: &GpuContext, spec: &FrontEndSpec) -> Result<Self> {
        let Some(&(width, height)) = spec.level_sizes.first() else {
            return Err(GpuError::InvalidInput("no pyramid levels".into()));
        };
        let sizes = spec.level_sizes.clone();
        let used = spec.used_levels.clone();
        if let Some(l) = used.iter().find(|&&l| l >= sizes.len()) {
            return Err(GpuError::InvalidInput(format!("level {l} of a {}-level pyramid", sizes.len())));
        }
        let n_angles = spec.gabor.len();
        let with_ori = n_angles > 0;
        if n_angles > MAX_ANGLES {
            return Err(GpuError::Unsupported(format!("{n_angles} Gabor angles (at most {MAX_ANGLES})")));
        }
        let taps = spec.gabor_size * spec.gabor_size;
        if with_ori
            && (spec.gabor_size.is_multiple_of(2) || spec.gabor.iter().any(|[e, o]| e.len() != taps || o.len() != taps))
        {
            return Err(GpuError::InvalidInput(format!(
                "Gabor kernels must be {0}x{0} with an odd side",
                spec.gabor_size
            )));
        }
        if spec.pyramid.taps.is_empty() {
            return Err(GpuError::InvalidInput("an empty pyramid kernel".into()));
        }
        let top = sizes.len() - 1;
        let input_bytes = (3 * width * height).div_ceil(4) * 4;
        let gabor_planes = used.iter().map(|&l| n_angles * sizes[l].0 * sizes[l].1).max().unwrap_or(0);
        let largest = 4 * (width * height).max(input_bytes / 4).max(gabor_planes) as u64;
        if largest > ctx.limits().max_storage_buffer_binding_size || largest > ctx.limits().max_buffer_size {
            return Err(GpuError::InvalidInput(format!(
                "a {width}x{height} frame needs storage buffers of {largest} bytes; this device binds at most {}",
                ctx.limits().max_storage_buffer_binding_size
            )));
        }

        let device = &ctx.device;
        let pipelines: Vec<wgpu::ComputePipeline> = SHADERS
            .iter()
            .map(|(label, source, entry)| {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(label),
                    source: wgpu::ShaderSource::Wgsl((*source).into()),
                });
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(label),
                    layout: None,
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
            })
            .collect();
        let storage = |n: usize, label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 4 * n.max(1) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let init = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let uniform = |words: [u32; 8]| init("dims", bytemuck::cast_slice(&words), wgpu::BufferUsages::UNIFORM);
        let bind_parts = |program: Program, resources: Vec<wgpu::BindingResource>| {
            let layout = pipelines[program as usize].get_bind_group_layout(0);
            let entries: Vec<wgpu::BindGroupEntry> = resources
                .into_iter()
                .enumerate()
                .map(|(i, resource)| wgpu::BindGroupEntry { binding: i as u32, resource })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout: &layout, entries: &entries })
        };
        let bind = |program: Program, buffers: &[&wgpu::Buffer]| {
            bind_parts(program, buffers.iter().map(|b| b.as_entire_binding()).collect())
        };
        let pass = |program: Program, bind_group: wgpu::BindGroup, groups: [u32; 3]| Pass {
            pipeline: pipelines[program as usize].clone(),
            bind_group,
            groups,
        };

        let input = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rgb8"),
            size: input_bytes as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let rgb: Vec<Vec<wgpu::Buffer>> =
            (0..3).map(|_| sizes.iter().map(|&(w, h)| storage(w * h, "colour level")).collect()).collect();
        let tmp = storage((0..top).map(|l| sizes[l].0 * sizes[l + 1].1).max().unwrap_or(1), "pyramid rows");
        let mut passes = Vec::new();

        let n = width * height;
        let blocks = n.div_ceil(256);
        let unpack_dims = uniform([n as u32, 0, 0, 0, 0, 0, 0, 0]);
        let unpack_groups = [blocks.min(65535) as u32, blocks.div_ceil(65535) as u32, 1];
        passes.push(pass(
            Program::Unpack,
            bind(Program::Unpack, &[&unpack_dims, &input, &rgb[0][0], &rgb[1][0], &rgb[2][0]]),
            unpack_groups,
        ));
        let unpack = batch::Unpack {
            pipeline: pipelines[Program::Unpack as usize].clone(),
            dims: unpack_dims.clone(),
            level0: [rgb[0][0].clone(), rgb[1][0].clone(), rgb[2][0].clone()],
            groups: unpack_groups,
        };

        // Tap tables from the CPU's own rule (PyramidKernel::taps_for), padded with zero
        // weights to the kernel's length.
        let k = spec.pyramid.taps.len().max(3);
        let table = |n_out: usize, n_in: usize| -> Vec<u32> {
            let mut taps = Vec::new();
            let mut words = Vec::with_capacity(2 * k * n_out);
            for j in 0..n_out {
                spec.pyramid.taps_for(j, n_in, &mut taps);
                for t in 0..k {
                    let (i, w) = taps.get(t).copied().unwrap_or((0, 0.0));
                    words.extend([i as u32, w.to_bits()]);
                }
            }
            words
        };
        for l in 0..top {
            let ((wi, hi), (wo, ho)) = (sizes[l], sizes[l + 1]);
            let vt = init("vertical taps", bytemuck::cast_slice(&table(ho, hi)), wgpu::BufferUsages::STORAGE);
            let ht = init("horizontal taps", bytemuck::cast_slice(&table(wo, wi)), wgpu::BufferUsages::STORAGE);
            let vd = uniform([wi as u32, hi as u32, wi as u32, ho as u32, k as u32, 0, 0, 0]);
            let hd = uniform([wi as u32, ho as u32, wo as u32, ho as u32, k as u32, 0, 0, 0]);
            for c in 0..3 {
                passes.push(pass(
                    Program::PyrVertical,
                    bind(Program::PyrVertical, &[&vd, &rgb[c][l], &vt, &tmp]),
                    [groups(wi, 64), groups(ho, 4), 1],
                ));
                passes.push(pass(
                    Program::PyrHorizontal,
                    bind(Program::PyrHorizontal, &[&hd, &tmp, &ht, &rgb[c][l + 1]]),
                    [groups(wo, 64), groups(ho, 4), 1],
                ));
            }
        }

        let weights = spec.intensity_weights;
        let threshold = spec.color_threshold;
        let kernels: Vec<f32> = if with_ori {
            (0..taps).flat_map(|t| spec.gabor.iter().flat_map(move |[e, o]| [e[t], o[t]])).collect()
        } else {
            vec![0.0; 2]
        };
        let kernels = init("gabor kernels", bytemuck::cast_slice(&kernels), wgpu::BufferUsages::STORAGE);
        // Every used level's opponency planes in one buffer, and their Gabor energies in
        // another (a dispatch may not read and write one buffer), each plane at an offset
        // the device can bind: the map-level stages read them all through two bindings, and
        // two copies read them back. Offsets count floats in the two buffers one after the
        // other.
        let align = (ctx.limits().min_storage_buffer_offset_alignment as usize / 4).max(1);
        let up = |v: usize| v.div_ceil(align) * align;
        let mut offsets: Vec<LevelOffsets> = Vec::with_capacity(used.len());
        let mut end = 0usize;
        for &l in &used {
            let n = sizes[l].0 * sizes[l].1;
            let o = [end, up(end + n), up(up(end + n) + n)].map(|v| v as u64);
            end = up(o[2] as usize + n);
            offsets.push([o[0], o[1], o[2], 0]);
        }
        let opp_floats = end;
        for (li, &l) in used.iter().enumerate() {
            offsets[li][3] = end as u64;
            end = up(end + n_angles * sizes[l].0 * sizes[l].1);
        }
        let most = ctx.limits().max_storage_buffer_binding_size.min(ctx.limits().max_buffer_size);
        if 4 * opp_floats.max(end - opp_floats) as u64 > most {
            return Err(GpuError::InvalidInput(format!(
                "a {width}x{height} frame's levels need {} bytes in one buffer; this device binds at most {most}",
                4 * opp_floats.max(end - opp_floats),
            )));
        }
        let planes = storage(opp_floats, "levels");
        let energies = storage(end - opp_floats, "gabor energies");
        let part = |buffer, at: u64, floats: usize| {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset: 4 * at,
                size: std::num::NonZeroU64::new(4 * floats.max(1) as u64),
            })
        };
        for (li, &l) in used.iter().enumerate() {
            let (w, h) = sizes[l];
            let o = offsets[li];
            let dims = uniform([
                (w * h) as u32,
                0,
                0,
                0,
                weights[0].to_bits(),
                weights[1].to_bits(),
                weights[2].to_bits(),
                threshold.to_bits(),
            ]);
            let resources = vec![
                dims.as_entire_binding(),
                rgb[0][l].as_entire_binding(),
                rgb[1][l].as_entire_binding(),
                rgb[2][l].as_entire_binding(),
                part(&planes, o[0], w * h),
                part(&planes, o[1], w * h),
                part(&planes, o[2], w * h),
            ];
            passes.push(pass(
                Program::Opponency,
                bind_parts(Program::Opponency, resources),
                [groups(w * h, 256), 1, 1],
            ));
            if with_ori {
                let dims = uniform([w as u32, h as u32, spec.gabor_size as u32, n_angles as u32, 0, 0, 0, 0]);
                let resources = vec![
                    dims.as_entire_binding(),
                    part(&planes, o[0], w * h),
                    kernels.as_entire_binding(),
                    part(&energies, o[3] - opp_floats as u64, n_angles * w * h),
                ];
                passes.push(pass(
                    Program::Gabor,
                    bind_parts(Program::Gabor, resources),
                    [groups(w, 16), groups(h, 16), 1],
                ));
            }
        }
        let back = match &spec.back_end {
            Some(b) => Some(BackEnd::new(ctx, b, &sizes, &used, &offsets, n_angles, [&planes, &energies], opp_floats)?),
            None => None,
        };
        let (opp_bytes, planes_bytes) = (4 * opp_floats as u64, 4 * end as u64);
        let maps_bytes = back.as_ref().map_or(0, |b| 4 * (b.n_maps * b.map_size.0 * b.map_size.1) as u64);
        let most = ctx.limits().max_compute_workgroups_per_dimension;
        if let Some(p) = passes.iter().find(|p| p.groups.iter().any(|&g| g > most)) {
            return Err(GpuError::InvalidInput(format!(
                "a {width}x{height} frame needs {:?} workgroups in one dispatch; this device allows {most} per dimension",
                p.groups
            )));
        }
        // The maps first, then the levels: a frame that reads back only the maps maps the
        // start of the buffer.
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (maps_bytes + planes_bytes).max(4),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            ctx: ctx.clone(),
            width,
            height,
            sizes,
            used,
            n_angles,
            passes,
            input,
            planes,
            energies,
            offsets,
            opp_bytes,
            planes_bytes,
            back,
            maps_bytes,
            staging,
            bytes: vec![0; input_bytes],
            timings: FrontEndTimings::default(),
            unpack,
            batch: None,
        })
    }

    /// Runs the front end on an 8-bit RGB frame: `opponency[k][l]` (k: intensity, red-green,
    /// blue-yellow) and `orientation[l][a]` receive level `l`'s planes for every used level;
    /// the outer vectors grow to the pyramid's height, other levels are left as they are.
    /// The map-level stages, if built, do not run.
    pub fn process(
        &mut self,
        frame: &Plane<[u8; 3]>,
        opponency: &mut [Vec<Plane<f32>>; 3],
        orientation: &mut Vec<Vec<Plane<f32>>>,
    ) -> Result<()> {
        self.run(frame, None, Some((opponency, orientation)))
    }

    /// Runs the whole pipeline (built with [`FrontEndSpec::back_end`]) on an 8-bit RGB frame
    /// and reads back its maps into `maps`, in order: the feature maps, the sub-feature
    /// maps, the conspicuity maps and the saliency map (each resized to the map size);
    /// `levels`, when given, receives the used levels' planes as [`Self::process`] does.
    pub fn process_maps<'a>(
        &mut self,
        frame: &Plane<[u8; 3]>,
        maps: impl IntoIterator<Item = &'a mut Plane<f32>>,
        levels: Option<LevelsOut>,
    ) -> Result<()> {
        if self.back.is_none() {
            return Err(GpuError::InvalidInput("this GPU engine was built without the map-level stages".into()));
        }
        let mut maps = maps.into_iter();
        self.run(frame, Some(&mut maps), levels)
    }

    /// Uploads `frame`, runs the front end (and the back end when `maps` is given), and reads
    /// back what is asked.
    fn run(
        &mut self,
        frame: &Plane<[u8; 3]>,
        maps: Option<&mut dyn Iterator<Item = &mut Plane<f32>>>,
        levels: Option<LevelsOut>,
    ) -> Result<()> {
        let t0 = Instant::now();
        self.pack(frame)?;
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        queue.write_buffer(&self.input, 0, &self.bytes);
        let t1 = Instant::now();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("saliency") });
        let back = self.back.as_ref().filter(|_| maps.is_some());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            for p in self.passes.iter().chain(back.into_iter().flat_map(|b| &b.passes)) {
                p.record(&mut pass);
            }
        }
        if let Some(b) = back {
            encoder.copy_buffer_to_buffer(&b.maps, 0, &self.staging, 0, self.maps_bytes);
        }
        if levels.is_some() {
            let at = self.maps_bytes;
            encoder.copy_buffer_to_buffer(&self.planes, 0, &self.staging, at, self.opp_bytes);
            if self.planes_bytes > self.opp_bytes {
                let rest = self.planes_bytes - self.opp_bytes;
                encoder.copy_buffer_to_buffer(&self.energies, 0, &self.staging, at + self.opp_bytes, rest);
            }
        }
        let end = if levels.is_some() { self.maps_bytes + self.planes_bytes } else { self.maps_bytes };
        queue.submit([encoder.finish()]);
        self.wait_for_read(&self.staging, end)?;
        let t2 = Instant::now();
        if end > 0 {
            {
                let view = self.staging.get_mapped_range(..end).map_err(|e| GpuError::Readback(e.to_string()))?;
                let data: &[f32] = bytemuck::cast_slice(&view);
                if let (Some(b), Some(maps)) = (&self.back, maps) {
                    let (w, h) = b.map_size;
                    for (k, dst) in maps.take(b.n_maps).enumerate() {
                        copy_plane(&data[k * w * h..(k + 1) * w * h], w, h, dst);
                    }
                }
                if let Some((opponency, orientation)) = levels {
                    let data = &data[(self.maps_bytes / 4) as usize..];
                    self.read_levels(data, opponency, orientation);
                }
            }
            self.staging.unmap();
        }
        self.timings = FrontEndTimings { upload: t1 - t0, gpu: t2 - t1, readback: t2.elapsed() };
        Ok(())
    }

    /// Packs `frame`'s bytes into the upload buffer, after checking its size.
    fn pack(&mut self, frame: &Plane<[u8; 3]>) -> Result<()> {
        if frame.size() != (self.width, self.height) {
            return Err(GpuError::InvalidInput(format!(
                "frame is {}x{}, the GPU engine was built for {}x{}",
                frame.width(),
                frame.height(),
                self.width,
                self.height
            )));
        }
        let row_bytes = 3 * self.width;
        for (y, row) in frame.rows().enumerate() {
            self.bytes[y * row_bytes..(y + 1) * row_bytes].copy_from_slice(row.as_flattened());
        }
        Ok(())
    }

    /// Waits until the submitted work is done and the first `end` bytes of `buffer` are
    /// mapped for reading (nothing is mapped when `end` is 0).
    fn wait_for_read(&self, buffer: &wgpu::Buffer, end: u64) -> Result<()> {
        let readback = |e: &dyn std::fmt::Display| GpuError::Readback(e.to_string());
        let rx = (end > 0).then(|| {
            let (tx, rx) = mpsc::channel();
            buffer.slice(..end).map_async(wgpu::MapMode::Read, move |r| {
                // The receiver waits below; a send can only fail if it is gone.
                let _ = tx.send(r);
            });
            rx
        });
        self.ctx.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| readback(&e))?;
        if let Some(rx) = rx {
            rx.recv().map_err(|e| readback(&e))?.map_err(|e| readback(&e))?;
        }
        Ok(())
    }

    /// Copies the used levels' planes out of `data` (the level buffer's contents).
    fn read_levels(&self, data: &[f32], opponency: &mut [Vec<Plane<f32>>; 3], orientation: &mut Vec<Vec<Plane<f32>>>) {
        let n_levels = self.sizes.len();
        for p in opponency.iter_mut() {
            if p.len() < n_levels {
                p.resize_with(n_levels, Plane::default);
            }
        }
        if orientation.len() < n_levels {
            orientation.resize_with(n_levels, Vec::new);
        }
        for (li, &l) in self.used.iter().enumerate() {
            let (w, h) = self.sizes[l];
            let o = self.offsets[li].map(|v| v as usize);
            for k in 0..3 {
                copy_plane(&data[o[k]..o[k] + w * h], w, h, &mut opponency[k][l]);
            }
            let ori = &mut orientation[l];
            ori.resize_with(self.n_angles, Plane::default);
            for (a, plane) in ori.iter_mut().enumerate() {
                let at = o[3] + a * w * h;
                copy_plane(&data[at..at + w * h], w, h, plane);
            }
        }
    }

    /// Where the last frame's time went.
    pub fn timings(&self) -> FrontEndTimings {
        self.timings
    }

    /// The device this front end runs on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }
}

/// `dst` (resized to `w` x `h`) from `src`, row-major.
fn copy_plane(src: &[f32], w: usize, h: usize, dst: &mut Plane<f32>) {
    dst.resize(w, h);
    for (y, row) in src.chunks_exact(w.max(1)).take(h).enumerate() {
        dst.row_mut(y).copy_from_slice(row);
    }
}
