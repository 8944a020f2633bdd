//! How many items (pixels, photons) one invocation of a tracing pass takes in turn.
//!
//! A tracing invocation that starts its next item as soon as one ends (path regeneration,
//! Novák, Havran and Dachsbacher 2010) keeps its SIMD lanes busy where path lengths differ. On
//! a CPU adapter a workgroup's lanes run as SIMD vectors and each vector runs until its longest
//! path ends, so there each lane takes `CPU_SAMPLES_PER_LANE` traced samples. A GPU hides
//! divergence with occupancy instead: one item per invocation there, unless the items outnumber
//! the invocations one dispatch can launch.

/// Traced samples per lane on a CPU adapter: of 4, 8, 16, 32, 64 and 128 pixels per invocation
/// at one sample each, 32 took the least time for `pt` on lavapipe (BENCHMARKS.md).
pub const CPU_SAMPLES_PER_LANE: u32 = 32;

/// Items each invocation takes, for `items` of `samples_per_item` traced samples each, when a
/// dispatch launches at most `most_invocations`.
pub fn items_per_invocation(
    device: wgpu::DeviceType,
    items: u32,
    samples_per_item: u32,
    most_invocations: u32,
) -> u32 {
    let preferred = match device {
        wgpu::DeviceType::Cpu => CPU_SAMPLES_PER_LANE.div_ceil(samples_per_item.max(1)),
        _ => 1,
    };
    preferred
        .max(items.div_ceil(most_invocations.max(1)))
        .max(1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::DeviceType::{Cpu, DiscreteGpu};

    // Catches a CPU rule that stops regenerating (one item per lane) or over-fills lanes that
    // already trace several samples per item.
    #[test]
    fn cpu_lanes_take_about_32_samples_gpus_one_item() {
        assert_eq!(items_per_invocation(Cpu, 128 * 128, 1, u32::MAX), 32);
        assert_eq!(items_per_invocation(Cpu, 128 * 128, 4, u32::MAX), 8);
        assert_eq!(items_per_invocation(Cpu, 128 * 128, 64, u32::MAX), 1);
        assert_eq!(items_per_invocation(Cpu, 3, 1, u32::MAX), 32);
        assert_eq!(
            items_per_invocation(DiscreteGpu, 1920 * 1080, 1, u32::MAX),
            1
        );
    }

    // Catches a dispatch that would launch more invocations than the adapter allows (a render
    // refused, or items left untraced on large films and photon counts).
    #[test]
    fn every_item_is_covered_within_the_invocation_limit() {
        let most = 65535 * 64;
        for device in [Cpu, DiscreteGpu] {
            for items in [0, 1, 63, 64, 65, most - 1, most, most + 1, 16384 * 16384] {
                let k = items_per_invocation(device, items, 1, most);
                let invocations = items.div_ceil(k);
                assert!(
                    invocations <= most,
                    "{items} items: {invocations} invocations"
                );
                assert!(invocations as u64 * k as u64 >= items as u64);
            }
        }
    }
}
