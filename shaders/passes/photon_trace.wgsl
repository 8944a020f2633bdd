// Photon tracing. Each photon leaves a light chosen in proportion to its power (area lights:
// uniform position, cosine direction; point lights: uniform direction); the pass traces it
// through mirrors and dielectrics and writes a photon hit where it deposits. Which hit points
// receive it is the gather's business (the hit-point structure nodes), not this pass's.
//
// Mode CAUSTIC deposits only at the first diffuse vertex after at least one specular vertex and
// stops there (L S+ D: what the hybrid's path tracer leaves out). Mode ALL deposits at every
// diffuse vertex and continues (photon mapping alone). Only Lambertian vertices take deposits
// (the camera's hit points are Lambertian); at a vertex whose sampled lobe is glossy (or
// plastic's base) a caustic photon stops, because the camera path traces that vertex, and a
// photon in mode ALL scatters on without depositing. Delta lobes are specular vertices, and
// with GLOSSY (a `glossy_threshold` above 0) microfacet lobes smoother than the threshold: a
// caustic photon continues through them carrying the specular lobes' share of its flux (all of
// it for rough conductors and dielectrics, the coating's for rough plastic), as the camera pass
// leaves exactly that share to it.
//
// With `aim` (caustic mode only) photons leave only in directions that meet the sphere around
// every specular surface (Jensen's projection maps, reduced to one sphere): a photon sent
// elsewhere reaches a diffuse surface first and would be discarded, so leaving those directions
// out changes nothing but the cost. The flux is divided by the cone's density instead.

#import common::rng::{rng_stream, rng_next_f32, rng_next_vec2}
#import common::sampling::{PI, sample_cosine_hemisphere, sample_uniform_sphere, sample_cone, max_component, any_not_finite, basis_from_normal, square_to_disk_concentric}
#import common::scene::{scene_info, lights, Light, NO_HIT, UNBOUNDED, MATERIAL_DIFFUSE, LIGHT_POINT, LIGHT_SPOT, LIGHT_PROJECTOR, LIGHT_DIRECTIONAL, LIGHT_CONSTANT, LIGHT_ENVMAP}
#import common::intersection::Hit
#import common::traversal::intersect_photon
#import common::surface::{Surface, surface_at, offset_ray_origin, spawn_origin}
#import common::path_step::{arrive, bounce}
#ifdef MEDIA
#import common::scene::{materials, NO_MEDIUM}
#import common::medium::{MAX_CROSSINGS, medium_at, medium_after, transmittance_along, sample_free_flight}
#endif
#ifdef BLENDS
#import common::scene::MATERIAL_NULL
#import bsdfs::blendbsdf::diffuse_probability
#else
#ifdef MEDIA
#import common::scene::MATERIAL_NULL
#endif
#endif
#ifdef GLOSSY
#import common::material::material_specular_share
#endif
#import common::lights::{pick_emitting_light, sample_area_light_point}
#ifdef POINT_LIGHTS
#import common::lights::delta_intensity
#endif
#ifdef ENVIRONMENT
#import common::environment::sample_environment_light
#endif
#import bsdfs::normalmap::frame_factor
#import common::hit_points::{PhotonHitsOut, PhotonHit}
#import gpu::dispatch::next_item

struct PhotonUniform {
    photons: u32,
    seed: u32,
    iteration: u32,
    mode: u32,
    max_depth: u32,
    rr_depth: u32,
    // 1 / photons: deposits are flux per emitted photon of this iteration.
    flux_scale: f32,
    // Workgroups per row of the 2D dispatch (one row holds at most 65535).
    groups_per_row: u32,
    // 1: aim caustic photons at the specular surfaces' bounding sphere.
    aim: u32,
    // Microfacet lobes smoother than this are specular vertices (read with GLOSSY only).
    glossy_threshold: f32,
    // Invocations launched: each takes every invocations-th photon.
    invocations: u32,
    pad_c: u32,
    // The sphere `aim` aims at: around the specular surfaces (and the glossy ones with GLOSSY).
    aim_center: vec3<f32>,
    aim_radius: f32,
}

