#define_import_path common::intersection

// Where a ray meets one primitive of the scene: Möller-Trumbore on a triangle, a sphere's root,
// a box's slabs, and which of two hits a ray keeps (coplanar faces and their ties).

#import common::scene::{NO_HIT, Sphere, T_INFINITE, Triangle, scene_info, spheres, triangle_at, triangles}

struct Hit {
    t: f32,
    // Index into triangles, or num_triangles + index into spheres; NO_HIT on a miss.
    prim: u32,
    // Whether the ray meets the front (the geometric normal's side) of `prim`: what decides ties
    // between coplanar faces (keep_closer).
    front: bool,
}

// Where a ray crosses one primitive: the distance (T_INFINITE when it misses) and whether it
// meets the primitive's front.
struct Crossing {
    t: f32,
    front: bool,
}


// Möller-Trumbore on triangle `index`. Returns the distance, T_INFINITE when missed or
// degenerate, and the side met. Only the three vectors it needs are loaded: on lavapipe, storage loads dominate
// traversal time, and loading the whole struct costs about a fifth more.
fn triangle_crossing(index: u32, origin: vec3<f32>, dir: vec3<f32>) -> Crossing {
#ifdef TRIANGLES_CHUNKED
    let tri = triangle_at(index);
    let vertex = tri.vertex;
    let edge_a = tri.edge_a;
    let edge_b = tri.edge_b;
#else
    let vertex = triangles[index].vertex;
    let edge_a = triangles[index].edge_a;
    let edge_b = triangles[index].edge_b;
#endif
    let p = cross(dir, edge_b);
    let det = dot(edge_a, p);
    if det == 0.0 {
        return Crossing(T_INFINITE, false);
    }
    let inv_det = 1.0 / det;
    let to_origin = origin - vertex;
    let u = dot(to_origin, p) * inv_det;
    if u < 0.0 || u > 1.0 {
        return Crossing(T_INFINITE, false);
    }
    // Scaled before the last dot product: dot(edge_b, cross(to_origin, edge_a)) is a length
    // cubed, which overflows f32 for scenes past about 1e12 (and underflows below 1e-12).
    let q = cross(to_origin, edge_a) * inv_det;
    let v = dot(dir, q);
    if v < 0.0 || u + v > 1.0 {
        return Crossing(T_INFINITE, false);
    }
    let t = dot(edge_b, q);
    // det = -dot(dir, cross(edge_a, edge_b)): positive when the ray meets the front.
    return Crossing(select(T_INFINITE, t, t > 0.0), det > 0.0);
}

// The barycentrics (of vertex + edge_a, vertex + edge_b) where a ray hits triangle `tri`, by
// the same arithmetic as triangle_crossing.
fn triangle_barycentrics(tri: Triangle, origin: vec3<f32>, dir: vec3<f32>) -> vec2<f32> {
    let p = cross(dir, tri.edge_b);
    let inv_det = 1.0 / dot(tri.edge_a, p);
    let to_origin = origin - tri.vertex;
    let q = cross(to_origin, tri.edge_a) * inv_det;
    return vec2<f32>(dot(to_origin, p) * inv_det, dot(dir, q));
}

#ifdef SPHERES
// Nearest positive root, computed as in Haines et al., "Precision Improvements for Ray/Sphere
// Intersection" (Ray Tracing Gems, ch. 7), which keeps grazing and distant hits accurate.
fn intersect_sphere(sphere: Sphere, origin: vec3<f32>, dir: vec3<f32>) -> f32 {
    let f = origin - sphere.center;
    let b = -dot(f, dir);
    let l = f + b * dir;
    let r2 = sphere.radius * sphere.radius;
    let discriminant = r2 - dot(l, l);
    if discriminant < 0.0 {
        return T_INFINITE;
    }
    let c = dot(f, f) - r2;
    let q = b + select(-1.0, 1.0, b >= 0.0) * sqrt(discriminant);
    var t0 = T_INFINITE;
    if q != 0.0 {
        t0 = c / q;
    }
    let t1 = q;
    let near = min(t0, t1);
    let far = max(t0, t1);
    if near > 0.0 {
        return near;
    }
    return select(T_INFINITE, far, far > 0.0);
}
#endif

