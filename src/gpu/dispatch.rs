//! Dispatch grids for one-dimensional work: a dimension holds at most 65535 workgroups, so
//! larger work is spread over rows that kernels flatten again (shaders/gpu/dispatch.wgsl).

/// Most workgroups a dispatch may have in one dimension (WebGPU's default limit).
const MAX_GROUPS_PER_DIMENSION: u32 = 65535;

/// A dispatch grid of at least `groups` workgroups: one row while it fits, else rows of the
/// widest allowed size (kernels flatten the grid with `common::dispatch` and skip the excess).
pub fn workgroup_grid(groups: u32) -> [u32; 3] {
    if groups <= MAX_GROUPS_PER_DIMENSION {
        [groups, 1, 1]
    } else {
        [
            MAX_GROUPS_PER_DIMENSION,
            groups.div_ceil(MAX_GROUPS_PER_DIMENSION),
            1,
        ]
    }
}
