// Path tracing with next-event estimation, MIS (power heuristic) for area lights, Mitsuba's depth
// rule (max_depth counts segments) and optional Russian roulette. Each iteration adds
// `samples_per_iteration` samples to every pixel's running sum (xyz) and count (w); an
// invocation renders one or more pixels in turn (`main`, src/passes/lanes.rs).
//
// With `merge_depth` > 0 the first `merge_depth` diffuse vertices of the first sample are
// photon-mapped (docs/design.md section 1): each is recorded as a hit point, and emission reached from
// it through one or more specular vertices is dropped, because photon mapping adds exactly that.
// Only Lambertian vertices are photon-mapped (a hit point's weight is albedo / pi): glossy and
// plastic-base vertices are path traced (NEE with MIS), and emission reached from them through
// specular vertices is kept; photons stop there (photon_trace.wgsl). Delta lobes (mirror,
// dielectrics, smooth conductor, plastic's coating) are the specular vertices, and with GLOSSY
// (a `glossy_threshold` above 0) so are microfacet lobes smoother than the threshold: after a
// photon-mapped vertex, their next-event estimation and the emission reached through them (and
// further specular vertices) are left to photons, in the share `PathState.mapped`.
// With `trace_beyond` 0 (photon mapping only) a path stops at its first photon-mapped vertex.
//
// With `splat` (a tent or Gaussian pixel filter, samples kept on the film) the pass filters as
// Mitsuba's film does: a sample lands uniformly in its pixel and adds filter-weighted radiance
// to every pixel within the filter's radius (entry point `splat`, run after `main`, gathers
// each pixel's share from its neighbours' samples), each pixel the weighted mean. A sample that
// records hit points keeps the filter-distributed position instead (the caustic's pixel filter
// is the distribution of its hit points) and counts `fis_weight`, the weight a splatted sample
// brings a pixel on average, so that both kinds of sample estimate the same filtered pixel.
// A filter with negative lobes (`splat` 2) splats those samples too: they are drawn from |f|
// (common::signed_filter), so each is splatted with f over the density of all pixels' draws
// at its position, and only its hit points carry its signed weight f / (q F_W).

#import common::rng::{rng_stream, rng_next_f32, rng_next_vec2}
#import common::sampling::{PI, INV_PI, power_heuristic, max_component, any_not_finite}
#import common::scene::{scene_info, materials, Material, NO_HIT, NO_LIGHT, UNBOUNDED, MATERIAL_DIFFUSE}
#import common::intersection::Hit
#import common::traversal::intersect_scene
#import common::surface::{Surface, surface_at, spawn_origin}
#import common::material::material_has_continuous_lobe
#import common::path_step::{Vertex, arrive, bounce, direct_light}
#ifdef BLENDS
#import common::scene::MATERIAL_NULL
#else
#ifdef MEDIA
#import common::scene::MATERIAL_NULL
#endif
#endif
#ifdef MEDIA
#import common::scene::NO_MEDIUM
#import common::medium::{MAX_CROSSINGS, Medium, medium_at, medium_after, sample_free_flight, phase_sample, phase_eval}
#import common::path_step::{medium_vertex, front_normal}
#endif
#ifdef GLOSSY
#import common::material::material_specular_share
#endif
#import common::camera::{CameraRay, camera_ray, camera_ray_through, has_lens, film_index, film_pixel}
#import common::signed_filter::signed_draw_density
#import common::pixel_filter::{filter_radius, filter_weight}
#import common::lights::area_light_pdf
#ifdef ENVIRONMENT
#import common::environment::escaped
#endif
#import common::bsdf::BsdfSample
#import common::hit_points::{HitPoint, HitPointBuffer, RadiusBuffer, PhotonHitsIn, NO_PIXEL, initial_radius}
#import common::photon_grid::{PhotonGridInfo, photon_cell, photon_bucket}
#import gpu::sample_mask::{SampleMask, SAMPLED}

struct PathTraceUniform {
    sample_base: u32,
    samples_per_iteration: u32,
    seed: u32,
    max_depth: u32,
    rr_depth: u32,
    // Photon-mapped diffuse vertices per path (hit-point slots per pixel); 0 = none.
    merge_depth: u32,
    // 1: write this iteration's hit points; 0: keep the ones stored (ppm) and only refresh their
    // radii from the estimator's.
    record: u32,
    // 1: continue paths past photon-mapped vertices (hybrid); 0: stop there (photon mapping only).
    trace_beyond: u32,
    // 1: look caustics up in the photon grid at diffuse vertices past the hit points.
    lookups: u32,
    // 1: splat samples through the pixel filter (see the top of the file); 2: also splat the
    // samples that record hit points (a filter with negative lobes).
    splat: u32,
    // What a filter-distributed sample counts when splatting (1 otherwise).
    fis_weight: f32,
    // Microfacet lobes smoother than this are specular vertices (read with GLOSSY only).
    glossy_threshold: f32,
}