@group(1) @binding(0) var<uniform> params: PhotonUniform;
@group(1) @binding(1) var<storage, read_write> photon_hits: PhotonHitsOut;
// [segments low, segments high, hits dropped low, high]: 64-bit totals from 32-bit atomics.
// (Photon counts are exact on the CPU: every iteration emits `photons`.)
@group(1) @binding(2) var<storage, read_write> counters: array<atomic<u32>, 4>;
// RGB flux emitted so far (already scaled by flux_scale): the light's power per iteration.
#ifdef FLOAT_ATOMICS
@group(1) @binding(3) var<storage, read_write> emitted: array<atomic<f32>, 3>;
#else
@group(1) @binding(3) var<storage, read_write> emitted: array<atomic<u32>, 3>;
#endif

const MODE_CAUSTIC: u32 = 0u;
const MODE_ALL: u32 = 1u;
const WORKGROUP: u32 = 64u;
const SAFETY_MAX_DEPTH: u32 = 1024u;

var<workgroup> group_flux: array<vec3<f32>, WORKGROUP>;
var<workgroup> group_segments: atomic<u32>;

const COUNTER_SEGMENTS: u32 = 0u;
const COUNTER_DROPPED: u32 = 2u;

fn add_u64(index: u32, value: u32) {
    if value == 0u {
        return;
    }
    let old = atomicAdd(&counters[index], value);
    if old > 0xffffffffu - value {
        atomicAdd(&counters[index + 1u], 1u);
    }
}

fn add_emitted(channel: u32, value: f32) {
#ifdef FLOAT_ATOMICS
    atomicAdd(&emitted[channel], value);
#else
    var old = atomicLoad(&emitted[channel]);
    loop {
        let updated = bitcast<u32>(bitcast<f32>(old) + value);
        let r = atomicCompareExchangeWeak(&emitted[channel], old, updated);
        if r.exchanged {
            break;
        }
        old = r.old_value;
    }
#endif
}

// A direction towards the specular bounding sphere, uniform over the cone it subtends from
// `origin`, with the cone's solid angle; `valid` is false where no cone applies (no specular
// surface, aiming off, or `origin` inside the sphere).
struct Aim {
    dir: vec3<f32>,
    solid_angle: f32,
    valid: bool,
}

fn aim_at_specular(origin: vec3<f32>, u: vec2<f32>) -> Aim {
    var aim: Aim;
    aim.valid = false;
    let radius = params.aim_radius;
    if params.aim == 0u || params.mode != MODE_CAUSTIC || radius <= 0.0 {
        return aim;
    }
    let to_center = params.aim_center - origin;
    let d2 = dot(to_center, to_center);
    let r2 = radius * radius;
    if d2 <= r2 {
        return aim;
    }
    let s2 = r2 / d2;
    let one_minus_cos = s2 / (1.0 + sqrt(1.0 - s2));
    aim.dir = sample_cone(to_center / sqrt(d2), one_minus_cos, u);
    aim.solid_angle = 2.0 * PI * one_minus_cos;
    aim.valid = true;
    return aim;
}

struct Photon {
    origin: vec3<f32>,
    dir: vec3<f32>,
    flux: vec3<f32>,
    valid: bool,
    // The medium it travels in (common::medium; with MEDIA only), or NO_MEDIUM.
    medium: u32,
}

// Flux per photon of this iteration; a photon with nothing (or not a number) to carry is invalid.
fn normalised(emitted: Photon) -> Photon {
    var photon = emitted;
    photon.flux *= params.flux_scale;
    photon.valid = !any_not_finite(photon.flux) && max_component(photon.flux) > 0.0;
    return photon;
}

// A photon `light` sent, normalised, in the medium the light lies in.
fn from_light(light: Light, emitted: Photon) -> Photon {
    var photon = normalised(emitted);
    photon.medium = light.medium;
    return photon;
}

