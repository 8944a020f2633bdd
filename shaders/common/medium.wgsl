#define_import_path common::medium

// Homogeneous participating media (compiled with MEDIA only): their records, free-flight
// sampling, phase functions and the transmittance of a shadow ray through media and the null
// surfaces that bound them. src/scene/medium.rs is the CPU form the tests compare against.
//
// A path's medium is the offset of its record in bsdf_tables (NO_MEDIUM: vacuum); it changes
// only where the path crosses a shape whose material names an interior or exterior medium, to
// the one on the side it leaves towards (Mitsuba's target_medium).

#import common::scene::{bsdf_tables, materials, Material, NO_HIT, NO_MEDIUM, T_INFINITE, MATERIAL_NULL}
#import common::sampling::{PI, basis_from_normal}
#import common::rng::{rng_next_f32, rng_next_vec2}
#import common::traversal::traverse
#import common::surface::{surface_at, spawn_origin, offset_ray_origin, SHADOW_EPSILON}

const PHASE_ISOTROPIC: u32 = 0u;
const PHASE_HG: u32 = 1u;
const PHASE_RAYLEIGH: u32 = 2u;
// Null surfaces a shadow ray crosses before it counts as blocked.
const MAX_CROSSINGS: u32 = 32u;
const NO_GRID: u32 = 0xffffffffu;
// Tentative collisions a ray takes through a grid medium before it gives up (counted as
// absorbed): a majorant this far above a ray's densities wastes the work anyway.
const MAX_TRACKING_STEPS: u32 = 4096u;
const WRAP_CLAMP: u32 = 0u;
const WRAP_REPEAT: u32 = 1u;
const WRAP_MIRROR: u32 = 2u;

struct Medium {
    sigma_t: vec3<f32>,
    albedo: vec3<f32>,
    phase: u32,
    // Henyey-Greenstein's mean cosine.
    g: f32,
    // Next-event estimation at its scattering points (Mitsuba's sample_emitters).
    sample_emitters: bool,
    // A heterogeneous medium: where its grid's values start in bsdf_tables (NO_GRID: none),
    // sigma_t is then `sigma_t` times the grid's value at each point; the majorant bounds it.
    grid: u32,
    majorant: f32,
    channels: u32,
    res: vec3<u32>,
    nearest: bool,
    wrap: u32,
    // World to the grid's unit cube: three rows of an affine map.
    to_local: mat3x4<f32>,
}

// The record at `offset` (src/scene/medium.rs, Medium::gpu_record).
fn medium_at(offset: u32) -> Medium {
    let sigma_t = vec3<f32>(bsdf_tables[offset], bsdf_tables[offset + 1u], bsdf_tables[offset + 2u]);
    let albedo = vec3<f32>(bsdf_tables[offset + 4u], bsdf_tables[offset + 5u], bsdf_tables[offset + 6u]);
    let flags = u32(bsdf_tables[offset + 8u]);
    let res = vec3<u32>(u32(bsdf_tables[offset + 12u]), u32(bsdf_tables[offset + 13u]), u32(bsdf_tables[offset + 14u]));
    var rows: mat3x4<f32>;
    for (var r = 0u; r < 3u; r++) {
        let o = offset + 16u + 4u * r;
        rows[r] = vec4<f32>(bsdf_tables[o], bsdf_tables[o + 1u], bsdf_tables[o + 2u], bsdf_tables[o + 3u]);
    }
    return Medium(sigma_t, albedo, u32(bsdf_tables[offset + 3u]), bsdf_tables[offset + 7u], (flags & 1u) != 0u, bitcast<u32>(bsdf_tables[offset + 9u]), bsdf_tables[offset + 10u], u32(bsdf_tables[offset + 11u]), res, (flags & 2u) != 0u, u32(bsdf_tables[offset + 15u]), rows);
}

// The grid's cell index `i` along an axis of `n` cells as its wrap mode reads it.
fn wrap_cell(i: i32, n: i32, wrap: u32) -> u32 {
    if wrap == WRAP_REPEAT {
        return u32(((i % n) + n) % n);
    }
    if wrap == WRAP_MIRROR {
        let period = select(i / n, (i + 1) / n - 1, i < 0);
        let m = i - period * n;
        return u32(select(n - 1 - m, m, (period & 1) == 0));
    }
    return u32(clamp(i, 0, n - 1));
}

fn grid_cell(m: Medium, cell: vec3<i32>) -> vec3<f32> {
    let n = vec3<i32>(m.res);
    let x = wrap_cell(cell.x, n.x, m.wrap);
    let y = wrap_cell(cell.y, n.y, m.wrap);
    let z = wrap_cell(cell.z, n.z, m.wrap);
    let index = m.grid + ((z * m.res.y + y) * m.res.x + x) * m.channels;
    if m.channels == 1u {
        return vec3<f32>(bsdf_tables[index]);
    }
    return vec3<f32>(bsdf_tables[index], bsdf_tables[index + 1u], bsdf_tables[index + 2u]);
}

