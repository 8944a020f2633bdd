//! The GPU hit-point BVH (`hit_point_bvh_lbvh`) and the radix sort under it, on lavapipe: the
//! sort against a stable CPU sort, the tree's structure and range queries against brute force,
//! refit-only against the same checks after radii shrink, every internal box against the exact
//! union of its leaves', and whole renders against the CPU SAH builder's.

mod common;

use common::pass_harness::{
    PassHarness, check_range_queries, hit_point, hit_point_resource, photon_hits_resource,
    write_hit_points,
};
use common::rng::Rng;
use common::*;
use glam::Vec3;
use hppm::gpu::GpuContext;
use hppm::gpu::radix_sort::RadixSort;
use hppm::graph::exec::Wiring;
use hppm::graph::pass::Resource;
use hppm::passes::hit_point_bvh_lbvh::{
    BuildCounts, HitPointBvhLbvh, KIND as LBVH, LbvhParams, RefitOnly,
};
use hppm::passes::hit_points::{GpuHitPoint, NO_PIXEL, TREE_HEADER_BYTES, sphere_box};
use hppm::scene::Scene;
use hppm::scene::bvh::BvhNode;
use std::collections::HashMap;
use std::path::Path;

// ---------------------------------------------------------------------------------------------
// Radix sort.

fn storage_buffer(gpu: &GpuContext, words: &[u32]) -> wgpu::Buffer {
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    gpu.create_buffer_init("test pairs", bytemuck::cast_slice(words), usage)
        .expect("buffer")
}

/// Sorts `keys` (values: their indices) on the GPU and checks against `sort_by_key`, which is
/// stable, so the values must match too.
fn check_sort(gpu: &GpuContext, sort: &mut RadixSort, name: &str, keys: &[u32]) {
    let values: Vec<u32> = (0..keys.len() as u32).collect();
    let key_buffer = storage_buffer(gpu, keys);
    let value_buffer = storage_buffer(gpu, &values);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    sort.record(
        gpu,
        &mut encoder,
        &key_buffer,
        &value_buffer,
        keys.len() as u32,
    )
    .expect("record");
    gpu.queue.submit([encoder.finish()]);
    let got_keys: Vec<u32> = gpu.read_pod(&key_buffer, keys.len()).expect("keys");
    let got_values: Vec<u32> = gpu.read_pod(&value_buffer, keys.len()).expect("values");
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values).collect();
    expected.sort_by_key(|&(k, _)| k);
    let got: Vec<(u32, u32)> = got_keys.into_iter().zip(got_values).collect();
    if let Some(i) = (0..expected.len()).find(|&i| got[i] != expected[i]) {
        panic!(
            "{name} ({} keys): first difference at {i}: got {:?}, expected {:?}",
            keys.len(),
            got[i],
            expected[i]
        );
    }
}

#[test]
fn radix_sort_matches_a_stable_cpu_sort() {
    let gpu = gpu();
    let shaders =
        hppm::gpu::shaders::ShaderLibrary::new(gpu.has_float_atomics(), HashMap::new(), &[])
            .expect("gpu modules compose");
    let mut sort = RadixSort::new(&gpu, &shaders).expect("radix sort");
    let mut rng = Rng(7);
    let mut random =
        |n: usize, modulus: u32| -> Vec<u32> { (0..n).map(|_| rng.next_u32() % modulus).collect() };
    check_sort(&gpu, &mut sort, "empty", &[]);
    check_sort(&gpu, &mut sort, "one", &[42]);
    check_sort(&gpu, &mut sort, "two, reversed", &[u32::MAX, 3]);
    // Around one invocation's 16 pairs and one block's 4096: partial invocations, a partial
    // last block, and a block of one pair.
    for n in [15, 16, 17, 1023, 4095, 4096, 4097] {
        check_sort(&gpu, &mut sort, "random", &random(n, u32::MAX));
    }
    check_sort(&gpu, &mut sort, "all equal", &[0xdead_beef; 5000]);
    let sorted: Vec<u32> = (0..70_000u32).map(|i| i * 61_000).collect();
    check_sort(&gpu, &mut sort, "already sorted", &sorted);
    let reversed: Vec<u32> = sorted.iter().rev().copied().collect();
    check_sort(&gpu, &mut sort, "reversed", &reversed);
    check_sort(&gpu, &mut sort, "many duplicates", &random(50_000, 100));
    // Keys that differ in one digit only (the others' passes must keep the order).
    let one_digit: Vec<u32> = random(20_000, 16).iter().map(|k| k << 20).collect();
    check_sort(&gpu, &mut sort, "one digit", &one_digit);
    // 2^20: 256 blocks, and the scratch grows from the sizes above.
    check_sort(
        &gpu,
        &mut sort,
        "2^20 with duplicates",
        &random(1 << 20, 1 << 18),
    );
    // Smaller again: the grown scratch is reused.
    check_sort(
        &gpu,
        &mut sort,
        "after a larger sort",
        &random(3000, u32::MAX),
    );
}

