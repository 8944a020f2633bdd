//! Two independent halves of running-mean images: for each image a node keeps as the mean of
//! per-iteration estimates (a weighted sum and its weight per pixel), the sum of the estimates
//! of each pixel's odd updates and how many updates it had (shaders/gpu/odd_iterations.wgsl).
//! The even half is the rest of the mean; how far the halves differ measures the mean's noise
//! (src/render/error_estimate.rs). Every pixel is updated every iteration unless the band's
//! sample mask (adaptive sampling) leaves it alone.

use std::sync::Arc;

use super::binding::{Access, bind_buffers};
use super::dispatch::workgroup_grid;
use super::sample_mask::SampleMask;
use super::shaders::{ShaderFile, ShaderLibrary};
use super::{GpuContext, GpuError};

pub const SHADER: ShaderFile = crate::shader_file!("shaders/gpu/odd_iterations.wgsl");
const WORKGROUP: u32 = 256;
const PIXEL_BYTES: u64 = 16;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct SplitParams {
    pixels: u32,
    _pad: [u32; 3],
}

/// `SplitParams` against its WGSL twin (tests/shaders.rs checks it).
pub const LAYOUTS: &[super::layout::StructLayout] = &[crate::struct_layout!(
    SplitParams => "SplitParams" in SHADER, { pixels }
)];

/// One tracked image and its two state buffers.
struct Tracked {
    name: String,
    pixels: u32,
    previous: wgpu::Buffer,
    odd_sum: wgpu::Buffer,
    /// Held with the bind group that reads it.
    _params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The odd-iteration sums of a set of images, updated after every iteration.
pub struct OddIterations {
    pipeline: Option<wgpu::ComputePipeline>,
    tracked: Vec<Tracked>,
}

impl OddIterations {
    /// Tracks `images`, each named and holding `pixels` (sum, weight) vec4s, updating the
    /// pixels `mask` lets change.
    pub fn new(
        gpu: &GpuContext,
        shaders: &ShaderLibrary,
        images: &[(String, Arc<wgpu::Buffer>, u32)],
        mask: &SampleMask,
    ) -> Result<Self, GpuError> {
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let mut tracked = Vec::new();
        let mut pipeline = None;
        for (name, image, pixels) in images {
            let bytes = *pixels as u64 * PIXEL_BYTES;
            let previous = gpu.create_buffer(&format!("{name} previous mean"), bytes, usage)?;
            let odd_sum = gpu.create_buffer(&format!("{name} odd iterations"), bytes, usage)?;
            let split = SplitParams {
                pixels: *pixels,
                _pad: [0; 3],
            };
            let params = gpu.create_buffer_init(
                "odd iterations params",
                bytemuck::bytes_of(&split),
                wgpu::BufferUsages::UNIFORM,
            )?;
            let (layout, bind_group) = bind_buffers(
                gpu,
                "odd iterations",
                &[
                    (Access::Uniform, &params),
                    (Access::Read, image),
                    (Access::ReadWrite, &previous),
                    (Access::ReadWrite, &odd_sum),
                    (Access::Read, &mask.buffer),
                ],
            );
            if pipeline.is_none() {
                pipeline = Some(shaders.compute_pipeline(gpu, &SHADER, "main", &[&layout])?);
            }
            tracked.push(Tracked {
                name: name.clone(),
                pixels: *pixels,
                previous,
                odd_sum,
                _params: params,
                bind_group,
            });
        }
        Ok(Self { pipeline, tracked })
    }

    /// Submits the update after an iteration.
    pub fn update(&self, gpu: &GpuContext) {
        let Some(pipeline) = &self.pipeline else {
            return;
        };
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("odd iterations"),
            });
        for t in &self.tracked {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("odd iterations"),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &t.bind_group, &[]);
            let [x, y, z] = workgroup_grid(t.pixels.div_ceil(WORKGROUP).max(1));
            pass.dispatch_workgroups(x, y, z);
        }
        gpu.queue.submit([encoder.finish()]);
    }

    /// The tracked images' names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.tracked.iter().map(|t| t.name.as_str())
    }

    /// Every tracked image's odd-update sums (xyz: sum of estimates, w: the pixel's updates,
    /// odd and even), per pixel, in the order of [`OddIterations::names`].
    pub fn odd_sums(&self, gpu: &GpuContext) -> Result<Vec<Vec<[f32; 4]>>, GpuError> {
        self.tracked
            .iter()
            .map(|t| gpu.read_pod(&t.odd_sum, t.pixels as usize))
            .collect()
    }

    /// Buffers carried between iterations, named for a checkpoint.
    pub fn state_buffers(&self) -> Vec<(String, &wgpu::Buffer)> {
        self.tracked
            .iter()
            .flat_map(|t| {
                [
                    (format!("odd_iterations/{}/previous", t.name), &t.previous),
                    // Named apart from the format that counted odd updates only in w.
                    (
                        format!("odd_iterations/{}/odd_sum_updates", t.name),
                        &t.odd_sum,
                    ),
                ]
            })
            .collect()
    }
}
