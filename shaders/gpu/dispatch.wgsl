#define_import_path gpu::dispatch

// One-dimensional work spread over a two-dimensional grid of workgroups, because a dispatch
// dimension is limited to 65535 workgroups (about 16.7M invocations at 256 per workgroup) and
// the builders must handle more. src/gpu/dispatch.rs (`workgroup_grid`) chooses the grid.

const WORKGROUP_SIZE: u32 = 256u;

// The index of workgroup `group` in the flattened grid of `groups` workgroups.
fn flat_workgroup(group: vec3<u32>, groups: vec3<u32>) -> u32 {
    return group.y * groups.x + group.x;
}

// The index of invocation `local` of workgroup `group` when every workgroup has
// WORKGROUP_SIZE invocations.
fn flat_invocation(group: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return flat_workgroup(group, groups) * WORKGROUP_SIZE + local;
}

// Invocations in a grid of `groups` workgroups of WORKGROUP_SIZE: the stride of kernels whose
// invocations take several items in turn (src/passes/lanes.rs).
fn invocation_count(groups: vec3<u32>) -> u32 {
    return groups.x * groups.y * groups.z * WORKGROUP_SIZE;
}

// The item after `index` for an invocation striding by `stride` over `count` items; `count`
// once there is none (saturating: `index + stride` may pass u32's range).
fn next_item(index: u32, stride: u32, count: u32) -> u32 {
    if count - min(index, count) <= stride {
        return count;
    }
    return index + stride;
}
