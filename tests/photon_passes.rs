//! The photon-mapping passes run alone on small synthetic inputs: the hit-point BVH against
//! all-pairs search, photon deposits against a CPU tracer of the same photons, emitted power
//! against the lights' analytic power, and the merge against the update formulas in f64. The
//! float-atomic and compare-and-swap paths are both run and must agree.

mod common;

use common::pass_harness::{
    PassHarness, brute_force, check_range_queries, hit_point, hit_point_resource_with,
};
use common::*;
use glam::Vec3;
use hppm::gpu::GpuContext;
use hppm::gpu_scene::layout::GpuScene;
use hppm::graph::exec::Wiring;
use hppm::graph::pass::{ExecCtx, Pass, Recorder, Resource};
use hppm::passes::hit_point_bvh_sah::{self, HitPointBvhSah};
use hppm::passes::hit_points::{
    DEPOSIT_BYTES, DEPOSITS, GpuDepositCell, GpuHitPoint, GpuPhotonHit, NO_PIXEL, PhotonHitsHeader,
    build_tree,
};
use hppm::passes::photon_trace::{self, PhotonMode, PhotonTrace, PhotonTraceParams};
use hppm::passes::rng::Stream;
use hppm::passes::sppm::{self, Merge, MergeParams};
use hppm::scene::Scene;
use hppm::scene::bvh::{build_sah, closest_hit, scene_boxes};
use std::collections::HashMap;

/// (count, RGB flux) per hit point from a deposits buffer; the bytes are the same for both
/// atomics paths (a u32 count, then the f32 bits of each channel).
fn read_deposits(gpu: &GpuContext, deposits: &Resource) -> Vec<(u32, [f32; 3])> {
    let cells: Vec<GpuDepositCell> = gpu
        .read_pod(&deposits.buffer, deposits.len as usize)
        .expect("readback");
    cells.iter().map(|c| (c.count, c.flux)).collect()
}

// ---------------------------------------------------------------------------------------------
// Hit-point BVH range queries (CPU builder, GPU layout) against all pairs.

struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn vec3(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * scale
    }
}

fn check_queries(name: &str, points: &[GpuHitPoint], queries: &[Vec3]) {
    check_range_queries(name, &build_tree(points), points, queries);
}

#[test]
fn hit_point_tree_range_queries_match_brute_force() {
    let mut rng = Lcg(1);
    let queries: Vec<Vec3> = (0..2000).map(|_| rng.vec3(10.0)).collect();
    check_queries("empty", &[], &queries);
    check_queries("one point", &[hit_point(Vec3::splat(5.0), 1.0)], &queries);
    let random: Vec<GpuHitPoint> = (0..3000)
        .map(|_| hit_point(rng.vec3(10.0), 0.05 + rng.next()))
        .collect();
    check_queries("random", &random, &queries);
    // Queries at the hit points themselves: every one must find at least itself.
    let centres: Vec<Vec3> = random.iter().map(|h| Vec3::from(h.position)).collect();
    check_queries("random, queries at centres", &random, &centres);
    let coincident: Vec<GpuHitPoint> = (0..500)
        .map(|i| hit_point(Vec3::splat(3.0), 0.1 + i as f32 * 1e-3))
        .collect();
    check_queries("coincident", &coincident, &queries);
    let near_coincident: Vec<Vec3> = (0..200).map(|_| Vec3::splat(3.0) + rng.vec3(0.2)).collect();
    check_queries("coincident, near queries", &coincident, &near_coincident);
    let huge: Vec<GpuHitPoint> = (0..300).map(|_| hit_point(rng.vec3(10.0), 1e4)).collect();
    check_queries("huge radii", &huge, &queries[..100]);
    let tiny: Vec<GpuHitPoint> = (0..3000).map(|_| hit_point(rng.vec3(10.0), 1e-6)).collect();
    let at_tiny: Vec<Vec3> = tiny
        .iter()
        .step_by(3)
        .map(|h| Vec3::from(h.position) + Vec3::splat(3e-7))
        .collect();
    check_queries("tiny radii", &tiny, &at_tiny);
    let mut mixed = random.clone();
    for (i, hp) in mixed.iter_mut().enumerate() {
        if i % 3 == 0 {
            hp.pixel = NO_PIXEL;
        }
        if i % 7 == 0 {
            hp.radius = 0.0;
        }
    }
    check_queries("some invalid", &mixed, &queries);
}

