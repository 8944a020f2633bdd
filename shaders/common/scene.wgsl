#define_import_path common::scene

// Shader defs (src/shaders.rs, from the scene): SPHERES compiles in sphere intersection,
// DIELECTRIC the smooth and thin dielectric BSDFs, CONDUCTOR the smooth and rough conductors,
// PLASTIC plastic and rough plastic, ROUGH_DIELECTRIC the rough dielectric, POINT_LIGHTS
// point and spot lights and projectors, SPOT_LIGHTS spot lights, PROJECTORS projectors,
// DIRECTIONAL_LIGHTS directional lights,
// ENVIRONMENT a constant or map light seen by escaping rays. Code for what a scene
// lacks is left out of every kernel.

// The scene every pass shares (bind group 0). Layouts mirror src/scene/gpu_layout.rs.

struct SceneUniform {
    camera_origin: vec3<f32>,
    // The camera plane (one unit ahead) per image pixel, across and down (common::camera).
    plane_step_x: f32,
    camera_right: vec3<f32>,
    plane_step_y: f32,
    camera_up: vec3<f32>,
    // The pixel grid this dispatch's buffers hold: the film, or a tile of it at (tile_x, tile_y).
    width: u32,
    camera_forward: vec3<f32>,
    height: u32,
    bounds_min: vec3<f32>,
    pad_d: u32,
    bounds_max: vec3<f32>,
    scene_radius: f32,
    num_triangles: u32,
    num_spheres: u32,
    num_lights: u32,
    max_depth: u32,
    rr_depth: u32,
    // common::pixel_filter's FILTER_* kind, its parameter (tent radius, Gaussian stddev, Lanczos
    // lobes, Mitchell's B; filter_param_b has Mitchell's C), and
    // 1 when samples may leave the film (Mitsuba's sample_border).
    filter_kind: u32,
    filter_param: f32,
    sample_border: u32,
    // A sphere around every specular surface (radius 0 when there is none).
    specular_center: vec3<f32>,
    specular_radius: f32,
    // The constant or map light escaping rays see, or NO_LIGHT.
    environment: u32,
    film_width: u32,
    film_height: u32,
    tile_x: u32,
    tile_y: u32,
    // 1: camera rays pass through emitting shapes and see no environment (hide_emitters).
    hide_emitters: u32,
    // The camera plane at the image's top-left corner: the whole film's projection, and
    // where the image (a crop window, maybe) lies in it.
    plane_origin: vec2<f32>,
    // A thin lens: aperture radius (0: a pinhole) and focus distance along the view.
    aperture_radius: f32,
    focus_distance: f32,
    // The pixel filter's second parameter (Mitchell's C).
    filter_param_b: f32,
    pad_filter: u32,
    // A signed pixel filter's sampling table (common::signed_filter): node j at
    // j / nodes-per-pixel holds (integral of |f| from 0, integral of f from 0), two a vec4.
    filter_table: array<vec4<f32>, 64>,
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
    // Index into triangle_normals, or NO_NORMALS (shaded with the face normal).
    normals: u32,
}

// A triangle's texture coordinates at vertex, vertex + edge_a, vertex + edge_b.
struct TriangleUvs {
    a: vec2<f32>,
    b: vec2<f32>,
    c: vec2<f32>,
}

