#define_import_path common::traversal

// Finding what a ray hits in the whole scene: the BVH walk (or a test of every primitive in
// small scenes on a CPU adapter), closest hit for camera and photon rays, any hit for shadows.

#import common::scene::{BVH_STACK_SIZE, NO_HIT, T_INFINITE, bvh_node, bvh_nodes, prim_index, scene_info, spheres}
#import common::intersection::{Hit, intersect_box, keep_closer, prim_crossing, safe_inverse, tie_span, triangle_crossing}
#ifdef SPHERES
#import common::intersection::sphere_crossing
#endif

// Closest hit along the ray within (0, t_max). With `any_hit`, returns at the first hit found.
// `front_wins_ties`: see keep_closer.
fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, any_hit: bool, front_wins_ties: bool) -> Hit {
#ifdef EVERY_PRIM
    return test_every_prim(origin, dir, t_max, front_wins_ties);
#else
    return traverse_bvh(origin, dir, t_max, any_hit, front_wins_ties);
#endif
}

fn traverse_bvh(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, any_hit: bool, front_wins_ties: bool) -> Hit {
    var hit = Hit(t_max, NO_HIT, false);
    let inv_dir = safe_inverse(dir);
    var stack: array<u32, BVH_STACK_SIZE>;
    var top = 0u;
    var node_index = 0u;
    // An empty scene's root has an inverted box and no children (see src/scene/bvh.rs).
    if scene_info.num_triangles + scene_info.num_spheres == 0u {
        return Hit(T_INFINITE, NO_HIT, false);
    }
    let root = bvh_node(0u);
    if intersect_box(root.min, root.max, origin, inv_dir, t_max) == T_INFINITE {
        return Hit(T_INFINITE, NO_HIT, false);
    }
    loop {
        let node = bvh_node(node_index);
        if node.count > 0u {
            for (var i = 0u; i < node.count; i++) {
                let prim = prim_index(node.left_or_first + i);
                let kept = keep_closer(&hit, prim, prim_crossing(prim, origin, dir), origin, dir, front_wins_ties);
                if kept && any_hit {
                    return hit;
                }
            }
        } else {
            let left = node.left_or_first;
            let right = left + 1u;
            // A tie may lie in a box a hair beyond the closest hit so far.
            let reach = select(hit.t, hit.t + tie_span(origin, hit.t), front_wins_ties && hit.prim != NO_HIT);
#ifdef BVH_NODES_CHUNKED
            let left_node = bvh_node(left);
            let right_node = bvh_node(right);
            let t_left = intersect_box(left_node.min, left_node.max, origin, inv_dir, reach);
            let t_right = intersect_box(right_node.min, right_node.max, origin, inv_dir, reach);
#else
            let t_left = intersect_box(bvh_nodes[left].min, bvh_nodes[left].max, origin, inv_dir, reach);
            let t_right = intersect_box(bvh_nodes[right].min, bvh_nodes[right].max, origin, inv_dir, reach);
#endif
            let near_first = t_left <= t_right;
            let near = select(right, left, near_first);
            let far = select(left, right, near_first);
            let t_near = min(t_left, t_right);
            let t_far = max(t_left, t_right);
            if t_near < T_INFINITE {
                if t_far < T_INFINITE && top < BVH_STACK_SIZE {
                    stack[top] = far;
                    top += 1u;
                }
                node_index = near;
                continue;
            }
        }
        if top == 0u {
            break;
        }
        top -= 1u;
        node_index = stack[top];
    }
    if hit.prim == NO_HIT {
        hit.t = T_INFINITE;
    }
    return hit;
}

#ifdef EVERY_PRIM
// Small scenes on a CPU adapter test every primitive instead of walking the BVH
// (src/gpu_scene/resources.rs decides). Mesa 25.0's lavapipe loads a table entry once for
// all SIMD lanes only when its index is a compile-time constant; any other index, a loop
// counter included, costs a bounds-checked scalar load per lane (BENCHMARKS.md). So the tests
// are unrolled: each `first` below is a constant at its call site once the functions are
// inlined, and the defs TRIANGLES_FROM_<n> and SPHERES_FROM_<n> (n a power of two, the value
// the first index of that block) split the scene's primitives into blocks of powers of two.
// No test returns early (a masked-off lane runs every test anyway), but a block of four whose
// box no lane enters is skipped: binding 1 holds those boxes instead of the BVH's nodes.
fn test_triangles_1(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    keep_closer(hit, first, triangle_crossing(first, origin, dir), origin, dir, front_wins_ties);
}

