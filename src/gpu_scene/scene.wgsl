#define_import_path common::scene

// Shader defs (src/passes/shader_library.rs, from the scene): SPHERES compiles in sphere
// intersection, POINT_LIGHTS point and spot lights and projectors, SPOT_LIGHTS spot lights,
// PROJECTORS projectors, DIRECTIONAL_LIGHTS directional lights, ENVIRONMENT a constant or map
// light seen by escaping rays, and each BSDF unit's def its WGSL (src/bsdfs/). Code for what a
// scene lacks is left out of every kernel. The material kinds' numbers (MATERIAL_<KIND>) are
// generated from the BSDF registry and follow this file.

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
    // The medium around the camera (offset of its record in bsdf_tables), or NO_MEDIUM.
    camera_medium: u32,
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
    // A normalmap or bumpmap around the BSDF (bsdfs::normalmap's FRAME_*), its texture, the
    // bump map's scale and FRAME_FLAG_* bits.
    frame_kind: u32,
    frame_texture: u32,
    frame_scale: f32,
    frame_flags: u32,
    // A blend (bsdfs::blendbsdf): the two materials it chooses between, the probability of the
    // second and the scalar texture that replaces it, or NO_TEXTURE.
    children: vec2<u32>,
    blend_weight: f32,
    blend_weight_texture: u32,
    // Scalar textures replacing one component each of specular, eta and k (principled's
    // parameters): field_texture_count pairs (component of the nine, texture) of bsdf_tables
    // from field_textures (common::texture).
    field_textures: u32,
    field_texture_count: u32,
    // The media inside and outside the shape (offsets of their records in bsdf_tables,
    // common::medium), or NO_MEDIUM.
    interior: u32,
    exterior: u32,
    pad_media: vec2<u32>,
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
    // The medium its photons start in (offset of its record in bsdf_tables), or NO_MEDIUM.
    medium: u32,
    frame_y: vec3<f32>,
    pad_y: u32,
}

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
const NO_MEDIUM: u32 = 0xffffffffu;
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
// Tables BSDFs look up (rough plastic's transmittance per cos theta), lights' (environment maps)
// and the media's records (common::medium).
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
#endif

// Tables larger than one storage binding (a mesh of millions of triangles on an adapter that
// binds 128 MiB) are split into chunks; their bindings and the readers every access to such a
// table goes through (bvh_node, prim_index, triangle_at, triangle_normals_at, triangle_uvs_at,
// texture_word) follow this file, generated from one list (src/gpu_scene/tables.rs).
