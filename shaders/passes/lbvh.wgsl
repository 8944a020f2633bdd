// Linear BVH over the hit points' search spheres, built on the GPU (Lauterbach et al. 2009,
// "Fast BVH Construction on GPUs": sort by Morton code; hierarchy after Karras 2012,
// "Maximizing Parallelism in the Construction of BVHs, Octrees, and k-d Trees"), written in the
// layout photon_trace.wgsl traverses. Driven by src/passes/hit_point_bvh_lbvh.rs:
//   morton_codes, radix sort (radix_sort.wgsl), emit_hierarchy, then the bounds in three
//   dispatches (reset_bounds, refit, finish_bounds); while the hit points keep their positions
//   only those three run again, with the current radii.
//
// Every slot of the HitPoints buffer gets a leaf, so the tree has 2n - 1 nodes for n slots and
// its shape depends only on n and the keys. A slot without a hit point (pixel NO_PIXEL, or no
// positive radius) gets the key INVALID_KEY, which sorts it behind every valid one, and an empty
// box (min +FAR, max -FAR): no point is inside it, and it leaves its parents' unions unchanged,
// so traversal never reaches it.
//
// Node slots: internal node 0 of the Karras tree (the root) is node 0; the children of internal
// node i are nodes 2i + 1 and 2i + 2, so they are adjacent as the traversal wants, and every
// node but the root has exactly one parent, so slots 1..2n-2 are each used once.
//
// Depth: keys are 30-bit Morton codes, with INVALID_KEY differing from all of them in bit 31,
// and equal keys are told apart by their sorted position (Karras section 4), so a leaf is at
// most 1 + 30 + ceil(log2 n) levels deep: 55 for 10M slots, below TREE_STACK_SIZE (64).

#import common::scene::scene_info
#import common::hit_points::NO_PIXEL
#import common::hit_points::HitPointBuffer
#import gpu::dispatch::{WORKGROUP_SIZE, flat_invocation}

const INVALID_KEY: u32 = 0xffffffffu;
const FAR: f32 = 3.0e38;
// Morton cells per axis (10 bits each).
const MORTON_CELLS: f32 = 1024.0;