// ---------------------------------------------------------------------------------------------
// Tree structure and range queries.

const SCENE: &str = "tests/refs/scenes/cornell_glass_sphere/scene.xml";

fn read_tree(gpu: &GpuContext, tree: &Resource) -> Vec<BvhNode> {
    let bytes = gpu
        .read_buffer(&tree.buffer, 0, tree.buffer.size())
        .expect("tree readback");
    let node_count = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as usize;
    let start = TREE_HEADER_BYTES as usize;
    let end = start + node_count * std::mem::size_of::<BvhNode>();
    bytemuck::pod_collect_to_vec(&bytes[start..end])
}

fn contains(outer: &BvhNode, min: Vec3, max: Vec3) -> bool {
    Vec3::from(outer.min).cmple(min).all() && Vec3::from(outer.max).cmpge(max).all()
}

/// Depth of the deepest leaf below `root`, after checking every node (see the layout contract
/// in shaders/passes/lbvh.wgsl and shaders/common/hit_points.wgsl).
fn check_structure(name: &str, nodes: &[BvhNode], points: &[GpuHitPoint]) -> usize {
    let n = points.len();
    assert_eq!(nodes.len(), (2 * n).saturating_sub(1), "{name}: node count");
    let mut seen_node = vec![false; nodes.len()];
    let mut leaf_of = vec![None; n];
    let mut deepest = 0;
    let mut stack = if nodes.is_empty() {
        vec![]
    } else {
        vec![(0usize, 0usize)]
    };
    while let Some((i, depth)) = stack.pop() {
        assert!(!seen_node[i], "{name}: node {i} reached twice");
        seen_node[i] = true;
        deepest = deepest.max(depth);
        let node = &nodes[i];
        if node.count == 0 {
            for child in [node.left_or_first as usize, node.left_or_first as usize + 1] {
                assert!(child < nodes.len(), "{name}: node {i} links to {child}");
                let c = &nodes[child];
                assert!(
                    contains(node, Vec3::from(c.min), Vec3::from(c.max)) || c.min[0] > c.max[0],
                    "{name}: node {i} does not contain child {child}"
                );
                stack.push((child, depth + 1));
            }
            continue;
        }
        assert_eq!(
            node.count, 1,
            "{name}: leaf {i} holds {} points",
            node.count
        );
        let hp = node.left_or_first as usize;
        assert!(hp < n, "{name}: leaf {i} names hit point {hp}");
        assert!(
            leaf_of[hp].is_none(),
            "{name}: hit point {hp} in two leaves"
        );
        leaf_of[hp] = Some(i);
        if points[hp].is_valid() {
            let padded = sphere_box(&points[hp]);
            assert!(
                contains(node, padded.min, padded.max),
                "{name}: leaf {i} misses the sphere of hit point {hp}"
            );
        } else {
            assert!(
                (0..3).all(|a| node.min[a] > node.max[a]),
                "{name}: leaf {i} of invalid hit point {hp} is not empty"
            );
        }
    }
    assert!(seen_node.iter().all(|&s| s), "{name}: unreachable nodes");
    assert!(
        leaf_of.iter().all(Option::is_some),
        "{name}: slots without a leaf"
    );
    // Every ancestor's box contains the leaf boxes: by induction from the child checks above.
    deepest
}

/// The photon pass's traversal stack (TREE_STACK_SIZE) holds one entry per level plus two.
const MAX_TRAVERSABLE_DEPTH: usize = 62;

