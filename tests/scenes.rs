//! Scene loading: the reference scenes, our own format, broken inputs, and the scene BVH against
//! brute force. CPU only.

use glam::Vec3;
use hppm::scene::bvh::{Aabb, build_sah, scene_boxes};
use hppm::scene::{self, Bsdf, Scene};

fn repo(relative: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

fn load(relative: &str) -> Scene {
    scene::load(&repo(relative)).unwrap_or_else(|e| panic!("{relative}: {e}"))
}

fn total_area(s: &Scene) -> f32 {
    s.triangles
        .iter()
        .map(|t| 0.5 * (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length())
        .sum()
}

#[test]
fn reference_scenes_load() {
    let glass = load("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    assert_eq!(glass.triangles.len(), 12);
    assert_eq!(glass.spheres.len(), 2);
    assert_eq!(glass.camera.fov_x_deg, 39.3077);
    assert_eq!((glass.camera.width, glass.camera.height), (128, 128));
    assert_eq!(glass.integrator.max_depth, Some(12));
    assert_eq!(
        glass.integrator.rr_depth, None,
        "rr_depth 1000 > max_depth: no roulette"
    );
    assert_eq!(glass.spp_hint, Some(64));
    let emitters: Vec<_> = glass
        .materials
        .iter()
        .filter(|m| m.emission.max_element() > 0.0)
        .collect();
    assert_eq!(emitters.len(), 1);
    assert_eq!(emitters[0].emission, Vec3::new(18.387, 13.9873, 6.75357));
    assert!(glass.materials.iter().any(|m| m.bsdf == Bsdf::Mirror));
    assert!(glass.materials.iter().any(|m| m.bsdf
        == Bsdf::Dielectric {
            int_ior: 1.5,
            ext_ior: 1.0
        }));

    let point = load("tests/refs/scenes/point_light_caustic/scene.xml");
    assert_eq!(point.point_lights.len(), 1);
    assert_eq!(point.point_lights[0].intensity, Vec3::splat(40.0));
    assert_eq!(point.point_lights[0].position, Vec3::new(-2.0, 2.8, 0.0));

    let diffuse = load("tests/refs/scenes/cornell_diffuse/scene.xml");
    assert_eq!(diffuse.triangles.len(), 12 + 24);
    assert!(diffuse.materials.iter().all(|m| !m.bsdf.is_delta()));
}

#[test]
fn obj_scene_matches_the_cube_scene() {
    let cubes = load("tests/refs/scenes/cornell_diffuse/scene.xml");
    let objs = load("tests/refs/scenes/cornell_diffuse_obj/scene.xml");
    assert_eq!(cubes.triangles.len(), objs.triangles.len());
    let (lo_a, hi_a) = cubes.bounds();
    let (lo_b, hi_b) = objs.bounds();
    assert!((lo_a - lo_b).abs().max_element() < 1e-4 && (hi_a - hi_b).abs().max_element() < 1e-4);
    assert!((total_area(&cubes) - total_area(&objs)).abs() < 1e-3);
    // Every OBJ triangle's vertices are corners of the cube scene (same boxes, same placement).
    let corners: Vec<Vec3> = cubes.triangles.iter().flat_map(|t| t.v).collect();
    for t in &objs.triangles {
        for v in t.v {
            assert!(
                corners.iter().any(|c| (*c - v).length() < 1e-4),
                "vertex {v} not in the cube scene"
            );
        }
        // Outward normals: the OBJ boxes sit inside the room, so normals point away from their centre.
    }
}

#[test]
fn bundled_ron_scenes_load_and_match_the_xml() {
    let ron = load("scenes/cornell_box.ron");
    let xml = load("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    let dir = |c: &scene::Camera| (c.target - c.origin).normalize();
    assert_eq!(ron.camera.origin, xml.camera.origin);
    assert!((dir(&ron.camera) - dir(&xml.camera)).length() < 1e-6);
    assert!((ron.camera.up - xml.camera.up).length() < 1e-6);
    assert_eq!(
        (ron.camera.fov_x_deg, ron.camera.width, ron.camera.height),
        (xml.camera.fov_x_deg, xml.camera.width, xml.camera.height)
    );
    assert_eq!(ron.spheres.len(), xml.spheres.len());
    assert_eq!(ron.triangles.len(), xml.triangles.len());
    for (a, b) in ron.triangles.iter().zip(&xml.triangles) {
        for (p, q) in a.v.iter().zip(b.v) {
            assert!((*p - q).length() < 1e-5);
        }
        assert_eq!(
            ron.materials[a.material as usize],
            xml.materials[b.material as usize]
        );
    }
    let diffuse_ron = load("scenes/cornell_diffuse.ron");
    let diffuse_xml = load("tests/refs/scenes/cornell_diffuse/scene.xml");
    assert!((total_area(&diffuse_ron) - total_area(&diffuse_xml)).abs() < 1e-4);
    let furnace = load("scenes/furnace.ron");
    assert_eq!(furnace.integrator.max_depth, None);
}

/// Each broken input gives an error naming the file and the offending line; none panics.
#[test]
fn broken_inputs_name_file_and_line() {
    let cases = [
        ("syntax.xml", 4),
        ("unknown_tag.xml", 4),
        ("unknown_property.xml", 5),
        ("bad_number.xml", 3),
        ("nan.xml", 4),
        ("missing_obj.xml", 3),
        ("missing_ref.xml", 4),
        ("broken.obj", 5),
        ("broken_obj.xml", 5),
        ("unknown_material.ron", 5),
        ("unknown_field.ron", 5),
        ("nan.ron", 3),
    ];
    for (file, line) in cases {
        let path = repo(&format!("tests/data/scene_errors/{file}"));
        let err = scene::load(&path).expect_err(file).to_string();
        let expected_file = if file == "broken_obj.xml" {
            "broken.obj"
        } else {
            file
        };
        assert!(
            err.contains(&format!("{expected_file}:{line}:")),
            "{file}: expected line {line} in: {err}"
        );
    }
}

#[test]
fn truncated_and_mangled_scenes_never_panic() {
    let text =
        std::fs::read_to_string(repo("tests/refs/scenes/cornell_glass_sphere/scene.xml")).unwrap();
    let ron = std::fs::read_to_string(repo("scenes/cornell_box.ron")).unwrap();
    let path = repo("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    let mut seed = 12345u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 33) as usize
    };
    for i in 0..150 {
        let cut = next() % text.len();
        let _ = scene::mitsuba::parse(&path, &text[..cut]);
        let cut = next() % ron.len();
        let _ = scene::ron_format::parse(&repo("scenes/cornell_box.ron"), &ron[..cut]);
        // Swap two random byte ranges' worth of characters for junk.
        let mut mangled = ron.clone().into_bytes();
        let at = next() % mangled.len();
        mangled[at] = b"0(),:\"x9e-"[i % 10];
        if let Ok(s) = String::from_utf8(mangled) {
            let _ = scene::ron_format::parse(&repo("scenes/cornell_box.ron"), &s);
        }
    }
}

fn lcg(seed: &mut u64) -> f32 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 40) as f32 / (1u64 << 24) as f32
}

fn ray_box(b: &Aabb, o: Vec3, d: Vec3) -> Option<f32> {
    let inv = d.recip();
    let t0 = (b.min - o) * inv;
    let t1 = (b.max - o) * inv;
    let enter = t0.min(t1).max_element().max(0.0);
    let exit = t0.max(t1).min_element();
    (enter <= exit).then_some(enter)
}

fn check_bvh(boxes: &[Aabb], leaf: usize) {
    let bvh = build_sah(boxes, leaf);
    let mut seen = bvh.indices.clone();
    seen.sort_unstable();
    assert_eq!(
        seen,
        (0..boxes.len() as u32).collect::<Vec<_>>(),
        "each primitive exactly once"
    );
    for n in &bvh.nodes {
        let parent = Aabb {
            min: n.min.into(),
            max: n.max.into(),
        };
        if n.count > 0 {
            for &i in &bvh.indices[n.left_or_first as usize..(n.left_or_first + n.count) as usize] {
                assert!(parent.contains(&boxes[i as usize]));
            }
        } else if !boxes.is_empty() {
            for c in [n.left_or_first, n.left_or_first + 1] {
                let child = &bvh.nodes[c as usize];
                assert!(parent.contains(&Aabb {
                    min: child.min.into(),
                    max: child.max.into()
                }));
            }
        }
    }
    assert!(bvh.depth() <= 48, "depth {}", bvh.depth());
    let mut seed = 99u64;
    for _ in 0..200 {
        let p = Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) * 12.0 - 6.0;
        let mut found: Vec<u32> = Vec::new();
        bvh.point_query(p, |i| {
            if boxes[i as usize].contains_point(p) {
                found.push(i)
            }
        });
        found.sort_unstable();
        let brute: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| boxes[i as usize].contains_point(p))
            .collect();
        assert_eq!(found, brute);
        let d = (Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) - 0.5).normalize();
        let mut hits: Vec<u32> = Vec::new();
        bvh.ray_query(p, d, f32::MAX, |i, _| {
            if ray_box(&boxes[i as usize], p, d).is_some() {
                hits.push(i)
            }
        });
        hits.sort_unstable();
        let brute: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| ray_box(&boxes[i as usize], p, d).is_some())
            .collect();
        assert_eq!(hits, brute);
    }
}