#ifdef POINT_LIGHTS
// Point lights send photons over the sphere of directions, spot lights over their cutoff cone,
// projectors over their image; when aiming, over the cone towards the specular surfaces instead
// if that one is narrower (what leaves outside either carries no caustic).
//
// Directions are uniform (in solid angle, or for a projector in its image's uv) and each photon
// carries the intensity that way over the density, texture and falloff included: a textured
// spot as Mitsuba's sample_ray does. Mitsuba's projector samples its image by brightness
// instead; both are unbiased, and uniform needs no per-light sampling table, paying only in
// noise when most of the image is dark (the aimed cone has to be uniform anyway).
fn emit_point_photon(light: Light, u: vec2<f32>) -> Photon {
    var photon: Photon;
    photon.origin = light.position;
    var solid_angle = 4.0 * PI;
    var one_minus_cos = 2.0;
#ifdef SPOT_LIGHTS
    if light.kind == LIGHT_SPOT {
        // 1 - cos(c) without cancellation.
        let s = sin(0.5 * light.cutoff);
        one_minus_cos = 2.0 * s * s;
        solid_angle = 2.0 * PI * one_minus_cos;
    }
#endif
#ifdef PROJECTORS
    if light.kind == LIGHT_PROJECTOR {
        // A rectangular pyramid of half-angles a, b: 4 asin(sin a sin b).
        let tx = light.uv_factor;
        let ty = light.uv_factor / light.aspect;
        solid_angle = 4.0 * asin(tx * ty / sqrt((1.0 + tx * tx) * (1.0 + ty * ty)));
    }
#endif
    let aim = aim_at_specular(light.position, u);
    if aim.valid && aim.solid_angle < solid_angle {
        photon.dir = aim.dir;
        solid_angle = aim.solid_angle;
    } else if light.kind == LIGHT_PROJECTOR {
        // Uniform on the image at z = 1 (area `light.area`): solid-angle density
        // 1 / (area cos^3), so the photon carries intensity x area x cos^3.
        let p = light.uv_factor * vec2<f32>(1.0 - 2.0 * u.x, (1.0 - 2.0 * u.y) / light.aspect);
        photon.dir = normalize(p.x * light.frame_x + p.y * light.frame_y + light.axis);
        let c = dot(photon.dir, light.axis);
        photon.flux = delta_intensity(light, photon.dir) * (light.area * c * c * c / light.emit_prob);
        return photon;
    } else if one_minus_cos < 2.0 {
        photon.dir = sample_cone(light.axis, one_minus_cos, u);
    } else {
        photon.dir = sample_uniform_sphere(u);
    }
    // Intensity I over a solid angle with uniform density: I x solid angle per photon.
    photon.flux = delta_intensity(light, photon.dir) * (solid_angle / light.emit_prob);
    return photon;
}
#endif

// A photon from a light at infinity arriving from unit direction `towards_light`: it crosses a
// disc facing that direction, as large as the scene's bounding sphere (or, when aiming, the
// sphere around the specular surfaces: a photon missing it never meets one), placed beyond the
// scene. `radiance` over `pdf` is what the direction sample carries per unit area.
fn emit_distant_photon(light: Light, towards_light: vec3<f32>, radiance: vec3<f32>, pdf: f32, u: vec2<f32>) -> Photon {
    var photon: Photon;
    photon.valid = false;
    let scene_center = 0.5 * (scene_info.bounds_min + scene_info.bounds_max);
    var center = scene_center;
    var radius = scene_info.scene_radius;
    if params.aim != 0u && params.mode == MODE_CAUSTIC && params.aim_radius > 0.0 {
        center = params.aim_center;
        radius = params.aim_radius;
    }
    if !(radius > 0.0) || !(pdf > 0.0) {
        photon.flux = vec3<f32>(0.0);
        return photon;
    }
    let disc = radius * square_to_disk_concentric(u);
    let frame = basis_from_normal(towards_light);
    // Far enough along the direction that the disc's plane lies outside the bounding sphere.
    let back = 1.01 * (length(center - scene_center) + scene_info.scene_radius) + radius;
    photon.origin = center + frame[0] * disc.x + frame[1] * disc.y + towards_light * back;
    photon.dir = -towards_light;
    photon.flux = radiance * (PI * radius * radius / (pdf * light.emit_prob));
    return photon;
}