#ifdef SPHERES
fn sphere_crossing(sphere: Sphere, origin: vec3<f32>, dir: vec3<f32>) -> Crossing {
    let t = intersect_sphere(sphere, origin, dir);
    let outward = dot(dir, origin + t * dir - sphere.center) < 0.0;
    return Crossing(t, outward != (sphere.flip_normals != 0u));
}
#endif

fn prim_crossing(prim: u32, origin: vec3<f32>, dir: vec3<f32>) -> Crossing {
#ifdef SPHERES
    if prim >= scene_info.num_triangles {
        return sphere_crossing(spheres[prim - scene_info.num_triangles], origin, dir);
    }
#endif
    return triangle_crossing(prim, origin, dir);
}

// Slab test; returns the entry distance or T_INFINITE.
fn intersect_box(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> f32 {
    let t_lo = (lo - origin) * inv_dir;
    let t_hi = (hi - origin) * inv_dir;
    let t_near = min(t_lo, t_hi);
    let t_far = max(t_lo, t_hi);
    let enter = max(max(t_near.x, t_near.y), max(t_near.z, 0.0));
    let exit = min(min(t_far.x, t_far.y), min(t_far.z, t_max));
    return select(T_INFINITE, enter, enter <= exit);
}

// 1/dir with zero components replaced by a tiny signed value, so the slab test never computes
// 0 * inf.
fn safe_inverse(dir: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    let sign_dir = select(vec3<f32>(-1.0), vec3<f32>(1.0), dir >= vec3<f32>(0.0));
    let d = select(dir, sign_dir * tiny, abs(dir) < tiny);
    return 1.0 / d;
}

// Two hits closer than this along a ray count as one place (coplanar faces): the distances of
// two triangles in one plane differ by a few roundoffs of the coordinates' magnitude.
fn tie_span(origin: vec3<f32>, t: f32) -> f32 {
    let o = abs(origin);
    return 1e-5 * (t + max(max(o.x, o.y), o.z));
}

// Keeps `prim`, crossed at `c`, in `hit` if it is closer; returns whether it was kept.
//
// With `front_wins_ties` (photons), of two coplanar hits the one whose front faces the ray wins:
// where a dielectric's face lies on a diffuse surface (a glass standing on a table), a photon
// arriving at the contact lands on the table, as the reverse of a camera path leaving the table
// (which starts on the table's front side, past the contact) does; photons lost through the
// contact would darken the caustic the camera pass leaves to them.
//
// Otherwise the closer computed distance wins, as in Mitsuba's closest hit, and of two hits at
// exactly the same distance the front face, then the lower index. Which leaf the traversal
// reaches first depends on the tree and on the signs of the ray's direction, so a tie left to
// that order changed with position and direction: a camera ray inside a glass ring standing on
// a floor met the floor on one side of the scene and left through the glass's bottom on the
// other, and the ring came out a third darker on one half of the image (tests/coplanar.rs,
// docs/coplanar-contacts.md). The comparison is branch-free: it runs for every primitive tested.
fn keep_closer(hit: ptr<function, Hit>, prim: u32, c: Crossing, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) -> bool {
    if front_wins_ties && c.t < T_INFINITE && abs(c.t - (*hit).t) <= tie_span(origin, (*hit).t) {
        if (*hit).prim == NO_HIT || (c.front && !(*hit).front) {
            *hit = Hit(c.t, prim, c.front);
            return true;
        }
        return false;
    }
    let wins_tie = select(prim < (*hit).prim, c.front, c.front != (*hit).front);
    if (c.t < (*hit).t) | ((c.t == (*hit).t) & ((*hit).prim != NO_HIT) & wins_tie) {
        *hit = Hit(c.t, prim, c.front);
        return true;
    }
    return false;
}
