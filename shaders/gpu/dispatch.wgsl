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
