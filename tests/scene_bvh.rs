//! The SAH BVH and the CPU reference intersection against brute force. CPU only.

use std::path::Path;

use glam::Vec3;
use hppm::scene::bvh::split_boxes::split_references;
use hppm::scene::bvh::{
    Aabb, Bvh, BvhNode, MAX_SAH_DEPTH, build_sah, closest_hit, intersect_primitive,
    intersect_sphere, intersect_triangle, scene_boxes,
};
use hppm::scene::{Camera, Integrator, Material, Scene, Sphere, Triangle};

/// A deterministic pseudo-random stream (no extra dependency).
struct Rng(u64);

impl Rng {
    fn f32(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.f32(), self.f32(), self.f32())
    }

    /// Uniform in the cube [-r, r]^3.
    fn point(&mut self, r: f32) -> Vec3 {
        (self.vec3() * 2.0 - 1.0) * r
    }

    fn direction(&mut self) -> Vec3 {
        loop {
            let d = self.point(1.0);
            if d.length_squared() > 1e-4 && d.length_squared() <= 1.0 {
                return d.normalize();
            }
        }
    }
}

fn random_boxes(rng: &mut Rng, n: usize, size: f32) -> Vec<Aabb> {
    (0..n)
        .map(|_| {
            let c = rng.point(5.0);
            let h = rng.vec3() * size;
            Aabb {
                min: c - h,
                max: c + h,
            }
        })
        .collect()
}

fn node_box(bvh: &Bvh, i: usize) -> Aabb {
    bvh.node_box(i)
}

/// The structural invariants: a permutation of the indices, leaves within the size limit
/// (unless forced), every box containing its children's boxes and its primitives' boxes, every
/// node reachable once, and a bounded depth.
fn check_structure(boxes: &[Aabb], bvh: &Bvh, max_leaf: usize) {
    let mut seen = bvh.indices.clone();
    seen.sort_unstable();
    assert_eq!(seen, (0..boxes.len() as u32).collect::<Vec<_>>());
    if boxes.is_empty() {
        assert_eq!(bvh.nodes.len(), 1);
        let root = bvh.nodes[0];
        assert_eq!(root.min, [f32::MAX; 3]);
        assert_eq!(root.max, [-f32::MAX; 3]);
        assert_eq!((root.count, root.left_or_first), (0, 0));
        return;
    }
    let mut visited = vec![false; bvh.nodes.len()];
    let mut covered = 0;
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        assert!(!visited[i], "node {i} reached twice");
        visited[i] = true;
        let n = bvh.nodes[i];
        let parent = node_box(bvh, i);
        if n.count > 0 {
            assert!(n.count as usize <= max_leaf.max(1), "leaf of {}", n.count);
            let first = n.left_or_first as usize;
            for &p in &bvh.indices[first..first + n.count as usize] {
                assert!(parent.contains(&boxes[p as usize]));
            }
            covered += n.count as usize;
        } else {
            let left = n.left_or_first as usize;
            assert!(left > i && left + 1 < bvh.nodes.len());
            for c in [left, left + 1] {
                assert!(parent.contains(&node_box(bvh, c)));
                stack.push(c);
            }
        }
    }
    assert_eq!(covered, boxes.len());
    assert!(visited.iter().all(|&v| v), "unreachable nodes");
    assert!(
        bvh.depth() <= depth_bound(boxes.len()),
        "depth {}",
        bvh.depth()
    );
}

/// In nodes from the root (`Bvh::depth` counts the root as 1).
fn depth_bound(n: usize) -> u32 {
    MAX_SAH_DEPTH + (n as f64).log2().ceil() as u32 + 1
}

fn ray_hits_box(b: &Aabb, o: Vec3, d: Vec3) -> bool {
    let inv = d.recip();
    let t0 = (b.min - o) * inv;
    let t1 = (b.max - o) * inv;
    t0.min(t1).max_element().max(0.0) <= t0.max(t1).min_element()
}

