//! The hash-grid hit-point structure (`hit_point_grid`), on lavapipe: the node alone against an
//! all-pairs brute force of the same distance and normal tests (every photon counted once by
//! every hit point whose sphere holds it, and by no other), the grid's lists against the cells a
//! CPU computes for each hit point, empty inputs, and the one-line swap of the BVH node for the
//! grid in the hybrid graph, which must leave the image as it was.

mod common;

use std::collections::HashSet;

use common::pass_harness::{PassHarness, hit_point_resource, photon_hits_resource_with};
use common::rng::Rng;
use common::*;

use glam::Vec3;
use hppm::gpu::GpuContext;
use hppm::gpu_scene::layout::UNBOUNDED;
use hppm::passes::hit_point_grid::{
    CELLS_PER_HIT_POINT, GRID_INFO_BYTES, GridInfo, KIND, bucket_count,
};
use hppm::passes::hit_points::{GpuHitPoint, GpuPhotonHit, NO_PIXEL};
use hppm::scene::Scene;

const SCENE: &str = "tests/refs/scenes/cornell_glass_sphere/scene.xml";
const SIZE: (u32, u32) = (32, 32);

/// The node alone on the scene's shared resources, and the scene's bounds.
struct Harness<'a> {
    pass: PassHarness<'a>,
    bounds_min: Vec3,
    bounds_max: Vec3,
}

impl<'a> Harness<'a> {
    fn new(gpu: &'a GpuContext, scene: &Scene, float_atomics: bool) -> Self {
        let pass = PassHarness::new(gpu, scene, SIZE, float_atomics);
        let uniform = pass.scene().uniform;
        Self {
            pass,
            bounds_min: Vec3::from(uniform.bounds_min),
            bounds_max: Vec3::from(uniform.bounds_max),
        }
    }

    /// Runs `hit_point_grid` alone once over `points` and the first `count` of `hits` (the
    /// rest lie in the buffer past the header's count and must be ignored).
    fn run(&self, points: &[GpuHitPoint], hits: &[GpuPhotonHit], count: u32) -> Outcome {
        let gpu = self.pass.gpu;
        let hit_points = hit_point_resource(gpu, points);
        let photon_hits = photon_hits_resource_with(gpu, hits, count);
        let mut pass = (KIND.construct)("()").expect("params");
        let inputs = [("hit_points", &hit_points), ("photon_hits", &photon_hits)];
        let out = self.pass.prepare(&KIND, &mut *pass, &inputs);
        // Two iterations: the second must rebuild from a grid the first left behind.
        self.pass.run(&mut *pass, 0, 1);
        self.pass.run(&mut *pass, 1, 1);
        let deposits = &out["deposits"];
        let cells: Vec<hppm::passes::hit_points::GpuDepositCell> = gpu
            .read_pod(&deposits.buffer, points.len())
            .expect("deposits readback");
        let grid = &out["grid"];
        let bytes = gpu
            .read_buffer(&grid.buffer, 0, GRID_INFO_BYTES + 4 * grid.len)
            .expect("grid readback");
        let info: GridInfo = bytemuck::pod_read_unaligned(&bytes[..GRID_INFO_BYTES as usize]);
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(
            &bytes[GRID_INFO_BYTES as usize..(GRID_INFO_BYTES + 4 * grid.len) as usize],
        );
        Outcome {
            counts: cells.iter().map(|c| c.count).collect(),
            flux: cells.iter().map(|c| c.flux).collect(),
            inner_counts: cells.iter().map(|c| c.inner_count).collect(),
            inner_flux: cells.iter().map(|c| c.inner_flux).collect(),
            info,
            words,
        }
    }
}

struct Outcome {
    counts: Vec<u32>,
    flux: Vec<[f32; 3]>,
    /// The same within half the radius (the kernel-bias estimate's sums).
    inner_counts: Vec<u32>,
    inner_flux: Vec<[f32; 3]>,
    info: GridInfo,
    words: Vec<u32>,
}

fn hit_point(position: Vec3, radius: f32, normal: Vec3, pixel: u32) -> GpuHitPoint {
    GpuHitPoint {
        position: position.to_array(),
        pixel,
        normal: normal.to_array(),
        radius,
        wo: normal.to_array(),
        depth: 1,
        weight: [1.0; 3],
        footprint: radius,
    }
}

