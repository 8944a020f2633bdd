#define_import_path common::scene

// Shader defs (src/shaders.rs, from the scene): SPHERES compiles in sphere intersection,
// DIELECTRIC the dielectric BSDF, POINT_LIGHTS point-light sampling. Code for what a scene
// lacks is left out of every kernel.

// The scene every pass shares (bind group 0). Layouts mirror src/scene/gpu_layout.rs.

struct SceneUniform {
    camera_origin: vec3<f32>,
    tan_half_x: f32,
    camera_right: vec3<f32>,
    tan_half_y: f32,
    camera_up: vec3<f32>,
    width: u32,
    camera_forward: vec3<f32>,
    height: u32,
    bounds_min: vec3<f32>,
    // Ray offset, a fixed fraction of the scene's extent (scale invariance).
    epsilon: f32,
    bounds_max: vec3<f32>,
    scene_radius: f32,
    num_triangles: u32,
    num_spheres: u32,
    num_lights: u32,
    max_depth: u32,
    rr_depth: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
    // A sphere around every specular surface (radius 0 when there is none).
    specular_center: vec3<f32>,
    specular_radius: f32,
}

struct BvhNode {
    min: vec3<f32>,
    // Leaf: first index into prim_indices. Interior: left child; the right child follows it.
    left_or_first: u32,
    max: vec3<f32>,
    // Primitives in a leaf; 0 for interior nodes.
    count: u32,
}

struct Triangle {
    vertex: vec3<f32>,
    material: u32,
    edge_a: vec3<f32>,
    light: u32,
    edge_b: vec3<f32>,
    pad_a: u32,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    material: u32,
    light: u32,
    flip_normals: u32,
    pad_a: u32,
}

