//! Closest hits on the GPU (`intersect_scene`, shaders/common/traversal.wgsl) against a CPU
//! brute-force intersector in f64, on whatever adapter wgpu finds (lavapipe in CI), in every
//! octant of ray directions, through the scene BVH and through the unrolled every-primitive path
//! small scenes take.
//!
//! The fault these were written for: a glass ring standing on a floor (its bottom faces in the
//! floor's plane) rendered a third too dark on one half of the image, in `pt` and the hybrid
//! alike. A camera ray inside the glass reaches the floor and the glass's bottom at the same
//! computed distance; such exact ties went to whichever leaf the traversal reached first, which
//! changes with the ray's direction and with where the tree splits the scene, so the ray met the
//! floor on one side of the ring and left through the glass's bottom (into the void under the
//! floor) on the other. Measured on `glass_ring_tilted` (camera paths reaching the contact, 1M
//! samples): the floor won 31-37% of ties where x < 0 and 62-74% where x > 0, against Mitsuba's
//! 67-72% everywhere. Exact ties now go to the face the ray meets from the front, then to the
//! lower index, whatever the traversal order: 61-74% everywhere.

mod common;

use common::pass_harness::PassHarness;
use common::rng::Rng;
use common::*;
use glam::{DVec3, Vec3, Vec4};
use hppm::scene::Scene;

const KERNEL: &str = "#import common::scene::NO_HIT
#import common::traversal::intersect_scene
@group(1) @binding(0) var<storage, read> rays: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&out) { return; }
    let hit = intersect_scene(rays[2u * id.x].xyz, rays[2u * id.x + 1u].xyz);
    out[id.x] = vec4<f32>(select(f32(hit.prim), -1.0, hit.prim == NO_HIT), hit.t, 0.0, 0.0);
}
";

/// The primitive `intersect_scene` reports for each ray (origin, direction), or None.
fn gpu_hits(scene: &Scene, rays: &[(Vec3, Vec3)]) -> Vec<Option<u32>> {
    let gpu = gpu();
    let harness = PassHarness::new(&gpu, scene, (4, 4), false);
    let words: Vec<Vec4> = rays
        .iter()
        .flat_map(|(o, d)| [o.extend(1.0), d.extend(0.0)])
        .collect();
    harness
        .run_kernel("tests/coplanar.rs (kernel)", KERNEL, &words, rays.len())
        .iter()
        .map(|v| (v.x >= 0.0).then_some(v.x as u32))
        .collect()
}

/// Distance along the ray to triangle `v` in f64, and whether the ray meets its front (the side
/// its counter-clockwise normal points to).
fn hit_triangle(v: &[Vec3; 3], o: DVec3, d: DVec3) -> Option<(f64, bool)> {
    let [a, b, c] = v.map(|p| p.as_dvec3());
    let (ea, eb) = (b - a, c - a);
    let p = d.cross(eb);
    let det = ea.dot(p);
    if det == 0.0 {
        return None;
    }
    let to = o - a;
    let u = to.dot(p) / det;
    let q = to.cross(ea);
    let w = d.dot(q) / det;
    let t = eb.dot(q) / det;
    (u >= 0.0 && w >= 0.0 && u + w <= 1.0 && t > 0.0).then_some((t, d.dot(ea.cross(eb)) < 0.0))
}

/// The closest triangle by exact distance; of exact ties the one met from the front, then the
/// lower index. Also the relative gap to the next-closest distinct hit.
fn brute_force(scene: &Scene, o: Vec3, d: Vec3) -> Option<(u32, f64)> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let mut hits: Vec<(f64, bool, u32)> = scene
        .triangles
        .iter()
        .enumerate()
        .filter_map(|(i, t)| hit_triangle(&t.v, o, d).map(|(t, front)| (t, front, i as u32)))
        .collect();
    hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)).then(a.2.cmp(&b.2)));
    let best = *hits.first()?;
    let gap = hits
        .iter()
        .find(|h| h.0 != best.0)
        .map_or(f64::INFINITY, |h| (h.0 - best.0) / best.0);
    Some((best.2, gap))
}

