#define_import_path common::surface

// The surface a ray hit (position, normals, uvs, material) and where rays leave it: pbrt-v4's
// floating-point error bounds on points and its ray origin offsets, shadow rays between two
// surface points, Veach's shading-normal correction for photons.

#import common::scene::{NO_NORMALS, Sphere, scene_info, spheres, triangle_at, triangle_normals_at, triangle_uvs_at}
#import common::intersection::{Hit, triangle_barycentrics}
#import common::traversal::occluded

struct Surface {
    position: vec3<f32>,
    // Geometric normal on the front (emitting, outside) side, unit length.
    normal: vec3<f32>,
    material: u32,
    light: u32,
    // Per-component bound on how far `position` may lie from the exact surface (see
    // offset_ray_origin).
    error: vec3<f32>,
    // The normal BSDFs shade with: the interpolated vertex normal of a smooth mesh (on the
    // front side), else `normal`. As in Mitsuba, BSDFs judge directions by it: a sampled or
    // light direction it puts above the surface counts even where `normal` puts it below. Which
    // side a ray arrives from (and so a twosided material's face) is still `normal`'s to say.
    shading_normal: vec3<f32>,
    // Texture coordinates: interpolated from a triangle's corners; a sphere's Mitsuba
    // parameterisation (phi / 2 pi, theta / pi about +z).
    uv: vec2<f32>,
}

// --- Ray offsets: pbrt-v4's floating-point error bounds (Pharr, Jakob and Humphreys, "Physically
// Based Rendering", 4th ed., section 6.8: 6.8.5 bounds the points, 6.8.6 offsets the rays). Every
// surface point carries a per-component bound on its distance from the exact surface; a ray
// leaving it starts just beyond that bound along the geometric normal, so it cannot hit the
// surface it leaves, however far from the origin the point lies and however large the rest of
// the scene is. Nothing depends on the scene's extent.

// Unit roundoff of f32 (pbrt's MachineEpsilon).
const UNIT_ROUNDOFF: f32 = 5.9604645e-8;
// Shadow rays stop this fraction of their length short of the light (pbrt-v4's ShadowEpsilon):
// Möller-Trumbore's distance to the light's own plane is only good to a few roundoffs of the
// ray's length over the cosine at the light, which the far end's offset (a bound at the light
// point, independent of where the ray comes from) does not cover.
const SHADOW_EPSILON: f32 = 1e-4;

// pbrt-v4's gamma(n) = n u / (1 - n u): bounds n successive relative roundings.
fn gamma(n: f32) -> f32 {
    return n * UNIT_ROUNDOFF / (1.0 - n * UNIT_ROUNDOFF);
}

// The next float towards +infinity (pbrt-v4's NextFloatUp); -0 steps as +0. Infinity and NaN
// cannot occur: scenes are limited to |coordinates| <= 1e15 (src/scene/mod.rs).
fn next_float_up(v: f32) -> f32 {
    if v == 0.0 {
        return bitcast<f32>(1u);
    }
    let bits = bitcast<u32>(v);
    return bitcast<f32>(select(bits - 1u, bits + 1u, v > 0.0));
}

fn next_float_down(v: f32) -> f32 {
    return -next_float_up(-v);
}

fn round_away(value: f32, offset: f32) -> f32 {
    if offset > 0.0 {
        return next_float_up(value);
    }
    if offset < 0.0 {
        return next_float_down(value);
    }
    return value;
}

// Start of a ray leaving `position` (within `error` of its surface) towards `dir`: pbrt-v4's
// OffsetRayOrigin (6.8.6). The offset is the error box's extent along the normal,
// dot(|n|, error), to the side `dir` leaves on; the sum is then rounded one float further so
// that its own rounding cannot pull it back.
fn offset_ray_origin(position: vec3<f32>, error: vec3<f32>, normal: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let distance = dot(abs(normal), error);
    let offset = select(-distance, distance, dot(dir, normal) >= 0.0) * normal;
    let moved = position + offset;
    return vec3<f32>(round_away(moved.x, offset.x), round_away(moved.y, offset.y), round_away(moved.z, offset.z));
}