struct Material {
    albedo: vec3<f32>,
    kind: u32,
    emission: vec3<f32>,
    int_ior: f32,
    ext_ior: f32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

struct Light {
    position: vec3<f32>,
    kind: u32,
    radiance: vec3<f32>,
    prim: u32,
    select_prob: f32,
    area: f32,
    pad_a: u32,
    pad_b: u32,
}

const MATERIAL_DIFFUSE: u32 = 0u;
const MATERIAL_DIELECTRIC: u32 = 1u;
const MATERIAL_MIRROR: u32 = 2u;
const LIGHT_TRIANGLE: u32 = 0u;
const LIGHT_SPHERE: u32 = 1u;
const LIGHT_POINT: u32 = 2u;
const NO_LIGHT: u32 = 0xffffffffu;
const NO_HIT: u32 = 0xffffffffu;
const UNBOUNDED: u32 = 0xffffffffu;
const T_INFINITE: f32 = 3.0e38;
const BVH_STACK_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> scene_info: SceneUniform;
@group(0) @binding(1) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(3) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(4) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(5) var<storage, read> materials: array<Material>;
@group(0) @binding(6) var<storage, read> lights: array<Light>;
@group(0) @binding(7) var<storage, read> light_cdf: array<f32>;

struct Hit {
    t: f32,
    // Index into triangles, or num_triangles + index into spheres; NO_HIT on a miss.
    prim: u32,
}

struct Surface {
    position: vec3<f32>,
    // Geometric normal on the front (emitting, outside) side, unit length.
    normal: vec3<f32>,
    material: u32,
    light: u32,
}

// Möller-Trumbore on triangle `index`. Returns the distance, or T_INFINITE when missed or
// degenerate. Only the three vectors it needs are loaded: on lavapipe, storage loads dominate
// traversal time, and loading the whole struct costs about a fifth more.
fn intersect_triangle(index: u32, origin: vec3<f32>, dir: vec3<f32>) -> f32 {
    let vertex = triangles[index].vertex;
    let edge_a = triangles[index].edge_a;
    let edge_b = triangles[index].edge_b;
    let p = cross(dir, edge_b);
    let det = dot(edge_a, p);
    if det == 0.0 {
        return T_INFINITE;
    }
    let inv_det = 1.0 / det;
    let to_origin = origin - vertex;
    let u = dot(to_origin, p) * inv_det;
    if u < 0.0 || u > 1.0 {
        return T_INFINITE;
    }
    let q = cross(to_origin, edge_a);
    let v = dot(dir, q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return T_INFINITE;
    }
    let t = dot(edge_b, q) * inv_det;
    return select(T_INFINITE, t, t > 0.0);
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

fn intersect_prim(prim: u32, origin: vec3<f32>, dir: vec3<f32>) -> f32 {
#ifdef SPHERES
    if prim >= scene_info.num_triangles {
        return intersect_sphere(spheres[prim - scene_info.num_triangles], origin, dir);
    }
#endif
    return intersect_triangle(prim, origin, dir);
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

// Closest hit along the ray within (0, t_max). With `any_hit`, returns at the first hit found.
fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(t_max, NO_HIT);
    let inv_dir = safe_inverse(dir);
    var stack: array<u32, BVH_STACK_SIZE>;
    var top = 0u;
    var node_index = 0u;
    // An empty scene's root has an inverted box and no children (see src/scene/bvh.rs).
    if scene_info.num_triangles + scene_info.num_spheres == 0u {
        return Hit(T_INFINITE, NO_HIT);
    }
    if intersect_box(bvh_nodes[0].min, bvh_nodes[0].max, origin, inv_dir, t_max) == T_INFINITE {
        return Hit(T_INFINITE, NO_HIT);
    }
    loop {
        let node = bvh_nodes[node_index];
        if node.count > 0u {
            for (var i = 0u; i < node.count; i++) {
                let prim = prim_indices[node.left_or_first + i];
                let t = intersect_prim(prim, origin, dir);
                if t < hit.t {
                    hit = Hit(t, prim);
                    if any_hit {
                        return hit;
                    }
                }
            }
        } else {
            let left = node.left_or_first;
            let right = left + 1u;
            let t_left = intersect_box(bvh_nodes[left].min, bvh_nodes[left].max, origin, inv_dir, hit.t);
            let t_right = intersect_box(bvh_nodes[right].min, bvh_nodes[right].max, origin, inv_dir, hit.t);
            let near_first = t_left <= t_right;
            let near = select(right, left, near_first);
            let far = select(left, right, near_first);
            let t_near = min(t_left, t_right);
            let t_far = max(t_left, t_right);
            if t_near < T_INFINITE {
                if t_far < T_INFINITE && top < BVH_STACK_SIZE {
                    stack[top] = far;
                    top += 1u;
                }
                node_index = near;
                continue;
            }
        }
        if top == 0u {
            break;
        }
        top -= 1u;
        node_index = stack[top];
    }
    if hit.prim == NO_HIT {
        hit.t = T_INFINITE;
    }
    return hit;
}

fn intersect_scene(origin: vec3<f32>, dir: vec3<f32>) -> Hit {
    return traverse(origin, dir, T_INFINITE, false);
}

fn occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    return traverse(origin, dir, t_max, true).prim != NO_HIT;
}

fn surface_at(hit: Hit, origin: vec3<f32>, dir: vec3<f32>) -> Surface {
    let position = origin + hit.t * dir;
#ifdef SPHERES
    if hit.prim >= scene_info.num_triangles {
        let sphere = spheres[hit.prim - scene_info.num_triangles];
        var normal = normalize(position - sphere.center);
        if sphere.flip_normals != 0u {
            normal = -normal;
        }
        return Surface(position, normal, sphere.material, sphere.light);
    }
#endif
    let tri = triangles[hit.prim];
    return Surface(position, normalize(cross(tri.edge_a, tri.edge_b)), tri.material, tri.light);
}

// Start point for a ray leaving `position` towards the side of `normal` that `dir` points to.
fn offset_origin(position: vec3<f32>, normal: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let side = select(-1.0, 1.0, dot(dir, normal) >= 0.0);
    return position + side * scene_info.epsilon * normal;
}
