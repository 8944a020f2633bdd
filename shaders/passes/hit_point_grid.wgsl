// Uniform hash grid over the hit points' search spheres (Hachisuka & Jensen 2010, "Parallel
// Progressive Photon Mapping on GPUs"; pbrt-v4's SPPM), rebuilt every iteration from the current
// radii and gathered in the same dispatch sequence. Driven by src/passes/hit_point_grid.rs:
//   bounds (per slot), setup (one invocation), insert (per slot), main (per photon hit).
//
// Cells: a cube of edge `cell` from the scene's bounds_min, indexed by i32 coordinates (clamped
// far outside any hit point, so photons anywhere still get a cell) and hashed into `buckets`
// list heads. The edge is at least twice the largest padded radius with a margin, so a sphere's
// box overlaps at most 2 cells per axis and a hit point is listed under at most 8 cells. A photon
// looks in its one cell only: if it lies in a sphere it lies in the sphere's box, whose cells
// include the photon's, because both are computed by one monotone function of the position
// (`cell_of`), applied to the box corners and to the photon.
//
// Lists: entry e = 8 * slot + k is hit point `slot`'s k-th cell; links hold e + 1 (0 ends a
// list), so the heads reset to empty by zeroing. A hit point never enters one bucket twice, even
// when two of its cells hash alike, so a photon is deposited at most once per hit point.

#import common::scene::scene_info
#import common::hit_points::{NO_PIXEL, PhotonHit}
#import common::gather::{hit_points, photon_hits, photon_hit_count, gather_at}
#import gpu::dispatch::{WORKGROUP_SIZE, flat_invocation, invocation_count, next_item}
#import common::spatial_hash::{grid_cell, cell_hash}

// Radii are padded before they bound boxes, so that no photon the f32 distance test in
// gather_at accepts falls outside its hit point's box by rounding (as sphere_box does)...
const RADIUS_PAD: f32 = 1e-5;
// ...and floored where squares would underflow: gather_at compares d.d with r*r, and once r*r
// is 0 (or flushed subnormal) it accepts every d whose square is also 0, |d| up to ~1.1e-19.
const MIN_BOX_RADIUS: f32 = 2.2e-19;
// Radii beyond this bound boxes as if they were this large, and positions beyond it are left
// out: the grid covers photons within it, and larger boxes would overflow f32 at their corners.
const MAX_BOX_RADIUS: f32 = 1e30;
// Cell edge = 2 * largest padded radius * (1 + CELL_MARGIN); see `setup` for why a margin.
const CELL_MARGIN: f32 = 0.015625;
// Smallest cell edge as a fraction of the largest coordinate magnitude (also see `setup`).
const MIN_CELL_FRACTION: f32 = 6.103515625e-5; // 2^-14
// Cell coordinates are clamped at common::spatial_hash's CELL_LIMIT; hit points never come near
// it (their coordinates are below 2^15 by the MIN_CELL_FRACTION rule), photons far away may.
// Beyond any finite f32 but the largest: photons at FAR or farther (infinite, NaN) are skipped.
const FAR: f32 = 3.0e38;

struct GridUniform {
    // Hit-point slots.
    slots: u32,
    // Buckets - 1 (buckets is a power of two).
    bucket_mask: u32,
    // Entry links begin at words[buckets].
    buckets: u32,
    pad: u32,
}

// Mirrors `GridInfo` in src/passes/hit_point_grid.rs. Zeroed by the node before `bounds`.
struct GridInfo {
    // f32 bits of the largest padded radius (non-negative floats order like their bits).
    max_radius: atomic<u32>,
    // f32 bits of the largest |coordinate| + padded radius over valid hit points.
    magnitude: atomic<u32>,
    // Valid hit points.
    valid: atomic<u32>,
    // Entries pushed onto lists.
    inserted: atomic<u32>,
    // Boxes that overlapped more than 2 cells on an axis (the cell rule says never).
    clipped: atomic<u32>,
    cell: f32,
    inv_cell: f32,
    pad: u32,
}

struct Grid {
    info: GridInfo,
    // Bucket heads (buckets words), then entry links (8 per slot).
    words: array<atomic<u32>>,
}

@group(1) @binding(3) var<uniform> params: GridUniform;
@group(1) @binding(4) var<storage, read_write> grid: Grid;

// A hit point as the BVH builders take them (a pixel and a positive radius), at a finite
// position: a NaN or infinite one would poison the grid's bounds, and the BVH never reaches it
// either (its box contains no point).
fn in_grid(slot: u32) -> bool {
    let hp = hit_points.points[slot];
    let finite = all(abs(hp.position) <= vec3<f32>(MAX_BOX_RADIUS));
    return hp.pixel != NO_PIXEL && hp.radius > 0.0 && finite;
}

fn box_radius(slot: u32) -> f32 {
    let r = hit_points.points[slot].radius * (1.0 + RADIUS_PAD);
    return clamp(r, MIN_BOX_RADIUS, MAX_BOX_RADIUS);
}

