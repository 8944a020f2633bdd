//! `photon_grid` run alone on synthetic photon hits: its lists against a CPU mirror of its cells
//! and hash, its radius against Knaus & Zwicker's schedule, and range queries through its
//! lists (walked the way path_trace.wgsl's `nearby_photons` walks them) against all pairs.
//! The camera's use of it is checked by whole renders: the furnace matrix (tests/furnace.rs)
//! and the glass-sphere bias test (tests/bias.rs) run graphs/hybrid.ron, which uses it.

mod common;

use std::collections::HashSet;

use common::pass_harness::{PassHarness, photon_hits_resource_with};
use common::*;
use glam::Vec3;
use hppm::passes::hit_points::GpuPhotonHit;
use hppm::passes::photon_grid::{self, PhotonGrid, PhotonGridInfo, PhotonGridParams};
use hppm::passes::pppm::RadiusSchedule;

/// shaders/common/spatial_hash.wgsl's `grid_cell` from the grid's centre (`photon_cell`).
fn cell_of(info: &PhotonGridInfo, p: Vec3) -> [i32; 3] {
    let limit = 1073741824.0f32;
    std::array::from_fn(|i| {
        ((p[i] - info.center[i]) * info.inv_cell)
            .floor()
            .clamp(-limit, limit) as i32
    })
}

/// shaders/common/spatial_hash.wgsl's `cell_hash`, masked as `photon_bucket` does.
fn bucket_of(info: &PhotonGridInfo, c: [i32; 3]) -> u32 {
    let u = c.map(|v| v as u32);
    let mut h =
        u[0].wrapping_mul(73856093) ^ u[1].wrapping_mul(19349663) ^ u[2].wrapping_mul(83492791);
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 16;
    h & info.bucket_mask
}

struct Built {
    info: PhotonGridInfo,
    words: Vec<u32>,
}

impl Built {
    /// The photon indices on bucket `b`'s list, in list order.
    fn list(&self, b: u32) -> Vec<u32> {
        let links = self.info.bucket_mask as usize + 1;
        let mut out = Vec::new();
        let mut link = self.words[b as usize];
        while link != 0 {
            assert!(out.len() <= self.info.count as usize, "bucket {b}: a cycle");
            out.push(link - 1);
            link = self.words[links + link as usize - 1];
        }
        out
    }

    /// Photons within `r` of `x`, through the (at most 2 x 2 x 2) cells the sphere's box spans.
    fn query(&self, hits: &[GpuPhotonHit], x: Vec3) -> HashSet<u32> {
        let r = self.info.radius;
        let lo = cell_of(&self.info, x - Vec3::splat(r));
        let hi = cell_of(&self.info, x + Vec3::splat(r));
        let mut found = HashSet::new();
        for z in lo[2]..=hi[2].min(lo[2] + 1) {
            for y in lo[1]..=hi[1].min(lo[1] + 1) {
                for xc in lo[0]..=hi[0].min(lo[0] + 1) {
                    let cell = [xc, y, z];
                    for i in self.list(bucket_of(&self.info, cell)) {
                        let p = Vec3::from(hits[i as usize].position);
                        if cell_of(&self.info, p) == cell && (p - x).length_squared() <= r * r {
                            assert!(found.insert(i), "photon {i} found twice");
                        }
                    }
                }
            }
        }
        found
    }
}

fn photon(p: Vec3) -> GpuPhotonHit {
    GpuPhotonHit {
        position: p.into(),
        remaining: 8,
        wi: [0.0, 1.0, 0.0],
        flux: [1.0, 1.0, 1.0],
        ..Default::default()
    }
}

/// Clustered and scattered photons in [-2, 2] x [0, 1.5] x [-2, 2], a NaN and an infinite one,
/// and hits past the header's count that the grid must not list.
fn synthetic_hits() -> (Vec<GpuPhotonHit>, u32) {
    let mut rng = Lcg(7);
    let mut hits = Vec::new();
    for i in 0..6000 {
        let p = if i % 3 == 0 {
            Vec3::new(0.3, 0.0, -0.2) + 0.05 * rng.vec3()
        } else {
            Vec3::new(2.0 * rng.signed(), 1.5 * rng.unit(), 2.0 * rng.signed())
        };
        hits.push(photon(p));
    }
    hits.push(photon(Vec3::new(f32::NAN, 0.0, 0.0)));
    hits.push(photon(Vec3::new(f32::INFINITY, 0.0, 0.0)));
    let count = hits.len() as u32;
    for _ in 0..100 {
        hits.push(photon(Vec3::new(0.3, 0.0, -0.2)));
    }
    (hits, count)
}

struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn signed(&mut self) -> f32 {
        2.0 * self.unit() - 1.0
    }
    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.signed(), self.signed(), self.signed())
    }
}