struct PhotonGridIn {
    info: PhotonGridInfo,
    words: array<u32>,
}

@group(1) @binding(0) var<uniform> params: PathTraceUniform;
@group(1) @binding(1) var<storage, read_write> radiance: array<vec4<f32>>;
// The counters, [rays low, rays high, discarded low, discarded high] (64-bit totals from 32-bit
// atomics), then this iteration's splatted samples (radiance, and 1 in w, or 1 / the draw
// density for a drawn one; 0 for a sample that is not splatted or was dropped),
// samples_per_iteration per pixel; with `splat` 2 then each pixel's drawn sample's offset from
// its centre (xy).
struct Film {
    counters: array<atomic<u32>, 4>,
    samples: array<vec4<f32>>,
}

@group(1) @binding(2) var<storage, read_write> film: Film;
@group(1) @binding(3) var<storage, read_write> hit_points: HitPointBuffer;
// The estimator's radii as of the previous iteration (0: none yet, take the rule's first).
@group(1) @binding(4) var<storage, read> radii: RadiusBuffer;
// This iteration's caustic photon hits and the grid over them (stand-ins when not looking up).
@group(1) @binding(5) var<storage, read> photons: PhotonHitsIn;
@group(1) @binding(6) var<storage, read> photon_grid: PhotonGridIn;
// Adaptive sampling: the pixels to sample (with hit points recorded, every pixel is).
@group(1) @binding(7) var<storage, read> sample_mask: SampleMask;

const COUNTER_RAYS: u32 = 0u;
const COUNTER_DISCARDED: u32 = 2u;
// Hard stop for unbounded depth with Russian roulette off; a closed lossless scene would
// otherwise never end a path.
const SAFETY_MAX_DEPTH: u32 = 1024u;

fn add_u64(index: u32, value: u32) {
    if value == 0u {
        return;
    }
    let old = atomicAdd(&film.counters[index], value);
    if old > 0xffffffffu - value {
        atomicAdd(&film.counters[index + 1u], 1u);
    }
}

struct PathState {
    origin: vec3<f32>,
    dir: vec3<f32>,
    throughput: vec3<f32>,
    // Solid-angle density of the last BSDF sample, for MIS when it reaches a light.
    bsdf_pdf: f32,
    // The last vertex was delta (or the camera): emission reached through it takes full weight.
    after_delta: bool,
    // The last diffuse vertex was photon-mapped: emission reached from it through specular
    // vertices belongs to photon mapping.
    after_merge: bool,
    diffuse_vertices: u32,
    // Distance travelled from the camera, for the pixel footprint at a hit point.
    travelled: f32,
    // GLOSSY only. Per channel, the share of the throughput whose light photon mapping carries
    // if the path now meets it through specular lobes only: 1 from a photon-mapped vertex on,
    // kept through specular lobes, cut to the coating's share at a rough plastic whose coating
    // is specular, 0 after any other lobe.
    mapped: vec3<f32>,
    // GLOSSY only: the last vertex was not diffuse, so `mapped` applies to what is reached now.
    after_specular: bool,
    // The last vertex was a mask's pass-through (BLENDS only).
    through_null: bool,
    // Light gathered so far (throughput-weighted).
    radiance: vec3<f32>,
    // The segment traced next, counting from 1 at the camera.
    depth: u32,
    // The medium the path travels in (common::medium), or NO_MEDIUM.
    medium: u32,
    // Distance from the last scattering vertex to `origin` (null surfaces crossed since), for
    // the light's density when the path reaches it.
    since_scatter: f32,
}

// Where the camera pass hands a sample over to photon mapping.
struct HitPointSink {
    pixel: u32,
    // Record hit points for this sample (the first sample of the iteration, when recording).
    enabled: bool,
    // What the sample counts in its pixel (its camera ray's weight): a hit point's weight
    // carries it, negative where a pixel filter is.
    film_weight: f32,
}

// Whether this iteration's first sample of each pixel records hit points (`main` draws it, and
// with `splat` 2 the splat kernel finds it again).
fn records_hit_points() -> bool {
    return params.merge_depth > 0u && params.record != 0u;
}

fn record_hit_point(sink: HitPointSink, slot: u32, surface: Surface, wo: vec3<f32>, depth: u32, weight: vec3<f32>, travelled: f32) {
    let index = sink.pixel * params.merge_depth + slot;
    let footprint = travelled * abs(scene_info.plane_step_x);
    var radius = radii.radii[index];
    if radius <= 0.0 {
        radius = initial_radius(radii.rule, footprint);
    }
    hit_points.points[index] = HitPoint(surface.position, sink.pixel, surface.normal, radius, wo, depth, weight * sink.film_weight, footprint);
}