fn check_queries(boxes: &[Aabb], bvh: &Bvh, rng: &mut Rng) {
    for _ in 0..150 {
        let p = rng.point(6.0);
        let mut found = Vec::new();
        bvh.point_query(p, |i| {
            if boxes[i as usize].contains_point(p) {
                found.push(i);
            }
        });
        found.sort_unstable();
        let brute: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| boxes[i as usize].contains_point(p))
            .collect();
        assert_eq!(found, brute, "point query at {p}");

        let d = rng.direction();
        let mut hits = Vec::new();
        bvh.ray_query(p, d, f32::INFINITY, |i, _| {
            if ray_hits_box(&boxes[i as usize], p, d) {
                hits.push(i);
            }
        });
        hits.sort_unstable();
        let brute: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| ray_hits_box(&boxes[i as usize], p, d))
            .collect();
        assert_eq!(hits, brute, "ray query from {p} along {d}");
    }
}

fn check(boxes: &[Aabb], max_leaf: usize, rng: &mut Rng) {
    let bvh = build_sah(boxes, max_leaf);
    check_structure(boxes, &bvh, max_leaf);
    check_queries(boxes, &bvh, rng);
}

#[test]
fn random_boxes_of_every_size() {
    let mut rng = Rng(7);
    for (n, size, leaf) in [
        (1, 0.5, 4),
        (2, 0.5, 1),
        (1000, 0.3, 4),
        (300, 1e-6, 1),
        (50, 1e3, 2),
        (700, 0.05, 8),
    ] {
        let boxes = random_boxes(&mut rng, n, size);
        check(&boxes, leaf, &mut rng);
    }
    let mut mixed = random_boxes(&mut rng, 200, 0.01);
    mixed.extend(random_boxes(&mut rng, 5, 100.0));
    check(&mixed, 4, &mut rng);
}

#[test]
fn empty_and_degenerate_inputs() {
    let mut rng = Rng(11);
    check(&[], 4, &mut rng);
    let empty = build_sah(&[], 4);
    empty.point_query(Vec3::ZERO, |_| panic!("empty BVH visited a primitive"));
    empty.ray_query(Vec3::ZERO, Vec3::X, f32::INFINITY, |_, _| {
        panic!("empty BVH visited a primitive")
    });
    assert_eq!(empty.depth(), 1);

    // All coincident: split by count, so leaves still respect the limit.
    let point = Aabb {
        min: Vec3::splat(1.0),
        max: Vec3::splat(1.0),
    };
    check(&vec![point; 500], 4, &mut rng);
    let unit = Aabb {
        min: Vec3::splat(-1.0),
        max: Vec3::splat(1.0),
    };
    check(&vec![unit; 257], 3, &mut rng);
    // Flat boxes (triangles in a plane) and centroids on one line.
    let flat: Vec<Aabb> = (0..300)
        .map(|i| {
            let x = i as f32 * 0.01;
            Aabb {
                min: Vec3::new(x, 0.0, -1.0),
                max: Vec3::new(x + 0.5, 0.0, 1.0),
            }
        })
        .collect();
    check(&flat, 2, &mut rng);
    // Centroids that differ by less than one ulp of their spread's reciprocal.
    let tiny: Vec<Aabb> = (0..100)
        .map(|i| {
            let c = Vec3::new(1.0 + i as f32 * f32::EPSILON, 1.0, 1.0);
            Aabb { min: c, max: c }
        })
        .collect();
    check(&tiny, 1, &mut rng);
    // A leaf size of 0 is taken as 1.
    let boxes = random_boxes(&mut rng, 64, 0.2);
    check(&boxes, 0, &mut rng);
}

/// Nested boxes of geometrically growing size make SAH peel off a few boxes per level, past
/// `MAX_SAH_DEPTH`: the count-split fallback must still bound the depth (the GPU traversal
/// stack has 64 entries).
#[test]
fn depth_stays_bounded_for_adversarial_input() {
    let boxes: Vec<Aabb> = (0..900)
        .map(|i| Aabb {
            min: Vec3::ZERO,
            max: Vec3::new(1.1f32.powi(i), 1.0, 1.0),
        })
        .collect();
    let bvh = build_sah(&boxes, 1);
    check_structure(&boxes, &bvh, 1);
    assert!(
        bvh.depth() > MAX_SAH_DEPTH + 1,
        "not adversarial: depth {}",
        bvh.depth()
    );
    assert!(depth_bound(u32::MAX as usize) - 1 <= 64);
}