// Whether nothing lies between two surface points: the shadow ray is offset at both ends (the
// far end towards the near one, so a light set into a huge wall is not hidden by that wall)
// and stops SHADOW_EPSILON short. A point light passes zero error and normal: no offset there.
fn unoccluded(from_point: vec3<f32>, from_error: vec3<f32>, from_normal: vec3<f32>, to_point: vec3<f32>, to_error: vec3<f32>, to_normal: vec3<f32>) -> bool {
    let origin = offset_ray_origin(from_point, from_error, from_normal, to_point - from_point);
    let end = offset_ray_origin(to_point, to_error, to_normal, origin - to_point);
    let span = end - origin;
    let distance = length(span);
    if !(distance > 0.0) {
        return true;
    }
    return !occluded(origin, span / distance, distance * (1.0 - SHADOW_EPSILON));
}

// A point on a triangle or sphere with its geometric normal (front side) and error bound.
struct SurfacePoint {
    position: vec3<f32>,
    normal: vec3<f32>,
    error: vec3<f32>,
}

// The point vertex + u edge_a + v edge_b of a triangle, (u, v) = b. pbrt-v4 (6.8.5) bounds its
// interpolation b0 p0 + b1 p1 + b2 p2 by gamma(7) (|b0 p0| + |b1 p1| + |b2 p2|): its b_i are
// computed ratios that need not sum to one, which moves the point off the plane. Here
// b0 = 1 - u - v is implicit, so whatever u and v are (rounded as they may be) they name a point
// of the stored plane, and only the interpolation's own two products and two sums leave it:
// gamma(3) (|vertex| + |u edge_a| + |v edge_b|) per component.
//
// pbrt's watertight intersector also bounds its own t and refuses hits closer than that; our
// Möller-Trumbore does not, so the bound also covers the error with which it decides the side
// of this plane a spawned origin o lies on. That side is the sign of
// dot(edge_b, cross(o - vertex, edge_a)) / det; with to = |u edge_a| + |v edge_b| >= |o - vertex|
// (to first order), rounding o - vertex moves the origin by at most u |to| off the plane, and
// the cross product (gamma(2)), the scaling by 1/det (gamma(1)) and the dot product (gamma(3))
// err by at most gamma(6) dot(|edge_b|, abscross(to, |edge_a|)), abscross being the cross
// product with every term's magnitude added; divided by |edge_a x edge_b| that is a distance
// off the plane. It grows as 1 / sin of the angle at `vertex`: a sliver needs a wider berth.
// Both are computed from unit edges so that nothing is a length cubed. Measured in f32 on the
// CPU (1e6 random triangles per case, sizes 1e-17 to 1e17, slivers of sin 0.001, hits within
// 1e-6 of the shared edge of a quad): the interpolation bound alone lets 4e-5 to 1e-4 of spawned
// rays hit their own triangle (slivers: a third) and 2e-4 hit the neighbour; with this term,
// none.
//
// The normal, too, comes from unit edges: normalize(cross(edge_a, edge_b)) squares a length
// squared, which overflows f32 for scenes past about 1e9 and underflows below 1e-9.
fn triangle_point(vertex: vec3<f32>, edge_a: vec3<f32>, edge_b: vec3<f32>, b: vec2<f32>) -> SurfacePoint {
    let along_a = b.x * edge_a;
    let along_b = b.y * edge_b;
    let position = vertex + along_a + along_b;
    let to = abs(along_a) + abs(along_b);
    let unit_a = edge_a * inverseSqrt(dot(edge_a, edge_a));
    let unit_b = edge_b * inverseSqrt(dot(edge_b, edge_b));
    let plane = cross(unit_a, unit_b);
    let normal = normalize(plane);
    let a = abs(unit_a);
    let abs_cross = vec3<f32>(to.y * a.z + to.z * a.y, to.z * a.x + to.x * a.z, to.x * a.y + to.y * a.x);
    let side_error = gamma(6.0) * dot(abs(unit_b), abs_cross) / length(plane) + gamma(1.0) * length(to);
    let error = gamma(3.0) * (abs(vertex) + to) + side_error * abs(normal);
    return SurfacePoint(position, normal, error);
}

