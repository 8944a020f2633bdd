#define_import_path common::spatial_hash

// Uniform grids hashed into power-of-two tables, as the hash grids over hit points
// (passes/hit_point_grid.wgsl) and over photons (common/photon_grid.wgsl) use them.

// Cell coordinates are clamped here before the i32 conversion; points far outside a grid's
// reach share its edge cells instead of overflowing.
const CELL_LIMIT: f32 = 1073741824.0; // 2^30

// The cell holding `position` in a grid of cells of edge 1 / `inv_cell` from `origin`: one
// monotone function of the position, so a point inside a box lies in a cell between those of
// the box's corners.
fn grid_cell(position: vec3<f32>, origin: vec3<f32>, inv_cell: f32) -> vec3<i32> {
    let c = floor((position - origin) * inv_cell);
    return vec3<i32>(clamp(c, vec3<f32>(-CELL_LIMIT), vec3<f32>(CELL_LIMIT)));
}

// Teschner et al. 2003's spatial hash, then murmur3's finaliser: tables are powers of two, so
// buckets are the low bits, which the products alone leave depending on low bits only.
fn cell_hash(c: vec3<i32>) -> u32 {
    var h = (u32(c.x) * 73856093u) ^ (u32(c.y) * 19349663u) ^ (u32(c.z) * 83492791u);
    h ^= h >> 16u;
    h *= 0x85ebca6bu;
    h ^= h >> 13u;
    h *= 0xc2b2ae35u;
    h ^= h >> 16u;
    return h;
}