#[test]
fn aabb_helpers() {
    let e = Aabb::empty();
    assert!(e.is_empty() && e.surface_area() == 0.0);
    assert_eq!(e, Aabb::EMPTY);
    let b = e.grow(Vec3::ZERO).grow(Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(b.min, Vec3::ZERO);
    assert_eq!(b.max, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(b.surface_area(), 2.0 * (2.0 + 6.0 + 3.0));
    assert_eq!(b.centroid(), Vec3::new(0.5, 1.0, 1.5));
    assert_eq!(e.union(b), b);
    assert!(b.contains(&e) && b.contains(&b) && !e.contains(&b));
    let t = Aabb::of_triangle(&[Vec3::X, Vec3::Y, Vec3::NEG_Z]);
    assert_eq!(
        (t.min, t.max),
        (Vec3::new(0.0, 0.0, -1.0), Vec3::new(1.0, 1.0, 0.0))
    );
    let s = Aabb::of_sphere(Vec3::ONE, 2.0);
    assert_eq!((s.min, s.max), (Vec3::splat(-1.0), Vec3::splat(3.0)));
}

#[test]
fn primitive_intersections() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let t = intersect_triangle(&tri, Vec3::new(0.2, 0.2, 2.0), Vec3::NEG_Z);
    assert_eq!(t, Some(2.0));
    // From behind too; never behind the origin; edges and outside.
    assert_eq!(
        intersect_triangle(&tri, Vec3::new(0.2, 0.2, -1.0), Vec3::Z),
        Some(1.0)
    );
    assert_eq!(
        intersect_triangle(&tri, Vec3::new(0.2, 0.2, -1.0), Vec3::NEG_Z),
        None
    );
    assert_eq!(
        intersect_triangle(&tri, Vec3::new(0.6, 0.6, 1.0), Vec3::NEG_Z),
        None
    );
    assert_eq!(
        intersect_triangle(&tri, Vec3::new(0.2, 0.2, 0.0), Vec3::X),
        None
    );
    let degenerate = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
    assert_eq!(
        intersect_triangle(&degenerate, Vec3::new(0.5, 0.0, 1.0), Vec3::NEG_Z),
        None
    );

    let c = Vec3::new(0.0, 0.0, -5.0);
    let hit = intersect_sphere(c, 1.0, Vec3::ZERO, Vec3::NEG_Z).unwrap();
    assert!((hit - 4.0).abs() < 1e-6);
    // Unnormalised direction: t in units of dir.
    let hit = intersect_sphere(c, 1.0, Vec3::ZERO, Vec3::NEG_Z * 2.0).unwrap();
    assert!((hit - 2.0).abs() < 1e-6);
    let inside = intersect_sphere(c, 1.0, c, Vec3::X).unwrap();
    assert!((inside - 1.0).abs() < 1e-6);
    assert_eq!(intersect_sphere(c, 1.0, Vec3::ZERO, Vec3::Z), None);
    assert_eq!(
        intersect_sphere(c, 1.0, Vec3::new(2.0, 0.0, 0.0), Vec3::NEG_Z),
        None
    );
    // Far away and tiny: the stable quadratic still finds it.
    let far = intersect_sphere(Vec3::new(0.0, 0.0, -1e4), 1e-2, Vec3::ZERO, Vec3::NEG_Z).unwrap();
    assert!((far - (1e4 - 1e-2)).abs() < 1e-2);
}

fn random_scene(rng: &mut Rng, triangles: usize, spheres: usize) -> Scene {
    let material = Material {
        media: Default::default(),
        bsdf: hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.5)),
        back: None,
        emission: Vec3::ZERO,
        textures: Default::default(),
    };
    Scene {
        media: Default::default(),
        source: "random".into(),
        camera: Camera {
            origin: Vec3::Z * 10.0,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_x_deg: 40.0,
            width: 8,
            height: 8,
            filter: hppm::scene::filter::PixelFilter::Box,
            sample_border: false,
            crop: None,
            lens: None,
        },
        integrator: Integrator::default(),
        spp_hint: None,
        materials: vec![material],
        triangles: (0..triangles)
            .map(|_| {
                let c = rng.point(4.0);
                let size = 0.05 + rng.f32();
                Triangle {
                    v: [
                        c + rng.point(size),
                        c + rng.point(size),
                        c + rng.point(size),
                    ],
                    material: 0,
                    normals: None,
                    uvs: None,
                }
            })
            .collect(),
        spheres: (0..spheres)
            .map(|_| Sphere {
                center: rng.point(4.0),
                radius: 0.05 + 0.5 * rng.f32(),
                material: 0,
                flip_normals: false,
            })
            .collect(),
        point_lights: Vec::new(),
        emitters: Default::default(),
        textures: Vec::new(),
    }
}