fn test_triangles_2(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_1(hit, first, origin, dir, front_wins_ties);
    test_triangles_1(hit, first + 1u, origin, dir, front_wins_ties);
}

fn test_triangles_4(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    // Binding 1 holds a box per block of four (src/gpu_scene/resources.rs, block_boxes),
    // with `count` 1 where it is worth testing. A box no lane enters skips the four tests: lavapipe
    // jumps over code no lane runs.
    let block = bvh_nodes[first / 4u];
    if block.count != 0u {
        // A tie may lie a hair beyond the closest hit so far (as in traverse_bvh).
        let reach = select((*hit).t, (*hit).t + tie_span(origin, (*hit).t), front_wins_ties && (*hit).prim != NO_HIT);
        if intersect_box(block.min, block.max, origin, safe_inverse(dir), reach) == T_INFINITE {
            return;
        }
    }
    test_triangles_2(hit, first, origin, dir, front_wins_ties);
    test_triangles_2(hit, first + 2u, origin, dir, front_wins_ties);
}

fn test_triangles_8(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_4(hit, first, origin, dir, front_wins_ties);
    test_triangles_4(hit, first + 4u, origin, dir, front_wins_ties);
}

fn test_triangles_16(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_8(hit, first, origin, dir, front_wins_ties);
    test_triangles_8(hit, first + 8u, origin, dir, front_wins_ties);
}

fn test_triangles_32(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_16(hit, first, origin, dir, front_wins_ties);
    test_triangles_16(hit, first + 16u, origin, dir, front_wins_ties);
}

fn test_triangles_64(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_32(hit, first, origin, dir, front_wins_ties);
    test_triangles_32(hit, first + 32u, origin, dir, front_wins_ties);
}

#ifdef SPHERES
fn test_spheres_1(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    keep_closer(hit, scene_info.num_triangles + first, sphere_crossing(spheres[first], origin, dir), origin, dir, front_wins_ties);
}

fn test_spheres_2(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_spheres_1(hit, first, origin, dir, front_wins_ties);
    test_spheres_1(hit, first + 1u, origin, dir, front_wins_ties);
}

fn test_spheres_4(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_spheres_2(hit, first, origin, dir, front_wins_ties);
    test_spheres_2(hit, first + 2u, origin, dir, front_wins_ties);
}

fn test_spheres_8(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_spheres_4(hit, first, origin, dir, front_wins_ties);
    test_spheres_4(hit, first + 4u, origin, dir, front_wins_ties);
}
#endif

fn test_every_prim(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, front_wins_ties: bool) -> Hit {
    var hit = Hit(t_max, NO_HIT, false);
#ifdef TRIANGLES_FROM_64
    test_triangles_64(&hit, #{TRIANGLES_FROM_64}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_32
    test_triangles_32(&hit, #{TRIANGLES_FROM_32}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_16
    test_triangles_16(&hit, #{TRIANGLES_FROM_16}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_8
    test_triangles_8(&hit, #{TRIANGLES_FROM_8}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_4
    test_triangles_4(&hit, #{TRIANGLES_FROM_4}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_2
    test_triangles_2(&hit, #{TRIANGLES_FROM_2}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_1
    test_triangles_1(&hit, #{TRIANGLES_FROM_1}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_8
    test_spheres_8(&hit, #{SPHERES_FROM_8}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_4
    test_spheres_4(&hit, #{SPHERES_FROM_4}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_2
    test_spheres_2(&hit, #{SPHERES_FROM_2}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_1
    test_spheres_1(&hit, #{SPHERES_FROM_1}u, origin, dir, front_wins_ties);
#endif
    if hit.prim == NO_HIT {
        hit.t = T_INFINITE;
    }
    return hit;
}
#endif

fn intersect_scene(origin: vec3<f32>, dir: vec3<f32>) -> Hit {
    return traverse(origin, dir, T_INFINITE, false, false);
}

// The closest hit of a photon (see traverse's `front_wins_ties`).
fn intersect_photon(origin: vec3<f32>, dir: vec3<f32>) -> Hit {
    return traverse(origin, dir, T_INFINITE, false, true);
}

fn occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    return traverse(origin, dir, t_max, true, false).prim != NO_HIT;
}
