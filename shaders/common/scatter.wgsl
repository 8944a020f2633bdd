#define_import_path common::scatter

// How a ray leaves a surface, shared by the camera and photon passes: one chain over the
// material kinds with a transport mode (radiance for camera paths, importance for photons,
// which carry flux and take no 1/eta^2 at a refraction), as pbrt-v4 samples its BSDFs. The
// Lambertian lobe stays with each pass: that is where they differ (hit points, deposits).

#import common::scene::{Material, MATERIAL_MIRROR, MATERIAL_DIELECTRIC}
#import common::surface::Surface
#import common::rng::{rng_next_f32, rng_next_vec2}
#import common::bsdf::{BsdfSample, no_sample, reflect_about}
#ifdef DIELECTRIC
#import bsdfs::dielectric::sample_dielectric
#endif
#import common::material::material_sample
#import bsdfs::normalmap::ShadingFrame

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
