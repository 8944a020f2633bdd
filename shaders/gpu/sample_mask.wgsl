#define_import_path gpu::sample_mask

// Adaptive sampling's per-pixel flags (src/gpu/sample_mask.rs): which pixels the camera
// samples this iteration, and which pixels' images may change (those within a splatting pixel
// filter's reach of a sampled one). A pixel whose image does not change also keeps its halves
// for the error estimate as they are (shaders/gpu/odd_iterations.wgsl).

struct SampleMask {
    // 0: every pixel is sampled and updated, and `words` is not read.
    enabled: u32,
    // How many pixels are sampled.
    sampled: u32,
    pad_a: u32,
    pad_b: u32,
    // Each pixel's flags, then the sampled pixels' indices in increasing order (`sampled` of
    // them): camera invocations take those in turn, so skipped pixels leave no lane idle.
    words: array<u32>,
}

const SAMPLED: u32 = 1u;
const UPDATED: u32 = 2u;
