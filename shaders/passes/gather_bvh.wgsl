// The BVH gather, shared by both BVH builders (hit_point_bvh_sah, hit_point_bvh_lbvh): for each
// photon hit an invocation walks the tree over hit-point spheres and adds the photon to every
// hit point whose sphere contains it (common::gather decides what counts). An invocation takes
// photon hits index, index + invocations, ... and starts the next walk in the same loop as soon
// as one ends, so a SIMD group runs for its lanes' longest total, not each photon's longest.

#import common::hit_points::{HitPointTree, TREE_STACK_SIZE, point_in_box}
#import common::gather::{photon_hits, photon_hit_count, gather_at}
#import gpu::dispatch::{WORKGROUP_SIZE, flat_invocation, invocation_count, next_item}

@group(1) @binding(3) var<storage, read> tree: HitPointTree;

@compute @workgroup_size(WORKGROUP_SIZE, 1, 1)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let count = photon_hit_count();
    let stride = invocation_count(groups);
    var index = flat_invocation(group, groups, local);
    if index >= count || tree.node_count == 0u {
        return;
    }
    var hit = photon_hits.hits[index];
    var stack: array<u32, TREE_STACK_SIZE>;
    var top = 1u;
    stack[0] = 0u;
    loop {
        if top == 0u {
            index = next_item(index, stride, count);
            if index == count {
                break;
            }
            hit = photon_hits.hits[index];
            top = 1u;
            stack[0] = 0u;
        }
        top -= 1u;
        let node = tree.nodes[stack[top]];
        if !point_in_box(hit.position, node.min, node.max) {
            continue;
        }
        if node.count > 0u {
            gather_at(node.left_or_first, hit);
        } else if top + 2u <= TREE_STACK_SIZE {
            stack[top] = node.left_or_first;
            stack[top + 1u] = node.left_or_first + 1u;
            top += 2u;
        }
    }
}