struct LbvhUniform {
    // Hit-point slots (leaves).
    count: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

// HitPointNode with the bounds as atomic words. From reset_bounds to finish_bounds an internal
// node's words hold ordered bits (see ordered_bits), which refit's invocations combine with
// atomicMin/atomicMax; otherwise they hold f32 bits. The layout (32 bytes) is that of
// HitPointNode, so the gather reads the same buffer as a HitPointTree.
struct AtomicNode {
    lo: array<atomic<u32>, 3>,
    left_or_first: u32,
    hi: array<atomic<u32>, 3>,
    count: u32,
}

struct AtomicTree {
    node_count: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
    nodes: array<AtomicNode>,
}

struct Box {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

@group(1) @binding(0) var<uniform> params: LbvhUniform;
@group(1) @binding(1) var<storage, read> hit_points: HitPointBuffer;
// Morton keys, then (after the sort) in sorted order.
@group(1) @binding(2) var<storage, read_write> keys: array<u32>;
// Hit-point slot of each key: the sort's values, so after it the slot of leaf k.
@group(1) @binding(3) var<storage, read_write> values: array<u32>;
@group(1) @binding(4) var<storage, read_write> tree: AtomicTree;
// Node slot and parent (internal node index) of leaf k at k, of internal node i at count + i.
@group(1) @binding(5) var<storage, read_write> node_slots: array<u32>;
@group(1) @binding(6) var<storage, read_write> parents: array<u32>;

fn has_hit_point(slot: u32) -> bool {
    return hit_points.points[slot].pixel != NO_PIXEL && hit_points.points[slot].radius > 0.0;
}

// Bits 0..9 of `v` moved to bits 0, 3, 6, ..., 27.
fn spread_bits(v: u32) -> u32 {
    var x = v & 0x3ffu;
    x = (x | (x << 16u)) & 0x030000ffu;
    x = (x | (x << 8u)) & 0x0300f00fu;
    x = (x | (x << 4u)) & 0x030c30c3u;
    x = (x | (x << 2u)) & 0x09249249u;
    return x;
}

// 30-bit Morton code of `p` in the scene's bounds; points outside are clamped to the border
// cells (still correct, only a looser tree).
fn morton_code(p: vec3<f32>) -> u32 {
    let lo = scene_info.bounds_min;
    let extent = max(scene_info.bounds_max - lo, vec3<f32>(1e-30));
    let unit = clamp((p - lo) / extent, vec3<f32>(0.0), vec3<f32>(1.0));
    let cell = min(vec3<u32>(unit * MORTON_CELLS), vec3<u32>(1023u));
    return (spread_bits(cell.x) << 2u) | (spread_bits(cell.y) << 1u) | spread_bits(cell.z);
}

@compute @workgroup_size(256)
fn morton_codes(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let slot = flat_invocation(group, groups, local);
    if slot >= params.count {
        return;
    }
    var key = INVALID_KEY;
    if has_hit_point(slot) {
        key = morton_code(hit_points.points[slot].position);
    }
    keys[slot] = key;
    values[slot] = slot;
}

// Length of the common prefix of the keys at sorted positions i and j, with the positions
// appended to tell equal keys apart; -1 when j is outside the leaves (Karras's delta).
fn common_prefix(i: i32, j: i32) -> i32 {
    if j < 0 || j >= i32(params.count) {
        return -1;
    }
    let a = keys[i];
    let b = keys[j];
    if a == b {
        return 32 + i32(countLeadingZeros(u32(i) ^ u32(j)));
    }
    return i32(countLeadingZeros(a ^ b));
}

// Records that node `slot` is child `index` (a leaf, or internal node `index`) of internal node
// `parent`, and writes the node's link.
fn attach_child(parent: u32, slot: u32, index: u32, is_leaf: bool) {
    if is_leaf {
        node_slots[index] = slot;
        parents[index] = parent;
        tree.nodes[slot].left_or_first = values[index];
        tree.nodes[slot].count = 1u;
    } else {
        node_slots[params.count + index] = slot;
        parents[params.count + index] = parent;
        tree.nodes[slot].left_or_first = 2u * index + 1u;
        tree.nodes[slot].count = 0u;
    }
}

// One invocation per internal node i: finds the range of sorted leaves it covers and where the
// range splits (Karras 2012, figure 4).
@compute @workgroup_size(256)
fn emit_hierarchy(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let node = flat_invocation(group, groups, local);
    if node + 1u >= params.count {
        return;
    }
    let i = i32(node);
    let direction = select(-1, 1, common_prefix(i, i + 1) > common_prefix(i, i - 1));
    let sibling_prefix = common_prefix(i, i - direction);
    var reach = 2;
    while common_prefix(i, i + reach * direction) > sibling_prefix {
        reach *= 2;
    }
    var length = 0;
    for (var step = reach / 2; step >= 1; step /= 2) {
        if common_prefix(i, i + (length + step) * direction) > sibling_prefix {
            length += step;
        }
    }
    let other_end = i + length * direction;
    let node_prefix = common_prefix(i, other_end);
    var split = 0;
    var step = length;
    loop {
        step = (step + 1) / 2;
        if common_prefix(i, i + (split + step) * direction) > node_prefix {
            split += step;
        }
        if step <= 1 {
            break;
        }
    }
    let left = i + split * direction + min(direction, 0);
    attach_child(node, 2u * node + 1u, u32(left), min(i, other_end) == left);
    attach_child(node, 2u * node + 2u, u32(left + 1), max(i, other_end) == left + 1);
    if node == 0u {
        node_slots[params.count] = 0u;
        tree.nodes[0].left_or_first = 1u;
        tree.nodes[0].count = 0u;
    }
}

// The padded box of the hit point's sphere, as `sphere_box` in src/passes/hit_points.rs computes
// it (same f32 operations, so the same box), or the empty box without a hit point.
fn leaf_box(slot: u32) -> Box {
    if !has_hit_point(slot) {
        return Box(vec3<f32>(FAR), vec3<f32>(-FAR));
    }
    let centre = hit_points.points[slot].position;
    let radius = hit_points.points[slot].radius * (1.0f + 1e-5f);
    return Box(centre - radius, centre + radius);
}

fn store_box(slot: u32, b: Box) {
    atomicStore(&tree.nodes[slot].lo[0], bitcast<u32>(b.lo.x));
    atomicStore(&tree.nodes[slot].lo[1], bitcast<u32>(b.lo.y));
    atomicStore(&tree.nodes[slot].lo[2], bitcast<u32>(b.lo.z));
    atomicStore(&tree.nodes[slot].hi[0], bitcast<u32>(b.hi.x));
    atomicStore(&tree.nodes[slot].hi[1], bitcast<u32>(b.hi.y));
    atomicStore(&tree.nodes[slot].hi[2], bitcast<u32>(b.hi.z));
}

// f32 bits to a u32 with the same order (for all but NaNs; -0 sorts below +0): negatives have
// the sign bit set and compare reversed as magnitudes, so all their bits flip; non-negatives
// only get the sign bit, which puts them above every negative. Unsigned atomicMin/atomicMax on
// these words are then min/max of the floats, which WGSL has no atomics for.
fn ordered_bits(x: f32) -> u32 {
    let bits = bitcast<u32>(x);
    return select(bits | 0x80000000u, ~bits, (bits & 0x80000000u) != 0u);
}

fn from_ordered_bits(word: u32) -> f32 {
    return bitcast<f32>(select(~word, word & 0x7fffffffu, (word & 0x80000000u) != 0u));
}

// The slot of internal node i (the root, internal node 0, is slot 0).
fn internal_slot(node: u32) -> u32 {
    return node_slots[params.count + node];
}

// One invocation per internal node: the empty box in ordered bits, which every union starts
// from. Its own dispatch, because WebGPU orders whole dispatches (every store of one is
// visible to the next) and nothing finer across workgroups.
@compute @workgroup_size(256)
fn reset_bounds(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let node = flat_invocation(group, groups, local);
    if node + 1u >= params.count {
        return;
    }
    let slot = internal_slot(node);
    let lo = ordered_bits(FAR);
    let hi = ordered_bits(-FAR);
    for (var a = 0u; a < 3u; a++) {
        atomicStore(&tree.nodes[slot].lo[a], lo);
        atomicStore(&tree.nodes[slot].hi[a], hi);
    }
}

// One invocation per leaf: writes the leaf's box (as f32; nothing else writes a leaf), then
// climbs towards the root, folding the box into each ancestor's ordered words with atomicMin
// on the 3 lo words and atomicMax on the 3 hi words.
//
// Why this is exact under WGSL's memory model, where atomics are relaxed and one invocation's
// accesses to different words may be seen in any order by another: no invocation reads a value
// another one wrote, except through a read-modify-write. The RMWs on one word are totally
// ordered (the word's modification order) and each reads the value the previous one left, so a
// word ends as the min (max) of its reset value and the operands of all RMWs on it, whatever
// the interleaving. Every operand is the box of a leaf below the node, so what remains to show is that
// every valid leaf below it is bounded by the reset value or some operand, despite the early
// stop: an invocation stops climbing at the first node where none of its 6 RMWs changed its
// word (each read a value at least as tight as its operand).
//
// Claim, per word w and internal node N: for each valid leaf L below N, the reset value or
// the operand of some RMW on N.w is at least as tight as L.w. At L's parent, L's own RMW is
// one. From N to its parent P: if the reset value is at least as tight as L.w, it is P's
// reset value too. Otherwise let m be the tightest operand on N.w (at least as tight as L.w
// by the claim, tighter than the reset value) and R the first RMW in N.w's modification order
// with operand m. The reset value and every earlier operand are looser than m, so R read a
// looser value and changed N.w, so R's invocation did not stop at N: it made an RMW with
// operand m on P.w. So the early stop only drops operands that another invocation carries on,
// and after the dispatch each word is exactly the min (max) over the reset value and the
// valid leaves below it.
//
// Leaves without a hit point carry the reset values themselves (the empty box), which change
// nothing, so they do not climb. No invocation waits for another, so nothing rests on
// forward progress between workgroups either.
@compute @workgroup_size(256)
fn refit(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let leaf = flat_invocation(group, groups, local);
    if leaf >= params.count {
        return;
    }
    if params.count == 1u {
        // A single leaf is the root; there is no hierarchy to emit.
        tree.nodes[0].left_or_first = 0u;
        tree.nodes[0].count = 1u;
        store_box(0u, leaf_box(0u));
        return;
    }
    let slot = values[leaf];
    let b = leaf_box(slot);
    store_box(node_slots[leaf], b);
    if !has_hit_point(slot) {
        return;
    }
    let lo = vec3<u32>(ordered_bits(b.lo.x), ordered_bits(b.lo.y), ordered_bits(b.lo.z));
    let hi = vec3<u32>(ordered_bits(b.hi.x), ordered_bits(b.hi.y), ordered_bits(b.hi.z));
    var node = parents[leaf];
    loop {
        let at = internal_slot(node);
        var changed = false;
        for (var a = 0u; a < 3u; a++) {
            changed = changed | (atomicMin(&tree.nodes[at].lo[a], lo[a]) > lo[a]);
            changed = changed | (atomicMax(&tree.nodes[at].hi[a], hi[a]) < hi[a]);
        }
        if !changed || node == 0u {
            return;
        }
        node = parents[params.count + node];
    }
}

// One invocation per internal node, in its own dispatch after refit (so after all its RMWs):
// the ordered words back to f32, the layout the gather reads.
@compute @workgroup_size(256)
fn finish_bounds(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let node = flat_invocation(group, groups, local);
    if node + 1u >= params.count {
        return;
    }
    let slot = internal_slot(node);
    for (var a = 0u; a < 3u; a++) {
        let lo = from_ordered_bits(atomicLoad(&tree.nodes[slot].lo[a]));
        let hi = from_ordered_bits(atomicLoad(&tree.nodes[slot].hi[a]));
        atomicStore(&tree.nodes[slot].lo[a], bitcast<u32>(lo));
        atomicStore(&tree.nodes[slot].hi[a], bitcast<u32>(hi));
    }
}
