//! Adapter enumeration and choice.

use super::GpuError;

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
}

/// Lower is better: real GPUs first, software rasterisers last; within a type, the native APIs
/// before GL (GL lacks float atomics and has few storage buffers per stage).
fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let device = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan | wgpu::Backend::Metal => 0,
        wgpu::Backend::Dx12 => 1,
        _ => 2,
    };
    (device, backend)
}

/// All adapters, best first (the order `--adapter INDEX` refers to).
fn sorted_adapters() -> Vec<wgpu::Adapter> {
    let mut adapters = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::all()));
    adapters.sort_by_key(|a| rank(&a.get_info()));
    adapters
}

pub fn adapter_label(info: &wgpu::AdapterInfo) -> String {
    format!(
        "{} ({:?}, {:?})",
        info.name.trim(),
        info.backend,
        info.device_type
    )
}

/// Name, backend and the optional features hppm uses, best adapter first.
pub fn list_adapters() -> Vec<(wgpu::AdapterInfo, wgpu::Features, wgpu::Limits)> {
    sorted_adapters()
        .into_iter()
        .map(|a| (a.get_info(), a.features(), a.limits()))
        .collect()
}

fn describe(adapters: &[wgpu::Adapter]) -> String {
    adapters
        .iter()
        .enumerate()
        .map(|(i, a)| format!("  {i}: {}", adapter_label(&a.get_info())))
        .collect::<Vec<_>>()
        .join("\n")
}

pub(super) fn choose(choice: Option<&str>) -> Result<wgpu::Adapter, GpuError> {
    let mut adapters = sorted_adapters();
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter);
    }
    let Some(choice) = choice else {
        return Ok(adapters.swap_remove(0));
    };
    let index = match choice.trim().parse::<usize>() {
        Ok(i) if i < adapters.len() => Some(i),
        Ok(_) => None,
        Err(_) => {
            let wanted = choice.to_lowercase();
            adapters.iter().position(|a| {
                adapter_label(&a.get_info())
                    .to_lowercase()
                    .contains(&wanted)
            })
        }
    };
    match index {
        Some(i) => Ok(adapters.swap_remove(i)),
        None => Err(GpuError::AdapterNotFound {
            requested: choice.to_string(),
            available: describe(&adapters),
        }),
    }
}