// Extinction at world point `p` (a grid medium's grid looked up as Mitsuba's gridvolume does,
// src/scene/grid.rs: cell-centred samples, trilinear or nearest, the wrap mode past the faces).
fn extinction_at(m: Medium, p: vec3<f32>) -> vec3<f32> {
    if m.grid == NO_GRID {
        return m.sigma_t;
    }
    let local = vec4<f32>(p, 1.0) * m.to_local;
    let res = vec3<f32>(m.res);
    if m.nearest {
        return m.sigma_t * grid_cell(m, vec3<i32>(floor(local * res)));
    }
    let pos = local * res - 0.5;
    let lower = floor(pos);
    let f = pos - lower;
    let base = vec3<i32>(lower);
    var value = vec3<f32>(0.0);
    for (var corner = 0u; corner < 8u; corner++) {
        let bit = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let w = select(vec3<f32>(1.0) - f, f, bit == vec3<u32>(1u));
        value += w.x * w.y * w.z * grid_cell(m, base + vec3<i32>(bit));
    }
    return m.sigma_t * value;
}

fn transmittance(m: Medium, distance: f32) -> vec3<f32> {
    return exp(-m.sigma_t * distance);
}

// Where a ray through a medium first interacts, up to `t_max` (the next surface).
struct FreeFlight {
    t: f32,
    // It scattered at `t` (else it reached t_max).
    scattered: bool,
    // Transmittance (times sigma_s where it scattered) over the density of what was sampled.
    weight: vec3<f32>,
    // Where it scattered: the transmittance over the density per unit extinction, what a
    // photon stores there (so that stored flux per unit volume estimates the fluence).
    fluence: vec3<f32>,
}

// Samples the distance to the next interaction by one colour channel's extinction chosen
// uniformly, weighted by the mean of the three channels' densities (one-sample MIS, balance
// heuristic, over the channels): chromatic media stay unbiased and bounded in weight. Mitsuba
// draws one channel per path instead; both converge to the same image.
fn sample_homogeneous_flight(m: Medium, t_max: f32, u: vec2<f32>) -> FreeFlight {
    let channel = min(u32(u.x * 3.0), 2u);
    let sigma = m.sigma_t[channel];
    var t = T_INFINITE;
    if sigma > 0.0 {
        t = -log(1.0 - u.y) / sigma;
    }
    if t < t_max {
        let tr = transmittance(m, t);
        let density = dot(m.sigma_t * tr, vec3<f32>(1.0 / 3.0));
        let fluence = select(vec3<f32>(0.0), tr / density, density > 0.0);
        return FreeFlight(t, true, m.albedo * m.sigma_t * fluence, fluence);
    }
    let tr = transmittance(m, t_max);
    let density = dot(tr, vec3<f32>(1.0 / 3.0));
    return FreeFlight(t_max, false, select(vec3<f32>(0.0), tr / density, density > 0.0), vec3<f32>(0.0));
}

// Where a ray from `origin` along `dir` first interacts in medium `m`, up to `t_max`.
fn sample_free_flight(m: Medium, origin: vec3<f32>, dir: vec3<f32>, t_max: f32, rng: ptr<function, vec4<u32>>) -> FreeFlight {
#ifdef GRID_MEDIA
    if m.grid != NO_GRID {
        return track_collision(m, origin, dir, t_max, rng);
    }
#endif
    return sample_homogeneous_flight(m, t_max, rng_next_vec2(rng));
}

// The fraction of light that crosses `distance` from `origin` along `dir` in `m` without
// interacting: exact in a homogeneous medium, an unbiased estimate in a grid medium (ratio
// tracking, Novak et al. 2014).
fn transmittance_along(m: Medium, origin: vec3<f32>, dir: vec3<f32>, distance: f32, rng: ptr<function, vec4<u32>>) -> vec3<f32> {
#ifdef GRID_MEDIA
    if m.grid != NO_GRID {
        var tr = vec3<f32>(1.0);
        var t = 0.0;
        for (var step = 0u; step < MAX_TRACKING_STEPS; step++) {
            t -= log(1.0 - rng_next_f32(rng)) / m.majorant;
            if !(t < distance) {
                return tr;
            }
            tr *= max(vec3<f32>(0.0), vec3<f32>(1.0) - extinction_at(m, origin + t * dir) / m.majorant);
            if max(tr.x, max(tr.y, tr.z)) <= 0.0 {
                return tr;
            }
        }
        return vec3<f32>(0.0);
    }
#endif
    return transmittance(m, distance);
}