// The caustic this iteration's photons bring to vertex `v` (`depth` camera segments from the
// camera), as the radiance it sends back along `back_dir`: only photons whose whole path obeys
// max_depth count. On a Lambertian surface the flux arriving from the front over the disc's
// area (Knaus & Zwicker's estimate, with a constant kernel) times albedo / pi; in a medium (`v`
// in the one at offset `medium`) each photon's flux times the phase function from its
// direction, over the ball's volume (Jensen and Christensen 1998's volume radiance estimate,
// with its extinction already in the stored flux, photon_trace.wgsl), which the camera path's
// throughput after scattering (sigma_s over the distance's density) turns into what the vertex
// sends. One call site for both, as for the light sample (see direct_light).
fn caustic_from_photons(v: Vertex, depth: u32, medium: u32) -> vec3<f32> {
    let r = photon_grid.info.radius;
    var normal = v.surface.normal;
    var scale = v.material.albedo * INV_PI / (PI * (r * r));
#ifdef MEDIA
    if v.in_medium {
        normal = vec3<f32>(0.0);
        scale = vec3<f32>(1.0 / (4.0 / 3.0 * PI * r * r * r));
    }
#endif
    return scale * nearby_photons(v.surface.position, normal, depth, v.in_medium, v.back_dir, medium);
}

// The flux of this iteration's photons within the grid's radius of `position` whose whole path
// obeys max_depth: surface photons arriving from the front of `normal`, or (`in_medium`, with
// MEDIA) photons that scattered in a medium, each weighted by the phase function of the medium
// at offset `medium` towards `towards`.
fn nearby_photons(position: vec3<f32>, normal: vec3<f32>, depth: u32, in_medium: bool, towards: vec3<f32>, medium: u32) -> vec3<f32> {
    let info = photon_grid.info;
#ifdef MEDIA
    var m: Medium;
    if in_medium {
        m = medium_at(medium);
    }
#endif
    let r2 = info.radius * info.radius;
    let lo = photon_cell(info, position - vec3<f32>(info.radius));
    let hi = min(photon_cell(info, position + vec3<f32>(info.radius)), lo + vec3<i32>(1));
    let links = info.bucket_mask + 1u;
    let words = arrayLength(&photon_grid.words);
    // The cells and their lists walked in one loop: a SIMD group then runs for its lanes'
    // longest walk, not the sum of each nesting level's longest.
    let span = vec3<u32>(hi - lo) + vec3<u32>(1u);
    let cells = span.x * span.y * span.z;
    var next_cell = 0u;
    var cell = lo;
    var link = 0u;
    var flux = vec3<f32>(0.0);
    // A list is at most every photon hit long; the bound keeps a corrupt one finite.
    let most_steps = (info.count + 1u) * cells;
    for (var steps = 0u; steps < most_steps; steps++) {
        if link == 0u {
            if next_cell == cells {
                break;
            }
            let c = vec3<u32>(next_cell % span.x, (next_cell / span.x) % span.y, next_cell / (span.x * span.y));
            cell = lo + vec3<i32>(c);
            link = photon_grid.words[photon_bucket(info, cell)];
            next_cell += 1u;
            continue;
        }
        let hit = photons.hits[link - 1u];
        let next = links + link - 1u;
        link = select(0u, photon_grid.words[next], next < words);
        // Buckets hold other cells' lists too: take each photon in its own cell only.
        if any(photon_cell(info, hit.position) != cell) {
            continue;
        }
        let d = hit.position - position;
        if !(dot(d, d) <= r2) {
            continue;
        }
        if hit.remaining != UNBOUNDED && depth > hit.remaining {
            continue;
        }
#ifdef MEDIA
        if (hit.in_medium != 0u) != in_medium {
            continue;
        }
        if in_medium {
            flux += hit.flux * phase_eval(m, -hit.wi, towards);
            continue;
        }
#endif
        if dot(hit.wi, normal) <= 0.0 {
            continue;
        }
        flux += hit.flux;
    }
    return flux;
}

// Emission the path reaches now takes full weight, not MIS's: light sampling could not have
// found it (the last vertex was delta, the camera, or a pass-through whose surface blocked
// the light sample of the vertex before).
fn full_weight(path: PathState) -> bool {
    return path.after_delta || path.through_null;
}

// Per channel, the share of the light a path reaches now that path tracing counts: all of it,
// but for light reached from a photon-mapped vertex through specular vertices only, whose
// photons' share photon mapping counts (docs/design.md section 1). Without glossy lobes in the
// partition that share is all or nothing and the state is two flags; with them it is `mapped`.
fn path_traced_share(path: PathState) -> vec3<f32> {
#ifdef GLOSSY
    return select(vec3<f32>(1.0), vec3<f32>(1.0) - path.mapped, path.after_specular);
#else
    return select(vec3<f32>(1.0), vec3<f32>(0.0), path.after_delta && path.after_merge);
#endif
}