fn brute_force(scene: &Scene, o: Vec3, d: Vec3) -> Option<(f32, u32)> {
    let n = (scene.triangles.len() + scene.spheres.len()) as u32;
    (0..n)
        .filter_map(|p| intersect_primitive(scene, p, o, d).map(|t| (t, p)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

fn assert_same_hits(scene: &Scene, rng: &mut Rng, rays: usize, spread: f32) {
    let boxes = scene_boxes(scene);
    assert_eq!(boxes.len(), scene.triangles.len() + scene.spheres.len());
    for leaf in [1, 4] {
        let bvh = build_sah(&boxes, leaf);
        check_structure(&boxes, &bvh, leaf);
        let mut hits = 0;
        for _ in 0..rays {
            let o = rng.point(spread);
            let d = rng.direction();
            let fast = closest_hit(scene, &bvh, o, d);
            let slow = brute_force(scene, o, d);
            match (fast, slow) {
                (Some((tf, pf)), Some((ts, ps))) => {
                    // Equal distances may come from different primitives (a shared edge).
                    assert!(
                        tf == ts,
                        "t {tf} vs {ts} (prims {pf}, {ps}) from {o} along {d}"
                    );
                    hits += 1;
                }
                (None, None) => {}
                other => panic!("BVH vs brute force: {other:?} from {o} along {d}"),
            }
        }
        assert!(hits > rays / 20, "too few hits ({hits}) to test anything");
    }
}

#[test]
fn closest_hit_equals_brute_force_on_random_scenes() {
    let mut rng = Rng(42);
    let scene = random_scene(&mut rng, 600, 60);
    assert_same_hits(&scene, &mut rng, 1500, 6.0);
    let only_spheres = random_scene(&mut rng, 0, 150);
    assert_same_hits(&only_spheres, &mut rng, 500, 3.0);
}

#[test]
fn closest_hit_equals_brute_force_in_the_reference_scenes() {
    let mut rng = Rng(5);
    for file in [
        "tests/refs/scenes/cornell_diffuse/scene.xml",
        "tests/refs/scenes/cornell_glass_sphere/scene.xml",
        "tests/refs/scenes/point_light_caustic/scene.xml",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        let scene = hppm::loaders::load(&path).unwrap();
        assert_same_hits(&scene, &mut rng, 400, 0.95);
    }
    // Looking straight down the Cornell box above the boxes hits the back wall at z = -1.
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/refs/scenes/cornell_diffuse/scene.xml");
    let scene = hppm::loaders::load(&path).unwrap();
    let bvh = build_sah(&scene_boxes(&scene), 4);
    let (t, prim) = closest_hit(&scene, &bvh, Vec3::new(0.0, 0.5, 3.9), Vec3::NEG_Z).unwrap();
    assert!((t - 4.9).abs() < 1e-5);
    assert!(
        (4..6).contains(&prim),
        "the back wall is rectangle 2 (triangles 4, 5)"
    );
    // The glass sphere is primitive triangles.len() + 0.
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    let scene = hppm::loaders::load(&path).unwrap();
    let bvh = build_sah(&scene_boxes(&scene), 4);
    let (_, prim) = closest_hit(&scene, &bvh, Vec3::new(0.42, 0.5, 0.42), Vec3::NEG_Y).unwrap();
    assert_eq!(prim as usize, scene.triangles.len());
}

/// A million boxes build in reasonable time even in the test profile; the optimized build is
/// several times faster.
#[test]
fn a_million_boxes_build() {
    let mut rng = Rng(3);
    let boxes = random_boxes(&mut rng, 1_000_000, 0.01);
    let start = std::time::Instant::now();
    let bvh = build_sah(&boxes, 4);
    let elapsed = start.elapsed();
    eprintln!(
        "1M boxes: {elapsed:?}, {} nodes, depth {}",
        bvh.nodes.len(),
        bvh.depth()
    );
    assert_eq!(bvh.indices.len(), boxes.len());
    assert!(bvh.depth() < 64);
    assert!(elapsed.as_secs_f32() < 20.0, "{elapsed:?}");
}

/// Two unit cubes two apart: the root's area is 14 and each leaf's 6, so the tree costs
/// (14 + 6 + 6) / 14 primitive tests per ray (one box test costing one primitive test), and one
/// leaf of both costs 2. Would catch a cost that forgets the box tests, the leaves' counts or
/// the normalisation by the root.
#[test]
fn sah_cost_of_a_known_tree() {
    let cube = |x: f32| Aabb {
        min: Vec3::new(x, 0.0, 0.0),
        max: Vec3::new(x + 1.0, 1.0, 1.0),
    };
    let bvh = build_sah(&[cube(0.0), cube(2.0)], 1);
    assert_eq!(bvh.nodes.len(), 3);
    assert!(
        (bvh.sah_cost() - 26.0 / 14.0).abs() < 1e-6,
        "{}",
        bvh.sah_cost()
    );
    let one = bvh.collapsed_to(1);
    assert_eq!(one.nodes.len(), 1);
    assert_eq!(one.nodes[0].count, 2);
    assert!((one.sah_cost() - 2.0).abs() < 1e-6, "{}", one.sah_cost());
}

/// A collapsed tree is still a tree over every box (each leaf's primitives inside its box,
/// every node reachable once, queries equal to brute force), within its node budget, with the
/// index table untouched. Would catch a merged leaf that drops or repeats a sibling's
/// primitives, a child renumbered wrongly, or orphaned nodes left in the array.
#[test]
fn collapsing_keeps_every_box_and_query() {
    let mut rng = Rng(11);
    for n in [1usize, 2, 3, 17, 300] {
        let boxes = random_boxes(&mut rng, n, 0.4);
        let bvh = build_sah(&boxes, 4);
        let built = bvh.nodes.len();
        for budget in [
            0,
            1,
            2,
            3,
            built / 2,
            built.saturating_sub(2),
            built,
            built + 5,
        ] {
            let collapsed = bvh.collapsed_to(budget);
            assert!(
                collapsed.nodes.len() <= budget.max(1).min(built),
                "{n} boxes to {budget}: {} nodes",
                collapsed.nodes.len()
            );
            assert_eq!(collapsed.indices, bvh.indices);
            if budget >= built {
                assert_eq!(collapsed.nodes, bvh.nodes, "a tree within budget changed");
            }
            check_structure(&boxes, &collapsed, n);
            check_queries(&boxes, &collapsed, &mut rng);
        }
    }
}

/// A collapse bounded by the primitive tests it may add gives up exactly when the full
/// collapse would add more: it returns the same tree when the bound holds what the merges
/// added (by `expected_tests`, computed here), and `None` when the bound is half of that. Would
/// catch an early stop that counts a merge's cost without the box test it removes (it would
/// give up on trees within the bound), or one that never stops.
#[test]
fn bounded_collapse_gives_up_exactly_past_its_bound() {
    let mut rng = Rng(13);
    let boxes = random_boxes(&mut rng, 300, 0.4);
    let bvh = build_sah(&boxes, 4);
    let tests = |b: &Bvh| b.expected_tests().primitives;
    for budget in [bvh.nodes.len() / 2, bvh.nodes.len() / 4, 9] {
        let full = bvh.collapsed_to(budget);
        let added = tests(&full) - tests(&bvh);
        assert!(added > 0.0, "budget {budget}: no tests added");
        let within = bvh.collapsed_within(budget, added * 1.001 + 1e-6);
        assert_eq!(within.map(|b| b.nodes), Some(full.nodes), "budget {budget}");
        assert!(
            bvh.collapsed_within(budget, added * 0.5).is_none(),
            "budget {budget}"
        );
    }
    // A tree within budget needs no merge, whatever the bound.
    assert!(bvh.collapsed_within(bvh.nodes.len(), 0.0).is_some());
}

/// Merging one pair must merge the cheapest one: the collapsed tree's cost equals the least
/// cost any single merge gives, computed here from the nodes for every candidate. Would catch
/// a merge order by count or by index instead of by cost, or a wrong sign in the cost.
#[test]
fn collapsing_merges_the_cheapest_pair_first() {
    let mut rng = Rng(12);
    let boxes = random_boxes(&mut rng, 40, 0.6);
    let bvh = build_sah(&boxes, 1);
    let area = |n: &BvhNode| n.bounds().surface_area();
    let root_area = area(&bvh.nodes[0]);
    let cheapest = bvh
        .nodes
        .iter()
        .filter(|n| n.count == 0)
        .filter_map(|n| {
            let (l, r) = (
                &bvh.nodes[n.left_or_first as usize],
                &bvh.nodes[n.left_or_first as usize + 1],
            );
            (l.count > 0 && r.count > 0).then(|| {
                (area(n) * ((l.count + r.count) as f32 - 1.0)
                    - area(l) * l.count as f32
                    - area(r) * r.count as f32)
                    / root_area
            })
        })
        .fold(f32::INFINITY, f32::min);
    assert!(cheapest.is_finite());
    let collapsed = bvh.collapsed_to(bvh.nodes.len() - 2);
    assert_eq!(collapsed.nodes.len(), bvh.nodes.len() - 2);
    let expected = bvh.sah_cost() + cheapest;
    assert!(
        (collapsed.sah_cost() - expected).abs() <= 1e-4 * expected,
        "{} against {expected}",
        collapsed.sah_cost()
    );
}

/// Split references ([`split_references`]) in a BVH must find exactly the hits brute force
/// finds, on a scene of the triangles they exist for: the water glass's fans (each wedge from
/// a disk's centre to its rim) and its walls' long thin triangles, and random ones. And every
/// point of every triangle must lie in a box of one of its references. Would catch a clipped
/// box that lost a sliver of its triangle (a ray through that sliver misses: a crack), a
/// reference mapped to the wrong primitive, or a split past the reference budget.
#[test]
fn split_references_keep_every_hit() {
    let mut rng = Rng(21);
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/refs/scenes/water_glass/scene.xml");
    let glass = hppm::loaders::load(&path).unwrap();
    let random = random_scene(&mut rng, 300, 20);
    for (scene, spread) in [(&glass, 0.6), (&random, 6.0)] {
        let refs = split_references(scene, 1.0);
        let prims = scene.triangles.len() + scene.spheres.len();
        assert!(refs.boxes.len() > prims, "nothing was split");
        assert!(refs.boxes.len() <= 2 * prims);
        assert_eq!(refs.prims.len(), refs.boxes.len());
        let own = scene_boxes(scene);
        for (b, &p) in refs.boxes.iter().zip(&refs.prims) {
            assert!(
                own[p as usize].contains(b),
                "a reference box outside its primitive's"
            );
        }
        for (i, t) in scene.triangles.iter().enumerate() {
            for _ in 0..20 {
                let (mut u, mut v) = (rng.f32(), rng.f32());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let p = t.v[0] + u * (t.v[1] - t.v[0]) + v * (t.v[2] - t.v[0]);
                let covered = refs
                    .boxes
                    .iter()
                    .zip(&refs.prims)
                    .any(|(b, &q)| q as usize == i && b.contains_point(p));
                assert!(covered, "triangle {i}: {p} in no reference box");
            }
        }
        let mut bvh = build_sah(&refs.boxes, 4);
        for r in &mut bvh.indices {
            *r = refs.prims[*r as usize];
        }
        let mut hits = 0;
        for _ in 0..800 {
            let o = rng.point(spread) + Vec3::Y * 0.5 * spread;
            let d = rng.direction();
            let fast = closest_hit(scene, &bvh, o, d).map(|h| h.0);
            let slow = brute_force(scene, o, d).map(|h| h.0);
            assert_eq!(fast, slow, "from {o} along {d}");
            hits += usize::from(fast.is_some());
        }
        assert!(hits > 80, "too few hits ({hits}) to test anything");
    }
}
