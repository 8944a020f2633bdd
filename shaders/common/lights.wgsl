#define_import_path common::lights

#import common::scene::{scene_info, lights, light_cdf, triangle_at, Light, LIGHT_TRIANGLE, LIGHT_SPHERE, LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL, LIGHT_CONSTANT, LIGHT_ENVMAP, LIGHT_PROJECTOR, NO_TEXTURE}
#import common::surface::{SurfacePoint, triangle_point}
#ifdef TEXTURES
#import common::texture::texture_eval
#endif
#ifdef SPHERES
#import common::scene::spheres
#import common::surface::sphere_point
#endif
#import common::sampling::{sample_triangle_barycentrics, sample_uniform_sphere}
#ifdef ENVIRONMENT
#import common::environment::sample_environment_light
#endif

struct LightSample {
    // Unit direction from the shading point to the light.
    dir: vec3<f32>,
    distance: f32,
    // The point sampled on the light, its normal and error bound: the far end of the shadow ray
    // (zero normal and error for a point light).
    position: vec3<f32>,
    normal: vec3<f32>,
    error: vec3<f32>,
    // Radiance arriving along `dir` (area and environment lights), intensity x falloff /
    // distance^2 (point and spot lights) or irradiance (directional lights).
    radiance: vec3<f32>,
    // Solid-angle density of this sample including the light choice; for delta lights, the
    // probability of choosing the light.
    pdf: f32,
    is_delta: bool,
    valid: bool,
}