#ifdef GRID_MEDIA
// Delta tracking against the majorant with null collisions for colour (Mitsuba's volpath's
// scheme, Kutz et al. 2017): at a tentative collision the ray scatters with probability the
// mean extinction over the majorant, else goes on. Weights per channel keep every channel
// unbiased: sigma_s over the mean extinction at a real collision (as a homogeneous medium's
// albedo sigma_t tr / density), the null part over its mean at a null one.
fn track_collision(m: Medium, origin: vec3<f32>, dir: vec3<f32>, t_max: f32, rng: ptr<function, vec4<u32>>) -> FreeFlight {
    var weight = vec3<f32>(1.0);
    var t = 0.0;
    for (var step = 0u; step < MAX_TRACKING_STEPS; step++) {
        t -= log(1.0 - rng_next_f32(rng)) / m.majorant;
        if !(t < t_max) {
            return FreeFlight(t_max, false, weight, vec3<f32>(0.0));
        }
        let sigma = extinction_at(m, origin + t * dir);
        let real = (sigma.x + sigma.y + sigma.z) / (3.0 * m.majorant);
        if rng_next_f32(rng) < real {
            let fluence = weight / (real * m.majorant);
            return FreeFlight(t, true, m.albedo * sigma * fluence, fluence);
        }
        let null_part = max(vec3<f32>(0.0), vec3<f32>(m.majorant) - sigma);
        weight *= null_part / (m.majorant * (1.0 - real));
    }
    return FreeFlight(t_max, false, vec3<f32>(0.0), vec3<f32>(0.0));
}
#endif

fn henyey_greenstein(g: f32, cos_theta: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom));
}

// The phase function's density of scattering from travel direction `d_in` into `wo`.
fn phase_eval(m: Medium, d_in: vec3<f32>, wo: vec3<f32>) -> f32 {
    let cos_theta = clamp(dot(d_in, wo), -1.0, 1.0);
    if m.phase == PHASE_HG {
        return henyey_greenstein(m.g, cos_theta);
    }
    if m.phase == PHASE_RAYLEIGH {
        return 3.0 / (16.0 * PI) * (1.0 + cos_theta * cos_theta);
    }
    return 1.0 / (4.0 * PI);
}

// A direction drawn exactly from phase_eval around `d_in` (so its weight is 1).
fn phase_sample(m: Medium, d_in: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    var cos_theta = 1.0 - 2.0 * u.x;
    if m.phase == PHASE_HG && abs(m.g) >= 1e-3 {
        let g = m.g;
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        cos_theta = clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
    } else if m.phase == PHASE_RAYLEIGH {
        // The real root of cos^3 + 3 cos = 8u - 4 (the inverse of its CDF), by Cardano.
        let q = 4.0 * u.x - 2.0;
        let d = sqrt(q * q + 1.0);
        cos_theta = clamp(cube_root(q + d) + cube_root(q - d), -1.0, 1.0);
    }
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let phi = 2.0 * PI * u.y;
    let local = vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta);
    return normalize(basis_from_normal(d_in) * local);
}

fn cube_root(x: f32) -> f32 {
    return sign(x) * pow(abs(x), 1.0 / 3.0);
}

// The medium a ray enters on leaving a surface of `material` towards `dir` (the surface's
// front geometric normal `normal`), given the one it was in.
fn medium_after(material: Material, dir: vec3<f32>, normal: vec3<f32>, current: u32) -> u32 {
    if material.interior == NO_MEDIUM && material.exterior == NO_MEDIUM {
        return current;
    }
    return select(material.interior, material.exterior, dot(dir, normal) > 0.0);
}

// The fraction of light that travels from `to_point` back to `from_point` (each with its error
// bound and geometric normal, zero for a point in a medium or a point light), leaving the
// first in `medium`: the media's transmittance along the way, through null surfaces (the
// boundaries of media, which change the medium), 0 if any other surface lies between. Both
// ends are offset as common::surface's unoccluded offsets them.
fn transmittance_between(from_point: vec3<f32>, from_error: vec3<f32>, from_normal: vec3<f32>, to_point: vec3<f32>, to_error: vec3<f32>, to_normal: vec3<f32>, medium: u32, rng: ptr<function, vec4<u32>>) -> vec3<f32> {
    var origin = offset_ray_origin(from_point, from_error, from_normal, to_point - from_point);
    let end = offset_ray_origin(to_point, to_error, to_normal, origin - to_point);
    var current = medium;
    var tr = vec3<f32>(1.0);
    for (var crossing = 0u; crossing <= MAX_CROSSINGS; crossing++) {
        let span = end - origin;
        let distance = length(span);
        if !(distance > 0.0) {
            return tr;
        }
        let dir = span / distance;
        let reach = distance * (1.0 - SHADOW_EPSILON);
        let hit = traverse(origin, dir, reach, false, false);
        if hit.prim == NO_HIT {
            if current != NO_MEDIUM {
                tr *= transmittance_along(medium_at(current), origin, dir, distance, rng);
            }
            return tr;
        }
        let surface = surface_at(hit, origin, dir);
        let material = materials[surface.material];
        if material.kind != MATERIAL_NULL {
            return vec3<f32>(0.0);
        }
        if current != NO_MEDIUM {
            tr *= transmittance_along(medium_at(current), origin, dir, hit.t, rng);
        }
        current = medium_after(material, dir, surface.normal, current);
        origin = spawn_origin(surface, dir);
    }
    return vec3<f32>(0.0);
}
