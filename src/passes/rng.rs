//! The CPU twin of `shaders/common/rng.wgsl`: the same streams, draw for draw, so tests can
//! replay a kernel's random numbers and check that streams keyed by global indices never meet.

/// 4D PCG hash (Jarzynski & Olano 2020, "Hash Functions for GPU Rendering"), as `pcg4d` in
/// rng.wgsl. A bijection of 128 bits: every step is invertible ([`pcg4d_inverse`]).
pub fn pcg4d(input: [u32; 4]) -> [u32; 4] {
    let mut v = input.map(|x| x.wrapping_mul(1664525).wrapping_add(1013904223));
    mix(&mut v);
    for x in &mut v {
        *x ^= *x >> 16;
    }
    mix(&mut v);
    v
}

fn mix(v: &mut [u32; 4]) {
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
}

fn unmix(v: &mut [u32; 4]) {
    v[3] = v[3].wrapping_sub(v[1].wrapping_mul(v[2]));
    v[2] = v[2].wrapping_sub(v[0].wrapping_mul(v[1]));
    v[1] = v[1].wrapping_sub(v[2].wrapping_mul(v[0]));
    v[0] = v[0].wrapping_sub(v[1].wrapping_mul(v[3]));
}

/// The inverse of [`pcg4d`]: its existence is the proof that distinct keys give distinct draws.
pub fn pcg4d_inverse(output: [u32; 4]) -> [u32; 4] {
    // 1664525 is odd, so it has an inverse modulo 2^32 (Newton's iteration doubles the correct
    // low bits each step: 3 -> 6 -> 12 -> 24 -> 48).
    const A: u32 = 1664525;
    let mut a_inv = A;
    for _ in 0..4 {
        a_inv = a_inv.wrapping_mul(2u32.wrapping_sub(A.wrapping_mul(a_inv)));
    }
    let mut v = output;
    unmix(&mut v);
    for x in &mut v {
        // x ^ (x >> 16) leaves the top half alone, from which the bottom half follows.
        *x ^= *x >> 16;
    }
    unmix(&mut v);
    v.map(|x| x.wrapping_sub(1013904223).wrapping_mul(a_inv))
}

/// One random stream: `rng_stream` and the `rng_next_*` functions of rng.wgsl.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stream {
    state: [u32; 4],
}

impl Stream {
    /// The stream keyed by an element index (pixel, photon), a global sequence number (sample,
    /// iteration) and the kernel's seed word.
    pub fn new(index: u32, sequence: u32, seed: u32) -> Self {
        Self {
            state: [index, sequence, seed, 0],
        }
    }

    pub fn next_u32(&mut self) -> u32 {
        let word = pcg4d(self.state)[0];
        self.state[3] = self.state[3].wrapping_add(1);
        word
    }

    /// Uniform in [0, 1) from the top 24 bits, as `rng_next_f32`.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16777216.0)
    }
}

/// The seed word the camera pass hashes for a render's 64-bit seed.
pub fn camera_seed(seed: u64) -> u32 {
    super::seed32(seed)
}

/// Decorrelates photon random streams from camera streams that share the seed.
pub const PHOTON_STREAM: u32 = 0x9e37_79b9;

/// The seed word the photon pass hashes for a render's 64-bit seed.
pub fn photon_seed(seed: u64) -> u32 {
    super::seed32(seed) ^ PHOTON_STREAM
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    /// A seeded generator for the test's keys (not the one under test).
    fn splitmix(state: &mut u64) -> u64 {
        *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// pcg4d is a bijection: the inverse undoes it on random and edge inputs. Would catch a
    /// change to the hash that lets two keys share a draw (a non-invertible step).
    #[test]
    fn pcg4d_is_invertible() {
        let mut s = 1u64;
        let mut inputs = vec![[0; 4], [u32::MAX; 4], [1, 0, 0, 0], [0, 0, 0, 1]];
        for _ in 0..100_000 {
            let a = splitmix(&mut s);
            let b = splitmix(&mut s);
            inputs.push([a as u32, (a >> 32) as u32, b as u32, (b >> 32) as u32]);
        }
        for input in inputs {
            assert_eq!(pcg4d_inverse(pcg4d(input)), input, "{input:?}");
        }
    }

    /// The photon seed the shaders used before streams were keyed by global indices:
    /// pcg(index ^ pcg(iteration ^ pcg(seed))), one 32-bit word.
    fn old_photon_seed(index: u32, iteration: u32, seed: u32) -> u32 {
        fn pcg(input: u32) -> u32 {
            let state = input.wrapping_mul(747796405).wrapping_add(2891336453);
            let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
            (word >> 22) ^ word
        }
        pcg(index ^ pcg(iteration ^ pcg(seed)))
    }

    /// No two photon streams of a long render share their first draws: 2^21 (iteration, photon)
    /// keys drawn from 10^5 iterations of 2^20 photons, plus whole iterations side by side, give
    /// distinct first 64 bits. The same keys under the old 32-bit seed collide (thousands of
    /// times, as the birthday bound says), so this would catch a return to a 32-bit state.
    #[test]
    fn photon_streams_do_not_collide_over_a_long_render() {
        const ITERATIONS: u64 = 100_000;
        const PHOTONS: u64 = 1 << 20;
        let seed = photon_seed(7);
        let mut keys: Vec<(u32, u32)> = Vec::new();
        let mut s = 3u64;
        for _ in 0..(1 << 21) {
            let r = splitmix(&mut s);
            keys.push(((r % PHOTONS) as u32, ((r >> 32) % ITERATIONS) as u32));
        }
        // Two whole iterations far apart: the old seed made index ^ H(i) = index' ^ H(j) pairs.
        for index in 0..PHOTONS as u32 {
            keys.push((index, 0));
            keys.push((index, 99_999));
        }
        keys.sort_unstable();
        keys.dedup();
        let mut firsts = HashSet::with_capacity(keys.len());
        let mut old = HashSet::with_capacity(keys.len());
        let mut old_collisions = 0u64;
        for &(index, iteration) in &keys {
            let mut stream = Stream::new(index, iteration, seed);
            let first = (stream.next_u32() as u64) << 32 | stream.next_u32() as u64;
            assert!(
                firsts.insert(first),
                "photon {index} of iteration {iteration} repeats another stream's first draws"
            );
            if !old.insert(old_photon_seed(index, iteration, seed)) {
                old_collisions += 1;
            }
        }
        assert!(
            old_collisions > 1000,
            "the old seeding collided only {old_collisions} times: the test keys are too few"
        );
    }

    /// A camera and a photon stream with equal indices differ (the seed words differ), so the
    /// photons of iteration i do not replay the camera paths of sample i.
    #[test]
    fn camera_and_photon_streams_differ() {
        for (pixel, sample) in [(0, 0), (5, 9), (1 << 20, 4095)] {
            let mut camera = Stream::new(pixel, sample, camera_seed(7));
            let mut photon = Stream::new(pixel, sample, photon_seed(7));
            assert_ne!(camera.next_u32(), photon.next_u32());
        }
    }
}