fn emit_photon(rng: ptr<function, vec4<u32>>) -> Photon {
    var photon: Photon;
    photon.valid = false;
    if scene_info.num_lights == 0u {
        return photon;
    }
    let light = lights[pick_emitting_light(rng_next_f32(rng))];
    if light.emit_prob <= 0.0 {
        return photon;
    }
    let u_position = rng_next_vec2(rng);
    let u_direction = rng_next_vec2(rng);
#ifdef POINT_LIGHTS
    if light.kind == LIGHT_POINT || light.kind == LIGHT_SPOT || light.kind == LIGHT_PROJECTOR {
        return from_light(light, emit_point_photon(light, u_direction));
    }
#endif
#ifdef DIRECTIONAL_LIGHTS
    if light.kind == LIGHT_DIRECTIONAL {
        return from_light(light, emit_distant_photon(light, -light.axis, light.radiance, 1.0, u_position));
    }
#endif
#ifdef ENVIRONMENT
    if light.kind == LIGHT_CONSTANT || light.kind == LIGHT_ENVMAP {
        let s = sample_environment_light(light, u_direction);
        return from_light(light, emit_distant_photon(light, s.dir, s.radiance, s.pdf, u_position));
    }
#endif
    let point = sample_area_light_point(light, u_position);
    let aim = aim_at_specular(point.position, u_direction);
    if aim.valid {
        // L cos / (pdf_position pdf_direction) with pdfs 1 / A and 1 / solid angle; the
        // part of the cone behind the light carries nothing.
        photon.dir = aim.dir;
        let cos_light = max(dot(aim.dir, point.normal), 0.0);
        photon.flux = light.radiance * (cos_light * light.area * aim.solid_angle / light.emit_prob);
    } else {
        // One-sided Lambertian emitter of radiance L and area A: power pi A L.
        photon.dir = sample_cosine_hemisphere(point.normal, u_direction);
        photon.flux = light.radiance * (PI * light.area / light.emit_prob);
    }
    photon.origin = offset_ray_origin(point.position, point.error, point.normal, photon.dir);
    return from_light(light, photon);
}

// Stores a photon hit for the gather; one that does not fit is counted, never lost silently.
fn deposit(position: vec3<f32>, wi: vec3<f32>, flux: vec3<f32>, segments: u32) {
    store_hit(position, wi, flux, segments, 0u);
}

// The same for a photon that scattered in a medium (`in_medium` 1) or reached a surface (0).
fn store_hit(position: vec3<f32>, wi: vec3<f32>, flux: vec3<f32>, segments: u32, in_medium: u32) {
    let slot = atomicAdd(&photon_hits.count, 1u);
    if slot >= arrayLength(&photon_hits.hits) {
        atomicAdd(&photon_hits.dropped, 1u);
        add_u64(COUNTER_DROPPED, 1u);
        return;
    }
    var remaining = UNBOUNDED;
    if params.max_depth != UNBOUNDED {
        remaining = params.max_depth - segments;
    }
    photon_hits.hits[slot] = PhotonHit(position, remaining, wi, in_medium, flux, 0u);
}

// A photon in flight: where it is, what it carries, and how far it has come.
struct PhotonPath {
    photon: Photon,
    after_specular: bool,
    // The emitted flux's largest component, which Russian roulette compares against.
    initial: f32,
    segments: u32,
}

fn start_photon(emitted: Photon) -> PhotonPath {
    return PhotonPath(emitted, false, max_component(emitted.flux), 0u);
}

