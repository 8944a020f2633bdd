// Least-significant-digit radix sort of (key, value) u32 pairs, 4 bits per pass (driven by
// src/gpu/radix_sort.rs). Each pass runs three kernels over blocks of BLOCK pairs:
//   count_digits:   per-block digit histogram, stored digit-major (all blocks of digit 0, then
//                   digit 1, ...), so that one exclusive scan of it gives every block the first
//                   output position of each digit;
//   scan_histogram: that exclusive scan, by one workgroup looping over the histogram, which is
//                   short (16 words per 1024 pairs, 156k words for 10M pairs);
//   scatter:        writes each pair to its digit's position plus its rank among the pairs of
//                   the same digit before it in the block. Ranks come from one bit per
//                   invocation in a per-digit mask and a population count of the bits below,
//                   which keeps the pass stable without subgroup operations.
// Only 32-bit workgroup atomics and barriers are used, so it runs on every backend.

#import common::dispatch::{WORKGROUP_SIZE, flat_workgroup}

const RADIX: u32 = 16u;
// Pairs per block: each invocation handles one pair per round.
const ROUNDS: u32 = 4u;
const BLOCK: u32 = 1024u;
// 32-bit words in one digit's mask of the WORKGROUP_SIZE invocations.
const MASK_WORDS: u32 = 8u;
const NO_DIGIT: u32 = 16u;

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
var<workgroup> digit_base: array<u32, RADIX>;
var<workgroup> digit_masks: array<atomic<u32>, 128>;

fn digit_of(key: u32) -> u32 {
    return (key >> params.shift) & (RADIX - 1u);
}

// Index of the pair that invocation `local` handles in `round` of `block`.
fn pair_index(block: u32, round: u32, local: u32) -> u32 {
    return block * BLOCK + round * WORKGROUP_SIZE + local;
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
    for (var round = 0u; round < ROUNDS; round++) {
        let index = pair_index(block, round, local);
        if index < params.count {
            atomicAdd(&digit_counts[digit_of(src_keys[index])], 1u);
        }
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

// Dispatched as a single workgroup: chunks of BLOCK words, each invocation owning ROUNDS
// consecutive words, with the running total carried from chunk to chunk.
@compute @workgroup_size(256)
fn scan_histogram(@builtin(local_invocation_index) local: u32) {
    let total = params.blocks * RADIX;
    var carried = 0u;
    for (var start = 0u; start < total; start += BLOCK) {
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

// How many invocations before `local` set their bit in digit `digit`'s mask.
fn rank_in_round(digit: u32, local: u32) -> u32 {
    let word = local / 32u;
    var rank = 0u;
    for (var w = 0u; w < word; w++) {
        rank += countOneBits(atomicLoad(&digit_masks[digit * MASK_WORDS + w]));
    }
    let below = (1u << (local % 32u)) - 1u;
    return rank + countOneBits(atomicLoad(&digit_masks[digit * MASK_WORDS + word]) & below);
}

fn count_in_round(digit: u32) -> u32 {
    var total = 0u;
    for (var w = 0u; w < MASK_WORDS; w++) {
        total += countOneBits(atomicLoad(&digit_masks[digit * MASK_WORDS + w]));
    }
    return total;
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
    if local < RADIX {
        digit_base[local] = histogram[local * params.blocks + block];
    }
    for (var round = 0u; round < ROUNDS; round++) {
        if local < RADIX * MASK_WORDS {
            atomicStore(&digit_masks[local], 0u);
        }
        workgroupBarrier();
        let index = pair_index(block, round, local);
        var key = 0u;
        var digit = NO_DIGIT;
        if index < params.count {
            key = src_keys[index];
            digit = digit_of(key);
            atomicOr(&digit_masks[digit * MASK_WORDS + local / 32u], 1u << (local % 32u));
        }
        workgroupBarrier();
        if digit != NO_DIGIT {
            let position = digit_base[digit] + rank_in_round(digit, local);
            dst_keys[position] = key;
            dst_values[position] = src_values[index];
        }
        workgroupBarrier();
        if local < RADIX {
            digit_base[local] += count_in_round(local);
        }
        workgroupBarrier();
    }
}