fn check_tree(name: &str, nodes: &[BvhNode], points: &[GpuHitPoint], queries: &[Vec3]) {
    let depth = check_structure(name, nodes, points);
    assert!(depth <= MAX_TRAVERSABLE_DEPTH, "{name}: depth {depth}");
    check_range_queries(name, nodes, points, queries);
    // Queries at the centres: every valid hit point must find at least itself.
    let centres: Vec<Vec3> = points.iter().map(|h| Vec3::from(h.position)).collect();
    check_range_queries(&format!("{name}, at centres"), nodes, points, &centres);
}

fn build_on_gpu(h: &PassHarness<'_>, points: &[GpuHitPoint]) -> Vec<BvhNode> {
    let hit_points = hit_point_resource(h.gpu, points);
    let no_photons = photon_hits_resource(h.gpu, &[]);
    let mut bvh = HitPointBvhLbvh::new(LbvhParams::default());
    let inputs = [("hit_points", &hit_points), ("photon_hits", &no_photons)];
    let tree = h.prepare(&LBVH, &mut bvh, &inputs)["tree"].clone();
    h.run(&mut bvh, 0, 1);
    read_tree(h.gpu, &tree)
}

/// Prepares `bvh` over `points` (no photon hits) as a graph wires it when the `ppm` estimator
/// keeps the camera's hit points; returns the hit points and the tree.
fn prepare_kept(
    h: &PassHarness<'_>,
    bvh: &mut HitPointBvhLbvh,
    points: &[GpuHitPoint],
) -> (Resource, Resource) {
    let hit_points = hit_point_resource(h.gpu, points);
    let no_photons = photon_hits_resource(h.gpu, &[]);
    let inputs = [("hit_points", &hit_points), ("photon_hits", &no_photons)];
    let kept = Wiring {
        kept_inputs: vec!["hit_points"],
        ..Default::default()
    };
    let tree = h.prepare_wired(&LBVH, bvh, &inputs, &kept)["tree"].clone();
    (hit_points, tree)
}

fn scene_and_bounds() -> (Scene, Vec3, Vec3) {
    let scene = load_scene(SCENE);
    let (lo, hi) = scene.bounds();
    (scene, lo, hi)
}

#[test]
fn lbvh_trees_are_well_formed_and_queries_match_brute_force() {
    let gpu = gpu();
    let (scene, lo, hi) = scene_and_bounds();
    let h = PassHarness::new(&gpu, &scene, (32, 32), gpu.has_float_atomics());
    let extent = (hi - lo).max_element();
    let mut rng = Rng(3);
    let queries: Vec<Vec3> = (0..2000).map(|_| rng.in_box(lo, hi)).collect();
    let random = |rng: &mut Rng, n: usize, r: f32| -> Vec<GpuHitPoint> {
        (0..n)
            .map(|_| hit_point(rng.in_box(lo, hi), r * (0.1 + rng.unit())))
            .collect()
    };

    let empty = build_on_gpu(&h, &[]);
    assert!(empty.is_empty(), "no slots, no nodes");
    let one = vec![hit_point(lo.lerp(hi, 0.5), 0.1 * extent)];
    check_tree("one", &build_on_gpu(&h, &one), &one, &queries);
    let two = random(&mut rng, 2, 0.2 * extent);
    check_tree("two", &build_on_gpu(&h, &two), &two, &queries);

    let varied = random(&mut rng, 5000, 0.05 * extent);
    check_tree(
        "varied radii",
        &build_on_gpu(&h, &varied),
        &varied,
        &queries,
    );

    let mut mixed = random(&mut rng, 4097, 0.05 * extent);
    for (i, hp) in mixed.iter_mut().enumerate() {
        if i % 3 == 0 {
            hp.pixel = NO_PIXEL;
        }
        if i % 7 == 0 {
            hp.radius = 0.0;
        }
    }
    check_tree(
        "with invalid slots",
        &build_on_gpu(&h, &mixed),
        &mixed,
        &queries,
    );

    let mut none_valid = random(&mut rng, 300, 0.05 * extent);
    none_valid.iter_mut().for_each(|hp| hp.pixel = NO_PIXEL);
    check_tree(
        "none valid",
        &build_on_gpu(&h, &none_valid),
        &none_valid,
        &queries,
    );

    // Equal Morton codes: told apart by sorted position only.
    let centre = lo.lerp(hi, 0.3);
    let coincident: Vec<GpuHitPoint> = (0..3000)
        .map(|i| hit_point(centre, 0.01 * extent * (1.0 + i as f32 * 1e-3)))
        .collect();
    let near: Vec<Vec3> = (0..500)
        .map(|_| centre + rng.in_box(Vec3::splat(-0.05), Vec3::splat(0.05)) * extent)
        .collect();
    check_tree(
        "coincident",
        &build_on_gpu(&h, &coincident),
        &coincident,
        &near,
    );

    // Outside the scene bounds, clamped into the border cells: many equal codes again.
    let outside: Vec<GpuHitPoint> = (0..2000)
        .map(|_| {
            let p = rng.in_box(lo - extent, hi + extent);
            hit_point(p, 0.1 * extent * (0.1 + rng.unit()))
        })
        .collect();
    let wide: Vec<Vec3> = (0..2000)
        .map(|_| rng.in_box(lo - extent, hi + extent))
        .collect();
    check_tree(
        "outside the bounds",
        &build_on_gpu(&h, &outside),
        &outside,
        &wide,
    );

    // Many slots over several sort blocks and refit workgroups, most invalid, as in a frame
    // where few pixels see a diffuse surface through glass.
    let mut large = random(&mut rng, 150_000, 0.01 * extent);
    for (i, hp) in large.iter_mut().enumerate() {
        if i % 5 != 0 {
            hp.pixel = NO_PIXEL;
        }
    }
    let nodes = build_on_gpu(&h, &large);
    let depth = check_structure("150k slots", &nodes, &large);
    eprintln!("150k slots: depth {depth}");
    assert!(depth <= MAX_TRAVERSABLE_DEPTH);
    check_range_queries("150k slots", &nodes, &large, &queries);
}

