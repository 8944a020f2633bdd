// Probabilistic progressive photon mapping (Knaus & Zwicker 2011): each iteration is an
// independent density estimate at this iteration's hit points, with the radius the global
// schedule gives this iteration; the caustic image is the mean of the estimates. One
// invocation per pixel adds its estimate (summed over its hit-point slots) and a count of 1 to
// the pixel's running sum, so renders of disjoint iterations add up to one render's sums.

#import common::sampling::{PI, any_not_finite}
#import common::hit_points::{HitPointBuffer, RadiusBuffer, NO_PIXEL}
#import common::deposit_sums::{deposited_flux, inner_flux, deposit_count}

struct PppmUniform {
    width: u32,
    height: u32,
    slots_per_pixel: u32,
    // The schedule's radius factor for the next iteration this render runs.
    next_scale: f32,
}

@group(1) @binding(0) var<uniform> params: PppmUniform;
@group(1) @binding(1) var<storage, read> hit_points: HitPointBuffer;
// Binding 2: the deposits (common::deposit_sums).
@group(1) @binding(3) var<storage, read_write> radiance: array<vec4<f32>>;
// Only the rule is used: its scale is the schedule, its radii stay 0, so the camera pass gives
// every hit point the rule's radius for its footprint.
@group(1) @binding(4) var<storage, read_write> radii: RadiusBuffer;
// Pixel estimates dropped as NaN or Inf.
@group(1) @binding(5) var<storage, read_write> discarded: atomic<u32>;
// Per pixel the sum of each estimate's kernel bias, (4/3) (L(R) - L(R/2)), and their count.
@group(1) @binding(6) var<storage, read_write> kernel_bias: array<vec4<f32>>;

// This iteration's density estimates at slot `index`, over the disc and over half its radius:
// flux per emitted photon over the area.
struct SlotEstimate {
    whole: vec3<f32>,
    inner: vec3<f32>,
}

fn slot_estimate(index: u32) -> SlotEstimate {
    let point = hit_points.points[index];
    if point.pixel == NO_PIXEL || point.radius <= 0.0 || deposit_count(index) == 0u {
        return SlotEstimate(vec3<f32>(0.0), vec3<f32>(0.0));
    }
    let area = PI * point.radius * point.radius;
    return SlotEstimate(deposited_flux(index) / area, 4.0 * inner_flux(index) / area);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let pixel = id.y * params.width + id.x;
    if pixel == 0u {
        // Read by the camera pass of the next iteration, which runs after this dispatch.
        radii.rule.scale = params.next_scale;
    }
    var estimate = vec3<f32>(0.0);
    var inner = vec3<f32>(0.0);
    for (var slot = 0u; slot < params.slots_per_pixel; slot++) {
        let e = slot_estimate(pixel * params.slots_per_pixel + slot);
        estimate += e.whole;
        inner += e.inner;
    }
    let total = radiance[pixel] + vec4<f32>(estimate, 1.0);
    let bias = kernel_bias[pixel] + vec4<f32>((4.0 / 3.0) * (estimate - inner), 1.0);
    if any_not_finite(total.xyz) || any_not_finite(bias.xyz) {
        atomicAdd(&discarded, 1u);
    } else {
        radiance[pixel] = total;
        kernel_bias[pixel] = bias;
    }
}