#ifdef MEDIA
// A photon crossing its medium up to the next surface `t_max` away; false once it has ended.
// Before any specular vertex it carries the transmittance (exactly, or ratio tracking's
// estimate in a grid medium): where it would scatter is
// light the camera paths trace (L M ...). After one it is a caustic photon: it scatters at a
// distance drawn as the camera paths draw theirs, and there it is stored as a volumetric
// caustic (L S+ M) and ends; the camera paths' medium vertices gather it. The stored flux is
// what arrives there over the distance's density per unit extinction, so that the photons per
// unit volume estimate the fluence (Jensen and Christensen 1998's volume photon map).
fn cross_medium(photon: ptr<function, Photon>, segments: u32, t_max: f32, after_specular: bool, rng: ptr<function, vec4<u32>>) -> bool {
    let m = medium_at((*photon).medium);
    let origin = (*photon).origin;
    let dir = (*photon).dir;
    if !after_specular {
        (*photon).flux *= transmittance_along(m, origin, dir, t_max, rng);
        return true;
    }
    let flight = sample_free_flight(m, origin, dir, t_max, rng);
    if !flight.scattered {
        (*photon).flux *= flight.weight;
        return true;
    }
    store_hit(origin + dir * flight.t, -dir, (*photon).flux * flight.fluence, segments, 1u);
    return false;
}
#endif

#ifdef MEDIA
// Crosses `arrived` where it is a plain medium boundary, a null BSDF not a blend's: no vertex
// (as in Mitsuba's volpath), the photon's medium changes.
fn crosses_plain_boundary(photon: ptr<function, Photon>, arrived: Surface) -> bool {
    let material = materials[arrived.material];
    if material.kind != MATERIAL_NULL {
        return false;
    }
    (*photon).medium = medium_after(material, (*photon).dir, arrived.normal, (*photon).medium);
    (*photon).origin = spawn_origin(arrived, (*photon).dir);
    return true;
}
#endif

// Traces one segment of `path` and scatters it; false once the photon has ended.
fn extend_photon(path: ptr<function, PhotonPath>, rng: ptr<function, vec4<u32>>) -> bool {
    if (*path).segments >= min(params.max_depth, SAFETY_MAX_DEPTH) {
        return false;
    }
    var photon = (*path).photon;
    var after_specular = (*path).after_specular;
    (*path).segments += 1u;
    let segments = (*path).segments;
    let initial = (*path).initial;
    var hit: Hit;
    var arrived: Surface;
    // Without MEDIA one pass; with it, the segments of the ray between plain medium boundaries
    // (see path_trace's extend_path).
    var crossings = 0u;
    loop {
        hit = intersect_photon(photon.origin, photon.dir);
#ifdef MEDIA
        if photon.medium != NO_MEDIUM && !cross_medium(&photon, segments, hit.t, after_specular, rng) {
            return false;
        }
#endif
        if hit.prim == NO_HIT {
            return false;
        }
        arrived = surface_at(hit, photon.origin, photon.dir);
#ifdef MEDIA
        if crossings < MAX_CROSSINGS && crosses_plain_boundary(&photon, arrived) {
            crossings += 1u;
            continue;
        }
#endif
        break;
    }
    let wi = -photon.dir;
    // The side and blend child this vertex scatters with, textured, in its shading frame: a
    // normal or bump map's as the camera pass has it but for flipping invalid normals, which
    // depends on the viewer (taken as not flipped: exact wherever the camera direction sees
    // the perturbed normal from above). Its masking and shadow terminator belong to the
    // light's direction, here where the photon came from (`wi`).
    let v = arrive(arrived, hit.prim, wi, false, rng);
    let surface = v.surface;
    let material = v.material;
    let cos_i = v.cos_back;
#ifdef BLENDS
    if material.kind == MATERIAL_NULL {
        // A mask's pass-through: the photon goes on unchanged, its class with it.
        photon.origin = spawn_origin(surface, photon.dir);
#ifdef MEDIA
        // Or a medium's boundary; as in Mitsuba's volpath, neither counts towards max_depth.
        photon.medium = medium_after(materials[arrived.material], photon.dir, arrived.normal, photon.medium);
        (*path).segments -= 1u;
#endif
        (*path).photon = photon;
        return true;
    }
#endif
    if material.kind == MATERIAL_DIFFUSE {
        // One-sided, as the camera pass: the back of a diffuse surface absorbs.
        if cos_i <= 0.0 || dot(wi, surface.shading_normal) <= 0.0 {
            return false;
        }
        // The hit point weighs flux per unit area by the BSDF alone: the shading cosine
        // over the geometric one it arrived with turns it into what the camera pass would
        // gather there (1 on flat-shaded surfaces).
        var deposited = photon.flux * (dot(wi, surface.shading_normal) * frame_factor(v.shading, wi) / cos_i);
#ifdef BLENDS
        // The flux arriving is the same whichever child of a blend this photon took, but only
        // a diffuse one deposits it.
        if v.blended {
            deposited /= diffuse_probability(surface.material, v.facing, surface.uv);
        }
#endif
        if params.mode == MODE_CAUSTIC {
            if after_specular {
                deposit(surface.position, wi, deposited, segments);
            }
            return false;
        }
        deposit(surface.position, wi, deposited, segments);
        let out = bounce(v, false, rng);
        if !out.sample.valid {
            return false;
        }
        photon.dir = out.dir;
        photon.flux *= out.weight;
        after_specular = false;
    } else {
        // Every other kind, as the camera pass scatters but carrying flux.
        let out = bounce(v, false, rng);
        if !out.sample.valid {
            return false;
        }
#ifdef GLOSSY
        var share = vec3<f32>(1.0);
        if params.mode == MODE_CAUSTIC {
            share = material_specular_share(material, wi * v.shading.frame, out.sample, params.glossy_threshold);
            if max_component(share) <= 0.0 {
                return false;
            }
        }
#else
        if !out.sample.delta && params.mode == MODE_CAUSTIC {
            return false;
        }
#endif
        photon.dir = out.dir;
        photon.flux *= out.weight;
#ifdef GLOSSY
        photon.flux *= share;
        after_specular = out.sample.delta || params.mode == MODE_CAUSTIC;
#else
        after_specular = out.sample.delta;
#endif
    }
    photon.origin = spawn_origin(surface, photon.dir);
#ifdef MEDIA
    photon.medium = medium_after(materials[arrived.material], photon.dir, arrived.normal, photon.medium);
#endif
    if segments >= params.rr_depth {
        let survive = min(max_component(photon.flux) / initial, 0.95);
        if rng_next_f32(rng) >= survive {
            return false;
        }
        photon.flux /= survive;
    }
    if max_component(photon.flux) <= 0.0 {
        return false;
    }
    (*path).photon = photon;
    (*path).after_specular = after_specular;
    return true;
}

