// Least-significant-digit radix sort of (key, value) u32 pairs, 4 bits per pass (driven by
// src/gpu/radix_sort.rs). Each pass runs three kernels over blocks of BLOCK pairs, each
// invocation owning KEYS_PER_INVOCATION consecutive pairs of its block:
//   count_digits:   per-block digit histogram, stored digit-major (all blocks of digit 0, then
//                   digit 1, ...), so that one exclusive scan of it gives every block the first
//                   output position of each digit;
//   scan_histogram: that exclusive scan, by one workgroup looping over the histogram, which is
//                   short (16 words per 4096 pairs);
//   scatter:        each invocation counts the digits of its own pairs, a workgroup scan of those
//                   counts gives it, per digit, how many pairs of the block come before its own,
//                   and it writes its pairs in order: stable without subgroup operations.
// Only 32-bit atomics and workgroup barriers are used, so it runs on every backend. Many pairs per
// invocation keep barriers few: on CPU drivers (lavapipe) each barrier switches through every
// invocation of the workgroup, and with one pair per invocation barriers dominated (4x slower).

#import gpu::dispatch::{WORKGROUP_SIZE, flat_workgroup}

const RADIX: u32 = 16u;
const KEYS_PER_INVOCATION: u32 = 16u;
const BLOCK: u32 = 4096u;
// Two digits' counts share a word (16 bits each: a block has at most 4096 pairs of a digit).
const PACKED_WORDS: u32 = 8u;
// Histogram words the scan handles per round: ROUNDS per invocation.
const ROUNDS: u32 = 4u;
const SCAN_CHUNK: u32 = 1024u;

struct SortParams {
    // Pairs to sort.
    count: u32,
    // Bit position of this pass's digit.
    shift: u32,
    // ceil(count / BLOCK)
    blocks: u32,
    pad_a: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;
@group(0) @binding(1) var<storage, read> src_keys: array<u32>;
@group(0) @binding(2) var<storage, read> src_values: array<u32>;
@group(0) @binding(3) var<storage, read_write> dst_keys: array<u32>;
@group(0) @binding(4) var<storage, read_write> dst_values: array<u32>;
@group(0) @binding(5) var<storage, read_write> histogram: array<u32>;

var<workgroup> digit_counts: array<atomic<u32>, RADIX>;
var<workgroup> scan_partial: array<u32, WORKGROUP_SIZE>;
// Per invocation, its digit counts packed two to a word; scanned in place.
var<workgroup> packed_counts: array<array<u32, PACKED_WORDS>, WORKGROUP_SIZE>;

fn digit_of(key: u32) -> u32 {
    return (key >> params.shift) & (RADIX - 1u);
}

// Index of the first pair invocation `local` owns in `block`.
fn first_pair(block: u32, local: u32) -> u32 {
    return block * BLOCK + local * KEYS_PER_INVOCATION;
}

@compute @workgroup_size(256)
fn count_digits(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let block = flat_workgroup(group, groups);
    if block >= params.blocks {
        return;
    }
    if local < RADIX {
        atomicStore(&digit_counts[local], 0u);
    }
    workgroupBarrier();
    let first = first_pair(block, local);
    let end = min(first + KEYS_PER_INVOCATION, params.count);
    for (var index = first; index < end; index++) {
        atomicAdd(&digit_counts[digit_of(src_keys[index])], 1u);
    }
    workgroupBarrier();
    if local < RADIX {
        histogram[local * params.blocks + block] = atomicLoad(&digit_counts[local]);
    }
}

// Inclusive prefix sum of `scan_partial` across the workgroup (Hillis & Steele).
fn scan_workgroup(local: u32) {
    for (var offset = 1u; offset < WORKGROUP_SIZE; offset <<= 1u) {
        var added = 0u;
        if local >= offset {
            added = scan_partial[local - offset];
        }
        workgroupBarrier();
        scan_partial[local] += added;
        workgroupBarrier();
    }
}

// Dispatched as a single workgroup: chunks of SCAN_CHUNK words, each invocation owning ROUNDS
// consecutive words, with the running total carried from chunk to chunk.
@compute @workgroup_size(256)
fn scan_histogram(@builtin(local_invocation_index) local: u32) {
    let total = params.blocks * RADIX;
    var carried = 0u;
    for (var start = 0u; start < total; start += SCAN_CHUNK) {
        let first = start + local * ROUNDS;
        var words: array<u32, ROUNDS>;
        var own_sum = 0u;
        for (var k = 0u; k < ROUNDS; k++) {
            if first + k < total {
                words[k] = histogram[first + k];
            }
            own_sum += words[k];
        }
        scan_partial[local] = own_sum;
        workgroupBarrier();
        scan_workgroup(local);
        var running = carried + scan_partial[local] - own_sum;
        for (var k = 0u; k < ROUNDS; k++) {
            if first + k < total {
                histogram[first + k] = running;
            }
            running += words[k];
        }
        carried += scan_partial[WORKGROUP_SIZE - 1u];
        // Every invocation has read the chunk total before the next chunk overwrites it.
        workgroupBarrier();
    }
}

// Inclusive prefix sum of every invocation's packed counts (Hillis & Steele). Packed lanes
// never carry into each other: a digit's count in a block is at most BLOCK < 2^16.
fn scan_packed_counts(local: u32) {
    for (var offset = 1u; offset < WORKGROUP_SIZE; offset <<= 1u) {
        var added: array<u32, PACKED_WORDS>;
        if local >= offset {
            added = packed_counts[local - offset];
        }
        workgroupBarrier();
        for (var w = 0u; w < PACKED_WORDS; w++) {
            packed_counts[local][w] += added[w];
        }
        workgroupBarrier();
    }
}

fn unpack_count(words: array<u32, PACKED_WORDS>, digit: u32) -> u32 {
    return (words[digit / 2u] >> (16u * (digit % 2u))) & 0xffffu;
}

@compute @workgroup_size(256)
fn scatter(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let block = flat_workgroup(group, groups);
    if block >= params.blocks {
        return;
    }
    let first = first_pair(block, local);
    let end = min(first + KEYS_PER_INVOCATION, params.count);
    var own: array<u32, PACKED_WORDS>;
    for (var index = first; index < end; index++) {
        let digit = digit_of(src_keys[index]);
        own[digit / 2u] += 1u << (16u * (digit % 2u));
    }
    packed_counts[local] = own;
    workgroupBarrier();
    scan_packed_counts(local);
    // Exclusive: the pairs of each digit owned by earlier invocations of the block.
    var before = packed_counts[local];
    for (var w = 0u; w < PACKED_WORDS; w++) {
        before[w] -= own[w];
    }
    var written: array<u32, RADIX>;
    for (var index = first; index < end; index++) {
        let key = src_keys[index];
        let digit = digit_of(key);
        let position = histogram[digit * params.blocks + block] + unpack_count(before, digit)
            + written[digit];
        written[digit] += 1u;
        dst_keys[position] = key;
        dst_values[position] = src_values[index];
    }
}
