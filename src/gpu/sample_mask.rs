//! Adaptive sampling's per-pixel flags on the device (shaders/gpu/sample_mask.wgsl): which
//! pixels the camera samples in the next iterations and which pixels' images may change. The
//! renderer decides them (src/render/adaptive.rs); path_trace and the odd-iteration sums read them.
//! Until the renderer enables the mask, every pixel is sampled and updated.

use std::sync::Arc;

use super::{GpuContext, GpuError};

/// The camera samples the pixel.
pub const SAMPLED: u32 = 1;
/// The pixel's image may change: it is sampled, or within a splatting filter's reach of one
/// that is.
pub const UPDATED: u32 = 2;
const HEADER_BYTES: u64 = 16;

/// One band's mask: a header (`enabled`, how many pixels are sampled), one word of flags per
/// pixel, then the sampled pixels' indices.
#[derive(Clone)]
pub struct SampleMask {
    pub buffer: Arc<wgpu::Buffer>,
    pixels: u32,
}

impl SampleMask {
    /// A disabled mask over `pixels` pixels.
    pub fn new(gpu: &GpuContext, pixels: u32) -> Result<Self, GpuError> {
        let buffer = gpu.create_buffer(
            "sample mask",
            HEADER_BYTES + 8 * pixels as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        Ok(Self {
            buffer: Arc::new(buffer),
            pixels,
        })
    }

    pub fn pixels(&self) -> u32 {
        self.pixels
    }

    /// Enables the mask with one word of flags per pixel (the band's pixels in order; a
    /// longer slice is cut), or disables it (`None`).
    pub fn write(&self, gpu: &GpuContext, flags: Option<&[u32]>) {
        let Some(flags) = flags else {
            gpu.queue.write_buffer(&self.buffer, 0, &[0; 4]);
            return;
        };
        let flags = &flags[..flags.len().min(self.pixels as usize)];
        let sampled: Vec<u32> = (0..flags.len() as u32)
            .filter(|&i| flags[i as usize] & SAMPLED != 0)
            .collect();
        let mut bytes = Vec::with_capacity(HEADER_BYTES as usize + 8 * flags.len());
        bytes.extend_from_slice(bytemuck::cast_slice(&[1u32, sampled.len() as u32, 0, 0]));
        bytes.extend_from_slice(bytemuck::cast_slice(flags));
        bytes.extend_from_slice(bytemuck::cast_slice(&sampled));
        gpu.queue.write_buffer(&self.buffer, 0, &bytes);
    }
}
