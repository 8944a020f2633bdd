#define_import_path common::deposit_sums

// What every estimator reads of an iteration's deposits: binding 2 of its group 1, and each
// hit point's sums over the whole disc and over half its radius (the kernel-bias estimate,
// docs/error-estimate.md). The bytes are the same for both atomics paths.

#import common::hit_points::DepositCell

@group(1) @binding(2) var<storage, read_write> deposits: array<DepositCell>;

fn deposited_flux(cell: u32) -> vec3<f32> {
#ifdef FLOAT_ATOMICS
    return vec3<f32>(atomicLoad(&deposits[cell].flux[0]), atomicLoad(&deposits[cell].flux[1]), atomicLoad(&deposits[cell].flux[2]));
#else
    return vec3<f32>(bitcast<f32>(atomicLoad(&deposits[cell].flux[0])), bitcast<f32>(atomicLoad(&deposits[cell].flux[1])), bitcast<f32>(atomicLoad(&deposits[cell].flux[2])));
#endif
}

fn inner_flux(cell: u32) -> vec3<f32> {
#ifdef FLOAT_ATOMICS
    return vec3<f32>(atomicLoad(&deposits[cell].inner_flux[0]), atomicLoad(&deposits[cell].inner_flux[1]), atomicLoad(&deposits[cell].inner_flux[2]));
#else
    return vec3<f32>(bitcast<f32>(atomicLoad(&deposits[cell].inner_flux[0])), bitcast<f32>(atomicLoad(&deposits[cell].inner_flux[1])), bitcast<f32>(atomicLoad(&deposits[cell].inner_flux[2])));
#endif
}

fn deposit_count(cell: u32) -> u32 {
    return atomicLoad(&deposits[cell].count);
}