// After a bounce off a non-Lambertian BSDF: a specular lobe (delta, or glossy below the
// threshold) keeps the photons' share of what the path reaches next; any other lobe is a
// path-traced vertex, after which that light is path tracing's.
fn keep_photon_share(path: ptr<function, PathState>, material: Material, wi: vec3<f32>, s: BsdfSample) {
#ifdef GLOSSY
    (*path).mapped *= material_specular_share(material, wi, s, params.glossy_threshold);
    (*path).after_merge = max_component((*path).mapped) > 0.0;
    (*path).after_specular = true;
#else
    (*path).after_merge = (*path).after_merge && s.delta;
#endif
}

#ifdef ENVIRONMENT
// The environment seen by a path that escapes, under the same rules as an area light's
// emission: dropped when photon mapping counts it (reached from a photon-mapped vertex through
// specular ones; with GLOSSY, the share photons carry), MIS-weighted against light sampling
// after a non-delta vertex.
fn environment_emission(path: PathState) -> vec3<f32> {
    if scene_info.environment == NO_LIGHT {
        return vec3<f32>(0.0);
    }
    let kept = path_traced_share(path);
    if max_component(kept) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let seen = escaped(path.dir);
    var weight = 1.0;
    if !full_weight(path) {
        weight = power_heuristic(path.bsdf_pdf, seen.pdf);
    }
    return kept * seen.radiance * weight;
}
#endif

// The primary ray of a sample: through a uniform point of the pixel when it is splatted, else
// with the pixel filter's distribution. Always the stream's first two numbers (`splat` finds
// the point again from them); a thin lens takes the next two for its aperture.
fn primary_ray(pixel: vec2<u32>, splatted: bool, rng: ptr<function, vec4<u32>>) -> CameraRay {
    let u = rng_next_vec2(rng);
    var lens_u = vec2<f32>(0.0);
    if has_lens() {
        lens_u = rng_next_vec2(rng);
    }
    let on_film = film_pixel(pixel);
    if splatted {
        return camera_ray_through(vec2<f32>(on_film) + u, lens_u);
    }
    return camera_ray(on_film, u, lens_u);
}

// A camera path at the camera, along `ray`.
fn start_path(ray: CameraRay) -> PathState {
    return PathState(ray.origin, ray.dir, vec3<f32>(1.0), 0.0, true, false, 0u, 0.0, vec3<f32>(0.0), false, false, vec3<f32>(0.0), 1u, scene_info.camera_medium, 0.0);
}

// Emitting shapes a camera ray steps through under hide_emitters before it counts as hidden.
const MAX_EMITTER_SKIPS: u32 = 16u;

// The next surface along `path`. Under Mitsuba's hide_emitters (`hidden`) a camera ray steps
// through each emitting shape it meets, up to MAX_EMITTER_SKIPS of them, as Mitsuba skips them.
// The one call site of the closest-hit traversal (see direct_light for why one).
fn next_hit(path: ptr<function, PathState>, hidden: bool, rays: ptr<function, u32>) -> Hit {
    var hit: Hit;
    for (var skips = 0u; skips <= MAX_EMITTER_SKIPS; skips++) {
        *rays += 1u;
        hit = intersect_scene((*path).origin, (*path).dir);
        if !hidden || hit.prim == NO_HIT {
            break;
        }
        let surface = surface_at(hit, (*path).origin, (*path).dir);
        if surface.light == NO_LIGHT || skips == MAX_EMITTER_SKIPS {
            break;
        }
        (*path).origin = spawn_origin(surface, (*path).dir);
        (*path).travelled += hit.t;
    }
    return hit;
}

// Whether a path goes on from its vertex at the end of segment `depth`: not at max_depth, and
// past rr_depth only if it survives Russian roulette (its throughput then divided by the odds).
fn goes_on(path: ptr<function, PathState>, depth: u32, rng: ptr<function, vec4<u32>>) -> bool {
    if depth == min(params.max_depth, SAFETY_MAX_DEPTH) {
        return false;
    }
    if depth >= params.rr_depth {
        let survive = min(max_component((*path).throughput), 0.95);
        if rng_next_f32(rng) >= survive {
            return false;
        }
        (*path).throughput /= survive;
    }
    return true;
}

#ifdef MEDIA
// Crosses `arrived`, `t` along the path's ray, where it is a plain medium boundary: a null
// BSDF (not a blend's) that emits nothing. As in Mitsuba's volpath no vertex (max_depth does
// not count it) and nothing changes but the medium. Crossed inside extend_path's segment loop,
// not by a turn of the path loop: a SIMD group's lanes then wait on a traversal, not on
// a whole vertex's work (BENCHMARKS.md, media). Any other null surface goes the long way.
fn crosses_plain_boundary(path: ptr<function, PathState>, arrived: Surface, t: f32) -> bool {
    let material = materials[arrived.material];
    if material.kind != MATERIAL_NULL || arrived.light != NO_LIGHT {
        return false;
    }
    (*path).medium = medium_after(material, (*path).dir, arrived.normal, (*path).medium);
    (*path).since_scatter += t;
    (*path).travelled += t;
    (*path).origin = spawn_origin(arrived, (*path).dir);
    return true;
}
#endif