// Index of the light whose interval of the CDF from `start` contains u (binary search over
// inclusive prefix sums).
fn pick_in_light_cdf(start: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = scene_info.num_lights - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if u < light_cdf[start + mid] {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

// A light for next-event estimation, with probability `select_prob`.
fn pick_light(u: f32) -> u32 {
    return pick_in_light_cdf(0u, u);
}

// A light to emit a photon from, with probability `emit_prob`.
fn pick_emitting_light(u: f32) -> u32 {
    return pick_in_light_cdf(scene_info.num_lights, u);
}

// A point on an area light with its front-facing normal and error bound.
fn sample_area_light_point(light: Light, u: vec2<f32>) -> SurfacePoint {
#ifdef SPHERES
    if light.kind == LIGHT_SPHERE {
        // sample_uniform_sphere's direction is not exactly unit (its cosines and sines are a few
        // ulp off, or worse): sphere_point reprojects it onto the sphere.
        return sphere_point(spheres[light.prim], sample_uniform_sphere(u));
    }
#endif
    let tri = triangle_at(light.prim);
    return triangle_point(tri.vertex, tri.edge_a, tri.edge_b, sample_triangle_barycentrics(u));
}

// Solid-angle density of reaching area light `index` at distance `dist`, where the direction
// makes cosine `cos_light` with the light's normal.
fn area_light_pdf(index: u32, dist: f32, cos_light: f32) -> f32 {
    let light = lights[index];
    if cos_light <= 0.0 || light.area <= 0.0 {
        return 0.0;
    }
    return light.select_prob * dist * dist / (light.area * cos_light);
}

#ifdef POINT_LIGHTS
// Mitsuba's spot falloff (src/emitters/spot.cpp): full within the beam width of the axis, zero
// past the cutoff, linear in angle between.
fn spot_falloff(light: Light, cos_theta: f32) -> f32 {
    if cos_theta <= cos(light.cutoff) {
        return 0.0;
    }
    if cos_theta >= cos(light.beam_width) {
        return 1.0;
    }
    return clamp((light.cutoff - acos(clamp(cos_theta, -1.0, 1.0))) / (light.cutoff - light.beam_width), 0.0, 1.0);
}

// Intensity (W/sr) a point light, spot or projector sends along unit world direction `dir`
// (leaving it): Mitsuba's eval_direction times distance^2. A textured spot multiplies by its
// texture at u, v = 1/2 + (x, y) / (2 z tan(cutoff)) of the local direction (spot.cpp's
// direction_to_uv); a projector sends pi scale E(u, v) / cos^3 into its frustum, with
// u = 1/2 - x / (2 z t), v = 1/2 - aspect y / (2 z t) (its perspective camera's uv) and
// nothing outside [0, 1]^2, so that the plane z = 1 receives pi scale E (projector.cpp).
fn delta_intensity(light: Light, dir: vec3<f32>) -> vec3<f32> {
    var intensity = light.radiance;
#ifdef SPOT_LIGHTS
    if light.kind == LIGHT_SPOT {
        let cos_theta = dot(dir, light.axis);
        let falloff = spot_falloff(light, cos_theta);
        // As Mitsuba, no texture lookup where the falloff is zero (its uv is meaningless there).
        if falloff <= 0.0 {
            return vec3<f32>(0.0);
        }
        intensity *= falloff;
#ifdef TEXTURES
        if light.texture != NO_TEXTURE {
            let xy = vec2<f32>(dot(dir, light.frame_x), dot(dir, light.frame_y));
            let uv = vec2<f32>(0.5) + 0.5 * xy / (cos_theta * light.uv_factor);
            intensity *= texture_eval(light.texture, uv);
        }
#endif
    }
#endif
#ifdef PROJECTORS
    if light.kind == LIGHT_PROJECTOR {
        let z = dot(dir, light.axis);
        if z <= 0.0 {
            return vec3<f32>(0.0);
        }
        let k = 0.5 / (z * light.uv_factor);
        let uv = vec2<f32>(0.5 - dot(dir, light.frame_x) * k, 0.5 - light.aspect * dot(dir, light.frame_y) * k);
        if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) {
            return vec3<f32>(0.0);
        }
        intensity /= z * z * z;
#ifdef TEXTURES
        if light.texture != NO_TEXTURE {
            intensity *= texture_eval(light.texture, uv);
        }
#endif
    }
#endif
    return intensity;
}

// A point light, spot or projector seen from `from_point`: a delta direction; `pdf` is the
// light's selection probability.
fn sample_point_light(light: Light, from_point: vec3<f32>) -> LightSample {
    var result: LightSample;
    result.valid = false;
    let to_light = light.position - from_point;
    let dist2 = dot(to_light, to_light);
    if dist2 <= 0.0 {
        return result;
    }
    let dist = sqrt(dist2);
    result.dir = to_light / dist;
    result.distance = dist;
    result.position = light.position;
    result.normal = vec3<f32>(0.0);
    result.error = vec3<f32>(0.0);
    result.radiance = delta_intensity(light, -result.dir) / dist2;
    result.pdf = light.select_prob;
    result.is_delta = true;
    result.valid = max(result.radiance.x, max(result.radiance.y, result.radiance.z)) > 0.0;
    return result;
}
#endif

// Where a shadow ray towards a light at infinity may stop: twice as far from `from_point` as
// anything in the scene's bounding sphere can be.
fn distant_point(from_point: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let center = 0.5 * (scene_info.bounds_min + scene_info.bounds_max);
    return from_point + dir * (2.0 * (length(from_point - center) + scene_info.scene_radius));
}

// A light at infinity in direction `dir` (unit, towards it), for a shadow ray.
fn distant_sample(from_point: vec3<f32>, dir: vec3<f32>, radiance: vec3<f32>, pdf: f32, is_delta: bool) -> LightSample {
    var result: LightSample;
    result.dir = dir;
    result.position = distant_point(from_point, dir);
    result.distance = length(result.position - from_point);
    result.normal = vec3<f32>(0.0);
    result.error = vec3<f32>(0.0);
    result.radiance = radiance;
    result.pdf = pdf;
    result.is_delta = is_delta;
    result.valid = pdf > 0.0 && result.distance > 0.0;
    return result;
}

fn sample_light(from_point: vec3<f32>, u_pick: f32, u: vec2<f32>) -> LightSample {
    var result: LightSample;
    result.valid = false;
    if scene_info.num_lights == 0u {
        return result;
    }
    let index = pick_light(u_pick);
    let light = lights[index];
    if light.select_prob <= 0.0 {
        return result;
    }
#ifdef POINT_LIGHTS
    if light.kind == LIGHT_POINT || light.kind == LIGHT_SPOT || light.kind == LIGHT_PROJECTOR {
        return sample_point_light(light, from_point);
    }
#endif
#ifdef DIRECTIONAL_LIGHTS
    if light.kind == LIGHT_DIRECTIONAL {
        return distant_sample(from_point, -light.axis, light.radiance, light.select_prob, true);
    }
#endif
#ifdef ENVIRONMENT
    if light.kind == LIGHT_CONSTANT || light.kind == LIGHT_ENVMAP {
        let s = sample_environment_light(light, u);
        return distant_sample(from_point, s.dir, s.radiance, light.select_prob * s.pdf, false);
    }
#endif
    let point = sample_area_light_point(light, u);
    let to_light = point.position - from_point;
    let dist = length(to_light);
    if dist <= 0.0 {
        return result;
    }
    result.dir = to_light / dist;
    result.distance = dist;
    result.position = point.position;
    result.normal = point.normal;
    result.error = point.error;
    // One-sided emitters: nothing leaves the back.
    let cos_light = -dot(result.dir, point.normal);
    result.pdf = area_light_pdf(index, dist, cos_light);
    result.radiance = light.radiance;
    result.is_delta = false;
    result.valid = result.pdf > 0.0;
    return result;
}