#[test]
fn hit_point_tree_leaves_hold_one_hit_point_each_and_nodes_bound_children() {
    let mut rng = Lcg(2);
    let points: Vec<GpuHitPoint> = (0..1000)
        .map(|_| hit_point(rng.vec3(4.0), 0.01 + rng.next() * 0.2))
        .collect();
    let nodes = build_tree(&points);
    let mut seen = vec![0u32; points.len()];
    for n in &nodes {
        if n.count > 0 {
            assert_eq!(n.count, 1);
            seen[n.left_or_first as usize] += 1;
            let hp = &points[n.left_or_first as usize];
            for a in 0..3 {
                assert!(
                    n.min[a] <= hp.position[a] - hp.radius
                        && n.max[a] >= hp.position[a] + hp.radius
                );
            }
        } else {
            for child in [
                &nodes[n.left_or_first as usize],
                &nodes[n.left_or_first as usize + 1],
            ] {
                for a in 0..3 {
                    assert!(n.min[a] <= child.min[a] && n.max[a] >= child.max[a]);
                }
            }
        }
    }
    assert!(
        seen.iter().all(|&s| s == 1),
        "every hit point in exactly one leaf"
    );
}

// ---------------------------------------------------------------------------------------------
// Photon deposits against a CPU tracer of the same photons.

const PHOTON_SEED: u64 = 7;

fn floor_hit_points() -> Vec<GpuHitPoint> {
    let n = 24;
    let mut points = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let x = -1.9 + 3.8 * (i as f32 + 0.5) / n as f32;
            let z = -1.9 + 3.8 * (j as f32 + 0.5) / n as f32;
            let mut hp = hit_point(
                Vec3::new(x, 0.0, z),
                0.12 + 0.05 * ((i * 7 + j * 3) % 5) as f32,
            );
            hp.pixel = (j * n + i) as u32;
            hp.weight = [1.0, 0.5, 0.25];
            if (i + j) % 11 == 0 {
                hp.pixel = NO_PIXEL;
            }
            if (i * j) % 13 == 5 {
                // Facing down: photons reach it from behind and must be skipped.
                hp.normal = [0.0, -1.0, 0.0];
            }
            points.push(hp);
        }
    }
    points
}

/// Traces the photons of iteration 0 on the CPU with the shaders' random numbers and sampling,
/// depositing into every hit point within reach (all pairs). Caustic mode, one point light.
fn cpu_caustic_deposits(
    scene: &Scene,
    points: &[GpuHitPoint],
    photons: u32,
) -> Vec<(u32, [f64; 3])> {
    let bvh = build_sah(&scene_boxes(scene), 4);
    let light = scene.point_lights[0];
    let seed = hppm::passes::rng::photon_seed(PHOTON_SEED);
    let flux = light.intensity * (4.0 * std::f32::consts::PI) * (1.0 / photons as f32);
    let mut result = vec![(0u32, [0.0f64; 3]); points.len()];
    for index in 0..photons {
        let mut rng = Stream::new(index, 0, seed);
        let _pick = rng.next_f32();
        let _position = (rng.next_f32(), rng.next_f32());
        let u = (rng.next_f32(), rng.next_f32());
        let z = 1.0 - 2.0 * u.0;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u.1;
        let mut dir = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let mut origin = light.position;
        let mut after_specular = false;
        for segments in 1..=11u32 {
            let Some((t, prim)) = closest_hit(scene, &bvh, origin, dir) else {
                break;
            };
            let tri = &scene.triangles[prim as usize];
            let normal = (tri.v[1] - tri.v[0]).cross(tri.v[2] - tri.v[0]).normalize();
            let position = origin + t * dir;
            let wi = -dir;
            if wi.dot(normal) <= 0.0 {
                break;
            }
            match scene.materials[tri.material as usize].bsdf.kind() {
                "mirror" => {
                    dir = 2.0 * wi.dot(normal) * normal - wi;
                    after_specular = true;
                    let side = if dir.dot(normal) >= 0.0 { 1.0 } else { -1.0 };
                    // The shaders leave a surface by its rounding-error bound (offset_ray_origin
                    // in shaders/common/surface.wgsl), a few roundoffs of the position's
                    // magnitude; the model leaves it by as much.
                    let offset = 4.0 * f32::EPSILON * position.abs().max_element();
                    origin = position + side * offset * normal;
                }
                _ => {
                    if after_specular {
                        for i in brute_force(points, position) {
                            let hp = &points[i as usize];
                            if Vec3::from(hp.normal).dot(wi) > 0.0 && hp.depth + segments <= 12 {
                                result[i as usize].0 += 1;
                                for c in 0..3 {
                                    result[i as usize].1[c] += (flux[c] * hp.weight[c]) as f64;
                                }
                            }
                        }
                    }
                    break;
                }
            }
        }
    }
    result
}

