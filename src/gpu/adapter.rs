//! Adapter enumeration and choice.

use super::GpuError;

/// An instance of `backends` only: an instance with GL in it initialises EGL even if no GL
/// adapter is asked for. `WGPU_BACKEND` still narrows the choice.
fn instance(backends: wgpu::Backends) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    desc.backends &= backends;
    wgpu::Instance::new(desc)
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

/// The backends probed unless GL is asked for or nothing else is found.
const NATIVE: wgpu::Backends = wgpu::Backends::VULKAN
    .union(wgpu::Backends::METAL)
    .union(wgpu::Backends::DX12);

fn adapters_of(backends: wgpu::Backends) -> Vec<wgpu::Adapter> {
    let mut adapters = pollster::block_on(instance(backends).enumerate_adapters(backends));
    adapters.sort_by_key(|a| rank(&a.get_info()));
    adapters
}

/// Adapters best first, the native APIs' before GL's (the order `--adapter INDEX` refers to).
/// GL is probed only with `with_gl` or when no native adapter exists: probing it wakes Mesa's
/// EGL, which prints "XDG_RUNTIME_DIR is invalid or not set" on headless machines, and it
/// serves worse (no float atomics, 16 storage buffers per stage).
fn sorted_adapters(with_gl: bool) -> Vec<wgpu::Adapter> {
    let mut adapters = adapters_of(NATIVE);
    if with_gl || adapters.is_empty() {
        adapters.extend(adapters_of(wgpu::Backends::GL));
    }
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

/// Name, backend and the optional features hppm uses, best adapter first, GL included.
pub fn list_adapters() -> Vec<(wgpu::AdapterInfo, wgpu::Features, wgpu::Limits)> {
    sorted_adapters(true)
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

/// The adapter `choice` names (an index or part of its label) among `adapters`.
fn find(adapters: &[wgpu::Adapter], choice: &str) -> Option<usize> {
    match choice.trim().parse::<usize>() {
        Ok(i) => (i < adapters.len()).then_some(i),
        Err(_) => {
            let wanted = choice.to_lowercase();
            adapters.iter().position(|a| {
                adapter_label(&a.get_info())
                    .to_lowercase()
                    .contains(&wanted)
            })
        }
    }
}

pub(super) fn choose(choice: Option<&str>) -> Result<wgpu::Adapter, GpuError> {
    let mut adapters = sorted_adapters(false);
    let Some(choice) = choice else {
        return if adapters.is_empty() {
            Err(GpuError::NoAdapter)
        } else {
            Ok(adapters.swap_remove(0))
        };
    };
    if let Some(i) = find(&adapters, choice) {
        return Ok(adapters.swap_remove(i));
    }
    // Not among the native adapters: perhaps a GL one (the indexes continue after them).
    let mut adapters = sorted_adapters(true);
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter);
    }
    match find(&adapters, choice) {
        Some(i) => Ok(adapters.swap_remove(i)),
        None => Err(GpuError::AdapterNotFound {
            requested: choice.to_string(),
            available: describe(&adapters),
        }),
    }
}

/// Mesa's version in an adapter's driver string ("llvmpipe Mesa 22.3.6 (LLVM 15.0.6)").
pub fn mesa_version(info: &wgpu::AdapterInfo) -> Option<(u32, u32)> {
    mesa_version_in(&format!("{} {}", info.driver, info.driver_info))
}

fn mesa_version_in(text: &str) -> Option<(u32, u32)> {
    let after = text.split("Mesa ").nth(1)?;
    let mut parts = after.split(|c: char| !c.is_ascii_digit());
    let major = parts.next()?.parse().ok()?;
    let minor = parts.next()?.parse().ok()?;
    Some((major, minor))
}

/// Mesa whose lavapipe is much faster for hppm's kernels than older ones.
pub const FAST_LAVAPIPE_MESA: u32 = 25;

/// A warning for lavapipe from a Mesa older than `FAST_LAVAPIPE_MESA`.
pub fn old_lavapipe_warning(info: &wgpu::AdapterInfo) -> Option<String> {
    let software = info.device_type == wgpu::DeviceType::Cpu;
    let (major, minor) = mesa_version(info)?;
    (software && info.backend == wgpu::Backend::Vulkan && major < FAST_LAVAPIPE_MESA).then(|| {
        format!(
            "warning: lavapipe from Mesa {major}.{minor}: Mesa {FAST_LAVAPIPE_MESA} or newer runs \
             hppm about 2.7x faster (BENCHMARKS.md); on Debian 12 it is in bookworm-backports \
             (`.ci/install-lavapipe` installs it)"
        )
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn mesa_versions_are_read_from_driver_strings() {
        use super::mesa_version_in as v;
        assert_eq!(v("llvmpipe Mesa 22.3.6 (LLVM 15.0.6)"), Some((22, 3)));
        assert_eq!(
            v(" 4.5 (Core Profile) Mesa 25.0.7-2~bpo12+1"),
            Some((25, 0))
        );
        assert_eq!(v("NVIDIA 550.54"), None);
        assert_eq!(v("Mesa "), None);
    }
}