// ---------------------------------------------------------------------------------------------
// Refit-only.

fn shrink(points: &mut [GpuHitPoint], rng: &mut Rng) {
    for (i, hp) in points.iter_mut().enumerate() {
        hp.radius *= if i % 11 == 0 {
            0.0
        } else {
            0.3 + 0.6 * rng.unit()
        };
    }
}

fn topology(nodes: &[BvhNode]) -> Vec<(u32, u32)> {
    nodes.iter().map(|n| (n.left_or_first, n.count)).collect()
}

#[test]
fn refit_only_keeps_the_shape_and_follows_shrinking_radii() {
    let gpu = gpu();
    let (scene, lo, hi) = scene_and_bounds();
    let h = PassHarness::new(&gpu, &scene, (32, 32), gpu.has_float_atomics());
    let extent = (hi - lo).max_element();
    let mut rng = Rng(11);
    let queries: Vec<Vec3> = (0..2000).map(|_| rng.in_box(lo, hi)).collect();
    let mut points: Vec<GpuHitPoint> = (0..6000)
        .map(|i| {
            let mut hp = hit_point(rng.in_box(lo, hi), 0.05 * extent * (0.1 + rng.unit()));
            if i % 4 == 0 {
                hp.pixel = NO_PIXEL;
            }
            hp
        })
        .collect();
    let mut bvh = HitPointBvhLbvh::new(LbvhParams::default());
    let (hit_points, tree) = prepare_kept(&h, &mut bvh, &points);
    h.run(&mut bvh, 0, 1);
    let built = read_tree(&gpu, &tree);
    check_tree("built", &built, &points, &queries);
    for iteration in 1..4 {
        shrink(&mut points, &mut rng);
        write_hit_points(&gpu, &hit_points, &points);
        h.run(&mut bvh, iteration, 1);
        let refit = read_tree(&gpu, &tree);
        assert_eq!(
            topology(&refit),
            topology(&built),
            "refit changed the shape"
        );
        check_tree(&format!("refit {iteration}"), &refit, &points, &queries);
    }
    assert_eq!(bvh.builds(), BuildCounts { full: 1, refit: 3 });

    // `refit_only: Never` rebuilds every iteration even when the hit points are kept.
    let mut never = HitPointBvhLbvh::new(LbvhParams {
        refit_only: RefitOnly::Never,
    });
    prepare_kept(&h, &mut never, &points);
    h.run(&mut never, 0, 1);
    h.run(&mut never, 1, 1);
    assert_eq!(never.builds(), BuildCounts { full: 2, refit: 0 });
}

// ---------------------------------------------------------------------------------------------
// Exact bounds: each internal box is the union of its leaves', bit for bit.

/// `FAR` in shaders/passes/lbvh.wgsl: the empty box is (FAR, -FAR).
const FAR: f32 = 3.0e38;