// A triangle's unit vertex normals at vertex, vertex + edge_a, vertex + edge_b.
struct TriangleNormals {
    a: vec3<f32>,
    pad_a: u32,
    b: vec3<f32>,
    pad_b: u32,
    c: vec3<f32>,
    pad_c: u32,
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
    // Diffuse reflectance (diffuse, plastic's base).
    albedo: vec3<f32>,
    kind: u32,
    emission: vec3<f32>,
    int_ior: f32,
    // Specular reflectance (conductors, plastic's coating).
    specular: vec3<f32>,
    ext_ior: f32,
    // A conductor's complex index eta + i k.
    eta: vec3<f32>,
    alpha_u: f32,
    k: vec3<f32>,
    alpha_v: f32,
    // 0 Beckmann, 1 GGX.
    distribution: u32,
    // The material of the back side (twosided), or NO_BACK.
    back: u32,
    nonlinear: u32,
    specular_weight: f32,
    internal_reflectance: f32,
    // Rough plastic: first entry of its transmittance table in bsdf_tables.
    table: u32,
    // Textures replacing albedo and specular at each surface point (common::texture), or
    // NO_TEXTURE.
    diffuse_texture: u32,
    specular_texture: u32,
    // Scalar textures replacing alpha_u and alpha_v, or NO_TEXTURE.
    alpha_u_texture: u32,
    alpha_v_texture: u32,
    // A normalmap or bumpmap around the BSDF (common::normal_map's FRAME_*), its texture, the
    // bump map's scale and FRAME_FLAG_* bits.
    frame_kind: u32,
    frame_texture: u32,
    frame_scale: f32,
    frame_flags: u32,
    // A blend (common::blend): the two materials it chooses between, the probability of the
    // second and the scalar texture that replaces it, or NO_TEXTURE.
    children: vec2<u32>,
    blend_weight: f32,
    blend_weight_texture: u32,
    // Scalar textures replacing one component each of specular, eta and k (principled's
    // parameters): field_texture_count pairs (component of the nine, texture) of bsdf_tables
    // from field_textures (common::texture).
    field_textures: u32,
    field_texture_count: u32,
}

struct Light {
    // Point and spot lights, projectors: position.
    position: vec3<f32>,
    kind: u32,
    // Intensity (point, spot), radiance (area, constant; 1 for maps), irradiance
    // (directional) or pi x scale x irradiance (projector).
    radiance: vec3<f32>,
    // Area lights: the triangle or sphere.
    prim: u32,
    // Spot, projector: the axis it shines along. Directional: the direction its light travels.
    axis: vec3<f32>,
    select_prob: f32,
    // Area lights: their area. Distant lights: the area of the disc their photons leave from.
    // Projector: the image's area on the plane one unit ahead.
    area: f32,
    // Environment maps: where their table starts in bsdf_tables (common::environment).
    table: u32,
    // Spot: cutoff angle and beam width, radians.
    cutoff: f32,
    beam_width: f32,
    // Probability that a photon leaves this light (select_prob is NEE's).
    emit_prob: f32,
    // Spot, projector: the texture multiplying the intensity, or NO_TEXTURE.
    texture: u32,
    // Spot: tan(cutoff). Projector: tan(fov_x / 2).
    uv_factor: f32,
    // Projector: the image's width over height.
    aspect: f32,
    // Spot, projector: unit local x and y (the texture's axes).
    frame_x: vec3<f32>,
    pad_x: u32,
    frame_y: vec3<f32>,
    pad_y: u32,
}

const MATERIAL_DIFFUSE: u32 = 0u;
const MATERIAL_DIELECTRIC: u32 = 1u;
const MATERIAL_MIRROR: u32 = 2u;
const MATERIAL_CONDUCTOR: u32 = 3u;
const MATERIAL_ROUGH_CONDUCTOR: u32 = 4u;
const MATERIAL_PLASTIC: u32 = 5u;
const MATERIAL_ROUGH_PLASTIC: u32 = 6u;
const MATERIAL_ROUGH_DIELECTRIC: u32 = 7u;
const MATERIAL_THIN_DIELECTRIC: u32 = 8u;
const MATERIAL_BLEND: u32 = 9u;
const MATERIAL_NULL: u32 = 10u;
const MATERIAL_PRINCIPLED: u32 = 11u;
const MATERIAL_POLARIZED_PLASTIC: u32 = 12u;
const MATERIAL_PRINCIPLED_THIN: u32 = 13u;
const NO_BACK: u32 = 0xffffffffu;
const LIGHT_TRIANGLE: u32 = 0u;
const LIGHT_SPHERE: u32 = 1u;
const LIGHT_POINT: u32 = 2u;
const LIGHT_SPOT: u32 = 3u;
const LIGHT_DIRECTIONAL: u32 = 4u;
const LIGHT_CONSTANT: u32 = 5u;
const LIGHT_ENVMAP: u32 = 6u;
const LIGHT_PROJECTOR: u32 = 7u;
const NO_LIGHT: u32 = 0xffffffffu;
const NO_HIT: u32 = 0xffffffffu;
const NO_NORMALS: u32 = 0xffffffffu;
const NO_TEXTURE: u32 = 0xffffffffu;
const UNBOUNDED: u32 = 0xffffffffu;
const T_INFINITE: f32 = 3.0e38;
const BVH_STACK_SIZE: u32 = 64u;

