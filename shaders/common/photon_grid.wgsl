#define_import_path common::photon_grid

// A hash grid over one iteration's photon hits with one global search radius (Knaus & Zwicker
// 2011, "Progressive Photon Mapping: A Probabilistic Approach"), which the camera pass looks up
// at diffuse vertices past its hit points. Built by shaders/passes/photon_grid.wgsl, read by
// shaders/passes/path_trace.wgsl; layouts mirror src/passes/photon_grid.rs.
//
// Cells are cubes of edge a little over twice the radius, so the sphere around a lookup point
// overlaps at most 2 cells per axis; cell coordinates count from the scene's centre. Each bucket
// heads a list of the photon hits whose cell hashes to it: a head or link is a photon hit's index
// + 1, 0 ends a list, so the heads reset to empty by zeroing.

#import common::spatial_hash::{grid_cell, cell_hash}

struct PhotonGridInfo {
    // This iteration's search radius.
    radius: f32,
    inv_cell: f32,
    // Buckets - 1 (buckets is a power of two); links begin at words[bucket_mask + 1].
    bucket_mask: u32,
    // Photon hits listed.
    count: u32,
    center: vec3<f32>,
    pad: u32,
}

fn photon_cell(info: PhotonGridInfo, position: vec3<f32>) -> vec3<i32> {
    return grid_cell(position, info.center, info.inv_cell);
}

fn photon_bucket(info: PhotonGridInfo, cell: vec3<i32>) -> u32 {
    return cell_hash(cell) & info.bucket_mask;
}
