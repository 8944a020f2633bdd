#define_import_path common::rng

// Counter-based random streams. A stream is keyed by three words (an element index such as a
// pixel or photon, a global sequence number such as the sample or iteration index, and the
// seed); draw j of it is pcg4d(index, sequence, seed, j), the 4D PCG hash of Jarzynski & Olano
// 2020 ("Hash Functions for GPU Rendering"). pcg4d is a bijection of 128 bits, so two streams
// with different keys never share a draw: no 32-bit seed that 10^5 iterations of 2^20 photons
// would wrap (src/passes/rng.rs mirrors this on the CPU and tests it). Results do not depend
// on dispatch order, and a shard that renders iteration i draws what a single render does.

fn pcg4d(input: vec4<u32>) -> vec4<u32> {
    var v = input * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> vec4<u32>(16u);
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// The stream keyed (index, sequence, seed), before its first draw: the key in xyz, the draw
// counter in w.
fn rng_stream(index: u32, sequence: u32, seed: u32) -> vec4<u32> {
    return vec4<u32>(index, sequence, seed, 0u);
}

fn rng_next_u32(state: ptr<function, vec4<u32>>) -> u32 {
    let word = pcg4d(*state).x;
    (*state).w += 1u;
    return word;
}

// Uniform in [0, 1): the top 24 bits, so 1.0 is never returned.
fn rng_next_f32(state: ptr<function, vec4<u32>>) -> f32 {
    return f32(rng_next_u32(state) >> 8u) * (1.0 / 16777216.0);
}

fn rng_next_vec2(state: ptr<function, vec4<u32>>) -> vec2<f32> {
    let x = rng_next_f32(state);
    let y = rng_next_f32(state);
    return vec2<f32>(x, y);
}