@group(0) @binding(0) var<uniform> scene_info: SceneUniform;
// A table that fits a uniform binding may be bound as one on a CPU adapter (the def, set by
// src/passes/scene_resources.rs's TablePlacement, holds its length): lavapipe loads a divergent
// index from a uniform buffer with a plain gather, and from a storage buffer with a masked,
// bounds-checked load per lane, several times the instructions (BENCHMARKS.md).
#ifdef BVH_NODES_UNIFORM
@group(0) @binding(1) var<uniform> bvh_nodes: array<BvhNode, #{BVH_NODES_UNIFORM}>;
#else
@group(0) @binding(1) var<storage, read> bvh_nodes: array<BvhNode>;
#endif
#ifdef PRIM_INDICES_UNIFORM
// Four indices a vec4: a uniform array's stride is a multiple of 16 bytes.
@group(0) @binding(2) var<uniform> prim_indices: array<vec4<u32>, #{PRIM_INDICES_UNIFORM}>;
#else
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
#endif
#ifdef TRIANGLES_UNIFORM
@group(0) @binding(3) var<uniform> triangles: array<Triangle, #{TRIANGLES_UNIFORM}>;
#else
@group(0) @binding(3) var<storage, read> triangles: array<Triangle>;
#endif
#ifdef SPHERES_UNIFORM
@group(0) @binding(4) var<uniform> spheres: array<Sphere, #{SPHERES_UNIFORM}>;
#else
@group(0) @binding(4) var<storage, read> spheres: array<Sphere>;
#endif
#ifdef MATERIALS_UNIFORM
@group(0) @binding(5) var<uniform> materials: array<Material, #{MATERIALS_UNIFORM}>;
#else
@group(0) @binding(5) var<storage, read> materials: array<Material>;
#endif
#ifdef LIGHTS_UNIFORM
@group(0) @binding(6) var<uniform> lights: array<Light, #{LIGHTS_UNIFORM}>;
#else
@group(0) @binding(6) var<storage, read> lights: array<Light>;
#endif
@group(0) @binding(7) var<storage, read> light_cdf: array<f32>;
// Tables BSDFs look up (rough plastic's transmittance per cos theta).
@group(0) @binding(8) var<storage, read> bsdf_tables: array<f32>;
#ifdef TRIANGLE_NORMALS_UNIFORM
@group(0) @binding(9) var<uniform> triangle_normals: array<TriangleNormals, #{TRIANGLE_NORMALS_UNIFORM}>;
#else
@group(0) @binding(9) var<storage, read> triangle_normals: array<TriangleNormals>;
#endif
// One per triangle (Mitsuba's default, the barycentrics, where the mesh has none).
@group(0) @binding(10) var<storage, read> triangle_uvs: array<TriangleUvs>;
#ifdef TEXTURES
// Texture headers then their data, as 32-bit words (src/scene/texture.rs, gpu_words); bound
// only for scenes with textures.
@group(0) @binding(11) var<storage, read> textures: array<u32>;
#ifdef TEXTURES_CHUNKED
@group(0) @binding(56) var<storage, read> textures_1: array<u32>;
#endif
#ifdef TEXTURES_CHUNK_2
@group(0) @binding(57) var<storage, read> textures_2: array<u32>;
#endif
#ifdef TEXTURES_CHUNK_3
@group(0) @binding(58) var<storage, read> textures_3: array<u32>;
#endif
#ifdef TEXTURES_CHUNK_4
@group(0) @binding(59) var<storage, read> textures_4: array<u32>;
#endif
#ifdef TEXTURES_CHUNK_5
@group(0) @binding(60) var<storage, read> textures_5: array<u32>;
#endif
#ifdef TEXTURES_CHUNK_6
@group(0) @binding(61) var<storage, read> textures_6: array<u32>;
#endif
#ifdef TEXTURES_CHUNK_7
@group(0) @binding(62) var<storage, read> textures_7: array<u32>;
#endif
#endif

