#define_import_path common::path_step

// One step of a path, written once for every estimator: arriving at a surface (the side and
// the blend child chosen, textures looked up, the shading frame perturbed), leaving it (the
// Lambertian lobe or the BSDF's sampler, with the frame's corrections for the transport mode)
// and next-event estimation. Radiance is the camera's transport mode, importance the photons'
// (flux, no 1/eta^2 at a refraction), as pbrt-v4 samples its BSDFs. What a path does with a
// vertex (record a hit point, deposit a photon, drop the light photons carry) is the pass's
// policy around these calls: the light-transport partition of docs/light-transport.md, which a
// bidirectional estimator or a medium would replace with its own while reusing the steps.

#import common::scene::{Material, MATERIAL_DIFFUSE, MATERIAL_MIRROR, MATERIAL_DIELECTRIC}
#import common::surface::{Surface, unoccluded, photon_shading_correction}
#import common::rng::{rng_next_f32, rng_next_vec2}
#import common::sampling::{INV_PI, sample_cosine_hemisphere, power_heuristic, max_component}
#import common::bsdf::{BsdfSample, no_sample, reflect_about}
#ifdef DIELECTRIC
#import bsdfs::dielectric::sample_dielectric
#endif
#import common::material::{material_eval, material_sample}
#ifdef GLOSSY
#import common::material::material_specular_eval
#endif
#import common::lights::sample_light
#import bsdfs::blendbsdf::choose_material
#ifdef TEXTURES
#import common::texture::textured_material
#endif
#import bsdfs::normalmap::{ShadingFrame, plain_frame, frame_factor}
#ifdef NORMAL_MAPS
#import bsdfs::normalmap::shading_frame
#endif
#ifdef MEDIA
#import common::scene::materials
#import common::medium::{medium_at, medium_after, phase_eval, transmittance_between}
#endif

// The surface as the chosen side sees it: a twosided material's back turns the normals over.
fn seen_from(surface: Surface, back: bool) -> Surface {
    var s = surface;
    if back {
        s.normal = -s.normal;
        s.shading_normal = -s.shading_normal;
    }
    return s;
}

struct Scattered {
    // World direction the ray leaves by.
    dir: vec3<f32>,
    // f cos / pdf with the material's tint, before the shading frame's corrections (which the
    // camera and the photon pass apply each their own way).
    weight: vec3<f32>,
    // The lobe's sample in the shading frame: its pdf, whether it is delta, whether any.
    sample: BsdfSample,
}

fn no_scatter() -> Scattered {
    return Scattered(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), no_sample());
}

// Leaves a surface of any kind but Lambertian. `back_dir` points back along the arriving ray
// (to the camera for radiance, to the light for photons) and `cos_geometric` is its cosine with
// the seen side's geometric normal. Random numbers: none for a mirror, one for a smooth
// dielectric, three for the others, in that order.
fn scatter(material: Material, shading: ShadingFrame, cos_geometric: f32, back_dir: vec3<f32>, radiance: bool, rng: ptr<function, vec4<u32>>) -> Scattered {
    let n = shading.frame[2];
    if material.kind == MATERIAL_MIRROR {
        // One-sided, as Mitsuba's conductor: nothing from behind.
        if cos_geometric <= 0.0 || dot(back_dir, n) <= 0.0 {
            return no_scatter();
        }
        let dir = reflect_about(back_dir, n);
        return Scattered(dir, vec3<f32>(1.0), BsdfSample(dir * shading.frame, vec3<f32>(1.0), 1.0, true, true));
    }
    if material.kind == MATERIAL_DIELECTRIC {
#ifdef DIELECTRIC
        let s = sample_dielectric(back_dir, n, material.int_ior, material.ext_ior, rng_next_f32(rng), radiance);
        let weight = select(material.albedo, material.specular, s.reflected) * s.weight;
        return Scattered(s.dir, weight, BsdfSample(s.dir * shading.frame, weight, 1.0, true, true));
#else
        return no_scatter();
#endif
    }
    let u1 = rng_next_f32(rng);
    let s = material_sample(material, back_dir * shading.frame, u1, rng_next_vec2(rng), radiance);
    if !s.valid {
        return no_scatter();
    }
    return Scattered(normalize(shading.frame * s.wo), s.weight, s);
}

