// The tonemap pass: each pixel's mean radiance times 2^exposure, through a tone curve. The
// output holds the mapped value with a weight of 1 (it is a display image, not a sum).

#import custom::tone_curves::tone_curve

struct TonemapUniform {
    width: u32,
    height: u32,
    curve: u32,
    scale: f32,
}

@group(0) @binding(0) var<uniform> params: TonemapUniform;
@group(0) @binding(1) var<storage, read> image: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> mapped: array<vec4<f32>>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let pixel = id.y * params.width + id.x;
    let sum = image[pixel];
    let mean = select(vec3<f32>(0.0), sum.xyz / sum.w, sum.w != 0.0);
    mapped[pixel] = vec4<f32>(tone_curve(params.curve, mean * params.scale), 1.0);
}