// The cell of `x`: monotone in each coordinate (subtraction, multiplication by a positive
// number, floor and clamp all are), which the one-cell lookup relies on.
fn cell_of(x: vec3<f32>) -> vec3<i32> {
    return grid_cell(x, scene_info.bounds_min, grid.info.inv_cell);
}

fn bucket_of(c: vec3<i32>) -> u32 {
    return cell_hash(c) & params.bucket_mask;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn bounds(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let slot = flat_invocation(group, groups, local);
    if slot >= params.slots || !in_grid(slot) {
        return;
    }
    let r = box_radius(slot);
    let p = abs(hit_points.points[slot].position);
    atomicMax(&grid.info.max_radius, bitcast<u32>(r));
    atomicMax(&grid.info.magnitude, bitcast<u32>(max(max(p.x, p.y), p.z) + r));
    atomicAdd(&grid.info.valid, 1u);
}

// Chooses the cell edge. A box of width w spans at most 2 cells per axis when its computed width
// in cell units, (hi - o) * inv - (lo - o) * inv, is at most 1. In exact arithmetic that is
// 2r / cell <= 1 / (1 + CELL_MARGIN); rounding adds at most about 10 u M / cell (u = 2^-24, M the
// largest magnitude: the corners, the subtraction and the product each round once, for both
// corners), which the margin covers while cell >= 2^-14 M (10 * 2^-10 < 1/65). So the edge is
// also floored at MIN_CELL_FRACTION * M: only radii far below the scene's f32 resolution make
// that floor count, and then cells just hold more hit points.
@compute @workgroup_size(1)
fn setup() {
    var cell = 1.0;
    if atomicLoad(&grid.info.valid) > 0u {
        let radius = bitcast<f32>(atomicLoad(&grid.info.max_radius));
        let o = abs(scene_info.bounds_min);
        let points = bitcast<f32>(atomicLoad(&grid.info.magnitude));
        let magnitude = max(points, max(max(o.x, o.y), o.z));
        cell = max(2.0 * radius * (1.0 + CELL_MARGIN), magnitude * MIN_CELL_FRACTION);
    }
    grid.info.cell = cell;
    grid.info.inv_cell = 1.0 / cell;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn insert(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let slot = flat_invocation(group, groups, local);
    if slot >= params.slots || !in_grid(slot) {
        return;
    }
    let p = hit_points.points[slot].position;
    let r = box_radius(slot);
    let lo = cell_of(p - r);
    let hi_unclipped = cell_of(p + r);
    // Never taken by the cell rule; keeps the 8 entries of the slot its own if the rule broke,
    // and says so, since photons in the lost cells would then be missed.
    let hi = min(hi_unclipped, lo + vec3<i32>(1));
    if any(hi != hi_unclipped) {
        atomicAdd(&grid.info.clipped, 1u);
    }
    var used: array<u32, 8>;
    var count = 0u;
    for (var k = 0u; k < 8u; k++) {
        let c = lo + vec3<i32>(vec3<u32>(k & 1u, (k >> 1u) & 1u, k >> 2u));
        if any(c > hi) {
            continue;
        }
        let bucket = bucket_of(c);
        var seen = false;
        for (var j = 0u; j < count; j++) {
            seen = seen || used[j] == bucket;
        }
        if seen {
            continue;
        }
        used[count] = bucket;
        count += 1u;
        let entry = 8u * slot + k;
        let next = atomicExchange(&grid.words[bucket], entry + 1u);
        atomicStore(&grid.words[params.buckets + entry], next);
    }
    atomicAdd(&grid.info.inserted, count);
}

// The gather: each photon hit walks the list of its cell's bucket. Entries of other cells that
// share the bucket are rejected by gather_at's distance test, like entries whose sphere does not
// reach the photon.
fn first_link(hit: PhotonHit) -> u32 {
    // gather_at rejects by `d.d > r*r`, which a NaN distance passes; the BVH's box test keeps
    // such photons out, here they would reach every hit point of some bucket.
    if !all(abs(hit.position) <= vec3<f32>(FAR)) {
        return 0u;
    }
    return atomicLoad(&grid.words[bucket_of(cell_of(hit.position))]);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let count = photon_hit_count();
    let stride = invocation_count(groups);
    var index = flat_invocation(group, groups, local);
    if index >= count || atomicLoad(&grid.info.inserted) == 0u {
        return;
    }
    // Lists are acyclic (each entry is pushed once); the bound only keeps a corrupted grid from
    // hanging the device.
    let entries = 8u * params.slots;
    // Photon hits index, index + invocations, ... each list walked in the same loop as the
    // next one starts (as gather_bvh.wgsl's walks).
    var hit = photon_hits.hits[index];
    var link = first_link(hit);
    var steps = 0u;
    loop {
        if link == 0u || steps >= entries {
            index = next_item(index, stride, count);
            if index == count {
                break;
            }
            hit = photon_hits.hits[index];
            link = first_link(hit);
            steps = 0u;
            continue;
        }
        let entry = link - 1u;
        gather_at(entry >> 3u, hit);
        link = atomicLoad(&grid.words[params.buckets + entry]);
        steps++;
    }
}