// A path's vertex at a surface, as the material's chosen side sees it.
struct Vertex {
    // Its normals turned over for a twosided material's back; its shading normal the frame's.
    surface: Surface,
    // The side's BSDF (a blend's chosen child) with its textures looked up.
    material: Material,
    shading: ShadingFrame,
    // Back along the arriving ray: towards the camera for radiance, the light for importance.
    back_dir: vec3<f32>,
    // Its cosine with the seen side's geometric normal, and with the surface's own (before a
    // back side turned it).
    cos_back: f32,
    facing: f32,
    back: bool,
    // A blend chose among children (random numbers were drawn).
    blended: bool,
    // A scattering point in a medium (MEDIA only): `surface` holds its position alone, and
    // the medium's phase function stands for the BSDF.
    in_medium: bool,
}

// Arrives at `surface` (of primitive `prim`) from `back_dir`: the side and blend child chosen
// (random numbers only at blends), their textures looked up, the normal or bump map's frame.
// `radiance` is the camera's view, whose invalid perturbed normals are flipped as its viewer
// sees them; a photon takes them as not flipped.
fn arrive(surface_hit: Surface, prim: u32, back_dir: vec3<f32>, radiance: bool, rng: ptr<function, vec4<u32>>) -> Vertex {
    let facing = dot(back_dir, surface_hit.normal);
    let chosen = choose_material(surface_hit.material, facing, surface_hit.uv, rng);
    var surface = seen_from(surface_hit, chosen.back);
    var material = chosen.material;
#ifdef TEXTURES
    // Before any use of the colours: NEE, the bounce, hit-point weights, deposits.
    material = textured_material(material, surface.uv);
#endif
    // The BSDF's frame: a normal or bump map turns the shading normal every use below shades
    // with (which vertices are diffuse or specular stays the material's kind).
    var shading = plain_frame(surface.shading_normal);
#ifdef NORMAL_MAPS
    shading = shading_frame(material, surface, prim, chosen.back, back_dir, radiance);
    surface.shading_normal = shading.frame[2];
#endif
    let cos_back = select(facing, -facing, chosen.back);
    return Vertex(surface, material, shading, back_dir, cos_back, facing, chosen.back, chosen.blended, false);
}

#ifdef MEDIA
// A scattering point at `position` in a medium, arrived at from `back_dir`: no normal and no
// error bound (a shadow ray leaves it as it is), the medium's phase function its BSDF.
fn medium_vertex(position: vec3<f32>, back_dir: vec3<f32>) -> Vertex {
    var v: Vertex;
    v.surface.position = position;
    v.back_dir = back_dir;
    v.in_medium = true;
    return v;
}
#endif

// How a path leaves a vertex.
struct Bounce {
    dir: vec3<f32>,
    // f cos / pdf times the shading frame's corrections for the transport mode: the normal
    // map's factor towards the light (`dir` for radiance, where the photon came from for
    // importance) and, for photons, Veach's correction for the shading normal.
    weight: vec3<f32>,
    // The lobe's sample in the shading frame: its pdf (a Lambertian vertex's cos / pi),
    // whether it is delta, whether any.
    sample: BsdfSample,
}

// Leaves `v`: cosine-weighted from a Lambertian vertex, by the BSDF's sampler otherwise (see
// `scatter` for the random numbers each kind takes).
fn bounce(v: Vertex, radiance: bool, rng: ptr<function, vec4<u32>>) -> Bounce {
    var dir: vec3<f32>;
    var weight: vec3<f32>;
    var sample: BsdfSample;
    if v.material.kind == MATERIAL_DIFFUSE {
        dir = sample_cosine_hemisphere(v.surface.shading_normal, rng_next_vec2(rng));
        let cos_o = dot(dir, v.surface.shading_normal);
        // Cosine sampling: f cos / pdf = albedo.
        weight = v.material.albedo;
        sample = BsdfSample(dir * v.shading.frame, weight, cos_o * INV_PI, false, cos_o > 0.0);
    } else {
        let out = scatter(v.material, v.shading, v.cos_back, v.back_dir, radiance, rng);
        dir = out.dir;
        weight = out.weight;
        sample = out.sample;
    }
    if radiance {
        weight = weight * frame_factor(v.shading, dir);
    } else {
        weight = weight * frame_factor(v.shading, v.back_dir) * photon_shading_correction(v.surface, v.back_dir, dir);
    }
    return Bounce(dir, weight, sample);
}