// What a path meets at the end of its segment: `ENDS` there, `PASSES` through it with no vertex
// of its own (a medium's boundary, a mask), or `SCATTERS` from vertex `v`, sampling light there
// or not, looking photons up there or not.
const ENDS: u32 = 0u;
const PASSES: u32 = 1u;
const SCATTERS: u32 = 2u;

struct Arrival {
    what: u32,
    v: Vertex,
    samples_light: bool,
    // The vertex takes the caustic from the photon grid (and the path then drops it).
    looks_up: bool,
}

fn arrival_of(what: u32) -> Arrival {
    var a: Arrival;
    a.what = what;
    return a;
}

// Traces the next segment of `path`, adds the light it reaches to its radiance and samples the
// direction after it. Returns whether the path goes on. A vertex in a medium and one on a
// surface share the light sample, so that a SIMD group whose lanes meet both runs the shadow
// ray's code once, not once for each (BENCHMARKS.md, media).
fn extend_path(path: ptr<function, PathState>, sink: HitPointSink, rng: ptr<function, vec4<u32>>, rays: ptr<function, u32>) -> bool {
    // `depth` counts segments traced so far, this one included (Mitsuba's rule).
    let depth = (*path).depth;
    if depth > min(params.max_depth, SAFETY_MAX_DEPTH) {
        return false;
    }
    // Mitsuba's hide_emitters: what the camera sees directly leaves out every emitter.
    let hidden = depth == 1u && scene_info.hide_emitters != 0u;
    var hit: Hit;
    var arrived: Surface;
    // Without MEDIA one pass; with it, the segments of the ray between plain medium boundaries,
    // up to a scattering in a medium (`scattered_at` along the last one).
    var crossings = 0u;
    var scattered_at = -1.0;
    loop {
        hit = next_hit(path, hidden, rays);
#ifdef MEDIA
        if (*path).medium != NO_MEDIUM {
            let flight = sample_free_flight(medium_at((*path).medium), (*path).origin, (*path).dir, hit.t, rng);
            (*path).throughput *= flight.weight;
            if flight.scattered {
                scattered_at = flight.t;
                break;
            }
        }
#endif
        if hit.prim == NO_HIT {
#ifdef ENVIRONMENT
            if !hidden {
                (*path).radiance += (*path).throughput * environment_emission(*path);
            }
#endif
            return false;
        }
        arrived = surface_at(hit, (*path).origin, (*path).dir);
#ifdef MEDIA
        if crossings < MAX_CROSSINGS && crosses_plain_boundary(path, arrived, hit.t) {
            crossings += 1u;
            continue;
        }
#endif
        break;
    }
    var arrival: Arrival;
    if scattered_at >= 0.0 {
#ifdef MEDIA
        arrival = arrive_in_medium(path, scattered_at, depth, rng);
#endif
    } else {
        arrival = arrive_at_surface(path, hit, arrived, hidden, depth, sink, rng);
    }
    if arrival.what != SCATTERS {
        return arrival.what == PASSES;
    }
    let v = arrival.v;
    if arrival.looks_up {
        (*path).radiance += (*path).throughput * caustic_from_photons(v, depth, (*path).medium);
    }
    // One next-event estimate for every vertex and lobe light sampling can reach (see
    // direct_light).
    if arrival.samples_light {
        (*path).radiance += (*path).throughput * direct_light(v, (*path).medium, (*path).mapped, params.glossy_threshold, rng, rays);
    }
    if v.in_medium {
#ifdef MEDIA
        leave_medium_vertex(path, v, rng);
#endif
    } else if !leave_surface(path, v, rng) {
        return false;
    }
    if max_component((*path).throughput) <= 0.0 {
        return false;
    }
    (*path).depth = depth + 1u;
    return true;
}