#ifdef SPHERES
// The point of a sphere in the direction of `local` from its centre: pbrt-v4 (6.8.5) reprojects
// onto the sphere, local * r / |local|, which leaves gamma(5) |local| of error whatever error
// `local` had. With inverseSqrt (2 ulp in Vulkan, 4 roundoffs) in place of a correctly rounded
// sqrt and division that is gamma(7.5); adding the centre rounds once more, relative to
// |centre| + |local|: gamma(9) |local| + gamma(1) |centre|. The outward normal is unit `local`.
fn sphere_point(sphere: Sphere, local: vec3<f32>) -> SurfacePoint {
    let inv_length = inverseSqrt(dot(local, local));
    let on_sphere = local * (sphere.radius * inv_length);
    let position = sphere.center + on_sphere;
    let error = gamma(9.0) * abs(on_sphere) + gamma(1.0) * abs(sphere.center);
    let outward = local * inv_length;
    return SurfacePoint(position, select(outward, -outward, sphere.flip_normals != 0u), error);
}
#endif

fn surface_at(hit: Hit, origin: vec3<f32>, dir: vec3<f32>) -> Surface {
#ifdef SPHERES
    if hit.prim >= scene_info.num_triangles {
        let sphere = spheres[hit.prim - scene_info.num_triangles];
        let point = sphere_point(sphere, origin + hit.t * dir - sphere.center);
        return Surface(point.position, point.normal, sphere.material, sphere.light, point.error, point.normal, sphere_uv(point.position - sphere.center));
    }
#endif
    // From the barycentrics, not origin + t dir: the distance carries the error of the whole
    // ray (large when the origin is far from the triangle), the barycentrics only the plane's.
    let tri = triangle_at(hit.prim);
    let b = triangle_barycentrics(tri, origin, dir);
    let point = triangle_point(tri.vertex, tri.edge_a, tri.edge_b, b);
    var shading = point.normal;
    if tri.normals != NO_NORMALS {
        let n = triangle_normals_at(tri.normals);
        let interpolated = (1.0 - b.x - b.y) * n.a + b.x * n.b + b.y * n.c;
        let length_squared = dot(interpolated, interpolated);
        // Opposite vertex normals can cancel: such a point shades flat.
        if length_squared > 1e-12 {
            shading = interpolated * inverseSqrt(length_squared);
        }
    }
    let uvs = triangle_uvs_at(hit.prim);
    let uv = (1.0 - b.x - b.y) * uvs.a + b.x * uvs.b + b.y * uvs.c;
    return Surface(point.position, point.normal, tri.material, tri.light, point.error, shading, uv);
}

#ifdef SPHERES
// Mitsuba's sphere parameterisation of the point `local` from the centre: (phi / 2 pi,
// theta / pi) with theta from +z and phi from +x towards +y. The sphere's rotation is not
// stored, so this is about the world axes: right for spheres whose to_world does not rotate.
fn sphere_uv(local: vec3<f32>) -> vec2<f32> {
    let d = normalize(local);
    var phi = atan2(d.y, d.x);
    if phi < 0.0 {
        phi += 6.2831853;
    }
    return vec2<f32>(phi * 0.15915494, acos(clamp(d.z, -1.0, 1.0)) * 0.31830989);
}
#endif

// Veach's correction (thesis, section 5.3) of a photon's weight for the asymmetry shading
// normals add to a BSDF: |wi.ns| |wo.ng| / (|wi.ng| |wo.ns|) for a photon arriving from `wi`
// and leaving towards `wo` (both pointing away from the surface); 1 where the normals agree.
fn photon_shading_correction(surface: Surface, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let denominator = abs(dot(wi, surface.normal) * dot(wo, surface.shading_normal));
    if !(denominator > 0.0) {
        return 0.0;
    }
    return abs(dot(wi, surface.shading_normal) * dot(wo, surface.normal)) / denominator;
}

// Start point for a ray leaving `surface` towards `dir`.
fn spawn_origin(surface: Surface, dir: vec3<f32>) -> vec3<f32> {
    return offset_ray_origin(surface.position, surface.error, surface.normal, dir);
}