// A BSDF's value towards a light sample (cosine and frame factor included) and its pdf there.
struct BsdfTowards {
    value: vec3<f32>,
    pdf: f32,
}

// What the BSDF at `v` sends back along its `back_dir` of light arriving from world direction
// `dir` (cosine and frame factor included), and its pdf of sampling `dir`. With GLOSSY the
// `mapped` share of the specular lobes' part (lobes smoother than `glossy_threshold`) is left
// out: photons carry it.
fn bsdf_towards(v: Vertex, mapped: vec3<f32>, glossy_threshold: f32, dir: vec3<f32>) -> BsdfTowards {
    let material = v.material;
    let shading = v.shading;
    if material.kind == MATERIAL_DIFFUSE {
        let cos_i = dot(v.surface.shading_normal, dir);
        let factor = frame_factor(shading, dir);
        if cos_i <= 0.0 || factor <= 0.0 {
            return BsdfTowards(vec3<f32>(0.0), 0.0);
        }
        return BsdfTowards(material.albedo * INV_PI * cos_i * factor, cos_i * INV_PI);
    }
    let wi = v.back_dir * shading.frame;
    let local = dir * shading.frame;
    let e = material_eval(material, wi, local, true);
#ifdef GLOSSY
    let specular = material_specular_eval(material, wi, local, e, glossy_threshold);
    return BsdfTowards((e.value - mapped * specular) * frame_factor(shading, dir), e.pdf);
#else
    return BsdfTowards(e.value * frame_factor(shading, dir), e.pdf);
#endif
}

// The surface's geometric normal on its front side, whichever side `v` sees.
fn front_normal(v: Vertex) -> vec3<f32> {
    return select(v.surface.normal, -v.surface.normal, v.back);
}

// What vertex `v` sends back along its `back_dir` of light arriving from world direction `dir`,
// and its pdf of sampling `dir`: its BSDF's (see `bsdf_towards`), or in a medium (`medium`)
// the phase function's.
fn towards_light(v: Vertex, medium: u32, mapped: vec3<f32>, glossy_threshold: f32, dir: vec3<f32>) -> BsdfTowards {
#ifdef MEDIA
    if v.in_medium {
        let phase = phase_eval(medium_at(medium), -v.back_dir, dir);
        return BsdfTowards(vec3<f32>(phase), phase);
    }
#endif
    return bsdf_towards(v, mapped, glossy_threshold, dir);
}

// Next-event estimation at a camera path's vertex: one light sample, MIS-weighted against
// sampling the BSDF or phase function (see `bsdf_towards` for `mapped`). Light is added
// through `rays` shadow rays. Every vertex and lobe that light sampling can reach comes
// through one call site in a pass: lavapipe inlines each call of the shadow ray's traversal,
// its compile time grows with every copy, and a SIMD group runs each copy its lanes reach.
// With MEDIA the shadow ray leaves into the medium on the light's side (the path was in
// `medium`) and carries the transmittance of the media and null boundaries it crosses.
fn direct_light(v: Vertex, medium: u32, mapped: vec3<f32>, glossy_threshold: f32, rng: ptr<function, vec4<u32>>, rays: ptr<function, u32>) -> vec3<f32> {
    let surface = v.surface;
    let u_pick = rng_next_f32(rng);
    let u = rng_next_vec2(rng);
    let ls = sample_light(surface.position, u_pick, u);
    if !ls.valid {
        return vec3<f32>(0.0);
    }
    let towards = towards_light(v, medium, mapped, glossy_threshold, ls.dir);
    if max_component(towards.value) <= 0.0 {
        return vec3<f32>(0.0);
    }
    *rays += 1u;
#ifdef MEDIA
    var leaving = medium;
    if !v.in_medium {
        leaving = medium_after(materials[surface.material], ls.dir, front_normal(v), medium);
    }
    let tr = transmittance_between(surface.position, surface.error, surface.normal, ls.position, ls.error, ls.normal, leaving, rng);
    if max_component(tr) <= 0.0 {
        return vec3<f32>(0.0);
    }
#else
    if !unoccluded(surface.position, surface.error, surface.normal, ls.position, ls.error, ls.normal) {
        return vec3<f32>(0.0);
    }
    let tr = vec3<f32>(1.0);
#endif
    var weight = 1.0;
    if !ls.is_delta {
        weight = power_heuristic(ls.pdf, towards.pdf);
    }
    return towards.value * ls.radiance * tr * weight / ls.pdf;
}