#[test]
fn bvh_queries_match_brute_force() {
    let mut seed = 7u64;
    let mut random = |n: usize, size: f32| -> Vec<Aabb> {
        (0..n)
            .map(|_| {
                let c = Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) * 10.0 - 5.0;
                let h = Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) * size;
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect()
    };
    check_bvh(&[], 4);
    check_bvh(&random(1, 0.5), 4);
    check_bvh(&random(1000, 0.3), 4);
    check_bvh(&random(300, 1e-6), 1);
    check_bvh(&random(50, 1e3), 2);
    let point = Aabb {
        min: Vec3::splat(1.0),
        max: Vec3::splat(1.0),
    };
    check_bvh(&vec![point; 500], 4);
    let mut mixed = random(200, 0.01);
    mixed.extend(random(5, 100.0));
    check_bvh(&mixed, 4);
}

#[test]
fn scene_bvh_covers_triangles_then_spheres() {
    let s = load("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    let boxes = scene_boxes(&s);
    assert_eq!(boxes.len(), s.triangles.len() + s.spheres.len());
    let sphere = &s.spheres[0];
    assert_eq!(
        boxes[s.triangles.len()],
        Aabb::of_sphere(sphere.center, sphere.radius)
    );
}

#[test]
fn scaling_scales_geometry_and_point_light_intensity() {
    let s = load("tests/refs/scenes/point_light_caustic/scene.xml");
    let big = s.scaled(1000.0);
    assert_eq!(
        big.point_lights[0].intensity,
        s.point_lights[0].intensity * 1e6
    );
    assert_eq!(big.spheres[0].radius, s.spheres[0].radius * 1000.0);
    assert_eq!(big.camera.origin, s.camera.origin * 1000.0);
}
