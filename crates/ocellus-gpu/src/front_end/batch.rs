//! Batches: several frames through the whole pipeline in one submission and one readback.
//!
//! A frame alone pays the fixed costs of a round trip to the device (a submission, a fence,
//! mapping the readback buffer) that on a discrete GPU can exceed its compute time. A batch
//! uploads all its frames into slots of one input buffer, encodes the pipeline once per
//! frame (the intermediate buffers are reused: the device runs the frames one after the
//! other), copies each saliency map into its slot of a readback buffer, and waits once.

use super::{FrontEndTimings, GpuFrontEnd};
use crate::{GpuError, Result};
use ocellus_image::Plane;
use std::time::Instant;

/// The unpack pass's pieces, to bind it to each slot of a batch's input.
pub(crate) struct Unpack {
    pub(crate) pipeline: wgpu::ComputePipeline,
    pub(crate) dims: wgpu::Buffer,
    pub(crate) level0: [wgpu::Buffer; 3],
    pub(crate) groups: [u32; 3],
}

/// The buffers of a batch of up to `slots` frames.
pub(crate) struct Batch {
    slots: usize,
    /// Bytes between two frames in `input` (a multiple of the binding alignment).
    stride: u64,
    input: wgpu::Buffer,
    unpack: Vec<wgpu::BindGroup>,
    staging: wgpu::Buffer,
}

impl GpuFrontEnd {
    /// Grows the batch buffers to hold `slots` frames.
    fn batch_for(&mut self, slots: usize) -> Result<&Batch> {
        if self.batch.as_ref().is_none_or(|b| b.slots < slots) {
            let device = &self.ctx.device;
            let limits = self.ctx.limits();
            let align = u64::from(limits.min_storage_buffer_offset_alignment.max(4));
            let frame_bytes = self.bytes.len() as u64;
            let stride = frame_bytes.div_ceil(align) * align;
            let (map_w, map_h) = self.back.as_ref().map_or((0, 0), |b| b.map_size);
            let map_bytes = 4 * (map_w * map_h) as u64;
            if stride * slots as u64 > limits.max_buffer_size || map_bytes * slots as u64 > limits.max_buffer_size {
                return Err(GpuError::InvalidInput(format!(
                    "a batch of {slots} frames of {}x{} exceeds this device's largest buffer ({} bytes)",
                    self.width, self.height, limits.max_buffer_size
                )));
            }
            let input = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("rgb8 batch"),
                size: stride * slots as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let layout = self.unpack.pipeline.get_bind_group_layout(0);
            let unpack = (0..slots as u64)
                .map(|b| {
                    let slot = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &input,
                        offset: b * stride,
                        size: std::num::NonZeroU64::new(frame_bytes),
                    });
                    let [r, g, bl] = &self.unpack.level0;
                    let resources = [
                        self.unpack.dims.as_entire_binding(),
                        slot,
                        r.as_entire_binding(),
                        g.as_entire_binding(),
                        bl.as_entire_binding(),
                    ];
                    let entries: Vec<wgpu::BindGroupEntry> = resources
                        .into_iter()
                        .enumerate()
                        .map(|(i, resource)| wgpu::BindGroupEntry { binding: i as u32, resource })
                        .collect();
                    device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: None,
                        layout: &layout,
                        entries: &entries,
                    })
                })
                .collect();
            let staging = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("saliency batch readback"),
                size: (map_bytes * slots as u64).max(4),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.batch = Some(Batch { slots, stride, input, unpack, staging });
        }
        self.batch.as_ref().ok_or_else(|| GpuError::InvalidInput("no batch buffers".into()))
    }

    /// Runs the whole pipeline (built with `FrontEndSpec::back_end`) on every frame of
    /// `frames` in one submission and reads back only their saliency maps into `saliency`
    /// (one per frame, in order, each resized to the map size). Other maps and levels are
    /// not read back. The timings cover the whole batch.
    pub fn process_batch<'a>(
        &mut self,
        frames: &[&Plane<[u8; 3]>],
        saliency: impl IntoIterator<Item = &'a mut Plane<f32>>,
    ) -> Result<()> {
        let Some(back) = &self.back else {
            return Err(GpuError::InvalidInput("this GPU engine was built without the map-level stages".into()));
        };
        let ((map_w, map_h), sal_at) = (back.map_size, back.saliency_at);
        if let Some(f) = frames.iter().find(|f| f.size() != (self.width, self.height)) {
            return self.pack(f);
        }
        if frames.is_empty() {
            return Ok(());
        }
        let t0 = Instant::now();
        let stride = self.batch_for(frames.len())?.stride;
        for (b, frame) in frames.iter().enumerate() {
            self.pack(frame)?;
            if let Some(batch) = &self.batch {
                self.ctx.queue.write_buffer(&batch.input, b as u64 * stride, &self.bytes);
            }
        }
        let t1 = Instant::now();
        let (Some(batch), Some(back)) = (&self.batch, &self.back) else {
            return Err(GpuError::InvalidInput("no batch buffers".into()));
        };
        let map_bytes = 4 * (map_w * map_h) as u64;
        let mut encoder =
            self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("saliency batch") });
        for b in 0..frames.len() {
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
                pass.set_pipeline(&self.unpack.pipeline);
                pass.set_bind_group(0, &batch.unpack[b], &[]);
                let g = self.unpack.groups;
                pass.dispatch_workgroups(g[0], g[1], g[2]);
                // The first pass of the single-frame list is its own unpack.
                for p in self.passes.iter().skip(1).chain(&back.passes) {
                    p.record(&mut pass);
                }
            }
            encoder.copy_buffer_to_buffer(
                &back.maps,
                4 * sal_at as u64,
                &batch.staging,
                b as u64 * map_bytes,
                map_bytes,
            );
        }
        self.ctx.queue.submit([encoder.finish()]);
        let end = map_bytes * frames.len() as u64;
        self.wait_for_read(&batch.staging, end)?;
        let t2 = Instant::now();
        {
            let view = batch.staging.get_mapped_range(..end).map_err(|e| GpuError::Readback(e.to_string()))?;
            let data: &[f32] = bytemuck::cast_slice(&view);
            let n = map_w * map_h;
            for (b, dst) in saliency.into_iter().take(frames.len()).enumerate() {
                super::copy_plane(&data[b * n..(b + 1) * n], map_w, map_h, dst);
            }
        }
        batch.staging.unmap();
        self.timings = FrontEndTimings { upload: t1 - t0, gpu: t2 - t1, readback: t2.elapsed() };
        Ok(())
    }
}