/// Would catch: a photon listed twice or not at all (a caustic looked up twice or lost), one
/// listed under the wrong bucket, a listed NaN or a hit past the count, a cell edge too small for
/// the 2-cells-per-axis walk (photons within the radius missed), a radius off the schedule.
#[test]
fn the_photon_grid_lists_every_photon_once_and_finds_all_within_its_radius() {
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let h = PassHarness::new(&gpu, &scene, (16, 16), gpu.has_float_atomics());
    let (hits, count) = synthetic_hits();
    let input = photon_hits_resource_with(&gpu, &hits, count);
    let params = PhotonGridParams {
        radius: 0.03,
        lookup_photons: 8.0,
        alpha: 0.7,
    };
    let mut pass = PhotonGrid::new(params);
    let out = h.prepare(&photon_grid::KIND, &mut pass, &[("photon_hits", &input)]);
    let iteration = 7;
    h.run(&mut pass, iteration, 1);
    let grid = &out["grid"];
    let info: PhotonGridInfo = grid.read_header(&gpu).expect("readback");
    let built = Built {
        info,
        words: grid.read(&gpu).expect("readback"),
    };

    let u = &h.scene().uniform;
    let scale = RadiusSchedule::new(0.7f32 as f64)
        .ratio_at(iteration)
        .sqrt();
    let by_count = (8.0 / hits.len() as f64).sqrt();
    let expected_radius = by_count.min(0.03) * u.scene_radius as f64 * scale;
    assert!(
        (info.radius as f64 - expected_radius).abs() <= 1e-6 * expected_radius,
        "radius {} against the schedule's {expected_radius}",
        info.radius
    );
    assert_eq!(info.count, count);
    for i in 0..3 {
        assert_eq!(info.center[i], 0.5 * (u.bounds_min[i] + u.bounds_max[i]));
    }
    assert!(
        1.0 / info.inv_cell >= 2.0 * info.radius,
        "cells narrower than a sphere"
    );

    let mut listed = vec![0u32; hits.len()];
    for b in 0..=info.bucket_mask {
        for i in built.list(b) {
            listed[i as usize] += 1;
            let p = Vec3::from(hits[i as usize].position);
            assert_eq!(
                bucket_of(&info, cell_of(&info, p)),
                b,
                "photon {i} in the wrong bucket"
            );
        }
    }
    for (i, &n) in listed.iter().enumerate() {
        let finite = Vec3::from(hits[i].position).is_finite() && (i as u32) < count;
        assert_eq!(n, finite as u32, "photon {i} listed {n} times");
    }

    let mut rng = Lcg(99);
    let mut found_total = 0;
    for q in 0..400 {
        let x = if q % 2 == 0 {
            Vec3::new(0.3, 0.0, -0.2) + 0.06 * rng.vec3()
        } else {
            Vec3::new(2.0 * rng.signed(), 1.5 * rng.unit(), 2.0 * rng.signed())
        };
        let r2 = info.radius * info.radius;
        let brute: HashSet<u32> = (0..count)
            .filter(|&i| (Vec3::from(hits[i as usize].position) - x).length_squared() <= r2)
            .collect();
        let found = built.query(&hits, x);
        assert_eq!(found, brute, "query {q} at {x}");
        found_total += found.len();
    }
    assert!(
        found_total > 2000,
        "the queries must find photons ({found_total})"
    );
}

/// `hits` photons spread evenly over the square [-2, 2] x [-2, 2] of the plane y = 0.
fn even_hits(hits: usize, seed: u64) -> Vec<GpuPhotonHit> {
    let mut rng = Lcg(seed);
    (0..hits)
        .map(|_| photon(Vec3::new(2.0 * rng.signed(), 0.0, 2.0 * rng.signed())))
        .collect()
}

/// The first radius follows the photon count, so a lookup's expected work does not grow with
/// the image (photons per iteration follow the pixel count): 16 times the photons over the same
/// square give a radius a quarter as wide and as many photons per lookup. Would catch a radius
/// fixed to the scene (16 times the photons per lookup, the camera's cost in pixels squared), a
/// rule that ignores the cap, or one that overshoots the other way (a lookup that finds nothing).
#[test]
fn a_lookup_finds_as_many_photons_whatever_the_photon_count() {
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let h = PassHarness::new(&gpu, &scene, (16, 16), gpu.has_float_atomics());
    // No cap, so the count rule decides at both counts.
    let params = PhotonGridParams {
        radius: 1.0,
        ..Default::default()
    };
    let mut per_lookup = Vec::new();
    let mut radii = Vec::new();
    for hits in [4096usize, 65536] {
        let photons = even_hits(hits, 11);
        let input = photon_hits_resource_with(&gpu, &photons, hits as u32);
        let mut pass = PhotonGrid::new(params);
        let out = h.prepare(&photon_grid::KIND, &mut pass, &[("photon_hits", &input)]);
        h.run(&mut pass, 0, 1);
        let info: PhotonGridInfo = out["grid"].read_header(&gpu).expect("readback");
        let r_over_scene = info.radius as f64 / h.scene().uniform.scene_radius as f64;
        assert!(
            (r_over_scene - photon_grid::first_radius_fraction(params, hits as u64)).abs()
                < 1e-6 * r_over_scene,
            "{hits} hits: radius {r_over_scene} of the scene's"
        );
        let mut rng = Lcg(5);
        let lookups = 2000;
        let r2 = info.radius * info.radius;
        let found: usize = (0..lookups)
            .map(|_| {
                let x = Vec3::new(1.5 * rng.signed(), 0.0, 1.5 * rng.signed());
                photons
                    .iter()
                    .filter(|p| (Vec3::from(p.position) - x).length_squared() <= r2)
                    .count()
            })
            .sum();
        per_lookup.push(found as f64 / lookups as f64);
        radii.push(info.radius as f64);
    }
    eprintln!("radii {radii:?}, photons per lookup {per_lookup:?}");
    let radius_ratio = radii[1] / radii[0];
    assert!(
        (radius_ratio - 0.25).abs() < 1e-5,
        "16x the photons: radius ratio {radius_ratio}, not 1/4"
    );
    assert!(per_lookup[0] > 1.0, "lookups find photons: {per_lookup:?}");
    let growth = per_lookup[1] / per_lookup[0];
    assert!(
        (0.8..1.25).contains(&growth),
        "16x the photons: {growth}x the photons per lookup"
    );
}
