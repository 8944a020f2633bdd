//! A stable least-significant-digit radix sort of (u32 key, u32 value) pairs on the GPU, 4 bits
//! per pass (8 passes), recorded into a caller's command encoder: per-block digit histograms, one
//! exclusive scan of them, and a stable scatter (shaders/gpu/radix_sort.wgsl). It needs no
//! subgroup operations and no 64-bit atomics, so it runs wherever compute shaders do.

use std::num::NonZeroU64;

use super::dispatch::workgroup_grid;
use super::shaders::{ShaderFile, ShaderLibrary};
use super::{GpuContext, GpuError};

/// The sort's kernels.
pub const SHADER: ShaderFile = crate::shader_file!("shaders/gpu/radix_sort.wgsl");
const RADIX_BITS: u32 = 4;
const PASSES: u32 = u32::BITS / RADIX_BITS;
const RADIX: u64 = 1 << RADIX_BITS;
/// Pairs per workgroup (`BLOCK` in the shader).
const BLOCK: u32 = 4096;
/// One pass's parameters (`SortParams` in the shader).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct SortParams {
    count: u32,
    shift: u32,
    blocks: u32,
    _pad: u32,
}

const PARAMS_BYTES: u64 = std::mem::size_of::<SortParams>() as u64;

/// `SortParams` against its WGSL twin (tests/shaders.rs checks it).
pub const LAYOUTS: &[super::layout::StructLayout] = &[crate::struct_layout!(
    SortParams => "SortParams" in SHADER, { count, shift, blocks }
)];
/// The ping-pong partners of the caller's buffers and the histogram, sized for `capacity` pairs.
struct Scratch {
    capacity: u32,
    keys: wgpu::Buffer,
    values: wgpu::Buffer,
    histogram: wgpu::Buffer,
    /// One `SortParams` per pass, each at a uniform-offset-aligned position.
    params: wgpu::Buffer,
}

pub struct RadixSort {
    count_digits: wgpu::ComputePipeline,
    scan_histogram: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// Distance between the passes' params in `Scratch::params`.
    params_stride: u64,
    scratch: Option<Scratch>,
}

impl RadixSort {
    pub fn new(gpu: &GpuContext, shaders: &ShaderLibrary) -> Result<Self, GpuError> {
        let layout = sort_layout(gpu);
        let pipeline = |entry| shaders.compute_pipeline(gpu, &SHADER, entry, &[&layout]);
        Ok(Self {
            count_digits: pipeline("count_digits")?,
            scan_histogram: pipeline("scan_histogram")?,
            scatter: pipeline("scatter")?,
            layout,
            params_stride: (gpu.limits.min_uniform_buffer_offset_alignment as u64)
                .max(PARAMS_BYTES),
            scratch: None,
        })
    }

    /// Records into `encoder` the sort of the first `count` pairs (`keys[i]`, `values[i]`) by
    /// key, stable, in place: the sorted pairs end up in `keys` and `values` (both need STORAGE
    /// usage and room for `count` u32s). Scratch buffers are kept for later sorts of at most as
    /// many pairs. Several sorts may follow one another in one encoder: each uploads its params
    /// through a copy recorded in the encoder, so each sees its own `count`.
    pub fn record(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
        count: u32,
    ) -> Result<(), GpuError> {
        if count == 0 {
            return Ok(());
        }
        let blocks = count.div_ceil(BLOCK);
        self.reserve(gpu, count)?;
        let Some(scratch) = &self.scratch else {
            return Ok(());
        };
        let upload = gpu.create_buffer_init(
            "radix sort params upload",
            &self.params_bytes(count, blocks),
            wgpu::BufferUsages::COPY_SRC,
        )?;
        encoder.copy_buffer_to_buffer(&upload, 0, &scratch.params, 0, upload.size());
        let grid = workgroup_grid(blocks);
        for pass in 0..PASSES {
            // Even passes read the caller's buffers, odd ones the scratch: after an even number
            // of passes the result is back in the caller's.
            let (from, to) = if pass % 2 == 0 {
                ((keys, values), (&scratch.keys, &scratch.values))
            } else {
                ((&scratch.keys, &scratch.values), (keys, values))
            };
            let group = self.bind_group(gpu, scratch, pass, from, to);
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("radix sort pass"),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &group, &[]);
            compute.set_pipeline(&self.count_digits);
            compute.dispatch_workgroups(grid[0], grid[1], grid[2]);
            compute.set_pipeline(&self.scan_histogram);
            compute.dispatch_workgroups(1, 1, 1);
            compute.set_pipeline(&self.scatter);
            compute.dispatch_workgroups(grid[0], grid[1], grid[2]);
        }
        Ok(())
    }

    fn params_bytes(&self, count: u32, blocks: u32) -> Vec<u8> {
        let mut bytes = vec![0u8; (self.params_stride * PASSES as u64) as usize];
        for pass in 0..PASSES {
            let params = SortParams {
                count,
                shift: pass * RADIX_BITS,
                blocks,
                _pad: 0,
            };
            let at = (pass as u64 * self.params_stride) as usize;
            bytes[at..at + PARAMS_BYTES as usize].copy_from_slice(bytemuck::bytes_of(&params));
        }
        bytes
    }

    /// Makes sure the scratch buffers hold `count` pairs.
    fn reserve(&mut self, gpu: &GpuContext, count: u32) -> Result<(), GpuError> {
        if self.scratch.as_ref().is_some_and(|s| s.capacity >= count) {
            return Ok(());
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let pairs_bytes = count as u64 * 4;
        let histogram_bytes = count.div_ceil(BLOCK) as u64 * RADIX * 4;
        self.scratch = Some(Scratch {
            capacity: count,
            keys: gpu.create_buffer("radix sort keys", pairs_bytes, storage)?,
            values: gpu.create_buffer("radix sort values", pairs_bytes, storage)?,
            histogram: gpu.create_buffer("radix sort histogram", histogram_bytes, storage)?,
            params: gpu.create_buffer(
                "radix sort params",
                self.params_stride * PASSES as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            )?,
        });
        Ok(())
    }

    fn bind_group(
        &self,
        gpu: &GpuContext,
        scratch: &Scratch,
        pass: u32,
        from: (&wgpu::Buffer, &wgpu::Buffer),
        to: (&wgpu::Buffer, &wgpu::Buffer),
    ) -> wgpu::BindGroup {
        let params = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &scratch.params,
            offset: pass as u64 * self.params_stride,
            size: NonZeroU64::new(PARAMS_BYTES),
        });
        let buffers = [from.0, from.1, to.0, to.1, &scratch.histogram];
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: params,
        }];
        entries.extend(
            (1..)
                .zip(buffers)
                .map(|(binding, buffer)| wgpu::BindGroupEntry {
                    binding,
                    resource: buffer.as_entire_binding(),
                }),
        );
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("radix sort"),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// Params, source keys and values (read), destination keys and values, histogram.
fn sort_layout(gpu: &GpuContext) -> wgpu::BindGroupLayout {
    use crate::gpu::binding::Access;
    let accesses = [
        Access::Uniform,
        Access::Read,
        Access::Read,
        Access::ReadWrite,
        Access::ReadWrite,
        Access::ReadWrite,
    ];
    let entries: Vec<_> = (0..)
        .zip(accesses)
        .map(|(binding, access)| crate::gpu::binding::layout_entry(binding, access))
        .collect();
    gpu.cache.layout(&gpu.device, "radix sort", &entries)
}
