#define_import_path common::scene

// Shader defs (src/shaders.rs, from the scene): SPHERES compiles in sphere intersection,
// DIELECTRIC the smooth and thin dielectric BSDFs, CONDUCTOR the smooth and rough conductors,
// PLASTIC plastic and rough plastic, ROUGH_DIELECTRIC the rough dielectric, POINT_LIGHTS
// point and spot lights and projectors, SPOT_LIGHTS spot lights, PROJECTORS projectors,
// DIRECTIONAL_LIGHTS directional lights,
// ENVIRONMENT a constant or map light seen by escaping rays. Code for what a scene
// lacks is left out of every kernel.

// The scene every pass shares (bind group 0): its records, constants, bindings and the readers of
// tables split into chunks. Layouts mirror src/gpu_scene/layout.rs. Intersecting it is
// common::intersection and common::traversal's; the surface hit, common::surface's.

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
// src/gpu_scene/resources.rs's TablePlacement, holds its length): lavapipe loads a divergent
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
// own binding, chunk k at the table's chunk base + k - 1 (src/gpu_scene/resources.rs,
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
