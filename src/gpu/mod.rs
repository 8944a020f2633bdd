//! Device and adapter choice, buffers with size checks, readback and error capture.
//!
//! wgpu panics on errors it cannot hand back unless a handler is installed; this context installs
//! one that records the first error, so a validation or out-of-memory error becomes a `GpuError`
//! naming what was asked for instead of a panic.

use std::sync::{Arc, Mutex};

use wgpu::util::DeviceExt;

mod adapter;
pub mod binding;
pub mod dispatch;
pub mod layout;
pub mod odd_iterations;
pub mod pipeline_cache;
pub mod radix_sort;
pub mod sample_mask;
pub mod shaders;
pub mod timer;

pub use adapter::{adapter_label, list_adapters, mesa_version, old_lavapipe_warning};

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found (wgpu looked for Vulkan, Metal, DX12 and GL adapters).\n\
         On Debian or Ubuntu without a GPU driver, install Mesa's software Vulkan driver:\n    \
         apt-get install -y mesa-vulkan-drivers"
    )]
    NoAdapter,
    #[error("no adapter matches {requested:?}; available adapters:\n{available}")]
    AdapterNotFound {
        requested: String,
        available: String,
    },
    #[error("could not open a device on adapter {adapter}: {message}")]
    Device { adapter: String, message: String },
    #[error(
        "buffer \"{label}\" needs {size} bytes ({mib:.1} MiB) but adapter {adapter} allows at most \
         {limit} bytes ({limit_mib:.1} MiB) per {what}; render a smaller image, or ask less per \
         pixel (samples_per_iteration, merge_depth) or per iteration (photons_per_iteration)",
        mib = *size as f64 / 1048576.0,
        limit_mib = *limit as f64 / 1048576.0
    )]
    BufferTooLarge {
        label: String,
        size: u64,
        limit: u64,
        what: &'static str,
        adapter: String,
    },
    #[error(
        "out of GPU memory allocating buffer \"{label}\" of {size} bytes ({mib:.1} MiB) on {adapter}",
        mib = *size as f64 / 1048576.0
    )]
    OutOfMemory {
        label: String,
        size: u64,
        adapter: String,
    },
    #[error("GPU error on {adapter}: {message}")]
    Runtime { adapter: String, message: String },
    /// A shader that does not compose or validate, with naga_oil's report.
    #[error("{0}")]
    Shader(String),
}

/// An open device on the chosen adapter.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub features: wgpu::Features,
    pub limits: wgpu::Limits,
    first_error: Arc<Mutex<Option<String>>>,
    /// Pipelines and layouts built on this device, shared by every renderer on it.
    pub cache: pipeline_cache::PipelineCache,
}

/// Optional features used when the adapter has them; none is required.
const WANTED_FEATURES: wgpu::Features = wgpu::Features::SHADER_FLOAT32_ATOMIC
    .union(wgpu::Features::TIMESTAMP_QUERY)
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

impl GpuContext {
    /// Opens the adapter named by `choice` (an index from `hppm info` or a case-insensitive part
    /// of its name), or the best one: discrete before integrated before software.
    pub fn new(choice: Option<&str>) -> Result<Self, GpuError> {
        let adapter = adapter::choose(choice)?;
        Self::open(adapter)
    }

    /// Renders on a device a host program already has (its adapter, device and queue; wgpu's
    /// handles are clones of one device). hppm uses the optional features it wants that the
    /// device was created with (float atomics, timestamps) and the device's limits. The host's
    /// uncaptured-error handler stays in place, so GPU errors reach the host, not
    /// [`GpuContext::check_errors`].
    pub fn from_device(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        Self {
            info: adapter.get_info(),
            features: device.features() & WANTED_FEATURES,
            limits: device.limits(),
            adapter,
            device,
            queue,
            first_error: Arc::new(Mutex::new(None)),
            cache: pipeline_cache::PipelineCache::default(),
        }
    }