// The path arrives at surface `arrived` (`hit` along its segment): the emission it sees there,
// a medium's boundary or a mask passed through, a diffuse vertex's hit point or photon lookup.
fn arrive_at_surface(path: ptr<function, PathState>, hit: Hit, arrived: Surface, hidden: bool, depth: u32, sink: HitPointSink, rng: ptr<function, vec4<u32>>) -> Arrival {
    let wo = -(*path).dir;
    let cos_o = dot(wo, arrived.normal);
    (*path).travelled += hit.t;

    let kept = path_traced_share(*path);
    if arrived.light != NO_LIGHT && cos_o > 0.0 && !hidden && max_component(kept) > 0.0 {
        // The rest keeps its MIS weight (after a glossy lobe, its pdf, not a delta's).
        var weight = 1.0;
        if !full_weight(*path) {
            weight = power_heuristic((*path).bsdf_pdf, area_light_pdf(arrived.light, (*path).since_scatter + hit.t, cos_o));
        }
        (*path).radiance += (*path).throughput * kept * materials[arrived.material].emission * weight;
    }
    // The side and blend child this vertex scatters with, textured, in its shading frame.
    let v = arrive(arrived, hit.prim, wo, true, rng);
    let surface = v.surface;
    let material = v.material;
#ifdef MEDIA
    if material.kind == MATERIAL_NULL {
        // A medium's boundary (or a mask's pass-through): as in Mitsuba's volpath, no vertex
        // (max_depth does not count it) and nothing changes but the medium. Light sampled from
        // the vertex before passed through a boundary (null) but not a mask (a blend's null).
        (*path).medium = medium_after(materials[arrived.material], (*path).dir, arrived.normal, (*path).medium);
        (*path).since_scatter += hit.t;
        (*path).through_null = (*path).through_null || v.blended;
        (*path).origin = spawn_origin(surface, (*path).dir);
        return arrival_of(PASSES);
    }
#endif
    if !goes_on(path, depth, rng) {
        return arrival_of(ENDS);
    }
#ifdef BLENDS
    if material.kind == MATERIAL_NULL {
        // A mask's pass-through, a vertex as in Mitsuba (it counts towards max_depth) that
        // leaves the path's class alone. Light sampled from the vertex before was blocked by
        // this surface, so what lies behind it takes full weight.
        (*path).origin = spawn_origin(surface, (*path).dir);
        (*path).through_null = true;
        (*path).depth = depth + 1u;
        return arrival_of(PASSES);
    }
    (*path).through_null = false;
#endif

    let diffuse = material.kind == MATERIAL_DIFFUSE;
    var looked_up = false;
    if diffuse {
        // One-sided, as Mitsuba's diffuse: black from behind, and where the shading normal
        // turns away from the viewer.
        if v.cos_back <= 0.0 || dot(surface.shading_normal, wo) <= 0.0 {
            return arrival_of(ENDS);
        }
        (*path).diffuse_vertices += 1u;
        let at_hit_point = (*path).diffuse_vertices <= params.merge_depth;
        // Past the hit points the photon grid adds the caustic, which the path then drops.
        looked_up = params.lookups != 0u && !at_hit_point;
        (*path).after_merge = at_hit_point || looked_up;
#ifdef GLOSSY
        (*path).mapped = select(vec3<f32>(0.0), vec3<f32>(1.0), (*path).after_merge);
        (*path).after_specular = false;
#endif
        if at_hit_point {
            let weight = (*path).throughput * material.albedo * INV_PI;
            if sink.enabled && max_component(weight) > 0.0 {
                record_hit_point(sink, (*path).diffuse_vertices - 1u, surface, wo, depth, weight, (*path).travelled);
            }
            if params.trace_beyond == 0u {
                return arrival_of(ENDS);
            }
        }
    }
    return Arrival(SCATTERS, v, diffuse || material_has_continuous_lobe(material.kind), looked_up);
}

// Leaves surface vertex `v` by its BSDF's sample; false where it has none.
fn leave_surface(path: ptr<function, PathState>, v: Vertex, rng: ptr<function, vec4<u32>>) -> bool {
    let out = bounce(v, true, rng);
    if !out.sample.valid {
        return false;
    }
    (*path).dir = out.dir;
    (*path).throughput *= out.weight;
    (*path).after_delta = out.sample.delta;
    if !out.sample.delta {
        (*path).bsdf_pdf = out.sample.pdf;
    }
    if v.material.kind != MATERIAL_DIFFUSE {
        keep_photon_share(path, v.material, v.back_dir * v.shading.frame, out.sample);
    }
    (*path).origin = spawn_origin(v.surface, (*path).dir);
#ifdef MEDIA
    (*path).medium = medium_after(materials[v.surface.material], (*path).dir, front_normal(v), (*path).medium);
    (*path).since_scatter = 0.0;
#endif
    return true;
}

#ifdef MEDIA
// A camera path scatters in its medium, `t` along its segment: a vertex as a surface's is
// (Mitsuba's volpath counts it towards max_depth, Russian roulette as at a surface), with
// next-event estimation with the phase function (MIS against sampling it) where the medium
// samples emitters; the light reaching it through specular vertices is the volumetric
// caustic photons' where the graph looks photons up (docs/light-transport.md).
fn arrive_in_medium(path: ptr<function, PathState>, t: f32, depth: u32, rng: ptr<function, vec4<u32>>) -> Arrival {
    let position = (*path).origin + (*path).dir * t;
    (*path).travelled += t;
    if !goes_on(path, depth, rng) {
        return arrival_of(ENDS);
    }
    // With photon-grid lookups the vertex takes the volumetric caustic (L S+ M) from photons
    // and drops it from what the path reaches next, as a diffuse vertex past the hit points
    // takes the surface caustic; without, it is path traced whole.
    let looked_up = params.lookups != 0u;
    (*path).after_merge = looked_up;
#ifdef GLOSSY
    (*path).mapped = select(vec3<f32>(0.0), vec3<f32>(1.0), looked_up);
    (*path).after_specular = false;
#endif
    return Arrival(SCATTERS, medium_vertex(position, -(*path).dir), medium_at((*path).medium).sample_emitters, looked_up);
}