/// Runs hit_point_bvh_sah then photon_trace (caustic mode) alone; returns the deposits.
fn gpu_caustic_deposits(
    gpu: &GpuContext,
    scene: &Scene,
    points: &[GpuHitPoint],
    photons: u32,
    float_atomics: bool,
    aim: bool,
) -> Vec<(u32, [f32; 3])> {
    let h = PassHarness::new(gpu, scene, (32, 32), float_atomics);
    let hit_points = hit_point_resource_with(gpu, 1, points);
    let mut photon_pass = PhotonTrace::new(PhotonTraceParams {
        mode: PhotonMode::Caustic,
        photons_per_iteration: Some(photons),
        aim,
        ..Default::default()
    });
    let photon_hits = h.prepare(&photon_trace::KIND, &mut photon_pass, &[])["photon_hits"].clone();
    h.run(&mut photon_pass, 0, PHOTON_SEED);
    let mut bvh = HitPointBvhSah::default();
    let inputs = [("hit_points", &hit_points), ("photon_hits", &photon_hits)];
    let out = h.prepare(&hit_point_bvh_sah::KIND, &mut bvh, &inputs);
    h.run(&mut bvh, 0, PHOTON_SEED);
    read_deposits(gpu, &out["deposits"])
}

#[test]
fn photon_deposits_match_a_cpu_tracer_of_the_same_photons() {
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let points = floor_hit_points();
    let photons = 1 << 18;
    let expected = cpu_caustic_deposits(&scene, &points, photons);
    for float_atomics in [gpu.has_float_atomics(), false] {
        let got = gpu_caustic_deposits(&gpu, &scene, &points, photons, float_atomics, false);
        let expected_total: u64 = expected.iter().map(|e| e.0 as u64).sum();
        let mut count_mismatch = 0u64;
        let mut flux_got = [0.0f64; 3];
        let mut flux_expected = [0.0f64; 3];
        for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
            count_mismatch += (g.0 as i64 - e.0 as i64).unsigned_abs();
            for c in 0..3 {
                flux_got[c] += g.1[c] as f64;
                flux_expected[c] += e.1[c];
            }
            let hp = &points[i];
            if !hp.is_valid() || hp.normal[1] < 0.0 {
                assert_eq!(
                    g.0, 0,
                    "hit point {i} is invalid or faces away but got photons"
                );
            }
        }
        eprintln!(
            "float atomics {float_atomics}: {expected_total} deposits on the CPU, {count_mismatch} differ on the GPU; flux GPU {flux_got:?} CPU {flux_expected:?}"
        );
        assert!(
            expected_total > 10_000,
            "the test scene must produce caustic deposits"
        );
        // GPU and CPU sines differ in the last bits, which moves a deposit across a radius
        // boundary now and then; nothing else may differ.
        assert!(
            (count_mismatch as f64) < 2e-3 * expected_total as f64,
            "{count_mismatch} of {expected_total} deposits differ"
        );
        for c in 0..3 {
            let rel = (flux_got[c] - flux_expected[c]).abs() / flux_expected[c];
            assert!(rel < 2e-3, "channel {c}: flux differs by {rel}");
        }
    }
}

#[test]
fn float_atomic_and_compare_and_swap_deposits_agree() {
    let gpu = gpu();
    if !gpu.has_float_atomics() {
        eprintln!("adapter has no SHADER_FLOAT32_ATOMIC: only the CAS path exists here");
    }
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let points = floor_hit_points();
    let a = gpu_caustic_deposits(
        &gpu,
        &scene,
        &points,
        1 << 15,
        gpu.has_float_atomics(),
        true,
    );
    let b = gpu_caustic_deposits(&gpu, &scene, &points, 1 << 15, false, true);
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(x.0, y.0, "hit point {i}: counts differ");
        for c in 0..3 {
            // Only the order of the float additions may differ.
            assert!(
                (x.1[c] - y.1[c]).abs() <= 1e-5 * x.1[c].abs().max(1e-30),
                "hit point {i}: {:?} vs {:?}",
                x.1,
                y.1
            );
        }
    }
}