// Each invocation traces photons first, first + invocations, ... and emits the next as soon as
// one ends (path regeneration, src/passes/lanes.rs): a photon's own stream makes it the same
// photon whichever lane traces it.
@compute @workgroup_size(64, 1, 1)
fn main(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    var index = (group.y * params.groups_per_row + group.x) * WORKGROUP + local;
    var flux = vec3<f32>(0.0);
    var segments = 0u;
    var rng = vec4<u32>(0u);
    var path: PhotonPath;
    var tracing = false;
    loop {
        if !tracing {
            if index >= params.photons {
                break;
            }
            rng = rng_stream(index, params.iteration, params.seed);
            index = next_item(index, params.invocations, params.photons);
            let photon = emit_photon(&rng);
            if !photon.valid {
                continue;
            }
            flux += photon.flux;
            path = start_photon(photon);
        }
        tracing = extend_photon(&path, &rng);
        if !tracing {
            segments += path.segments;
        }
    }
    // One global atomic per workgroup for the counters, not one per photon.
    group_flux[local] = flux;
    atomicAdd(&group_segments, segments);
    workgroupBarrier();
    for (var stride = WORKGROUP / 2u; stride > 0u; stride /= 2u) {
        if local < stride {
            group_flux[local] += group_flux[local + stride];
        }
        workgroupBarrier();
    }
    if local == 0u {
        add_emitted(0u, group_flux[0].x);
        add_emitted(1u, group_flux[0].y);
        add_emitted(2u, group_flux[0].z);
        add_u64(COUNTER_SEGMENTS, atomicLoad(&group_segments));
    }
}