// Leaves a medium vertex by the phase function's sample.
fn leave_medium_vertex(path: ptr<function, PathState>, v: Vertex, rng: ptr<function, vec4<u32>>) {
    let m = medium_at((*path).medium);
    let d_in = (*path).dir;
    let wo = phase_sample(m, d_in, rng_next_vec2(rng));
    (*path).bsdf_pdf = phase_eval(m, d_in, wo);
    // Without light sampling here, light the path reaches next takes full weight.
    (*path).after_delta = !m.sample_emitters;
    (*path).through_null = false;
    (*path).dir = wo;
    (*path).origin = v.surface.position;
    (*path).since_scatter = 0.0;
}
#endif

// Clears (when recording) or refreshes the hit-point slots of `pixel_index` before its samples.
fn prepare_hit_points(pixel_index: u32, recording: bool) {
    for (var slot = 0u; slot < params.merge_depth; slot++) {
        let index = pixel_index * params.merge_depth + slot;
        if recording {
            hit_points.points[index].pixel = NO_PIXEL;
        } else if hit_points.points[index].pixel != NO_PIXEL && radii.radii[index] > 0.0 {
            hit_points.points[index].radius = radii.radii[index];
        }
    }
}

// Whether the sample mask leaves `pixel_index` out of this iteration. Hit points are recorded
// for every pixel: the estimators count each pixel's photons per iteration.
fn masked() -> bool {
    return params.merge_depth == 0u && sample_mask.enabled != 0u;
}

fn skipped(pixel_index: u32) -> bool {
    return masked() && (sample_mask.words[pixel_index] & SAMPLED) == 0u;
}

// The pixels this iteration samples, and the `item`-th of them.
fn sampled_pixels(pixels: u32) -> u32 {
    return select(pixels, sample_mask.sampled, masked());
}

fn sampled_pixel(item: u32, pixels: u32) -> u32 {
    return select(item, sample_mask.words[pixels + item], masked());
}

fn pixel_of(pixel_index: u32) -> vec2<u32> {
    return vec2<u32>(pixel_index % scene_info.width, pixel_index / scene_info.width);
}

// Each invocation renders the samples of pixels first, first + invocations, ... (of the
// sampled ones, with adaptive sampling) one after another, and starts the next sample in the
// same lane as soon as a path ends (path regeneration, Novak et al. 2010): SIMD lanes whose
// paths end early would otherwise idle until the longest path of their group ends.
@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let pixels = scene_info.width * scene_info.height;
    let invocations = groups.x * 64u;
    if id.x >= pixels {
        return;
    }
    let recording = records_hit_points();
    for (var p = id.x; p < pixels; p += invocations) {
        prepare_hit_points(p, recording);
    }
    // The invocation's items are the sampled pixels item, item + invocations, ...
    let items = sampled_pixels(pixels);
    var item = id.x;
    if item >= items {
        return;
    }
    var pixel_index = sampled_pixel(item, pixels);
    let spp = params.samples_per_iteration;
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    var accepted = 0u;
    var discarded = 0u;
    var rays = 0u;
    var s = 0u;
    var rng = rng_stream(film_index(pixel_index), params.sample_base, params.seed);
    var splatted = params.splat != 0u && !recording;
    var ray = primary_ray(pixel_of(pixel_index), splatted, &rng);
    var sink = HitPointSink(pixel_index, recording, ray.weight);
    var path = start_path(ray);
    loop {
        if extend_path(&path, sink, &rng, &rays) {
            continue;
        }
        let sample = path.radiance * ray.weight;
        // One NaN or Inf sample (or one that would overflow the sum) must not poison the
        // pixel: drop it and count it.
        if splatted || params.splat == 2u {
            // A uniformly placed sample counts 1 per unit area; a drawn one 1 / density.
            var splat_sample = vec4<f32>(path.radiance, 1.0);
            if !splatted {
                let density = signed_draw_density(ray.film_position);
                splat_sample.w = select(0.0, 1.0 / density, density > 0.0);
                // Where it was drawn, for `splat` (cheaper than drawing it again there).
                let centre = vec2<f32>(film_pixel(pixel_of(pixel_index))) + 0.5;
                film.samples[pixels * spp + pixel_index] = vec4<f32>(ray.film_position - centre, 0.0, 0.0);
            }
            let keep = !any_not_finite(splat_sample.xyz) && !any_not_finite(vec3<f32>(splat_sample.w));
            film.samples[pixel_index * spp + s] = select(vec4<f32>(0.0), splat_sample, keep);
            accepted += u32(keep);
        } else {
            if params.splat != 0u {
                film.samples[pixel_index * spp + s] = vec4<f32>(0.0);
            }
            // The sample's filter weight is in `sample`, and the pixel's count takes its mean,
            // not the weight itself: a ratio of signed sums blows up where the weights of a
            // few samples cancel (a pixel is then the plain mean of weighted samples, which a
            // signed filter leaves noisy in flat regions: weights ±1.85 for Lanczos 3, variance
            // 2.4 L^2 a sample; only with sample_border, as `splat` 2 splats the rest).
            let next = sum + sample * params.fis_weight;
            if !any_not_finite(next) {
                sum = next;
                weight += params.fis_weight;
                accepted += 1u;
            }
        }
        s += 1u;
        if s == spp {
            let total = radiance[pixel_index] + vec4<f32>(sum, weight);
            if any_not_finite(total.xyz) {
                accepted = 0u;
            } else {
                radiance[pixel_index] = total;
            }
            discarded += spp - accepted;
            sum = vec3<f32>(0.0);
            weight = 0.0;
            accepted = 0u;
            s = 0u;
            item += invocations;
            if item >= items {
                break;
            }
            pixel_index = sampled_pixel(item, pixels);
        }
        rng = rng_stream(film_index(pixel_index), params.sample_base + s, params.seed);
        let records = recording && s == 0u;
        splatted = params.splat != 0u && !records;
        ray = primary_ray(pixel_of(pixel_index), splatted, &rng);
        sink = HitPointSink(pixel_index, records, ray.weight);
        path = start_path(ray);
    }
    add_u64(COUNTER_RAYS, rays);
    add_u64(COUNTER_DISCARDED, discarded);
}