// Tables larger than one storage binding (a mesh of millions of triangles on an adapter that
// binds 128 MiB) are split into chunks of 2^<NAME>_CHUNK_SHIFT entries: chunk 0 at the table's
// own binding, chunk k at the table's chunk base + k - 1 (src/passes/scene_resources.rs,
// TablePlacement). <NAME>_CHUNKED is set from two chunks on, <NAME>_CHUNK_<k> for each k >= 2.
// Every read of such a table goes through its accessor below, which picks the chunk.
#ifdef BVH_NODES_CHUNKED
@group(0) @binding(16) var<storage, read> bvh_nodes_1: array<BvhNode>;
#ifdef BVH_NODES_CHUNK_2
@group(0) @binding(17) var<storage, read> bvh_nodes_2: array<BvhNode>;
#endif
#ifdef BVH_NODES_CHUNK_3
@group(0) @binding(18) var<storage, read> bvh_nodes_3: array<BvhNode>;
#endif
#ifdef BVH_NODES_CHUNK_4
@group(0) @binding(19) var<storage, read> bvh_nodes_4: array<BvhNode>;
#endif
#ifdef BVH_NODES_CHUNK_5
@group(0) @binding(20) var<storage, read> bvh_nodes_5: array<BvhNode>;
#endif
#ifdef BVH_NODES_CHUNK_6
@group(0) @binding(21) var<storage, read> bvh_nodes_6: array<BvhNode>;
#endif
#ifdef BVH_NODES_CHUNK_7
@group(0) @binding(22) var<storage, read> bvh_nodes_7: array<BvhNode>;
#endif
#endif
#ifdef PRIM_INDICES_CHUNKED
@group(0) @binding(24) var<storage, read> prim_indices_1: array<u32>;
#ifdef PRIM_INDICES_CHUNK_2
@group(0) @binding(25) var<storage, read> prim_indices_2: array<u32>;
#endif
#ifdef PRIM_INDICES_CHUNK_3
@group(0) @binding(26) var<storage, read> prim_indices_3: array<u32>;
#endif
#ifdef PRIM_INDICES_CHUNK_4
@group(0) @binding(27) var<storage, read> prim_indices_4: array<u32>;
#endif
#ifdef PRIM_INDICES_CHUNK_5
@group(0) @binding(28) var<storage, read> prim_indices_5: array<u32>;
#endif
#ifdef PRIM_INDICES_CHUNK_6
@group(0) @binding(29) var<storage, read> prim_indices_6: array<u32>;
#endif
#ifdef PRIM_INDICES_CHUNK_7
@group(0) @binding(30) var<storage, read> prim_indices_7: array<u32>;
#endif
#endif
#ifdef TRIANGLES_CHUNKED
@group(0) @binding(32) var<storage, read> triangles_1: array<Triangle>;
#ifdef TRIANGLES_CHUNK_2
@group(0) @binding(33) var<storage, read> triangles_2: array<Triangle>;
#endif
#ifdef TRIANGLES_CHUNK_3
@group(0) @binding(34) var<storage, read> triangles_3: array<Triangle>;
#endif
#ifdef TRIANGLES_CHUNK_4
@group(0) @binding(35) var<storage, read> triangles_4: array<Triangle>;
#endif
#ifdef TRIANGLES_CHUNK_5
@group(0) @binding(36) var<storage, read> triangles_5: array<Triangle>;
#endif
#ifdef TRIANGLES_CHUNK_6
@group(0) @binding(37) var<storage, read> triangles_6: array<Triangle>;
#endif
#ifdef TRIANGLES_CHUNK_7
@group(0) @binding(38) var<storage, read> triangles_7: array<Triangle>;
#endif
#endif
#ifdef TRIANGLE_NORMALS_CHUNKED
@group(0) @binding(40) var<storage, read> triangle_normals_1: array<TriangleNormals>;
#ifdef TRIANGLE_NORMALS_CHUNK_2
@group(0) @binding(41) var<storage, read> triangle_normals_2: array<TriangleNormals>;
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_3
@group(0) @binding(42) var<storage, read> triangle_normals_3: array<TriangleNormals>;
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_4
@group(0) @binding(43) var<storage, read> triangle_normals_4: array<TriangleNormals>;
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_5
@group(0) @binding(44) var<storage, read> triangle_normals_5: array<TriangleNormals>;
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_6
@group(0) @binding(45) var<storage, read> triangle_normals_6: array<TriangleNormals>;
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_7
@group(0) @binding(46) var<storage, read> triangle_normals_7: array<TriangleNormals>;
#endif
#endif
#ifdef TRIANGLE_UVS_CHUNKED
@group(0) @binding(48) var<storage, read> triangle_uvs_1: array<TriangleUvs>;
#ifdef TRIANGLE_UVS_CHUNK_2
@group(0) @binding(49) var<storage, read> triangle_uvs_2: array<TriangleUvs>;
#endif
#ifdef TRIANGLE_UVS_CHUNK_3
@group(0) @binding(50) var<storage, read> triangle_uvs_3: array<TriangleUvs>;
#endif
#ifdef TRIANGLE_UVS_CHUNK_4
@group(0) @binding(51) var<storage, read> triangle_uvs_4: array<TriangleUvs>;
#endif
#ifdef TRIANGLE_UVS_CHUNK_5
@group(0) @binding(52) var<storage, read> triangle_uvs_5: array<TriangleUvs>;
#endif
#ifdef TRIANGLE_UVS_CHUNK_6
@group(0) @binding(53) var<storage, read> triangle_uvs_6: array<TriangleUvs>;
#endif
#ifdef TRIANGLE_UVS_CHUNK_7
@group(0) @binding(54) var<storage, read> triangle_uvs_7: array<TriangleUvs>;
#endif
#endif

