// Lists this iteration's photon hits in a hash grid (shaders/common/photon_grid.wgsl). Driven by
// src/passes/photon_grid.rs, which zeroes the heads first: one invocation per photon hit pushes
// it onto its bucket's list.

#import common::hit_points::PhotonHitsIn
#import common::photon_grid::{PhotonGridInfo, photon_cell, photon_bucket}
#import gpu::dispatch::{WORKGROUP_SIZE, flat_invocation}

struct PhotonGridUniform {
    radius: f32,
    inv_cell: f32,
    bucket_mask: u32,
    pad_a: u32,
    center: vec3<f32>,
    pad_b: u32,
}

struct PhotonGridOut {
    info: PhotonGridInfo,
    // Bucket heads, then one link per photon hit.
    words: array<atomic<u32>>,
}

@group(0) @binding(0) var<storage, read> photon_hits: PhotonHitsIn;
@group(0) @binding(1) var<uniform> params: PhotonGridUniform;
@group(0) @binding(2) var<storage, read_write> grid: PhotonGridOut;

fn listed_count() -> u32 {
    let capacity = arrayLength(&grid.words) - (params.bucket_mask + 1u);
    return min(min(photon_hits.count, arrayLength(&photon_hits.hits)), capacity);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let index = flat_invocation(group, groups, local);
    let count = listed_count();
    let info = PhotonGridInfo(params.radius, params.inv_cell, params.bucket_mask, count, params.center, 0u);
    if index == 0u {
        grid.info = info;
    }
    if index >= count {
        return;
    }
    let position = photon_hits.hits[index].position;
    // A hit that is not a finite point is listed nowhere (no lookup could accept it). Tested on
    // the bits: compilers may assume floats are never NaN.
    let exponent = bitcast<vec3<u32>>(position) & vec3<u32>(0x7f800000u);
    if any(exponent == vec3<u32>(0x7f800000u)) {
        return;
    }
    let bucket = photon_bucket(info, photon_cell(info, position));
    let next = atomicExchange(&grid.words[bucket], index + 1u);
    atomicStore(&grid.words[params.bucket_mask + 1u + index], next);
}