/// A photon arriving along `wi` with flux 1 and no depth limit.
fn photon(position: Vec3, wi: Vec3) -> GpuPhotonHit {
    GpuPhotonHit {
        position: position.to_array(),
        remaining: UNBOUNDED,
        wi: wi.to_array(),
        in_medium: 0,
        flux: [1.0; 3],
        _pad_b: 0,
    }
}

/// gather_at's distance test in f32, with subnormal products and sums kept (IEEE) or flushed
/// to zero (as many GPUs do).
fn inside_f32(d: Vec3, r: f32, flush: bool) -> bool {
    let f = |x: f32| {
        if flush && x.abs() < f32::MIN_POSITIVE {
            0.0
        } else {
            x
        }
    };
    let dot = f(f(f(d.x * d.x) + f(d.y * d.y)) + f(d.z * d.z));
    dot <= f(r * r)
}

/// Whether gather_at (shaders/common/gather.wgsl) takes `hit` for `hp`, decided in f32 as the
/// kernel decides it: `Some` when the answer does not depend on rounding, `None` when the
/// photon lies on the sphere's surface within rounding (the kernel may sum the squares in
/// another order, or fused), on the normal plane, or where the answer depends on whether the
/// device flushes subnormals.
fn takes(hp: &GpuHitPoint, hit: &GpuPhotonHit) -> Option<bool> {
    if !hp.is_valid() {
        return Some(false);
    }
    let d32 = Vec3::from(hit.position) - Vec3::from(hp.position);
    let inside = inside_f32(d32, hp.radius, false);
    if inside != inside_f32(d32, hp.radius, true) {
        return None;
    }
    let d: [f64; 3] = std::array::from_fn(|i| hit.position[i] as f64 - hp.position[i] as f64);
    let d2: f64 = d.iter().map(|x| x * x).sum();
    let r2 = hp.radius as f64 * hp.radius as f64;
    if d2 > 0.0 && (d2 - r2).abs() <= 1e-5 * r2 {
        return None;
    }
    let facing: f64 = (0..3).map(|i| hp.normal[i] as f64 * hit.wi[i] as f64).sum();
    if inside && facing.abs() < 1e-6 {
        return None;
    }
    Some(inside && facing > 0.0)
}

/// Checks every hit point's photon count against the brute force over all pairs; returns the
/// number of (hit point, photon) pairs counted and of pairs left undecided by rounding.
fn check_counts(
    name: &str,
    points: &[GpuHitPoint],
    hits: &[GpuPhotonHit],
    got: &Outcome,
) -> (u64, u64) {
    let (mut pairs, mut undecided) = (0u64, 0u64);
    for (i, hp) in points.iter().enumerate() {
        let (mut sure, mut maybe) = (0u32, 0u32);
        for hit in hits {
            match takes(hp, hit) {
                Some(true) => sure += 1,
                Some(false) => {}
                None => maybe += 1,
            }
        }
        let count = got.counts[i];
        assert!(
            (sure..=sure + maybe).contains(&count),
            "{name}: hit point {i} ({hp:?}) gathered {count} photons, brute force {sure} \
             (+{maybe} on a boundary)"
        );
        // Flux 1 per photon and weight 1: the flux sum counts the photons again.
        for c in 0..3 {
            assert_eq!(got.flux[i][c], count as f32, "{name}: hit point {i} flux");
        }
        // Within half the radius, by the same test: would catch the inner sums taken at the
        // full radius (a bias estimate of 0) or at R/4 (the square's factor applied twice).
        let half = GpuHitPoint {
            radius: 0.5 * hp.radius,
            ..*hp
        };
        let (inner_sure, inner_maybe) =
            hits.iter()
                .fold((0u32, 0u32), |(s, m), hit| match takes(&half, hit) {
                    Some(true) => (s + 1, m),
                    Some(false) => (s, m),
                    None => (s, m + 1),
                });
        let inner = got.inner_counts[i];
        assert!(
            (inner_sure..=inner_sure + inner_maybe).contains(&inner),
            "{name}: hit point {i} gathered {inner} photons within R/2, brute force              {inner_sure} (+{inner_maybe} on a boundary)"
        );
        for c in 0..3 {
            assert_eq!(
                got.inner_flux[i][c], inner as f32,
                "{name}: hit point {i} inner flux"
            );
        }
        pairs += count as u64;
        undecided += maybe as u64;
    }
    (pairs, undecided)
}

