// Combines the path-traced image (sum and count per pixel) with the photon-mapped radiance into
// the final image, and writes a debug view of each pixel's first hit-point radius.

#import common::hit_points::HitPointBuffer

struct ResolveUniform {
    width: u32,
    height: u32,
    has_caustic: u32,
    has_hit_points: u32,
}

@group(1) @binding(0) var<uniform> params: ResolveUniform;
@group(1) @binding(1) var<storage, read> pt: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read> caustic: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read> hit_points: HitPointBuffer;
@group(1) @binding(4) var<storage, read_write> combined: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> radius: array<vec4<f32>>;

// The weighted sum over its weight; a pixel filter with negative lobes can leave a pixel's
// weight below 0 after few samples, which is still a weight (0 is none).
fn mean_of(sum: vec4<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), sum.xyz / sum.w, sum.w != 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let pixel = id.y * params.width + id.x;
    var value = mean_of(pt[pixel]);
    if params.has_caustic != 0u {
        value += mean_of(caustic[pixel]);
    }
    combined[pixel] = vec4<f32>(value, 1.0);
    var r = 0.0;
    let slots = hit_points.header.slots_per_pixel;
    if params.has_hit_points != 0u && slots > 0u {
        r = hit_points.points[pixel * slots].radius;
    }
    radius[pixel] = vec4<f32>(r, r, r, 1.0);
}
