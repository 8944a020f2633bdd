// Progressive photon mapping's per-hit-point update (Hachisuka et al. 2008; SPPM, Hachisuka &
// Jensen 2009), one invocation per pixel over its hit-point slots:
//   N' = N + alpha M,  R' = R sqrt((N + alpha M) / (N + M)),  tau' = (tau + Phi) R'^2 / R^2,
// and the pixel's photon-mapped radiance sum over slots of tau / (pi R^2 N_emitted). Deposits are
// flux per photon of one iteration, so N_emitted is the iteration count.

#import common::sampling::{PI, any_not_finite}
#import common::hit_points::{HitPointBuffer, DepositCell}

struct MergeParams {
    alpha: f32,
    // 1 / iterations so far (including this one).
    inv_iterations: f32,
    slots_per_pixel: u32,
    width: u32,
    height: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

struct SlotStats {
    tau: vec3<f32>,
    // Photon count of the progressive estimate (fractional: N' = N + alpha M).
    n: f32,
    // Photons gathered in total, exact as a 64-bit count.
    photons_low: u32,
    photons_high: u32,
    // Iterations whose deposit was dropped as NaN/Inf.
    discarded: u32,
    pad_a: u32,
}

@group(1) @binding(0) var<uniform> params: MergeParams;
@group(1) @binding(1) var<storage, read_write> hit_points: HitPointBuffer;
@group(1) @binding(2) var<storage, read_write> deposits: array<DepositCell>;
@group(1) @binding(3) var<storage, read_write> stats: array<SlotStats>;
@group(1) @binding(4) var<storage, read_write> radiance: array<vec4<f32>>;

fn deposited_flux(cell: u32) -> vec3<f32> {
#ifdef FLOAT_ATOMICS
    return vec3<f32>(atomicLoad(&deposits[cell].flux[0]), atomicLoad(&deposits[cell].flux[1]), atomicLoad(&deposits[cell].flux[2]));
#else
    return vec3<f32>(bitcast<f32>(atomicLoad(&deposits[cell].flux[0])), bitcast<f32>(atomicLoad(&deposits[cell].flux[1])), bitcast<f32>(atomicLoad(&deposits[cell].flux[2])));
#endif
}

// Applies this iteration's deposit to slot `index`; returns its current radiance estimate times
// the iteration count.
fn merge_slot(index: u32) -> vec3<f32> {
    let radius = hit_points.points[index].radius;
    if radius <= 0.0 {
        return vec3<f32>(0.0);
    }
    var s = stats[index];
    let m = atomicLoad(&deposits[index].count);
    let phi = deposited_flux(index);
    if m > 0u {
        if any_not_finite(phi) {
            s.discarded += 1u;
            stats[index] = s;
        } else {
            let mf = f32(m);
            // (N + alpha M) / (N + M), written so that it stays accurate when N >> M.
            let shrink = 1.0 - (1.0 - params.alpha) * mf / (s.n + mf);
            let new_radius = max(radius * sqrt(shrink), hit_points.header.min_radius);
            let area_ratio = (new_radius / radius) * (new_radius / radius);
            s.tau = (s.tau + phi) * area_ratio;
            s.n += params.alpha * mf;
            let low = s.photons_low + m;
            s.photons_high += select(0u, 1u, low < m);
            s.photons_low = low;
            stats[index] = s;
            hit_points.points[index].radius = new_radius;
            return s.tau / (PI * new_radius * new_radius);
        }
    }
    return s.tau / (PI * radius * radius);
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let pixel = id.y * params.width + id.x;
    var sum = vec3<f32>(0.0);
    for (var slot = 0u; slot < params.slots_per_pixel; slot++) {
        sum += merge_slot(pixel * params.slots_per_pixel + slot);
    }
    radiance[pixel] = vec4<f32>(sum * params.inv_iterations, 1.0);
}