/// The buckets `hit_point_grid.wgsl` hashes cell `c` to (Teschner's hash, murmur3 finaliser).
fn bucket_of(c: [i32; 3], mask: u32) -> u32 {
    let mut h = (c[0] as u32).wrapping_mul(73_856_093)
        ^ (c[1] as u32).wrapping_mul(19_349_663)
        ^ (c[2] as u32).wrapping_mul(83_492_791);
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 16;
    h & mask
}

/// `cell_of` in the shader, with the cell the GPU chose.
fn cell_of(x: Vec3, origin: Vec3, inv_cell: f32) -> [i32; 3] {
    let limit = (1u32 << 30) as f32;
    let c = ((x - origin) * inv_cell).floor();
    c.to_array().map(|v| v.clamp(-limit, limit) as i32)
}

/// `box_radius` in the shader.
fn box_radius(hp: &GpuHitPoint) -> f32 {
    (hp.radius * (1.0 + 1e-5f32)).clamp(2.2e-19, 1e30)
}

/// The grid's own contract, independent of where photons fall: the cell edge bounds every box
/// to 2 cells per axis, every list entry belongs to a valid hit point and sits in the bucket of
/// the cell its index names, no list holds a hit point twice, and every valid hit point is in
/// the bucket of every cell its box overlaps.
fn check_grid(name: &str, points: &[GpuHitPoint], got: &Outcome, origin: Vec3) {
    let info = &got.info;
    let valid: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].is_valid())
        .collect();
    assert_eq!(info.valid as usize, valid.len(), "{name}: valid hit points");
    assert_eq!(info.clipped, 0, "{name}: boxes wider than 2 cells");
    let max_radius = valid
        .iter()
        .map(|&i| box_radius(&points[i]))
        .fold(0.0f32, f32::max);
    assert_eq!(info.max_radius, max_radius, "{name}: largest box radius");
    if !valid.is_empty() {
        assert!(
            info.cell >= 2.0 * max_radius,
            "{name}: cell {} under twice the radius {max_radius}",
            info.cell
        );
    }
    let buckets = bucket_count(points.len() as u64) as usize;
    let mask = buckets as u32 - 1;
    let (heads, links) = got.words.split_at(buckets);
    assert_eq!(
        links.len() as u64,
        CELLS_PER_HIT_POINT * points.len() as u64,
        "{name}: entry pool"
    );
    let mut listed = HashSet::new();
    for (bucket, &head) in heads.iter().enumerate() {
        let mut in_bucket = HashSet::new();
        let mut link = head;
        while link != 0 {
            let entry = link as usize - 1;
            let (slot, k) = (entry / 8, entry % 8);
            let hp = &points[slot];
            assert!(hp.is_valid(), "{name}: invalid hit point {slot} listed");
            assert!(
                in_bucket.insert(slot),
                "{name}: hit point {slot} twice in bucket {bucket}"
            );
            let lo = cell_of(
                Vec3::from(hp.position) - box_radius(hp),
                origin,
                info.inv_cell,
            );
            let offset = [k & 1, (k >> 1) & 1, k >> 2].map(|o| o as i32);
            let cell = std::array::from_fn(|a| lo[a] + offset[a]);
            assert_eq!(
                bucket_of(cell, mask) as usize,
                bucket,
                "{name}: entry {entry}'s bucket"
            );
            listed.insert((slot, bucket as u32));
            link = links[entry];
            assert!(listed.len() <= links.len(), "{name}: a list loops");
        }
    }
    assert_eq!(
        listed.len(),
        info.inserted as usize,
        "{name}: entries pushed"
    );
    for &i in &valid {
        let hp = &points[i];
        let p = Vec3::from(hp.position);
        let r = box_radius(hp);
        let lo = cell_of(p - r, origin, info.inv_cell);
        let hi = cell_of(p + r, origin, info.inv_cell);
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let bucket = bucket_of([x, y, z], mask);
                    assert!(
                        listed.contains(&(i, bucket)),
                        "{name}: hit point {i} missing from cell {x} {y} {z}"
                    );
                }
            }
        }
    }
}

