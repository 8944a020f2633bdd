#define_import_path common::gather

// What every hit-point structure's gather shares: the first three bindings of its group 1 (hit
// points, this iteration's photon hits, the deposits it adds to) and the test that decides
// whether a photon hit counts for a hit point. Structures bind their own resources from 3 on.

#import common::scene::UNBOUNDED
#import common::hit_points::{HitPointBuffer, PhotonHitsIn, PhotonHit, DepositCell, NO_PIXEL}

@group(1) @binding(0) var<storage, read> hit_points: HitPointBuffer;
@group(1) @binding(1) var<storage, read> photon_hits: PhotonHitsIn;
@group(1) @binding(2) var<storage, read_write> deposits: array<DepositCell>;

fn photon_hit_count() -> u32 {
    return min(photon_hits.count, arrayLength(&photon_hits.hits));
}

fn add_deposit_flux(cell: u32, channel: u32, value: f32) {
#ifdef FLOAT_ATOMICS
    atomicAdd(&deposits[cell].flux[channel], value);
#else
    var old = atomicLoad(&deposits[cell].flux[channel]);
    loop {
        let updated = bitcast<u32>(bitcast<f32>(old) + value);
        let r = atomicCompareExchangeWeak(&deposits[cell].flux[channel], old, updated);
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
#endif
}

// The same for the photons within half the radius (WGSL passes no pointers to atomics).
fn add_inner_flux(cell: u32, channel: u32, value: f32) {
#ifdef FLOAT_ATOMICS
    atomicAdd(&deposits[cell].inner_flux[channel], value);
#else
    var old = atomicLoad(&deposits[cell].inner_flux[channel]);
    loop {
        let updated = bitcast<u32>(bitcast<f32>(old) + value);
        let r = atomicCompareExchangeWeak(&deposits[cell].inner_flux[channel], old, updated);
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
#endif
}

// Adds `hit` to hit point `index` when the hit lies inside its sphere; returns whether it did.
fn gather_at(index: u32, hit: PhotonHit) -> bool {
    let hp = hit_points.points[index];
    if hp.pixel == NO_PIXEL || !(hp.radius > 0.0) {
        return false;
    }
    // Written so that a NaN distance (a photon hit that is not a number) counts for nobody.
    let d = hit.position - hp.position;
    if !(dot(d, d) <= hp.radius * hp.radius) {
        return false;
    }
    // One-sided diffuse: light arriving from behind the hit point's surface adds nothing. A
    // photon that scattered in a medium is no surface's.
    if dot(hp.normal, hit.wi) <= 0.0 || hit.in_medium != 0u {
        return false;
    }
    // The whole path (camera part + photon part) obeys max_depth, as in path tracing.
    if hit.remaining != UNBOUNDED && hp.depth > hit.remaining {
        return false;
    }
    atomicAdd(&deposits[index].count, 1u);
    let added = hit.flux * hp.weight;
    add_deposit_flux(index, 0u, added.x);
    add_deposit_flux(index, 1u, added.y);
    add_deposit_flux(index, 2u, added.z);
    if dot(d, d) <= 0.25 * hp.radius * hp.radius {
        atomicAdd(&deposits[index].inner_count, 1u);
        add_inner_flux(index, 0u, added.x);
        add_inner_flux(index, 1u, added.y);
        add_inner_flux(index, 2u, added.z);
    }
    return true;
}