    fn open(adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let features = adapter.features() & WANTED_FEATURES;
        let limits = adapter.limits();
        let desc = wgpu::DeviceDescriptor {
            label: Some("hppm"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&desc)).map_err(|e| GpuError::Device {
                adapter: adapter_label(&info),
                message: e.to_string(),
            })?;
        let first_error = Arc::new(Mutex::new(None));
        let sink = first_error.clone();
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            if let Ok(mut slot) = sink.lock() {
                slot.get_or_insert_with(|| error.to_string());
            }
        }));
        Ok(Self {
            adapter,
            device,
            queue,
            info,
            features,
            limits,
            first_error,
            cache: pipeline_cache::PipelineCache::default(),
        })
    }

    /// "name (backend, device type)", recorded in every output.
    pub fn adapter_label(&self) -> String {
        adapter_label(&self.info)
    }

    pub fn has_float_atomics(&self) -> bool {
        self.features
            .contains(wgpu::Features::SHADER_FLOAT32_ATOMIC)
    }

    pub fn has_timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// The first GPU error since the device opened, if any, as a `GpuError`.
    pub fn check_errors(&self) -> Result<(), GpuError> {
        let message = self.first_error.lock().ok().and_then(|mut e| e.take());
        match message {
            Some(message) => Err(GpuError::Runtime {
                adapter: self.adapter_label(),
                message,
            }),
            None => Ok(()),
        }
    }

    fn check_size(
        &self,
        label: &str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> Result<(), GpuError> {
        let too_large = |limit: u64, what| GpuError::BufferTooLarge {
            label: label.to_string(),
            size,
            limit,
            what,
            adapter: self.adapter_label(),
        };
        if size > self.limits.max_buffer_size {
            return Err(too_large(self.limits.max_buffer_size, "buffer"));
        }
        let binding_limit = self.limits.max_storage_buffer_binding_size;
        if usage.contains(wgpu::BufferUsages::STORAGE) && size > binding_limit {
            return Err(too_large(binding_limit, "storage binding"));
        }
        Ok(())
    }

    /// Runs `create` inside an out-of-memory error scope so that an allocation failure names the
    /// buffer and its size.
    fn allocate(
        &self,
        label: &str,
        size: u64,
        create: impl FnOnce() -> wgpu::Buffer,
    ) -> Result<wgpu::Buffer, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let buffer = create();
        if pollster::block_on(scope.pop()).is_some() {
            return Err(GpuError::OutOfMemory {
                label: label.to_string(),
                size,
                adapter: self.adapter_label(),
            });
        }
        Ok(buffer)
    }

    /// A zero-initialised buffer of `size` bytes (at least 4: wgpu rejects empty bindings).
    pub fn create_buffer(
        &self,
        label: &str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> Result<wgpu::Buffer, GpuError> {
        let size = size.max(4).next_multiple_of(4);
        self.check_size(label, size, usage)?;
        self.allocate(label, size, || {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        })
    }

    /// A buffer holding `contents` (padded to 4 bytes, never empty).
    pub fn create_buffer_init(
        &self,
        label: &str,
        contents: &[u8],
        usage: wgpu::BufferUsages,
    ) -> Result<wgpu::Buffer, GpuError> {
        let mut padded;
        let mut bytes = contents;
        if bytes.is_empty() || !bytes.len().is_multiple_of(4) {
            padded = contents.to_vec();
            padded.resize(contents.len().max(4).next_multiple_of(4), 0);
            bytes = &padded;
        }
        let size = bytes.len() as u64;
        self.check_size(label, size, usage)?;
        self.allocate(label, size, || {
            self.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytes,
                    usage,
                })
        })
    }

    /// Waits for all submitted work, then reports any GPU error it raised.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Runtime {
                adapter: self.adapter_label(),
                message: e.to_string(),
            })?;
        self.check_errors()
    }

    /// Copies `size` bytes at `offset` of `buffer` (which needs COPY_SRC) back to the CPU.
    pub fn read_buffer(
        &self,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) -> Result<Vec<u8>, GpuError> {
        let size = size.next_multiple_of(4);
        let staging = self.create_buffer(
            "readback staging",
            size,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        )?;
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let (sender, receiver) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |result| {
            let _ = sender.send(result);
        });
        self.wait()?;
        let mapped = receiver.recv().ok().and_then(|r| r.ok());
        let runtime = |message: &str| GpuError::Runtime {
            adapter: self.adapter_label(),
            message: message.to_string(),
        };
        if mapped.is_none() {
            return Err(runtime("mapping the readback buffer failed"));
        }
        let view = staging
            .get_mapped_range(..)
            .map_err(|e| runtime(&e.to_string()))?;
        let bytes = view.to_vec();
        drop(view);
        staging.unmap();
        Ok(bytes)
    }

    /// Reads a buffer of plain-old-data elements back to the CPU.
    pub fn read_pod<T: bytemuck::Pod>(
        &self,
        buffer: &wgpu::Buffer,
        count: usize,
    ) -> Result<Vec<T>, GpuError> {
        let bytes = self.read_buffer(buffer, 0, (count * std::mem::size_of::<T>()) as u64)?;
        let usable = count * std::mem::size_of::<T>();
        Ok(bytemuck::pod_collect_to_vec(&bytes[..usable]))
    }
}
