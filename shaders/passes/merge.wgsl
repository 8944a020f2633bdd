// Progressive photon mapping's per-hit-point update (Hachisuka et al. 2008; SPPM, Hachisuka &
// Jensen 2009), one invocation per pixel over its hit-point slots:
//   N' = N + alpha M,  R' = R sqrt((N + alpha M) / (N + M)),  tau' = (tau + Phi) R'^2 / R^2,
// and the pixel's photon-mapped radiance sum over slots of tau / (pi R^2 N_emitted). Deposits are
// flux per photon of one iteration, so N_emitted is the iteration count.
//
// Over 10^5 iterations the literal recursions drift in f32 (by 1e-3 measured: N' gains a rounded
// alpha M every step, tau is rescaled by a rounded ratio near 1). So the state is kept in forms
// with no accumulated rounding: N = alpha * (exact photon total); tau / R^2 = sum of Phi_i / R_i^2
// (the recursion unrolled), so the estimate tau / (pi R^2) needs no rescaling; and R shrinks by
// R (1 - sqrt(1 - x)) computed as R x / (1 + sqrt(1 - x)), which has no cancellation.
//
// The same sum over the photons within R / 2 gives the estimate at half the radius, and with it
// the kernel's bias, (4/3) (L(R) - L(R/2)) per iteration (docs/error-estimate.md): written to
// `kernel_bias` as the mean over iterations, as the radiance is.

#import common::sampling::{PI, any_not_finite}
#import common::hit_points::{HitPointBuffer, RadiusBuffer, NO_PIXEL}
#import common::deposit_sums::{deposited_flux, inner_flux, deposit_count}

struct MergeUniform {
    alpha: f32,
    // 1 / iterations so far (including this one).
    inv_iterations: f32,
    slots_per_pixel: u32,
    width: u32,
    height: u32,
    // 1.0, from the CPU: see the compensated sum below.
    one: f32,
    pad_b: u32,
    pad_c: u32,
}

struct SlotStats {
    // tau / R^2 (see the header).
    tau_per_r2: vec3<f32>,
    // Photon count of the progressive estimate, alpha * photons (for reports; never accumulated).
    n: f32,
    // What the last additions to tau_per_r2 lost to rounding (Kahan's compensation).
    tau_carry: vec3<f32>,
    // Iterations whose deposit was dropped as NaN/Inf.
    discarded: u32,
    // Sum of the estimates at half the radius, 4 Phi_inner_i / R_i^2 (pi L(R/2) per iteration).
    inner_per_r2: vec3<f32>,
    // Photons gathered in total, exact as a 64-bit count.
    photons_low: u32,
    photons_high: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

@group(1) @binding(0) var<uniform> params: MergeUniform;
@group(1) @binding(1) var<storage, read> hit_points: HitPointBuffer;
// Binding 2: the deposits (common::deposit_sums).
@group(1) @binding(3) var<storage, read_write> stats: array<SlotStats>;
@group(1) @binding(4) var<storage, read_write> radiance: array<vec4<f32>>;
// This estimator's state: each slot's radius (0 until the slot first holds a hit point), read
// by the camera pass in the next iteration.
@group(1) @binding(5) var<storage, read_write> radii: RadiusBuffer;
@group(1) @binding(6) var<storage, read_write> kernel_bias: array<vec4<f32>>;

// pi times a slot's estimates summed over iterations, at its radius and at half of it.
struct SlotSums {
    whole: vec3<f32>,
    inner: vec3<f32>,
}

// Applies this iteration's deposit to slot `index`; returns its sums over iterations.
fn merge_slot(index: u32) -> SlotSums {
    var radius = radii.radii[index];
    if radius <= 0.0 {
        // A slot's first hit point brings the first radius the camera chose by the rule.
        if hit_points.points[index].pixel == NO_PIXEL || hit_points.points[index].radius <= 0.0 {
            return SlotSums(vec3<f32>(0.0), vec3<f32>(0.0));
        }
        radius = hit_points.points[index].radius;
        radii.radii[index] = radius;
    }
    var s = stats[index];
    let m = deposit_count(index);
    let phi = deposited_flux(index);
    let phi_inner = inner_flux(index);
    if m > 0u {
        if any_not_finite(phi) || any_not_finite(phi_inner) {
            s.discarded += 1u;
        } else {
            let mf = f32(m);
            let n = params.alpha * photon_total(s);
            // 1 - (N + alpha M) / (N + M), accurate when N >> M.
            let x = (1.0 - params.alpha) * mf / (n + mf);
            let shrink = radius * x / (1.0 + sqrt(1.0 - x));
            radii.radii[index] = max(radius - shrink, radii.rule.min_radius);
            // A compensated sum: once the radius sits on its floor the same term is added every
            // iteration, and a plain f32 sum drifts by about iterations x 2^-24 (4.4e-4 after
            // 10^5 measured); Kahan's keeps the error near one rounding (Higham 2002, 4.3).
            // Shader compilers treat float arithmetic as real arithmetic and fold
            // (tau + y) - tau - y to 0 (Mesa's NIR did: the drift stayed 4.4e-4); multiplying
            // by `one`, a uniform they cannot know is 1, keeps the compensation.
            let term = phi / (radius * radius) - s.tau_carry;
            let sum = s.tau_per_r2 + term;
            s.tau_carry = (sum - s.tau_per_r2 * params.one) - term;
            s.tau_per_r2 = sum;
            s.inner_per_r2 += 4.0 * phi_inner / (radius * radius);
            let low = s.photons_low + m;
            s.photons_high += select(0u, 1u, low < m);
            s.photons_low = low;
            s.n = params.alpha * photon_total(s);
        }
        stats[index] = s;
    }
    return SlotSums(s.tau_per_r2, s.inner_per_r2);
}

fn photon_total(s: SlotStats) -> f32 {
    return f32(s.photons_high) * 4294967296.0 + f32(s.photons_low);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let pixel = id.y * params.width + id.x;
    var whole = vec3<f32>(0.0);
    var inner = vec3<f32>(0.0);
    for (var slot = 0u; slot < params.slots_per_pixel; slot++) {
        let sums = merge_slot(pixel * params.slots_per_pixel + slot);
        whole += sums.whole;
        inner += sums.inner;
    }
    let mean = params.inv_iterations / PI;
    radiance[pixel] = vec4<f32>(whole * mean, 1.0);
    kernel_bias[pixel] = vec4<f32>((4.0 / 3.0) * (whole - inner) * mean, 1.0);
}
