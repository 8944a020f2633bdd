// Splits a running-mean image into two independent halves: after iteration N (1-based) of a
// render whose image is the mean of per-iteration estimates, this iteration's estimate is
// N m_N - (N - 1) m_(N-1); the odd iterations' estimates are summed. The even half is the rest
// of N m_N (src/app/error_estimate.rs turns the halves into a variance).

#import gpu::dispatch::flat_invocation

struct SplitParams {
    pixels: u32,
    // 1 when this iteration is odd.
    odd: u32,
    // N and N - 1.
    count: f32,
    previous_count: f32,
}

@group(0) @binding(0) var<uniform> params: SplitParams;
// The image as its node keeps it: per pixel a weighted sum and its weight.
@group(0) @binding(1) var<storage, read> image: array<vec4<f32>>;
// Its mean after the previous iteration.
@group(0) @binding(2) var<storage, read_write> previous: array<vec4<f32>>;
// The sum of the odd iterations' estimates (w: how many).
@group(0) @binding(3) var<storage, read_write> odd_sum: array<vec4<f32>>;

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
    let sum = image[pixel];
    let mean = select(vec3<f32>(0.0), sum.xyz / sum.w, sum.w != 0.0);
    if params.odd != 0u {
        let estimate = params.count * mean - params.previous_count * previous[pixel].xyz;
        odd_sum[pixel] += vec4<f32>(estimate, 1.0);
    }
    previous[pixel] = vec4<f32>(mean, 1.0);
}