/// f32 bits in an order where unsigned comparison is float comparison, as the refit's atomics
/// combine them, so that the union below is the one the GPU must give to the bit.
fn ordered(x: f32) -> u32 {
    let bits = x.to_bits();
    if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    }
}

/// The box of node `i` as ordered words (lo, hi), after checking that every internal node
/// below it holds exactly the union of its children's boxes, so of its leaves'.
fn exact_union(name: &str, nodes: &[BvhNode], i: usize) -> ([u32; 3], [u32; 3]) {
    let node = &nodes[i];
    let lo = node.min.map(ordered);
    let hi = node.max.map(ordered);
    if node.count > 0 {
        return (lo, hi);
    }
    let mut union = ([ordered(FAR); 3], [ordered(-FAR); 3]);
    for child in [node.left_or_first as usize, node.left_or_first as usize + 1] {
        let (child_lo, child_hi) = exact_union(name, nodes, child);
        for a in 0..3 {
            union.0[a] = union.0[a].min(child_lo[a]);
            union.1[a] = union.1[a].max(child_hi[a]);
        }
    }
    assert_eq!(
        (lo, hi),
        union,
        "{name}: node {i} holds ({:?}, {:?}), its leaves' union is ({:?}, {:?})",
        node.min,
        node.max,
        union.0.map(from_ordered),
        union.1.map(from_ordered)
    );
    (lo, hi)
}

fn from_ordered(word: u32) -> f32 {
    f32::from_bits(if word & 0x8000_0000 != 0 {
        word & 0x7fff_ffff
    } else {
        !word
    })
}

fn check_exact(name: &str, nodes: &[BvhNode], points: &[GpuHitPoint]) {
    check_structure(name, nodes, points);
    if !nodes.is_empty() {
        exact_union(name, nodes, 0);
    }
}

/// Radii as a shuffled sequence of distinct values, so which leaf widens an ancestor, and in
/// which order the leaves arrive there, is unrelated to their place in the tree.
fn shuffled(rng: &mut Rng, mut values: Vec<f32>) -> Vec<f32> {
    for i in (1..values.len()).rev() {
        values.swap(i, rng.next_u32() as usize % (i + 1));
    }
    values
}

#[test]
fn refit_gives_every_node_exactly_the_union_of_its_leaves() {
    let gpu = gpu();
    let (scene, lo, hi) = scene_and_bounds();
    let h = PassHarness::new(&gpu, &scene, (32, 32), gpu.has_float_atomics());
    let extent = (hi - lo).max_element();
    let mut rng = Rng(23);
    let mut cases: Vec<(&str, Vec<GpuHitPoint>)> = Vec::new();

    // One Morton code: every invocation climbs the same spine of ancestors, from many
    // workgroups at once, and a leaf keeps climbing while its radius is the largest yet.
    let centre = lo.lerp(hi, 0.6);
    let radii = shuffled(
        &mut rng,
        (0..40_000)
            .map(|i| 0.01 * extent * (1.0 + i as f32 * 1e-4))
            .collect(),
    );
    let coincident = radii.iter().map(|&r| hit_point(centre, r)).collect();
    cases.push(("coincident, shuffled radii", coincident));

    // Radii over four decades, a quarter of the slots empty: some deep leaves must widen the
    // root, and most stop low.
    let mut spread: Vec<GpuHitPoint> = (0..100_000)
        .map(|_| hit_point(rng.in_box(lo, hi), extent * rng.log_uniform(1e-5, 0.1)))
        .collect();
    spread
        .iter_mut()
        .step_by(4)
        .for_each(|hp| hp.pixel = NO_PIXEL);
    cases.push(("log-uniform radii", spread));

    // On a line along x: the y and z words of an ancestor are widened only by its largest
    // radius, the x words by its end points, so a leaf often changes some words and not others.
    let line = (0..30_000)
        .map(|_| {
            let mut p = centre;
            p.x = lo.x + (hi.x - lo.x) * rng.unit();
            hit_point(p, 0.001 * extent * (1.0 + 20.0 * rng.unit()))
        })
        .collect();
    cases.push(("on a line", line));

    // Below and around one workgroup, and the single leaf, which is the root.
    for n in [1, 2, 3, 255, 257] {
        let small = (0..n)
            .map(|_| hit_point(rng.in_box(lo, hi), 0.05 * extent * (0.1 + rng.unit())))
            .collect();
        cases.push(("small", small));
    }

    for (name, points) in &cases {
        // Each build may see another interleaving of the workgroups.
        for attempt in 0..3 {
            let nodes = build_on_gpu(&h, points);
            let n = points.len();
            check_exact(&format!("{name} ({n}), build {attempt}"), &nodes, points);
        }
    }

    // Refit-only, radii shrinking for some slots and growing for others: every box must be
    // recomputed from the empty box, not widened from the last iteration's.
    let spread = cases
        .iter()
        .position(|(name, _)| *name == "log-uniform radii");
    let mut points = cases.swap_remove(spread.expect("case")).1;
    let mut bvh = HitPointBvhLbvh::new(LbvhParams::default());
    let (hit_points, tree) = prepare_kept(&h, &mut bvh, &points);
    h.run(&mut bvh, 0, 1);
    check_exact("refit-only, built", &read_tree(&gpu, &tree), &points);
    for iteration in 1..4 {
        for hp in points.iter_mut() {
            hp.radius *= 0.2 + 1.6 * rng.unit();
        }
        write_hit_points(&gpu, &hit_points, &points);
        h.run(&mut bvh, iteration, 1);
        check_exact(
            &format!("refit-only, iteration {iteration}"),
            &read_tree(&gpu, &tree),
            &points,
        );
    }
    assert_eq!(bvh.builds(), BuildCounts { full: 1, refit: 3 });
}

