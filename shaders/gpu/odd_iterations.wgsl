// Splits a running-mean image into two independent halves: after a pixel's update c (its
// c-th iteration, 1-based) of a render whose image is the mean of per-iteration estimates,
// that update's estimate is c m_c - (c - 1) m_(c-1); the estimates of the pixel's odd updates
// are summed. The even half is the rest of c m_c (src/app/error_estimate.rs turns the halves
// into a variance). Without adaptive sampling every pixel is updated every iteration, so c is
// the render's iteration count; with it, a pixel the mask leaves alone keeps its count and
// halves (gpu::sample_mask).

#import gpu::dispatch::flat_invocation
#import gpu::sample_mask::{SampleMask, UPDATED}

struct SplitParams {
    pixels: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

@group(0) @binding(0) var<uniform> params: SplitParams;
// The image as its node keeps it: per pixel a weighted sum and its weight.
@group(0) @binding(1) var<storage, read> image: array<vec4<f32>>;
// Its mean after the pixel's previous update.
@group(0) @binding(2) var<storage, read_write> previous: array<vec4<f32>>;
// xyz: the sum of the odd updates' estimates; w: the pixel's updates so far.
@group(0) @binding(3) var<storage, read_write> odd_sum: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> mask: SampleMask;

fn mean_of(sum: vec4<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), sum.xyz / sum.w, sum.w != 0.0);
}

@compute @workgroup_size(256, 1, 1)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let pixel = flat_invocation(group, groups, local);
    if pixel >= params.pixels {
        return;
    }
    if mask.enabled != 0u && (mask.words[pixel] & UPDATED) == 0u {
        return;
    }
    let mean = mean_of(image[pixel]);
    var halves = odd_sum[pixel];
    let count = halves.w + 1.0;
    if (u32(count) & 1u) == 1u {
        halves += vec4<f32>(count * mean - (count - 1.0) * previous[pixel].xyz, 0.0);
    }
    halves.w = count;
    odd_sum[pixel] = halves;
    previous[pixel] = vec4<f32>(mean, 1.0);
}
