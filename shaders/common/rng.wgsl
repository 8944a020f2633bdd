#define_import_path common::rng

// PCG-style hash (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering"): a stateless
// stream per (pixel, sample, seed), so results do not depend on dispatch order.
fn pcg_hash(input: u32) -> u32 {
    let state = input * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Seeds a stream from three words; each is hashed in so nearby indices decorrelate.
fn rng_seed(a: u32, b: u32, c: u32) -> u32 {
    return pcg_hash(a ^ pcg_hash(b ^ pcg_hash(c)));
}

fn rng_next_u32(state: ptr<function, u32>) -> u32 {
    *state = *state * 747796405u + 2891336453u;
    let s = *state;
    let word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform in [0, 1): the top 24 bits, so 1.0 is never returned.
fn rng_next_f32(state: ptr<function, u32>) -> f32 {
    return f32(rng_next_u32(state) >> 8u) * (1.0 / 16777216.0);
}

fn rng_next_vec2(state: ptr<function, u32>) -> vec2<f32> {
    let x = rng_next_f32(state);
    let y = rng_next_f32(state);
    return vec2<f32>(x, y);
}