/// Random hit points in and around the scene (a quarter of its extent outside on every side)
/// with radii log-uniform in `radii` (fractions of the scene's extent), some invalid (no pixel,
/// or radius 0), groups of coincident ones; photons near every hit point (inside and just
/// outside its sphere, some at its centre, some near its box's faces) and spread over the same
/// region, arriving on the hit points' side.
fn random_case(
    rng: &mut Rng,
    (lo, hi): (Vec3, Vec3),
    n: usize,
    radii: (f32, f32),
) -> (Vec<GpuHitPoint>, Vec<GpuPhotonHit>) {
    let extent = (hi - lo).max_element();
    let (r_lo, r_hi) = (radii.0 * extent, radii.1 * extent);
    let (region_lo, region_hi) = (lo - 0.25 * extent, hi + 0.25 * extent);
    let up = Vec3::Y;
    let mut points = Vec::with_capacity(n);
    while points.len() < n {
        let position = rng.in_box(region_lo, region_hi);
        let normal = if rng.unit() < 0.8 {
            (up + 0.3 * rng.direction()).normalize()
        } else {
            rng.direction()
        };
        let radius = rng.log_uniform(r_lo, r_hi);
        let pixel = if rng.unit() < 0.1 {
            NO_PIXEL
        } else {
            points.len() as u32
        };
        let radius = if rng.unit() < 0.05 { 0.0 } else { radius };
        points.push(hit_point(position, radius, normal, pixel));
        // Coincident hit points: same place, other radii.
        if rng.unit() < 0.02 {
            for _ in 0..3 {
                let r = rng.log_uniform(r_lo, r_hi);
                points.push(hit_point(position, r, normal, points.len() as u32));
            }
        }
    }
    points.truncate(n);
    let mut hits = Vec::new();
    for hp in &points {
        let p = Vec3::from(hp.position);
        let n = Vec3::from(hp.normal);
        let r = if hp.radius > 0.0 { hp.radius } else { r_lo };
        hits.push(photon(p, n));
        for _ in 0..6 {
            let at = p + rng.direction() * r * 1.3 * rng.unit().cbrt();
            hits.push(photon(at, n));
        }
        // Along an axis to the sphere's box face, where a neighbouring cell begins.
        let axis = [Vec3::X, Vec3::Y, Vec3::Z][rng.next_u32() as usize % 3];
        hits.push(photon(p + axis * r * 0.999, n));
        hits.push(photon(p - axis * r * 0.999, n));
    }
    for _ in 0..n * 3 {
        let wi = if rng.unit() < 0.5 {
            up
        } else {
            rng.direction()
        };
        hits.push(photon(rng.in_box(region_lo, region_hi), wi));
    }
    (points, hits)
}

/// Extremes: one sphere larger than the scene, tiny radii (down to 1e-30, met only by photons
/// at their centre), hit points far outside the scene, photons far away.
fn extreme_case(rng: &mut Rng, lo: Vec3, hi: Vec3) -> (Vec<GpuHitPoint>, Vec<GpuPhotonHit>) {
    let extent = (hi - lo).max_element();
    let centre = 0.5 * (lo + hi);
    let up = Vec3::Y;
    let mut points = vec![hit_point(centre, 3.0 * extent, up, 0)];
    for i in 0..200u32 {
        let position = rng.in_box(lo, hi);
        let radius = match i % 4 {
            0 => 1e-30,
            1 => 1e-6 * extent,
            2 => rng.log_uniform(1e-3 * extent, 0.2 * extent),
            _ => 0.05 * extent,
        };
        points.push(hit_point(position, radius, up, i + 1));
    }
    for i in 0..10u32 {
        let far = centre + rng.direction() * extent * 1e3;
        points.push(hit_point(far, 0.1 * extent, up, 1000 + i));
    }
    // Near the world origin, where f32 squares underflow.
    points.push(hit_point(Vec3::new(1e-30, 0.0, 0.0), 1e-30, up, 2000));
    let mut hits = Vec::new();
    for hp in &points {
        let p = Vec3::from(hp.position);
        hits.push(photon(p, up));
        let r = hp.radius.min(extent);
        for _ in 0..4 {
            hits.push(photon(p + rng.direction() * r * 1.2 * rng.unit(), up));
        }
    }
    hits.push(photon(Vec3::new(4e-30, 0.0, 0.0), up));
    for _ in 0..500 {
        hits.push(photon(rng.in_box(lo, hi), up));
    }
    for _ in 0..20 {
        hits.push(photon(centre + rng.direction() * 1e12, up));
    }
    (points, hits)
}