#[test]
fn unknown_params_are_rejected() {
    let kind = hppm::passes::builtin_kinds()
        .iter()
        .find(|k| k.name == "hit_point_bvh_lbvh")
        .expect("registered");
    assert!((kind.construct)("(refit_only: Never)").is_ok());
    assert!((kind.construct)("(refit_only: Always)").is_err());
    assert!((kind.construct)("(leaf_size: 4)").is_err());
}

// ---------------------------------------------------------------------------------------------
// Whole renders: the GPU tree must give the image the CPU tree gives.

fn render_graph(
    graph_file: &str,
    replace: Option<(&str, &str)>,
    size: u32,
    spp: u64,
) -> hppm::image::Image {
    let gpu = gpu();
    let scene = load_scene(SCENE);
    let path = repo_path(graph_file);
    let mut text = std::fs::read_to_string(&path).expect("graph file");
    if let Some((from, to)) = replace {
        text = text.replace(from, to);
    }
    let graph = hppm::graph::parse_graph(Path::new(&path), &text, hppm::passes::builtin_kinds())
        .unwrap_or_else(|e| panic!("{graph_file}: {e}"));
    let mut r = hppm::render::Renderer::new(&gpu, &scene, graph, size, size, 9)
        .unwrap_or_else(|e| panic!("renderer: {e}"));
    render_to(&mut r, spp)
}

#[test]
fn hybrid_lbvh_renders_what_hybrid_renders() {
    let sah = render_graph("graphs/hybrid.ron", None, 48, 4);
    let lbvh = render_graph("graphs/hybrid_lbvh.ron", None, 48, 4);
    let difference = relmse(&lbvh, &sah);
    // Measured on lavapipe: 1.9e-17 (and 1.8e-17 for hybrid_ppm below). The trees differ, the
    // sets of hit points each photon finds do not; only the order of the float additions into a
    // hit point's deposit may.
    eprintln!("relMSE(hybrid_lbvh, hybrid) = {difference:e}, 48x48, 4 iterations, same seed");
    assert!(
        difference < 1e-6,
        "hybrid_lbvh differs from hybrid: {difference}"
    );

    // With `ppm` the hit points are kept, so every iteration after the first is a refit.
    let swap = (
        "pass: \"hit_point_bvh_sah\"",
        "pass: \"hit_point_bvh_lbvh\"",
    );
    let sah = render_graph("graphs/hybrid_ppm.ron", None, 48, 4);
    let lbvh = render_graph("graphs/hybrid_ppm.ron", Some(swap), 48, 4);
    let difference = relmse(&lbvh, &sah);
    eprintln!("relMSE(hybrid_ppm with lbvh, hybrid_ppm) = {difference:e}, 48x48, 4 iterations");
    assert!(
        difference < 1e-6,
        "refit-only differs from the SAH tree: {difference}"
    );
}
