//! Bind group layout and bind group built from one ordered list, so the two cannot drift apart:
//! binding i of the layout is entry i of the list.

use super::GpuContext;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    Uniform,
    Read,
    ReadWrite,
}

/// Layout entry `binding` of a compute-visible buffer with `access`.
pub fn layout_entry(binding: u32, access: Access) -> wgpu::BindGroupLayoutEntry {
    let ty = match access {
        Access::Uniform => wgpu::BufferBindingType::Uniform,
        Access::Read => wgpu::BufferBindingType::Storage { read_only: true },
        Access::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
    };
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Layout and bind group for `entries`, labelled `label`. The layout is the device's one for
/// these entries (`GpuContext::cache`), so pipelines built with it are shared.
pub fn bind_buffers(
    gpu: &GpuContext,
    label: &str,
    entries: &[(Access, &wgpu::Buffer)],
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let numbered: Vec<_> = (0u32..)
        .zip(entries)
        .map(|(i, (access, buffer))| (i, *access, *buffer))
        .collect();
    bind_buffers_at(gpu, label, &numbered)
}

/// As [`bind_buffers`], with each entry's binding number given.
pub fn bind_buffers_at(
    gpu: &GpuContext,
    label: &str,
    entries: &[(u32, Access, &wgpu::Buffer)],
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let layout_entries: Vec<_> = entries
        .iter()
        .map(|(binding, access, _)| layout_entry(*binding, *access))
        .collect();
    let device = &gpu.device;
    let layout = gpu.cache.layout(device, label, &layout_entries);
    let group_entries: Vec<_> = entries
        .iter()
        .map(|(binding, _, buffer)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &layout,
        entries: &group_entries,
    });
    (layout, group)
}
