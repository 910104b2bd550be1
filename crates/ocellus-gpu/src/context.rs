//! The device: one adapter, one device and its queue, shared by the engines built on it.

use crate::{GpuError, Result};

/// A GPU device and its queue.
#[derive(Debug, Clone)]
pub struct GpuContext {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
}

impl GpuContext {
    /// Opens the first high-performance adapter of any backend wgpu was built with; a
    /// software adapter (lavapipe) when there is no hardware one.
    pub fn new() -> Result<Self> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        };
        let adapter =
            pollster::block_on(instance.request_adapter(&options)).map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        // The adapter's own limits (storage buffers of a full-size frame exceed the defaults'
        // 128 MiB on large frames).
        let limits = adapter.limits();
        let desc = wgpu::DeviceDescriptor {
            label: Some("ocellus"),
            required_features: wgpu::Features::empty(),
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&desc)).map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(Self { device, queue, info, limits })
    }

    /// One device for the whole process, opened on first use ([`Self::new`]); engines built
    /// later share it instead of each opening an adapter (tens of milliseconds, and memory).
    /// A failure is remembered too: every later call returns the same error.
    pub fn shared() -> Result<Self> {
        static SHARED: std::sync::OnceLock<std::result::Result<GpuContext, String>> = std::sync::OnceLock::new();
        match SHARED.get_or_init(|| Self::new().map_err(|e| e.to_string())) {
            Ok(c) => Ok(c.clone()),
            Err(e) => Err(GpuError::NoAdapter(e.clone())),
        }
    }

    /// The adapter: name, backend, driver, and whether it is a CPU (software) device.
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// One line naming the adapter, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), Vulkan, Cpu".
    pub fn describe(&self) -> String {
        format!("{}, {:?}, {:?}", self.info.name, self.info.backend, self.info.device_type)
    }

    /// The device's limits.
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }
}