// Entry `i` of bvh_nodes, whichever way it is bound.
fn bvh_node(i: u32) -> BvhNode {
#ifdef BVH_NODES_CHUNKED
    let j = i & ((1u << #{BVH_NODES_CHUNK_SHIFT}) - 1u);
    switch i >> #{BVH_NODES_CHUNK_SHIFT} {
        case 1u: { return bvh_nodes_1[j]; }
#ifdef BVH_NODES_CHUNK_2
        case 2u: { return bvh_nodes_2[j]; }
#endif
#ifdef BVH_NODES_CHUNK_3
        case 3u: { return bvh_nodes_3[j]; }
#endif
#ifdef BVH_NODES_CHUNK_4
        case 4u: { return bvh_nodes_4[j]; }
#endif
#ifdef BVH_NODES_CHUNK_5
        case 5u: { return bvh_nodes_5[j]; }
#endif
#ifdef BVH_NODES_CHUNK_6
        case 6u: { return bvh_nodes_6[j]; }
#endif
#ifdef BVH_NODES_CHUNK_7
        case 7u: { return bvh_nodes_7[j]; }
#endif
        default: { return bvh_nodes[j]; }
    }
#else
    return bvh_nodes[i];
#endif
}

// Triangle `i`, whichever way it is bound.
fn triangle_at(i: u32) -> Triangle {
#ifdef TRIANGLES_CHUNKED
    let j = i & ((1u << #{TRIANGLES_CHUNK_SHIFT}) - 1u);
    switch i >> #{TRIANGLES_CHUNK_SHIFT} {
        case 1u: { return triangles_1[j]; }
#ifdef TRIANGLES_CHUNK_2
        case 2u: { return triangles_2[j]; }
#endif
#ifdef TRIANGLES_CHUNK_3
        case 3u: { return triangles_3[j]; }
#endif
#ifdef TRIANGLES_CHUNK_4
        case 4u: { return triangles_4[j]; }
#endif
#ifdef TRIANGLES_CHUNK_5
        case 5u: { return triangles_5[j]; }
#endif
#ifdef TRIANGLES_CHUNK_6
        case 6u: { return triangles_6[j]; }
#endif
#ifdef TRIANGLES_CHUNK_7
        case 7u: { return triangles_7[j]; }
#endif
        default: { return triangles[j]; }
    }
#else
    return triangles[i];
#endif
}

// Entry `i` of triangle_normals.
fn triangle_normals_at(i: u32) -> TriangleNormals {
#ifdef TRIANGLE_NORMALS_CHUNKED
    let j = i & ((1u << #{TRIANGLE_NORMALS_CHUNK_SHIFT}) - 1u);
    switch i >> #{TRIANGLE_NORMALS_CHUNK_SHIFT} {
        case 1u: { return triangle_normals_1[j]; }
#ifdef TRIANGLE_NORMALS_CHUNK_2
        case 2u: { return triangle_normals_2[j]; }
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_3
        case 3u: { return triangle_normals_3[j]; }
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_4
        case 4u: { return triangle_normals_4[j]; }
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_5
        case 5u: { return triangle_normals_5[j]; }
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_6
        case 6u: { return triangle_normals_6[j]; }
#endif
#ifdef TRIANGLE_NORMALS_CHUNK_7
        case 7u: { return triangle_normals_7[j]; }
#endif
        default: { return triangle_normals[j]; }
    }
#else
    return triangle_normals[i];
#endif
}

// Entry `i` of triangle_uvs.
fn triangle_uvs_at(i: u32) -> TriangleUvs {
#ifdef TRIANGLE_UVS_CHUNKED
    let j = i & ((1u << #{TRIANGLE_UVS_CHUNK_SHIFT}) - 1u);
    switch i >> #{TRIANGLE_UVS_CHUNK_SHIFT} {
        case 1u: { return triangle_uvs_1[j]; }
#ifdef TRIANGLE_UVS_CHUNK_2
        case 2u: { return triangle_uvs_2[j]; }
#endif
#ifdef TRIANGLE_UVS_CHUNK_3
        case 3u: { return triangle_uvs_3[j]; }
#endif
#ifdef TRIANGLE_UVS_CHUNK_4
        case 4u: { return triangle_uvs_4[j]; }
#endif
#ifdef TRIANGLE_UVS_CHUNK_5
        case 5u: { return triangle_uvs_5[j]; }
#endif
#ifdef TRIANGLE_UVS_CHUNK_6
        case 6u: { return triangle_uvs_6[j]; }
#endif
#ifdef TRIANGLE_UVS_CHUNK_7
        case 7u: { return triangle_uvs_7[j]; }
#endif
        default: { return triangle_uvs[j]; }
    }
#else
    return triangle_uvs[i];
#endif
}

// Entry `i` of prim_indices, whichever way it is bound.
#ifdef TEXTURES
// Word `i` of the texture table, which is split over several bindings when it is larger than
// one (TEXTURES_CHUNKED: chunks of 2^TEXTURES_CHUNK_SHIFT words).
fn texture_word(i: u32) -> u32 {
#ifdef TEXTURES_CHUNKED
    let j = i & ((1u << #{TEXTURES_CHUNK_SHIFT}) - 1u);
    switch i >> #{TEXTURES_CHUNK_SHIFT} {
        case 1u: { return textures_1[j]; }
#ifdef TEXTURES_CHUNK_2
        case 2u: { return textures_2[j]; }
#endif
#ifdef TEXTURES_CHUNK_3
        case 3u: { return textures_3[j]; }
#endif
#ifdef TEXTURES_CHUNK_4
        case 4u: { return textures_4[j]; }
#endif
#ifdef TEXTURES_CHUNK_5
        case 5u: { return textures_5[j]; }
#endif
#ifdef TEXTURES_CHUNK_6
        case 6u: { return textures_6[j]; }
#endif
#ifdef TEXTURES_CHUNK_7
        case 7u: { return textures_7[j]; }
#endif
        default: { return textures[j]; }
    }
#else
    return textures[i];
#endif
}
#endif

fn prim_index(i: u32) -> u32 {
#ifdef PRIM_INDICES_UNIFORM
    return prim_indices[i >> 2u][i & 3u];
#else
#ifdef PRIM_INDICES_CHUNKED
    let j = i & ((1u << #{PRIM_INDICES_CHUNK_SHIFT}) - 1u);
    switch i >> #{PRIM_INDICES_CHUNK_SHIFT} {
        case 1u: { return prim_indices_1[j]; }
#ifdef PRIM_INDICES_CHUNK_2
        case 2u: { return prim_indices_2[j]; }
#endif
#ifdef PRIM_INDICES_CHUNK_3
        case 3u: { return prim_indices_3[j]; }
#endif
#ifdef PRIM_INDICES_CHUNK_4
        case 4u: { return prim_indices_4[j]; }
#endif
#ifdef PRIM_INDICES_CHUNK_5
        case 5u: { return prim_indices_5[j]; }
#endif
#ifdef PRIM_INDICES_CHUNK_6
        case 6u: { return prim_indices_6[j]; }
#endif
#ifdef PRIM_INDICES_CHUNK_7
        case 7u: { return prim_indices_7[j]; }
#endif
        default: { return prim_indices[j]; }
    }
#else
    return prim_indices[i];
#endif
#endif
}

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

// Closest hit along the ray within (0, t_max). With `any_hit`, returns at the first hit found.
// `front_wins_ties`: see keep_closer.
fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, any_hit: bool, front_wins_ties: bool) -> Hit {
#ifdef EVERY_PRIM
    return test_every_prim(origin, dir, t_max, front_wins_ties);
#else
    return traverse_bvh(origin, dir, t_max, any_hit, front_wins_ties);
#endif
}

fn traverse_bvh(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, any_hit: bool, front_wins_ties: bool) -> Hit {
    var hit = Hit(t_max, NO_HIT, false);
    let inv_dir = safe_inverse(dir);
    var stack: array<u32, BVH_STACK_SIZE>;
    var top = 0u;
    var node_index = 0u;
    // An empty scene's root has an inverted box and no children (see src/scene/bvh.rs).
    if scene_info.num_triangles + scene_info.num_spheres == 0u {
        return Hit(T_INFINITE, NO_HIT, false);
    }
    let root = bvh_node(0u);
    if intersect_box(root.min, root.max, origin, inv_dir, t_max) == T_INFINITE {
        return Hit(T_INFINITE, NO_HIT, false);
    }
    loop {
        let node = bvh_node(node_index);
        if node.count > 0u {
            for (var i = 0u; i < node.count; i++) {
                let prim = prim_index(node.left_or_first + i);
                let kept = keep_closer(&hit, prim, prim_crossing(prim, origin, dir), origin, dir, front_wins_ties);
                if kept && any_hit {
                    return hit;
                }
            }
        } else {
            let left = node.left_or_first;
            let right = left + 1u;
            // A tie may lie in a box a hair beyond the closest hit so far.
            let reach = select(hit.t, hit.t + tie_span(origin, hit.t), front_wins_ties && hit.prim != NO_HIT);
#ifdef BVH_NODES_CHUNKED
            let left_node = bvh_node(left);
            let right_node = bvh_node(right);
            let t_left = intersect_box(left_node.min, left_node.max, origin, inv_dir, reach);
            let t_right = intersect_box(right_node.min, right_node.max, origin, inv_dir, reach);
#else
            let t_left = intersect_box(bvh_nodes[left].min, bvh_nodes[left].max, origin, inv_dir, reach);
            let t_right = intersect_box(bvh_nodes[right].min, bvh_nodes[right].max, origin, inv_dir, reach);
#endif
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

#ifdef EVERY_PRIM
// Small scenes on a CPU adapter test every primitive instead of walking the BVH
// (src/passes/scene_resources.rs decides). Mesa 25.0's lavapipe loads a table entry once for
// all SIMD lanes only when its index is a compile-time constant; any other index, a loop
// counter included, costs a bounds-checked scalar load per lane (BENCHMARKS.md). So the tests
// are unrolled: each `first` below is a constant at its call site once the functions are
// inlined, and the defs TRIANGLES_FROM_<n> and SPHERES_FROM_<n> (n a power of two, the value
// the first index of that block) split the scene's primitives into blocks of powers of two.
// No test returns early (a masked-off lane runs every test anyway), but a block of four whose
// box no lane enters is skipped: binding 1 holds those boxes instead of the BVH's nodes.
fn test_triangles_1(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    keep_closer(hit, first, triangle_crossing(first, origin, dir), origin, dir, front_wins_ties);
}

fn test_triangles_2(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_1(hit, first, origin, dir, front_wins_ties);
    test_triangles_1(hit, first + 1u, origin, dir, front_wins_ties);
}

fn test_triangles_4(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    // Binding 1 holds a box per block of four (src/passes/scene_resources.rs, block_boxes),
    // with `count` 1 where it is worth testing. A box no lane enters skips the four tests: lavapipe
    // jumps over code no lane runs.
    let block = bvh_nodes[first / 4u];
    if block.count != 0u {
        // A tie may lie a hair beyond the closest hit so far (as in traverse_bvh).
        let reach = select((*hit).t, (*hit).t + tie_span(origin, (*hit).t), front_wins_ties && (*hit).prim != NO_HIT);
        if intersect_box(block.min, block.max, origin, safe_inverse(dir), reach) == T_INFINITE {
            return;
        }
    }
    test_triangles_2(hit, first, origin, dir, front_wins_ties);
    test_triangles_2(hit, first + 2u, origin, dir, front_wins_ties);
}

fn test_triangles_8(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_4(hit, first, origin, dir, front_wins_ties);
    test_triangles_4(hit, first + 4u, origin, dir, front_wins_ties);
}

fn test_triangles_16(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_8(hit, first, origin, dir, front_wins_ties);
    test_triangles_8(hit, first + 8u, origin, dir, front_wins_ties);
}

fn test_triangles_32(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_16(hit, first, origin, dir, front_wins_ties);
    test_triangles_16(hit, first + 16u, origin, dir, front_wins_ties);
}

fn test_triangles_64(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_triangles_32(hit, first, origin, dir, front_wins_ties);
    test_triangles_32(hit, first + 32u, origin, dir, front_wins_ties);
}

#ifdef SPHERES
fn test_spheres_1(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    keep_closer(hit, scene_info.num_triangles + first, sphere_crossing(spheres[first], origin, dir), origin, dir, front_wins_ties);
}

fn test_spheres_2(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_spheres_1(hit, first, origin, dir, front_wins_ties);
    test_spheres_1(hit, first + 1u, origin, dir, front_wins_ties);
}

fn test_spheres_4(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_spheres_2(hit, first, origin, dir, front_wins_ties);
    test_spheres_2(hit, first + 2u, origin, dir, front_wins_ties);
}

fn test_spheres_8(hit: ptr<function, Hit>, first: u32, origin: vec3<f32>, dir: vec3<f32>, front_wins_ties: bool) {
    test_spheres_4(hit, first, origin, dir, front_wins_ties);
    test_spheres_4(hit, first + 4u, origin, dir, front_wins_ties);
}
#endif

fn test_every_prim(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, front_wins_ties: bool) -> Hit {
    var hit = Hit(t_max, NO_HIT, false);
#ifdef TRIANGLES_FROM_64
    test_triangles_64(&hit, #{TRIANGLES_FROM_64}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_32
    test_triangles_32(&hit, #{TRIANGLES_FROM_32}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_16
    test_triangles_16(&hit, #{TRIANGLES_FROM_16}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_8
    test_triangles_8(&hit, #{TRIANGLES_FROM_8}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_4
    test_triangles_4(&hit, #{TRIANGLES_FROM_4}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_2
    test_triangles_2(&hit, #{TRIANGLES_FROM_2}u, origin, dir, front_wins_ties);
#endif
#ifdef TRIANGLES_FROM_1
    test_triangles_1(&hit, #{TRIANGLES_FROM_1}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_8
    test_spheres_8(&hit, #{SPHERES_FROM_8}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_4
    test_spheres_4(&hit, #{SPHERES_FROM_4}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_2
    test_spheres_2(&hit, #{SPHERES_FROM_2}u, origin, dir, front_wins_ties);
#endif
#ifdef SPHERES_FROM_1
    test_spheres_1(&hit, #{SPHERES_FROM_1}u, origin, dir, front_wins_ties);
#endif
    if hit.prim == NO_HIT {
        hit.t = T_INFINITE;
    }
    return hit;
}
#endif

fn intersect_scene(origin: vec3<f32>, dir: vec3<f32>) -> Hit {
    return traverse(origin, dir, T_INFINITE, false, false);
}

// The closest hit of a photon (see traverse's `front_wins_ties`).
fn intersect_photon(origin: vec3<f32>, dir: vec3<f32>) -> Hit {
    return traverse(origin, dir, T_INFINITE, false, true);
}

fn occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    return traverse(origin, dir, t_max, true, false).prim != NO_HIT;
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