/// Two hit points in a 3-slot grid (8 buckets): their up to 8 cells each share buckets, so each
/// hit point's own cells collide in the hash, and a list holding a hit point twice would
/// deposit its photons twice.
fn collision_case(rng: &mut Rng, lo: Vec3, hi: Vec3) -> (Vec<GpuHitPoint>, Vec<GpuPhotonHit>) {
    let extent = (hi - lo).max_element();
    let up = Vec3::Y;
    let r = 0.1 * extent;
    let points = vec![
        hit_point(rng.in_box(lo, hi), r, up, 0),
        hit_point(rng.in_box(lo, hi), r, up, NO_PIXEL),
        hit_point(rng.in_box(lo, hi), r, up, 2),
    ];
    let mut hits = Vec::new();
    for hp in &points {
        for _ in 0..2000 {
            let at = Vec3::from(hp.position) + rng.direction() * r * 1.3 * rng.unit().cbrt();
            hits.push(photon(at, up));
        }
    }
    // Not positions: with 8 buckets mostly holding a hit point, their cell's list is likely
    // walked if they are not skipped, and gather_at alone would take a NaN distance.
    hits.push(photon(Vec3::NAN, up));
    hits.push(photon(Vec3::new(f32::INFINITY, 0.5, 0.5), up));
    hits.push(photon(Vec3::new(f32::NEG_INFINITY, 0.5, f32::NAN), up));
    (points, hits)
}

/// What this catches: a cell edge too small for the largest sphere (photons missed in cells a
/// box spans but the hit point was not inserted into), a lookup in the wrong cell or bucket,
/// a hit point listed twice in one bucket when two of its cells collide in the hash (photons
/// deposited twice), lists broken by concurrent pushes or by heads not reset between iterations
/// (lost or repeated entries), invalid hit points gathering, points outside the scene bounds
/// clamped into cells that lose them, photons past the header's count being read, and NaN or
/// infinite photon positions reaching gather_at (whose rejection test a NaN distance passes).
#[test]
fn grid_gather_matches_brute_force() {
    let gpu = gpu();
    let scene = load_scene(SCENE);
    let mut atomics = vec![gpu.has_float_atomics()];
    if atomics[0] {
        atomics.push(false);
    }
    for float_atomics in atomics {
        let h = Harness::new(&gpu, &scene, float_atomics);
        let (lo, hi) = (h.bounds_min, h.bounds_max);
        let mut rng = Rng(0x5eed_1234_abcd_0001);
        let cases = [
            (
                "random",
                random_case(&mut rng, (lo, hi), 3000, (2e-3, 6e-2)),
            ),
            // Radii far below the scene's size: the cell floor (a fraction of the largest
            // coordinate) sets the cell, not the radii.
            ("fine", random_case(&mut rng, (lo, hi), 2000, (1e-7, 1e-5))),
            ("extremes", extreme_case(&mut rng, lo, hi)),
            ("collisions", collision_case(&mut rng, lo, hi)),
        ];
        for (name, (points, mut hits)) in cases {
            let name = format!("{name} (float atomics {float_atomics})");
            let count = hits.len() as u32;
            // Past the header's count: photons on every hit point, which must not be gathered.
            let junk: Vec<GpuPhotonHit> = points
                .iter()
                .map(|hp| photon(Vec3::from(hp.position), Vec3::from(hp.normal)))
                .collect();
            hits.extend(junk);
            let got = h.run(&points, &hits, count);
            let hits = &hits[..count as usize];
            let (pairs, undecided) = check_counts(&name, &points, hits, &got);
            check_grid(&name, &points, &got, lo);
            eprintln!(
                "{name}: {} hit points ({} valid), {} photons, {pairs} deposits match brute \
                 force ({undecided} pairs on a boundary); cell {:.4e}, {} entries",
                points.len(),
                got.info.valid,
                hits.len(),
                got.info.cell,
                got.info.inserted
            );
            assert!(pairs > 1000, "{name}: the case must deposit photons");
        }
    }
}