/// Aiming caustic photons at the specular surfaces' bounding sphere only changes which photons
/// are spent: the flux each hit point gathers is the same in expectation, with more deposits.
#[test]
fn aimed_caustic_photons_gather_the_same_flux() {
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let points = floor_hit_points();
    let photons = 1 << 20;
    let fa = gpu.has_float_atomics();
    let plain = gpu_caustic_deposits(&gpu, &scene, &points, photons, fa, false);
    let aimed = gpu_caustic_deposits(&gpu, &scene, &points, photons, fa, true);
    let total = |d: &[(u32, [f32; 3])]| -> (u64, f64) {
        (
            d.iter().map(|x| x.0 as u64).sum(),
            d.iter().map(|x| x.1[0] as f64).sum(),
        )
    };
    let (n_plain, f_plain) = total(&plain);
    let (n_aimed, f_aimed) = total(&aimed);
    eprintln!(
        "unaimed: {n_plain} deposits, flux {f_plain:.4}; aimed: {n_aimed} deposits, flux {f_aimed:.4}"
    );
    assert!(
        (f_aimed - f_plain).abs() < 0.02 * f_plain,
        "total flux {f_aimed} vs {f_plain}"
    );
    assert!(n_aimed > n_plain, "aiming must not lose caustic photons");
    // Per quarter of the floor, so a wrong direction distribution shows too.
    for quarter in 0..4 {
        let sum = |d: &[(u32, [f32; 3])]| -> f64 {
            (0..points.len())
                .filter(|&i| {
                    let p = points[i].position;
                    ((p[0] > 0.0) as usize) * 2 + (p[2] > 0.0) as usize == quarter
                })
                .map(|i| d[i].1[0] as f64)
                .sum()
        };
        let (a, b) = (sum(&aimed), sum(&plain));
        assert!(
            (a - b).abs() <= 0.05 * b,
            "quarter {quarter}: aimed {a} vs unaimed {b}"
        );
    }
}

/// Caustic photon hits of iteration 0 (photon_trace alone, unaimed): (count, flux summed over
/// RGB) of those landing within `half` of the origin in x and z of the frame `tilt` turns.
fn caustic_hits_near_origin(
    gpu: &GpuContext,
    scene: &Scene,
    photons: u32,
    tilt: glam::Quat,
    half: f32,
) -> (u32, f64) {
    let h = PassHarness::new(gpu, scene, (16, 16), gpu.has_float_atomics());
    let mut pass = PhotonTrace::new(PhotonTraceParams {
        mode: PhotonMode::Caustic,
        photons_per_iteration: Some(photons),
        aim: false,
        ..Default::default()
    });
    let photon_hits = h.prepare(&photon_trace::KIND, &mut pass, &[])["photon_hits"].clone();
    h.run(&mut pass, 0, PHOTON_SEED);
    let header: PhotonHitsHeader = photon_hits.read_header(gpu).expect("readback");
    assert_eq!(header.dropped, 0, "the photon hits buffer overflowed");
    let hits: Vec<GpuPhotonHit> = photon_hits.read(gpu).expect("readback");
    hits[..header.count as usize]
        .iter()
        .filter(|hit| {
            let local = tilt.inverse() * Vec3::from(hit.position);
            local.x.abs() < half && local.z.abs() < half
        })
        .fold((0, 0.0), |(n, flux), hit| {
            (
                n + 1,
                flux + hit.flux.iter().map(|&c| c as f64).sum::<f64>(),
            )
        })
}