fn write_scene(name: &str, obj: &str, with_floor: bool) -> Scene {
    let dir = std::env::temp_dir().join(format!("hppm-coplanar-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("glass.obj"), obj).expect("obj");
    // The glass first, so that its faces have the lower indices: a tie left to index order
    // would go to the glass.
    let floor = if with_floor {
        r#"<shape type="rectangle">
            <transform name="to_world"><matrix value="4 0 0 0 0 0 1 0 0 -4 0 0 0 0 0 1"/></transform>
            <bsdf type="diffuse"/>
        </shape>"#
    } else {
        ""
    };
    let xml = format!(
        r#"<scene version="3.0.0">
        <sensor type="perspective"/>
        <shape type="obj"><string name="filename" value="glass.obj"/>
            <boolean name="face_normals" value="true"/>
            <bsdf type="dielectric"/></shape>
        {floor}
    </scene>"#
    );
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).expect("xml");
    let scene = hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_dir_all(&dir);
    scene
}

/// A slab of glass `cells` x `cells` squares of side 1/4 over [-c/8, c/8]^2, its bottom in the
/// plane y = 0 (facing -y) and its top at y = 1/4, walls left open: every coordinate a short
/// binary fraction, so that Möller-Trumbore computes distances to the bottom and to the floor
/// exactly and every ray through the contact is an exact tie.
fn glass_slab(cells: i32) -> String {
    let mut obj = String::new();
    let mut faces = String::new();
    let mut n = 0;
    let half = cells as f32 / 8.0;
    for (y, up) in [(0.0f32, false), (0.25, true)] {
        for i in 0..cells {
            for j in 0..cells {
                let (x0, z0) = (-half + 0.25 * i as f32, -half + 0.25 * j as f32);
                for (x, z) in [
                    (x0, z0),
                    (x0 + 0.25, z0),
                    (x0 + 0.25, z0 + 0.25),
                    (x0, z0 + 0.25),
                ] {
                    obj += &format!("v {x} {y} {z}\n");
                }
                // Counter-clockwise seen from +y: (a, d, c), (a, c, b); from -y reversed.
                let (a, b, c, d) = (n + 1, n + 2, n + 3, n + 4);
                if up {
                    faces += &format!("f {a} {d} {c}\nf {a} {c} {b}\n");
                } else {
                    faces += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
                }
                n += 4;
            }
        }
    }
    obj + &faces
}

/// Rays through the contact: from inside the slab down onto it (the floor, facing them, must
/// win) and from below the floor up onto it (the slab's bottom, facing them, must win), with
/// directions in all four (x, z) sign quadrants and along the axes.
fn contact_rays(rng: &mut Rng, cells: i32, count: usize) -> Vec<(Vec3, Vec3)> {
    let half = cells as f32 / 8.0 - 0.125;
    let steps = [-0.25f32, -0.125, -0.0625, 0.0, 0.0625, 0.125, 0.25];
    // Odd multiples of 1/64: never on a cell's boundary (multiples of 1/4), where the BVH's
    // boxes end. A ray with a zero direction component that lies exactly in a box's face plane
    // misses the box on one side of it (the slab test's exit is 0 there); only a hit exactly on
    // a triangle's edge can be in that box, and the triangle across the edge is found instead.
    let dyadic = |rng: &mut Rng, lim: f32| {
        (((rng.unit() * 2.0 - 1.0) * lim * 32.0).floor() * 2.0 + 1.0) / 64.0
    };
    (0..count)
        .map(|i| {
            let x = dyadic(rng, half * 0.5);
            let z = dyadic(rng, half * 0.5);
            let d = Vec3::new(
                steps[(rng.next_u32() % 7) as usize],
                if i % 4 == 3 { 1.0 } else { -1.0 },
                steps[(rng.next_u32() % 7) as usize],
            );
            let o = if d.y < 0.0 {
                Vec3::new(x, 0.125, z)
            } else {
                Vec3::new(x, -0.125, z)
            };
            (o, d)
        })
        .collect()
}

fn assert_contact_ties(cells: i32) {
    let scene = write_scene(&format!("slab{cells}"), &glass_slab(cells), true);
    let mut rng = Rng(0x5eed_0000 + cells as u64);
    let rays = contact_rays(&mut rng, cells, 4096);
    let gpu = gpu_hits(&scene, &rays);
    let mut wrong = Vec::new();
    for ((o, d), hit) in rays.iter().zip(&gpu) {
        let (expected, gap) = brute_force(&scene, *o, *d).expect("every ray meets the contact");
        assert!(gap > 0.0, "distinct distances");
        if *hit != Some(expected) {
            wrong.push(format!("{o} -> {d}: gpu {hit:?}, expected {expected}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "{} of {} rays through the contact ({} triangles) took the wrong face, e.g.\n{}",
        wrong.len(),
        rays.len(),
        scene.triangles.len(),
        wrong[..wrong.len().min(8)].join("\n")
    );
}

/// A 16 x 16 slab (1,026 triangles) on a floor, through the scene BVH. Would catch an exact tie
/// decided by traversal order (child order, which octant the ray points into): before the fix
/// 3,561 of these 4,096 rays took the wrong face.
#[test]
fn exact_ties_go_to_the_front_face_through_the_bvh() {
    assert_contact_ties(16);
}

/// A 2 x 2 slab (18 triangles): small enough that every primitive is tested in unrolled code in
/// index order, where the slab's faces come first. Would catch a tie left to index order: before
/// the fix every ray from above (3,072 of 4,096) met the slab's bottom instead of the floor.
#[test]
fn exact_ties_go_to_the_front_face_in_small_scenes() {
    assert_contact_ties(2);
}

/// Random triangles and random rays of every direction octant, zero components included:
/// wherever the closest hit is unambiguous (the next distance at least 1e-4 further), the GPU
/// reports the same triangle as the brute force. Would catch a slab test, inverse direction or
/// child order that loses hits for one sign of a direction component, and a leaf or stack that
/// drops a primitive.
#[test]
fn closest_hits_match_brute_force_in_every_octant() {
    let mut rng = Rng(0xc0ffee);
    let mut obj = String::new();
    for i in 0..400 {
        let c = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
        let s = rng.log_uniform(0.01, 1.0);
        for _ in 0..3 {
            let v = c + s * rng.direction();
            obj += &format!("v {} {} {}\n", v.x, v.y, v.z);
        }
        obj += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    let scene = write_scene("soup", &obj, false);
    let mut rays = Vec::new();
    for i in 0..8192 {
        let o = rng.in_box(Vec3::splat(-3.0), Vec3::splat(3.0));
        let mut d = rng.direction();
        // A quarter of the rays with one or two components exactly zero.
        if i % 4 == 0 {
            d[(rng.next_u32() % 3) as usize] = 0.0;
            if i % 8 == 0 {
                d[(rng.next_u32() % 3) as usize] = 0.0;
            }
        }
        if d.length_squared() > 0.0 {
            rays.push((o, d.normalize()));
        }
    }
    let gpu = gpu_hits(&scene, &rays);
    let (mut checked, mut octants) = (0, [0usize; 8]);
    for ((o, d), hit) in rays.iter().zip(&gpu) {
        let octant =
            (d.x < 0.0) as usize | ((d.y < 0.0) as usize) << 1 | ((d.z < 0.0) as usize) << 2;
        match brute_force(&scene, *o, *d) {
            Some((expected, gap)) if gap > 1e-4 => {
                assert_eq!(*hit, Some(expected), "ray {o} -> {d}");
                checked += 1;
                octants[octant] += 1;
            }
            _ => {}
        }
    }
    eprintln!("{checked} unambiguous hits checked, by octant {octants:?}");
    assert!(
        octants.iter().all(|&n| n > 100),
        "every octant tested: {octants:?}"
    );
}