/// Nothing to gather: no valid hit point, no photon hit, no hit-point slot at all. Deposits stay
/// zero and every run finishes.
#[test]
fn empty_inputs_deposit_nothing() {
    let gpu = gpu();
    let scene = load_scene(SCENE);
    let h = Harness::new(&gpu, &scene, gpu.has_float_atomics());
    let (lo, hi) = (h.bounds_min, h.bounds_max);
    let mut rng = Rng(99);
    let (mut points, hits) = random_case(&mut rng, (lo, hi), 500, (2e-3, 6e-2));
    let count = hits.len() as u32;

    // Every hit point invalid: without a pixel, or with radius 0.
    let invalid: Vec<GpuHitPoint> = (0..points.len())
        .map(|i| {
            let mut hp = points[i];
            if i % 2 == 0 {
                hp.pixel = NO_PIXEL;
            } else {
                hp.radius = 0.0;
            }
            hp
        })
        .collect();
    let got = h.run(&invalid, &hits, count);
    assert!(
        got.counts.iter().all(|&c| c == 0),
        "invalid hit points gathered"
    );
    assert_eq!((got.info.valid, got.info.inserted), (0, 0));
    assert!(got.words.iter().all(|&w| w == 0), "an empty grid has lists");

    // Valid hit points, no photon hit stored (the buffer holds some past the count).
    let got = h.run(&points, &hits, 0);
    assert!(
        got.counts.iter().all(|&c| c == 0),
        "photons past the count gathered"
    );
    assert!(got.info.inserted > 0);

    // No hit-point slot at all.
    points.clear();
    let got = h.run(&points, &hits, count);
    assert_eq!(got.info.valid, 0);
}

#[test]
fn unknown_params_are_rejected() {
    assert!((KIND.construct)("()").is_ok());
    assert!((KIND.construct)("(cell_size: 0.1)").is_err());
}

/// The graph's lines that are not comments.
fn graph_lines(relative: &str) -> Vec<String> {
    let text = std::fs::read_to_string(repo_path(relative)).expect("graph file");
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .map(str::to_string)
        .collect()
}

fn render(
    gpu: &GpuContext,
    scene: &Scene,
    graph: &str,
    seed: u64,
) -> Vec<(&'static str, hppm::image::Image)> {
    let graph = hppm::graph::load_graph(&repo_path(graph), hppm::passes::builtin_kinds())
        .unwrap_or_else(|e| panic!("{graph}: {e}"));
    let mut renderer =
        hppm::render::Renderer::new(gpu, scene, graph, 32, 32, seed).expect("renderer");
    for _ in 0..8 {
        renderer.iterate().expect("iteration");
    }
    let mut images = renderer.aovs().expect("aovs");
    images.push(("image", renderer.image().expect("image")));
    images
}

/// The grid finds the photons the BVH finds, so swapping the gather node in graphs/hybrid.ron
/// (the only line graphs/hybrid_grid.ron changes) leaves the image as it was, up to the order in
/// which deposits add their flux; and the caustic it feeds is not empty.
#[test]
fn swapping_the_bvh_for_the_grid_keeps_the_image() {
    let (bvh, grid) = (
        graph_lines("graphs/hybrid.ron"),
        graph_lines("graphs/hybrid_grid.ron"),
    );
    assert_eq!(bvh.len(), grid.len(), "graph files differ in length");
    let differ: Vec<(&String, &String)> = bvh.iter().zip(&grid).filter(|(a, b)| a != b).collect();
    assert_eq!(differ.len(), 1, "graph files differ in {differ:?}");
    assert!(
        differ[0].1.contains("pass: \"hit_point_grid\""),
        "{differ:?}"
    );

    let gpu = gpu();
    let scene = load_scene(SCENE);
    let seed = 7;
    let with_bvh = render(&gpu, &scene, "graphs/hybrid.ron", seed);
    let with_grid = render(&gpu, &scene, "graphs/hybrid_grid.ron", seed);
    assert_eq!(with_bvh.len(), with_grid.len());
    for ((name, a), (other, b)) in with_grid.iter().zip(&with_bvh) {
        assert_eq!(name, other);
        let relmse = a.relmse(b).expect("same size");
        eprintln!("{name}: relMSE grid vs BVH {relmse:.3e}");
        assert!(
            relmse <= 1e-5,
            "{name}: relMSE {relmse} between grid and BVH renders"
        );
    }
    let energy = |images: &[(&str, hppm::image::Image)], slot: &str| -> f64 {
        let (_, image) = images
            .iter()
            .find(|(n, _)| *n == slot)
            .unwrap_or_else(|| panic!("no {slot} image"));
        image.pixels.iter().flatten().map(|&v| v as f64).sum()
    };
    let caustic = energy(&with_grid, "caustic");
    eprintln!(
        "caustic energy {caustic:.4e}, image {:.4e}",
        energy(&with_grid, "image")
    );
    assert!(caustic > 0.0, "the grid's caustic is empty");
}