// Each pixel's share of this iteration's splatted samples within the filter's reach: the
// filter's weight at the sample's offset from the pixel centre, separable in x and y.
@compute @workgroup_size(8, 8, 1)
fn splat(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= scene_info.width || id.y >= scene_info.height {
        return;
    }
    let kind = scene_info.filter_kind;
    let param = vec2<f32>(scene_info.filter_param, scene_info.filter_param_b);
    let radius = filter_radius(kind, param.x);
    // A sample placed in its pixel reaches pixels `near` away; one drawn from a signed filter
    // (its pixel's first when `splat` is 2 and hit points are recorded) up to the radius from
    // its pixel's centre, so pixels `far` away.
    let near = i32(ceil(radius - 0.5));
    let recording = records_hit_points();
    let drawn_first = params.splat == 2u && recording;
    let far = select(near, i32(ceil(2.0 * radius)) - 1, drawn_first);
    let size = vec2<i32>(i32(scene_info.width), i32(scene_info.height));
    let spp = params.samples_per_iteration;
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    for (var dy = -far; dy <= far; dy++) {
        for (var dx = -far; dx <= far; dx++) {
            let q = vec2<i32>(id.xy) + vec2<i32>(dx, dy);
            if any(q < vec2<i32>(0)) || any(q >= size) {
                continue;
            }
            let placed_reach = abs(dx) <= near && abs(dy) <= near;
            let q_index = u32(q.y) * scene_info.width + u32(q.x);
            // A pixel the mask skipped holds an earlier iteration's samples.
            if skipped(q_index) {
                continue;
            }
            for (var s = 0u; s < spp; s++) {
                let drawn = drawn_first && s == 0u;
                if !drawn && !placed_reach {
                    continue;
                }
                // From the integer step, not film positions: the same rounding in every pixel
                // (and in a band of the image as in the whole).
                var within: vec2<f32>;
                if drawn {
                    within = film.samples[u32(size.x * size.y) * spp + q_index].xy;
                } else {
                    var rng = rng_stream(film_index(q_index), params.sample_base + s, params.seed);
                    within = rng_next_vec2(&rng) - 0.5;
                }
                let offset = vec2<f32>(f32(dx), f32(dy)) + within;
                // Most drawn samples of far neighbours land out of reach.
                if any(abs(offset) >= vec2<f32>(radius)) {
                    continue;
                }
                let sample = film.samples[q_index * spp + s];
                if sample.w == 0.0 {
                    continue;
                }
                let w = sample.w * filter_weight(kind, param, offset.x) * filter_weight(kind, param, offset.y);
                sum += w * sample.xyz;
                weight += w;
            }
        }
    }
    let pixel_index = id.y * scene_info.width + id.x;
    let total = radiance[pixel_index] + vec4<f32>(sum, weight);
    // A filter with negative lobes can sum to any sign; no sample sums to exactly 0.
    if weight != 0.0 && !any_not_finite(total.xyz) {
        radiance[pixel_index] = total;
    }
}