/// A glass slab standing on a diffuse floor (its bottom face in the floor's plane, as a drinking
/// glass on a table) under a point light: every photon refracted through the top lands on the
/// floor beneath, exactly as where the slab has no bottom face at all. The whole set is tilted,
/// so that the two planes agree only up to rounding and ties fall either way, as they do with
/// meshes; it is built with the floor first and last. Would catch photons leaving through the
/// coplanar contact (a tie between the slab's bottom and the floor going to the slab), which
/// lost about half of them here and darkened the caustic under water_glass's glass by 0.4% of
/// the image.
#[test]
fn photons_land_on_a_surface_a_dielectric_stands_on() {
    let gpu = gpu();
    let (axis, degrees) = (Vec3::new(0.8, 0.3, 0.5).normalize(), 27.0f32);
    let tilt = glam::Quat::from_axis_angle(axis, degrees.to_radians());
    let light = tilt * Vec3::new(0.1, 1.2, -0.05);
    let turn = format!(
        "Rotate(axis: ({}, {}, {}), degrees: {degrees})",
        axis.x, axis.y, axis.z
    );
    let floor = format!(
        r#"(shape: Rectangle, material: "floor", to_world: [Matrix((3, 0, 0, 0,  0, 0, 1, 0,  0, -3, 0, 0,  0, 0, 0, 1)), {turn}]),"#
    );
    let scene_with = |first: &str, second: &str| {
        ron_scene(
            "slab_on_floor.ron",
            &format!(
                r#"(
            camera: (origin: (0, 3, 3), target: (0, 0, 0), up: (0, 1, 0), fov_x: 40, width: 16, height: 16),
            materials: {{ "floor": Diffuse(reflectance: (0.5, 0.5, 0.5)), "glass": Dielectric(int_ior: 1.5) }},
            shapes: [ {first} {second} ],
            point_lights: [(position: ({}, {}, {}), intensity: (1, 1, 1))],
        )"#,
                light.x, light.y, light.z
            ),
        )
    };
    // y in [0, 0.2], |x|, |z| <= 1.5; photons landing within 1 of the origin entered the top
    // within 1.2 of it and never met a side.
    let slab = format!(
        r#"(shape: Cube, material: "glass", to_world: [Scale((1.5, 0.1, 1.5)), Translate((0, 0.1, 0)), {turn}]),"#
    );
    let top_only = format!(
        r#"(shape: Rectangle, material: "glass", to_world: [Matrix((1.5, 0, 0, 0,  0, 0, 1, 0.2,  0, -1.5, 0, 0,  0, 0, 0, 1)), {turn}]),"#
    );
    let photons = 1 << 18;
    let (n_open, flux_open) =
        caustic_hits_near_origin(&gpu, &scene_with(&floor, &top_only), photons, tilt, 1.0);
    assert!(
        n_open > 20_000,
        "the light must send photons through the slab"
    );
    for (order, scene) in [
        ("floor first", scene_with(&floor, &slab)),
        ("floor last", scene_with(&slab, &floor)),
    ] {
        let (n, flux) = caustic_hits_near_origin(&gpu, &scene, photons, tilt, 1.0);
        eprintln!(
            "slab on the floor ({order}): {n} photons ({flux:.5}); top face only: {n_open} ({flux_open:.5})"
        );
        let rel = (flux - flux_open).abs() / flux_open;
        assert!(
            rel < 2e-3,
            "{order}: {n} photons land under the slab, {n_open} without its bottom face: flux differs by {rel}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Emitted power.

#[test]
fn photons_carry_the_lights_power() {
    let gpu = gpu();
    // A point light (power 4 pi I) and a one-sided area light 2 x 1 (power pi A L).
    let scene = ron_scene(
        "two_lights.ron",
        r#"(
            camera: (origin: (0, 0, 5), target: (0, 0, 0), up: (0, 1, 0), fov_x: 40, width: 16, height: 16),
            materials: { "black": Diffuse(reflectance: (0, 0, 0)) },
            shapes: [
                (shape: Rectangle, material: "black", emission: Some((1.5, 2, 0.5)), to_world: [Scale((1, 0.5, 1))]),
            ],
            point_lights: [(position: (0, 0, 2), intensity: (0.3, 0.1, 0.2))],
        )"#,
    );
    let pi = std::f64::consts::PI;
    let expected = [
        pi * 2.0 * 1.5 + 4.0 * pi * 0.3,
        pi * 2.0 * 2.0 + 4.0 * pi * 0.1,
        pi * 2.0 * 0.5 + 4.0 * pi * 0.2,
    ];
    for float_atomics in [gpu.has_float_atomics(), false] {
        let h = PassHarness::new(&gpu, &scene, (16, 16), float_atomics);
        let mut photons = PhotonTrace::new(PhotonTraceParams {
            mode: PhotonMode::All,
            photons_per_iteration: Some(1 << 18),
            ..Default::default()
        });
        h.prepare(&photon_trace::KIND, &mut photons, &[]);
        h.run(&mut photons, 0, 1);
        let emitted = photons.emitted_flux(&gpu).expect("readback");
        eprintln!("float atomics {float_atomics}: emitted {emitted:?}, analytic {expected:?}");
        for c in 0..3 {
            let rel = (emitted[c] as f64 - expected[c]).abs() / expected[c];
            // Which light each photon picks is random: about 0.2% noise for 2^18 photons.
            assert!(
                rel < 0.01,
                "channel {c}: emitted {} vs power {}",
                emitted[c],
                expected[c]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Merge against the formulas in f64.

struct CpuSlot {
    n: f64,
    r: f64,
    tau: [f64; 3],
    photons: u64,
    /// Sum over iterations of (Phi - 4 Phi_inner) / R^2 at the iteration's radius.
    bias: [f64; 3],
}

impl CpuSlot {
    fn new(radius: f32) -> Self {
        CpuSlot {
            n: 0.0,
            r: radius as f64,
            tau: [0.0; 3],
            photons: 0,
            bias: [0.0; 3],
        }
    }

    /// The kernel-bias term of one iteration's deposit (flux within R and within R / 2).
    fn add_bias(&mut self, m: u32, flux: [f32; 3], inner: [f32; 3]) {
        if m == 0 || self.r <= 0.0 {
            return;
        }
        for c in 0..3 {
            self.bias[c] += (flux[c] as f64 - 4.0 * inner[c] as f64) / (self.r * self.r);
        }
    }

    /// The literal progressive update of one iteration's `m` photons of total flux `flux`.
    fn merge(&mut self, m: u32, flux: [f32; 3], alpha: f64, min_radius: f64) {
        if m == 0 || self.r <= 0.0 {
            return;
        }
        let mf = m as f64;
        let r_new = (self.r * ((self.n + alpha * mf) / (self.n + mf)).sqrt()).max(min_radius);
        for (tau, f) in self.tau.iter_mut().zip(flux) {
            *tau = (*tau + f as f64) * (r_new / self.r).powi(2);
        }
        self.n += alpha * mf;
        self.r = r_new;
        self.photons += m as u64;
    }
}

/// Deposit cells as the photon pass leaves them, with no photon within half the radius.
fn deposit_words(deposits: impl Iterator<Item = (u32, [f32; 3])>) -> Vec<GpuDepositCell> {
    deposits
        .map(|(m, f)| deposit_cell(m, f, [0.0; 3]))
        .collect()
}

fn deposit_cell(count: u32, flux: [f32; 3], inner_flux: [f32; 3]) -> GpuDepositCell {
    GpuDepositCell {
        count,
        flux,
        inner_flux,
        inner_count: if inner_flux == [0.0; 3] {
            0
        } else {
            count / 4 + 1
        },
    }
}

/// One slot's deposit of one iteration: photon count, flux, flux within half the radius.
type Deposit = (u32, [f32; 3], [f32; 3]);

/// A `Merge` (sppm) prepared on `hit_points` and `deposits`, and its outputs.
fn prepare_merge(
    h: &PassHarness<'_>,
    merge: &mut Merge,
    hit_points: &Resource,
    deposits: &Resource,
) -> HashMap<&'static str, Resource> {
    // As in a graph, its radii go back to the camera pass.
    let wiring = Wiring {
        consumed: vec!["radiance", "radii"],
        ..Default::default()
    };
    h.prepare_wired(
        &sppm::KIND,
        merge,
        &[("hit_points", hit_points), ("deposits", deposits)],
        &wiring,
    )
}

fn merge_with(alpha: f64) -> Merge {
    Merge::new(MergeParams {
        alpha: alpha as f32,
        ..Default::default()
    })
}

#[test]
fn merge_matches_the_progressive_update_in_f64() {
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let (width, height, slots) = (4u32, 2u32, 2u32);
    let count = (width * height * slots) as usize;
    let alpha = 0.7f64;
    let min_radius = 1e-5
        * GpuScene::new(&scene, width, height)
            .expect("layout")
            .uniform
            .scene_radius as f64;
    let mut rng = Lcg(9);
    let mut points: Vec<GpuHitPoint> = (0..count)
        .map(|i| {
            let mut hp = hit_point(rng.vec3(1.0), 0.05 + 0.1 * rng.next());
            hp.pixel = i as u32 / slots;
            hp
        })
        .collect();
    points[5].radius = 0.0; // never used: contributes nothing
    points[6].radius = 1.5 * min_radius as f32; // will hit the floor
    // Iterations of (count, flux, flux within half the radius) per slot; the last has counts
    // beyond 2^24.
    let iterations: Vec<Vec<Deposit>> = (0..4)
        .map(|it| {
            (0..count)
                .map(|i| {
                    let m = match (it, i % 4) {
                        (3, _) => (1 << 24) + 3 + i as u32,
                        (_, 0) => 0,
                        _ => 1 + (rng.next() * 40.0) as u32,
                    };
                    let f = [rng.next(), rng.next(), rng.next()].map(|v| v * m as f32 * 0.01);
                    let inner = f.map(|v| v * 0.5 * rng.next());
                    (m, f, inner)
                })
                .collect()
        })
        .collect();

    let mut results = Vec::new();
    for float_atomics in [gpu.has_float_atomics(), false] {
        let h = PassHarness::new(&gpu, &scene, (width, height), float_atomics);
        let hit_points = hit_point_resource_with(&gpu, slots, &points);
        let deposits_buffer = gpu
            .create_buffer(
                "test deposits",
                count as u64 * DEPOSIT_BYTES,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            )
            .expect("buffer");
        let deposits = Resource::new(DEPOSITS, deposits_buffer, count as u64);
        let mut merge = merge_with(alpha);
        let out = prepare_merge(&h, &mut merge, &hit_points, &deposits);
        for (it, deposit) in iterations.iter().enumerate() {
            let words: Vec<GpuDepositCell> = deposit
                .iter()
                .map(|&(m, f, inner)| deposit_cell(m, f, inner))
                .collect();
            gpu.queue
                .write_buffer(&deposits.buffer, 0, bytemuck::cast_slice(&words));
            h.run(&mut merge, it as u64, 0);
        }
        let stats = merge.slot_stats(&gpu).expect("stats");
        let radii: Vec<f32> = out["radii"].read(&gpu).expect("readback");
        let radiance: Vec<[f32; 4]> = gpu
            .read_pod(&out["radiance"].buffer, (width * height) as usize)
            .expect("readback");
        let bias: Vec<[f32; 4]> = gpu
            .read_pod(&out["kernel_bias"].buffer, (width * height) as usize)
            .expect("readback");
        results.push((stats, radii, radiance, bias));
    }

    // The same update on the CPU in f64.
    let mut cpu: Vec<CpuSlot> = points.iter().map(|p| CpuSlot::new(p.radius)).collect();
    for deposit in &iterations {
        for (s, &(m, f, inner)) in cpu.iter_mut().zip(deposit) {
            s.add_bias(m, f, inner);
            s.merge(m, f, alpha, min_radius);
        }
    }
    let close = |a: f64, b: f64| (a - b).abs() <= 2e-5 * b.abs().max(1e-12);
    for (stats, radii, radiance, bias) in &results {
        for (i, s) in cpu.iter().enumerate() {
            assert_eq!(stats[i].photons, s.photons, "slot {i}: exact photon total");
            assert!(
                close(stats[i].n as f64, s.n),
                "slot {i}: N {} vs {}",
                stats[i].n,
                s.n
            );
            assert!(
                close(radii[i] as f64, s.r),
                "slot {i}: R {} vs {}",
                radii[i],
                s.r
            );
            for c in 0..3 {
                assert!(
                    close(stats[i].tau[c] as f64, s.tau[c]),
                    "slot {i}: tau {:?} vs {:?}",
                    stats[i].tau,
                    s.tau
                );
            }
        }
        assert!(cpu[6].r == min_radius, "slot 6 reached the radius floor");
        assert!(
            cpu.iter().any(|s| s.photons > 1 << 24),
            "totals beyond 2^24 are exercised"
        );
        let k = iterations.len() as f64;
        for (p, pixel) in radiance.iter().enumerate() {
            for (c, &value) in pixel[..3].iter().enumerate() {
                let expected: f64 = (0..slots as usize)
                    .map(|j| &cpu[p * slots as usize + j])
                    .filter(|s| s.r > 0.0)
                    .map(|s| s.tau[c] / (std::f64::consts::PI * s.r * s.r) / k)
                    .sum();
                assert!(
                    close(value as f64, expected),
                    "pixel {p}: {value} vs {expected}"
                );
                // The kernel bias, (4/3) (L(R) - L(R/2)) averaged over iterations: would
                // catch the inner flux unscaled by 4, a missing 4/3, or the radius after
                // this iteration's shrink in place of the one the photons were gathered in.
                let expected_bias: f64 = (0..slots as usize)
                    .map(|j| &cpu[p * slots as usize + j])
                    .map(|s| 4.0 / 3.0 * s.bias[c] / std::f64::consts::PI / k)
                    .sum();
                let got = bias[p][c] as f64;
                assert!(
                    // Relative to the terms' size (the difference may cancel).
                    (got - expected_bias).abs() <= 1e-4 * expected.abs() + 1e-6,
                    "pixel {p}: kernel bias {got} vs {expected_bias}"
                );
            }
            assert_eq!(pixel[3], 1.0);
        }
    }
    eprintln!(
        "merge: {} slots x {} iterations match the f64 update",
        count,
        iterations.len()
    );
}

/// 10^5 SPPM iterations on a tiny image, the same deposits every iteration (a stiff mix: none,
/// one photon, and 70,000 photons per iteration, so totals pass 2^32). The radius never goes
/// below its floor, N, tau and the radiance stay finite and follow the f64 update, and the
/// photon totals are exact. Iterations are recorded 2,000 to a submission, as the renderer
/// pipelines them.
#[test]
fn merge_stays_finite_and_exact_over_a_hundred_thousand_iterations() {
    const ITERATIONS: u64 = 100_000;
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let (width, height) = (4u32, 2u32);
    let count = (width * height) as usize;
    let alpha = 0.7f64;
    let min_radius = 1e-5
        * GpuScene::new(&scene, width, height)
            .expect("layout")
            .uniform
            .scene_radius as f64;
    let counts = [0u32, 1, 3, 200, 3000, 70_000, 70_000, 12];
    let radii = [
        0.1f32,
        0.1,
        0.02,
        0.05,
        0.1,
        0.3,
        3.0 * min_radius as f32,
        0.07,
    ];
    let points: Vec<GpuHitPoint> = (0..count)
        .map(|i| {
            let mut hp = hit_point(Vec3::new(i as f32 * 0.1, 0.0, 0.0), radii[i]);
            hp.pixel = i as u32;
            hp
        })
        .collect();
    let flux: Vec<[f32; 3]> = (0..count)
        .map(|i| [0.5, 1.0, 2.0].map(|c| c * counts[i] as f32 * 1e-3))
        .collect();
    let h = PassHarness::new(&gpu, &scene, (width, height), gpu.has_float_atomics());
    let hit_points = hit_point_resource_with(&gpu, 1, &points);
    let words = deposit_words(counts.iter().copied().zip(flux.iter().copied()));
    let deposits_buffer = gpu
        .create_buffer_init(
            "constant deposits",
            bytemuck::cast_slice(&words),
            wgpu::BufferUsages::STORAGE,
        )
        .expect("buffer");
    let deposits = Resource::new(DEPOSITS, deposits_buffer, count as u64);
    let mut merge = merge_with(alpha);
    let out = prepare_merge(&h, &mut merge, &hit_points, &deposits);
    // The merge never clears deposits (the photon pass does), so each dispatch merges them again.
    let mut iteration = 0;
    while iteration < ITERATIONS {
        let mut recorder = Recorder::new(&gpu);
        for _ in 0..2_000.min(ITERATIONS - iteration) {
            let ctx = ExecCtx {
                gpu: &gpu,
                iteration,
                next_iteration: iteration + 1,
                first: iteration == 0,
                seed: 0,
            };
            merge.execute(&ctx, &mut recorder).expect("execute");
            iteration += 1;
        }
        recorder.flush().expect("flush");
    }
    let stats = merge.slot_stats(&gpu).expect("stats");
    let gpu_radii: Vec<f32> = out["radii"].read(&gpu).expect("readback");
    let radiance: Vec<[f32; 4]> = gpu
        .read_pod(&out["radiance"].buffer, count)
        .expect("readback");

    let mut worst = 0.0f64;
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-30);
    for i in 0..count {
        let mut cpu = CpuSlot::new(radii[i]);
        for _ in 0..ITERATIONS {
            cpu.merge(counts[i], flux[i], alpha, min_radius);
        }
        let s = stats[i];
        assert_eq!(s.photons, cpu.photons, "slot {i}: exact photon total");
        assert_eq!(s.discarded, 0);
        assert!(
            gpu_radii[i] as f64 >= min_radius * (1.0 - 1e-6),
            "slot {i}: radius {} below the floor {min_radius}",
            gpu_radii[i]
        );
        assert!(s.n.is_finite() && s.tau.iter().all(|t| t.is_finite()));
        assert!(radiance[i].iter().all(|v| v.is_finite()), "slot {i}");
        let pairs = [(s.n as f64, cpu.n), (gpu_radii[i] as f64, cpu.r)]
            .into_iter()
            .chain((0..3).map(|c| (s.tau[c] as f64, cpu.tau[c])));
        for (gpu_value, cpu_value) in pairs {
            if cpu_value != 0.0 {
                worst = worst.max(rel(gpu_value, cpu_value));
            }
        }
    }
    assert!(stats[5].photons > 1 << 32, "totals pass 2^32");
    assert!(
        rel(gpu_radii[6] as f64, min_radius) < 1e-6,
        "slot 6 sits on the floor: {} vs {min_radius}",
        gpu_radii[6]
    );
    // The slot on the radius floor adds the same Phi/R^2 every iteration: the case where a plain
    // f32 sum drifts most (4.4e-4 after 10^5 iterations, measured, growing with the count;
    // 10^7 would lose the estimate). With the compensated sum its error stays one rounding,
    // whatever the count.
    let mut floor_slot = CpuSlot::new(radii[6]);
    for _ in 0..ITERATIONS {
        floor_slot.merge(counts[6], flux[6], alpha, min_radius);
    }
    let floor_drift = (0..3)
        .map(|c| rel(stats[6].tau[c] as f64, floor_slot.tau[c]))
        .fold(0.0, f64::max);
    eprintln!(
        "merge: {ITERATIONS} iterations, worst relative deviation from f64 {worst:.2e}, \
         tau on the radius floor {floor_drift:.2e}"
    );
    assert!(floor_drift < 1e-6, "tau drifts on the floor: {floor_drift}");
    // Measured on lavapipe: 2.3e-5 (R of a shrinking slot, from rounding each shrink step; tau
    // follows it through R^2). N is exact. The literal f32 recursions drifted by 1.6e-3, the
    // uncompensated tau sum by 4.4e-4.
    assert!(worst < 1e-4, "f32 drift {worst}");
}
