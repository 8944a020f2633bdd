//! The scene as the GPU reads it. Each struct mirrors one in `src/gpu_scene/scene.wgsl`
//! (std430 layout: a `vec3<f32>` takes 12 bytes but aligns to 16, so each is followed by a
//! 4-byte scalar). Keep the two in step; `tests/shaders.rs` checks the sizes against naga's.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::media::{self, NO_MEDIUM};
use crate::bsdfs::BsdfRegistry;
pub use crate::scene::bsdf::GpuMaterial;
use crate::scene::bsdf::mean;
use crate::scene::bvh::split_boxes::split_references;
use crate::scene::bvh::{self, BvhNode};
use crate::scene::emitter::Environment;
use crate::scene::filter::FILTER_TABLE_NODES;
use crate::scene::texture::{self, NO_TEXTURE};
use crate::scene::{Bsdf, PerturbationKind, Scene, SceneError, SideTextures};

/// `GpuMaterial::frame_kind`: the shading frame as the shape gives it, or perturbed by a
/// normal map or a bump map (src/bsdfs/normalmap/frame.rs).
pub const FRAME_NONE: u32 = 0;
pub const FRAME_NORMAL_MAP: u32 = 1;
pub const FRAME_BUMP_MAP: u32 = 2;
/// `GpuMaterial::frame_flags`: Mitsuba's `flip_invalid_normals` and `use_shadowing_function`,
/// and the back side of a `twosided` the perturbation wraps.
pub const FRAME_FLAG_FLIP_INVALID: u32 = 1;
pub const FRAME_FLAG_SHADOWING: u32 = 2;
pub const FRAME_FLAG_OUTSIDE_TWOSIDED: u32 = 4;

/// `back` of a material without a back side of its own.
pub const NO_BACK: u32 = u32::MAX;

pub const LIGHT_TRIANGLE: u32 = 0;
pub const LIGHT_SPHERE: u32 = 1;
pub const LIGHT_POINT: u32 = 2;
pub const LIGHT_SPOT: u32 = 3;
pub const LIGHT_DIRECTIONAL: u32 = 4;
pub const LIGHT_CONSTANT: u32 = 5;
pub const LIGHT_ENVMAP: u32 = 6;
pub const LIGHT_PROJECTOR: u32 = 7;

/// `normals` of a triangle without vertex normals.
pub const NO_NORMALS: u32 = u32::MAX;
/// `light` of a primitive that emits nothing.
pub const NO_LIGHT: u32 = u32::MAX;
/// `max_depth` / `rr_depth` meaning "unbounded" / "never".
pub const UNBOUNDED: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuTriangle {
    pub vertex: [f32; 3],
    pub material: u32,
    pub edge_a: [f32; 3],
    pub light: u32,
    pub edge_b: [f32; 3],
    /// Index of the triangle's vertex normals in `GpuScene::triangle_normals`, or `NO_NORMALS`
    /// (shaded with its face normal).
    pub normals: u32,
}

/// A triangle's texture coordinates at `vertex`, `vertex + edge_a`, `vertex + edge_b` (one per
/// triangle, in triangle order; the barycentrics' corners for a triangle without any).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuTriangleUvs {
    pub a: [f32; 2],
    pub b: [f32; 2],
    pub c: [f32; 2],
}

/// A triangle's unit vertex normals, at `vertex`, `vertex + edge_a`, `vertex + edge_b`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuTriangleNormals {
    pub a: [f32; 3],
    pub _pad_a: u32,
    pub b: [f32; 3],
    pub _pad_b: u32,
    pub c: [f32; 3],
    pub _pad_c: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuSphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: u32,
    pub light: u32,
    pub flip_normals: u32,
    pub _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuLight {
    /// Point and spot lights, projectors: position. Others: unused.
    pub position: [f32; 3],
    pub kind: u32,
    /// Point and spot lights: intensity (W/sr). Area, constant and map lights: emitted
    /// radiance (a map's texels carry its own). Directional lights: irradiance. Projectors:
    /// pi x scale x irradiance (their intensity on the axis).
    pub radiance: [f32; 3],
    /// Triangle or sphere index of an area light.
    pub prim: u32,
    /// Spot lights and projectors: the unit axis they shine along (local +z). Directional
    /// lights: the unit direction the light travels in.
    pub axis: [f32; 3],
    /// Probability that next-event estimation picks this light: Mitsuba's rule, each emitter
    /// (a shape, a point or distant light) alike, and within a shape its parts by power.
    pub select_prob: f32,
    /// Area lights: their area. Constant and map lights: the area of the disc their photons
    /// leave from (the scene's bounding sphere's cross-section). Projectors: the image's area
    /// on the plane one unit ahead.
    pub area: f32,
    /// Environment maps: the first index of their table in `bsdf_tables`.
    pub table: u32,
    /// Spot lights: cutoff angle and beam width in radians.
    pub cutoff: f32,
    pub beam_width: f32,
    /// Probability that a photon leaves this light: its share of the scene's power, so that
    /// photons carry equal flux.
    pub emit_prob: f32,
    /// Spot lights and projectors: the texture (an index of `GpuScene::textures`' headers)
    /// multiplying their intensity, or `NO_TEXTURE`.
    pub texture: u32,
    /// Spot lights: tan(cutoff); projectors: tan(fov_x / 2). The local direction (x, y, z)
    /// meets the texture at (x, y) / (z uv_factor) on [-1, 1]^2 (y scaled by `aspect` too
    /// for projectors).
    pub uv_factor: f32,
    /// Projectors: the image's width over height.
    pub aspect: f32,
    /// Spot lights and projectors: their unit local x and y in the world.
    pub frame_x: [f32; 3],
    /// The medium its photons start in (the offset of its record), or `NO_MEDIUM`.
    pub medium: u32,
    pub frame_y: [f32; 3],
    pub _pad_y: u32,
}

/// Camera, bounds, counts and integrator settings: one uniform shared by every pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuSceneUniform {
    pub camera_origin: [f32; 3],
    /// The camera plane (one unit ahead, across `camera_right` and `camera_up`) per pixel of
    /// the image: x across, y down the rows (negative). See `plane_origin`.
    pub plane_step_x: f32,
    pub camera_right: [f32; 3],
    pub plane_step_y: f32,
    pub camera_up: [f32; 3],
    /// The pixel grid this render's buffers hold: the whole film, or one tile of it.
    pub width: u32,
    pub camera_forward: [f32; 3],
    pub height: u32,
    pub bounds_min: [f32; 3],
    /// The medium around the camera (the offset of its record), or `NO_MEDIUM`.
    pub camera_medium: u32,
    pub bounds_max: [f32; 3],
    pub scene_radius: f32,
    pub num_triangles: u32,
    pub num_spheres: u32,
    pub num_lights: u32,
    pub max_depth: u32,
    pub rr_depth: u32,
    /// The pixel filter: `filter::FILTER_*`, its parameter (tent radius, Gaussian stddev) and
    /// whether samples may leave the film (1) or each pixel's filter is cut at its edge (0).
    pub filter_kind: u32,
    pub filter_param: f32,
    pub sample_border: u32,
    /// A sphere around every specular (delta) surface; radius 0 when there is none. Caustic
    /// photons are aimed at it: a photon that misses it can never cross a specular vertex.
    pub specular_center: [f32; 3],
    pub specular_radius: f32,
    /// The index of the constant or map light that escaping rays see, or `NO_LIGHT`.
    pub environment: u32,
    /// The whole image, and where the pixel grid (`width` x `height`) lies in it: rays and
    /// random streams follow film pixels, so a tile renders exactly its part of the image.
    pub film_width: u32,
    pub film_height: u32,
    pub tile_x: u32,
    pub tile_y: u32,
    /// 1 when camera rays pass through emitting shapes and see no environment (Mitsuba's
    /// `hide_emitters`).
    pub hide_emitters: u32,
    /// Where the image's top-left corner meets the camera plane: with the steps above, the
    /// projection of the whole film and where the image (a crop window, maybe) lies in it.
    pub plane_origin: [f32; 2],
    /// A thin lens: the aperture's radius (0 for a pinhole) and the focus plane's distance
    /// along the view.
    pub aperture_radius: f32,
    pub focus_distance: f32,
    /// The pixel filter's second parameter (Mitchell's C) beside `filter_param`.
    pub filter_param_b: f32,
    pub _pad_filter: u32,
    /// A signed filter's sampling table ([`crate::scene::filter::PixelFilter::gpu_table`]); zeros otherwise.
    pub filter_table: [[f32; 4]; FILTER_TABLE_NODES / 2],
}

/// Everything the GPU needs to trace rays through a scene. Arrays are never empty (a zeroed
/// element is added) because wgpu rejects empty storage bindings; the counts in `uniform` say
/// how many entries are real.
pub struct GpuScene {
    pub uniform: GpuSceneUniform,
    pub bvh_nodes: Vec<BvhNode>,
    pub prim_indices: Vec<u32>,
    pub triangles: Vec<GpuTriangle>,
    pub triangle_normals: Vec<GpuTriangleNormals>,
    pub triangle_uvs: Vec<GpuTriangleUvs>,
    pub spheres: Vec<GpuSphere>,
    pub materials: Vec<GpuMaterial>,
    pub lights: Vec<GpuLight>,
    /// Inclusive prefix sums of `select_prob` (searched to pick a light for NEE), then of
    /// `emit_prob` (to pick one for a photon): twice as many entries as lights.
    pub light_cdf: Vec<f32>,
    /// Tables BSDFs look up (rough plastic's transmittance), addressed by `GpuMaterial::table`.
    pub bsdf_tables: Vec<f32>,
    /// Every texture, in `texture::gpu_words`' layout; empty (and then not bound at all) when
    /// no material has one.
    pub textures: Vec<u32>,
    /// Not uploaded: a sphere (centre, padded radius; radius 0 when there is none) around every
    /// surface with a delta or a microfacet lobe, which caustic photons aim at when a
    /// `glossy_threshold` makes glossy lobes specular vertices (`photon_trace`).
    pub glossy_sphere: [f32; 4],
    /// Not uploaded: the smallest roughness of any microfacet lobe (0 when textured; infinite
    /// without one), which a `glossy_threshold` must exceed to matter.
    pub smoothest_microfacet: f32,
    /// Not uploaded: the scene has participating media.
    pub media: bool,
}

/// The GPU form of one side's BSDF: the layout's fields (kind, emission, frame, texture slots),
/// then what the BSDF packs; its tables (if any) are appended to `tables`.
fn gpu_material(
    bsdf: &Bsdf,
    textures: &SideTextures,
    emission: Vec3,
    kind: u32,
    tables: &mut Vec<f32>,
) -> GpuMaterial {
    let mut m = GpuMaterial {
        albedo: [0.0; 3],
        kind,
        emission: emission.to_array(),
        int_ior: 1.0,
        specular: [1.0; 3],
        ext_ior: 1.0,
        eta: [0.0; 3],
        alpha_u: 0.0,
        k: [0.0; 3],
        alpha_v: 0.0,
        distribution: 0,
        back: NO_BACK,
        nonlinear: 0,
        specular_weight: 0.0,
        internal_reflectance: 0.0,
        table: 0,
        diffuse_texture: textures.diffuse.unwrap_or(NO_TEXTURE),
        specular_texture: textures.specular.unwrap_or(NO_TEXTURE),
        alpha_u_texture: textures.alpha_u.unwrap_or(NO_TEXTURE),
        alpha_v_texture: textures.alpha_v.unwrap_or(NO_TEXTURE),
        frame_kind: FRAME_NONE,
        frame_texture: NO_TEXTURE,
        frame_scale: 1.0,
        frame_flags: 0,
        children: [0; 2],
        blend_weight: 0.0,
        blend_weight_texture: textures.blend_weight.unwrap_or(NO_TEXTURE),
        field_textures: 0,
        field_texture_count: 0,
        interior: NO_MEDIUM,
        exterior: NO_MEDIUM,
        _pad_media: [0; 2],
    };
    if let Some(frame) = textures.frame {
        (m.frame_kind, m.frame_scale) = match frame.kind {
            PerturbationKind::Normal => (FRAME_NORMAL_MAP, 1.0),
            PerturbationKind::Bump { scale } => (FRAME_BUMP_MAP, scale),
        };
        m.frame_texture = frame.texture;
        let flag = |on: bool, bit: u32| if on { bit } else { 0 };
        m.frame_flags = flag(frame.flip_invalid_normals, FRAME_FLAG_FLIP_INVALID)
            | flag(frame.shadowing, FRAME_FLAG_SHADOWING)
            | flag(frame.outside_twosided, FRAME_FLAG_OUTSIDE_TWOSIDED);
    }
    bsdf.pack(&mut m, textures, tables);
    m
}

/// Every material's front, then the back sides of twosided ones (each front pointing at its
/// back), and the BSDF tables they use; each BSDF's kind numbered by `bsdfs`.
fn gpu_materials(
    scene: &Scene,
    bsdfs: &BsdfRegistry,
) -> Result<(Vec<GpuMaterial>, Vec<f32>), SceneError> {
    let number =
        |bsdf: &Bsdf| {
            bsdfs.number_of(bsdf.kind()).ok_or_else(|| SceneError::File {
            file: scene.source.clone(),
            message: format!(
                "the scene uses the BSDF kind \"{}\", which the registry it is rendered with \
                 does not have (its kinds: {})",
                bsdf.kind(),
                bsdfs.kinds().map(|(_, k)| k.name).collect::<Vec<_>>().join(", ")
            ),
        })
        };
    let mut tables = Vec::new();
    let mut materials = Vec::with_capacity(scene.materials.len());
    for m in &scene.materials {
        let kind = number(&m.bsdf)?;
        materials.push(gpu_material(
            &m.bsdf,
            &m.textures.front,
            m.emission,
            kind,
            &mut tables,
        ));
    }
    for i in 0..scene.materials.len() {
        if let Some(back) = &scene.materials[i].back {
            let index = materials.len() as u32;
            // The back emits nothing: area emitters are one-sided.
            let textures = &scene.materials[i].textures.back;
            let kind = number(back)?;
            materials.push(gpu_material(back, textures, Vec3::ZERO, kind, &mut tables));
            materials[i].back = index;
        }
    }
    Ok((materials, tables))
}

/// A light, its unnormalised power and the emitter it is part of.
struct LightEntry {
    light: GpuLight,
    power: f32,
    emitter: u64,
}

/// Lights with their power and emitter: emitting triangles of one material are one emitter
/// (the Mitsuba loader gives every shape its own material), every other light its own. An
/// environment map's table is appended to `tables`.
fn collect_lights(scene: &Scene, tables: &mut Vec<f32>) -> Vec<LightEntry> {
    let mut lights = Vec::new();
    let emission = |m: u32| {
        scene
            .materials
            .get(m as usize)
            .map_or(Vec3::ZERO, |mat| mat.emission)
    };
    let light = |kind, radiance: Vec3| GpuLight {
        kind,
        radiance: radiance.to_array(),
        texture: NO_TEXTURE,
        ..Zeroable::zeroed()
    };
    // Emitters after the triangles' materials are numbered from here.
    let mut next = scene.materials.len() as u64;
    let mut own = move || {
        next += 1;
        next
    };
    let entry = |light, power, emitter| LightEntry {
        light,
        power,
        emitter,
    };
    let area_light = |kind, prim, radiance: Vec3, area: f32, emitter| {
        let light = GpuLight {
            prim,
            area,
            ..light(kind, radiance)
        };
        // One-sided Lambertian emitter: power = pi * area * radiance.
        entry(light, std::f32::consts::PI * area * mean(radiance), emitter)
    };
    for (i, t) in scene.triangles.iter().enumerate() {
        let radiance = emission(t.material);
        // In f64: the cross product's squared length is a length to the fourth, which
        // overflows f32 for scenes past about 1e9.
        let [a, b, c] = t.v.map(|v| v.as_dvec3());
        let area = (0.5 * (b - a).cross(c - a).length()) as f32;
        if radiance.max_element() > 0.0 && area > 0.0 {
            let emitter = t.material as u64;
            lights.push(area_light(
                LIGHT_TRIANGLE,
                i as u32,
                radiance,
                area,
                emitter,
            ));
        }
    }
    for (i, s) in scene.spheres.iter().enumerate() {
        let radiance = emission(s.material);
        let area = 4.0 * std::f32::consts::PI * s.radius * s.radius;
        if radiance.max_element() > 0.0 && area > 0.0 {
            lights.push(area_light(LIGHT_SPHERE, i as u32, radiance, area, own()));
        }
    }
    for p in &scene.point_lights {
        if p.intensity.max_element() > 0.0 {
            let point = GpuLight {
                position: p.position.to_array(),
                ..light(LIGHT_POINT, p.intensity)
            };
            let power = 4.0 * std::f32::consts::PI * mean(p.intensity);
            lights.push(entry(point, power, own()));
        }
    }
    for s in &scene.emitters.spots {
        if s.intensity.max_element() > 0.0 && s.cutoff > 0.0 {
            let spot = GpuLight {
                position: s.position.to_array(),
                axis: s.axis.to_array(),
                cutoff: s.cutoff,
                beam_width: s.beam_width,
                texture: s.texture.unwrap_or(NO_TEXTURE),
                uv_factor: s.cutoff.tan(),
                frame_x: s.frame[0].to_array(),
                frame_y: s.frame[1].to_array(),
                ..light(LIGHT_SPOT, s.intensity)
            };
            // A textured spot's power includes the texture's mean over its cone.
            lights.push(entry(spot, mean(s.power_with(&scene.textures)), own()));
        }
    }
    for p in &scene.emitters.projectors {
        if p.irradiance.max_element() > 0.0 {
            let projector = GpuLight {
                position: p.position.to_array(),
                axis: p.frame[2].to_array(),
                area: p.sensor_area(),
                texture: p.texture.unwrap_or(NO_TEXTURE),
                uv_factor: p.tan_half_fov,
                aspect: p.aspect,
                frame_x: p.frame[0].to_array(),
                frame_y: p.frame[1].to_array(),
                ..light(LIGHT_PROJECTOR, p.irradiance * std::f32::consts::PI)
            };
            let power = mean(p.power_with(&scene.textures));
            lights.push(entry(projector, power, own()));
        }
    }
    // Distant lights send their photons from a disc as large as the scene's bounding sphere:
    // their power is what crosses it.
    let (lo, hi) = scene.bounds();
    let disc_area = std::f32::consts::PI * (0.5 * (hi - lo).length()).powi(2);
    for d in &scene.emitters.directionals {
        if d.irradiance.max_element() > 0.0 {
            let directional = GpuLight {
                axis: d.direction.to_array(),
                area: disc_area,
                ..light(LIGHT_DIRECTIONAL, d.irradiance)
            };
            lights.push(entry(directional, disc_area * mean(d.irradiance), own()));
        }
    }
    if let Some(env) = &scene.emitters.environment {
        let power = disc_area * mean(env.radiance_integral());
        // A sunsky renders as the map baked from it.
        let environment = match (env, env.map()) {
            (Environment::Constant { radiance }, _) => light(LIGHT_CONSTANT, *radiance),
            (_, Some(map)) => GpuLight {
                table: map.append_gpu_table(tables),
                ..light(LIGHT_ENVMAP, Vec3::ONE)
            },
            (_, None) => unreachable!("every environment but a constant is a map"),
        };
        if power > 0.0 {
            let environment = GpuLight {
                area: disc_area,
                ..environment
            };
            lights.push(entry(environment, power, own()));
        }
    }
    lights
}

/// Selection probabilities and their CDFs: for NEE each emitter with power alike and its
/// parts by power (Mitsuba 3 picks emitters uniformly), for photons every light by power.
fn normalise_lights(entries: Vec<LightEntry>) -> (Vec<GpuLight>, Vec<f32>) {
    let total: f64 = entries.iter().map(|e| e.power as f64).sum();
    let mut emitter_power: std::collections::HashMap<u64, f64> = Default::default();
    for e in &entries {
        *emitter_power.entry(e.emitter).or_default() += e.power as f64;
    }
    let emitters = emitter_power.values().filter(|&&p| p > 0.0).count() as f64;
    let mut lights: Vec<GpuLight> = Vec::with_capacity(entries.len());
    for e in &entries {
        let share = |part: f64, whole: f64| if whole > 0.0 { part / whole } else { 0.0 };
        let of_emitter = share(e.power as f64, emitter_power[&e.emitter]);
        lights.push(GpuLight {
            select_prob: (share(1.0, emitters) * of_emitter) as f32,
            emit_prob: share(e.power as f64, total) as f32,
            ..e.light
        });
    }
    let cdf = |prob: &dyn Fn(&GpuLight) -> f32| {
        let mut running = 0.0f64;
        let mut cdf: Vec<f32> = lights
            .iter()
            .map(|l| {
                running += prob(l) as f64;
                running as f32
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        cdf
    };
    let mut cdfs = cdf(&|l| l.select_prob);
    cdfs.extend(cdf(&|l| l.emit_prob));
    (lights, cdfs)
}

fn camera_uniform(scene: &Scene, width: u32, height: u32) -> GpuSceneUniform {
    let cam = &scene.camera;
    let forward = (cam.target - cam.origin).normalize_or_zero();
    // Right-handed, y up: image x grows along forward x up, image y along the camera's up.
    let right = forward.cross(cam.up).normalize_or_zero();
    let up = right.cross(forward);
    // The fov spans the whole film (a crop window shows part of it); as without a crop, pixels
    // stay square, so the vertical extent follows the projected film's shape.
    let ([film_w, film_h], [offset_x, offset_y]) = cam.projected_film((width, height));
    let tan_half_x = ((cam.fov_x_deg as f64).to_radians() * 0.5).tan();
    let tan_half_y = tan_half_x * film_h / film_w.max(f64::MIN_POSITIVE);
    let step_x = 2.0 * tan_half_x / film_w;
    let step_y = -2.0 * tan_half_y / film_h;
    let (filter_kind, [filter_param, filter_param_b]) = cam.filter.gpu_code();
    let (aperture_radius, focus_distance) = cam
        .lens
        .map_or((0.0, 1.0), |l| (l.aperture_radius, l.focus_distance));
    GpuSceneUniform {
        camera_origin: cam.origin.to_array(),
        plane_step_x: step_x as f32,
        camera_right: right.to_array(),
        plane_step_y: step_y as f32,
        camera_up: up.to_array(),
        width,
        camera_forward: forward.to_array(),
        height,
        film_width: width,
        film_height: height,
        filter_kind,
        filter_param,
        filter_param_b,
        filter_table: cam.filter.gpu_table(),
        sample_border: cam.sample_border as u32,
        plane_origin: [
            (-tan_half_x + offset_x * step_x) as f32,
            (tan_half_y + offset_y * step_y) as f32,
        ],
        aperture_radius,
        focus_distance,
        ..Zeroable::zeroed()
    }
}

/// Extra references per primitive that triangles fitting their boxes badly may be split into
/// before the BVH is built. On water_glass (fans and long thin walls) the split tree takes 18%
/// fewer primitive tests per ray by the surface area heuristic, `pt` ran 8-10% faster and the
/// photon pass 25% faster, with the same image; 0.25 and 0.5 gained less (BENCHMARKS.md). The
/// splits stop earlier where no box is worth splitting (water_glass ends at 1.76 per primitive).
pub const SPLIT_EXTRA: f32 = 1.0;

impl GpuScene {
    /// Bytes of the tables uploaded for the scene.
    pub fn table_bytes(&self) -> u64 {
        use std::mem::size_of_val;
        [
            size_of_val(self.bvh_nodes.as_slice()),
            size_of_val(self.prim_indices.as_slice()),
            size_of_val(self.triangles.as_slice()),
            size_of_val(self.triangle_normals.as_slice()),
            size_of_val(self.triangle_uvs.as_slice()),
            size_of_val(self.spheres.as_slice()),
            size_of_val(self.materials.as_slice()),
            size_of_val(self.lights.as_slice()),
            size_of_val(self.light_cdf.as_slice()),
            size_of_val(self.bsdf_tables.as_slice()),
            size_of_val(self.textures.as_slice()),
        ]
        .iter()
        .map(|&b| b as u64)
        .sum()
    }

    /// Renders the `width` x `height` pixels at (`x`, `y`) of the film instead of all of it
    /// (a tile of an image whose buffers would not fit one binding).
    pub fn set_tile(&mut self, x: u32, y: u32, width: u32, height: u32) {
        let u = &mut self.uniform;
        u.tile_x = x;
        u.tile_y = y;
        u.width = width;
        u.height = height;
    }

    /// Lays out `scene` for rendering at `width` x `height`.
    /// The scene with its BSDFs numbered as hppm's own registry numbers them
    /// ([`Self::with_bsdfs`] for a registry with a program's BSDFs).
    pub fn new(scene: &Scene, width: u32, height: u32) -> Result<Self, SceneError> {
        Self::with_bsdfs(scene, width, height, BsdfRegistry::builtin_ref())
    }

    /// The scene as the GPU reads it, its material kinds numbered by `bsdfs` (the registry the
    /// kernels' WGSL is generated from). Refused when the scene uses a BSDF kind `bsdfs` lacks.
    pub fn with_bsdfs(
        scene: &Scene,
        width: u32,
        height: u32,
        bsdfs: &BsdfRegistry,
    ) -> Result<Self, SceneError> {
        // The BVH is built over split references (src/scene/bvh/split_boxes.rs); its leaves then
        // name primitives, each possibly in several leaves.
        let refs = split_references(scene, SPLIT_EXTRA);
        let mut bvh = bvh::build_sah(&refs.boxes, 4);
        for r in &mut bvh.indices {
            *r = refs.prims[*r as usize];
        }
        let (mut materials, mut bsdf_tables) = gpu_materials(scene, bsdfs)?;
        let (mut lights, light_cdf) = normalise_lights(collect_lights(scene, &mut bsdf_tables));
        let medium_offsets = media::append_records(scene, &mut bsdf_tables);
        for (gpu, m) in materials.iter_mut().zip(&scene.materials) {
            gpu.interior = media::offset_of(m.media.interior, &medium_offsets);
            gpu.exterior = media::offset_of(m.media.exterior, &medium_offsets);
        }
        for light in &mut lights {
            light.medium = if scene.media.is_empty() {
                NO_MEDIUM
            } else {
                media::offset_of(
                    media::medium_at(scene, light_origin(scene, light)),
                    &medium_offsets,
                )
            };
        }
        let mut light_of_prim = vec![NO_LIGHT; scene.triangles.len() + scene.spheres.len()];
        for (i, l) in lights.iter().enumerate() {
            let prim = match l.kind {
                LIGHT_TRIANGLE => l.prim as usize,
                LIGHT_SPHERE => scene.triangles.len() + l.prim as usize,
                _ => continue,
            };
            if let Some(slot) = light_of_prim.get_mut(prim) {
                *slot = i as u32;
            }
        }
        let mut triangle_normals = Vec::new();
        let triangles = scene
            .triangles
            .iter()
            .zip(&light_of_prim)
            .map(|(t, &light)| GpuTriangle {
                vertex: t.v[0].to_array(),
                material: t.material,
                edge_a: (t.v[1] - t.v[0]).to_array(),
                light,
                edge_b: (t.v[2] - t.v[0]).to_array(),
                normals: t.normals.map_or(NO_NORMALS, |[a, b, c]| {
                    triangle_normals.push(GpuTriangleNormals {
                        a: a.to_array(),
                        b: b.to_array(),
                        c: c.to_array(),
                        ..Zeroable::zeroed()
                    });
                    triangle_normals.len() as u32 - 1
                }),
            })
            .collect::<Vec<_>>();
        let triangle_uvs = scene
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t
                    .uvs
                    .unwrap_or([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]);
                GpuTriangleUvs {
                    a: a.to_array(),
                    b: b.to_array(),
                    c: c.to_array(),
                }
            })
            .collect::<Vec<_>>();
        let spheres = scene
            .spheres
            .iter()
            .zip(&light_of_prim[scene.triangles.len()..])
            .map(|(s, &light)| GpuSphere {
                center: s.center.to_array(),
                radius: s.radius,
                material: s.material,
                light,
                flip_normals: s.flip_normals as u32,
                _pad: 0,
            })
            .collect::<Vec<_>>();
        let textures = if scene.features().textures {
            texture::gpu_words(&scene.textures)
        } else {
            Vec::new()
        };

        let (lo, hi) = scene.bounds();
        let scene_radius = 0.5 * (hi - lo).length();
        let mut uniform = camera_uniform(scene, width, height);
        uniform.bounds_min = lo.to_array();
        uniform.bounds_max = hi.to_array();
        uniform.camera_medium = media::offset_of(scene.media.camera, &medium_offsets);
        uniform.scene_radius = scene_radius;
        uniform.num_triangles = triangles.len() as u32;
        uniform.num_spheres = spheres.len() as u32;
        uniform.num_lights = lights.len() as u32;
        uniform.environment = lights
            .iter()
            .position(|l| matches!(l.kind, LIGHT_CONSTANT | LIGHT_ENVMAP))
            .map_or(NO_LIGHT, |i| i as u32);
        uniform.max_depth = scene.integrator.max_depth.unwrap_or(UNBOUNDED);
        uniform.rr_depth = scene.integrator.rr_depth.unwrap_or(UNBOUNDED);
        uniform.hide_emitters = scene.integrator.hide_emitters as u32;
        let [x, y, z, radius] = padded_sphere(bounding_sphere(scene, |b: &Bsdf| b.is_delta()));
        uniform.specular_center = [x, y, z];
        uniform.specular_radius = radius;
        let glossy_sphere = padded_sphere(bounding_sphere(scene, |b: &Bsdf| {
            b.is_delta() || b.has_microfacet_lobe()
        }));
        let smoothest_microfacet = scene
            .features()
            .smoothest_microfacet
            .unwrap_or(f32::INFINITY);

        Ok(Self {
            uniform,
            bvh_nodes: bvh.nodes,
            prim_indices: non_empty(bvh.indices),
            triangles: non_empty(triangles),
            triangle_normals: non_empty(triangle_normals),
            triangle_uvs: non_empty(triangle_uvs),
            spheres: non_empty(spheres),
            materials: non_empty(materials),
            lights: non_empty(lights),
            light_cdf: non_empty(light_cdf),
            bsdf_tables: non_empty(bsdf_tables),
            textures,
            glossy_sphere,
            smoothest_microfacet,
            media: !scene.media.is_empty(),
        })
    }
}

/// (centre, radius) padded so that rounding never lets a surface poke out of the sphere: the
/// GPU's points on those surfaces are within a few roundoffs of their magnitude, at most
/// |center| + radius (shaders/common/surface.wgsl, triangle_point and sphere_point), far inside
/// 1e-4 of it. All zero for `None`.
fn padded_sphere(sphere: Option<(Vec3, f32)>) -> [f32; 4] {
    match sphere {
        Some((center, radius)) => {
            let padded = radius + 1e-4 * (radius + center.abs().max_element());
            [center.x, center.y, center.z, padded]
        }
        None => [0.0; 4],
    }
}

/// A sphere containing every primitive one of whose BSDFs is `kept` (the specular ones, for
/// aiming photons): centred on their bounding box, with the radius that just reaches the
/// farthest vertex or sphere surface, so that one such sphere gets exactly its own bounds.
/// `None` when the scene has no such surface.
fn bounding_sphere(scene: &Scene, kept: impl Fn(&Bsdf) -> bool) -> Option<(Vec3, f32)> {
    let is_specular = |material: u32| {
        scene
            .with_nested(material)
            .iter()
            .any(|(_, m)| m.bsdfs().any(&kept))
    };
    let triangles = || scene.triangles.iter().filter(|t| is_specular(t.material));
    let spheres = || scene.spheres.iter().filter(|s| is_specular(s.material));
    let mut bounds = bvh::Aabb::EMPTY;
    for t in triangles() {
        bounds = bounds.union(bvh::Aabb::of_triangle(&t.v));
    }
    for s in spheres() {
        bounds = bounds.union(bvh::Aabb::of_sphere(s.center, s.radius));
    }
    if bounds.is_empty() {
        return None;
    }
    let center = bounds.centroid();
    let radius = triangles()
        .flat_map(|t| t.v)
        .map(|v| v.distance(center))
        .chain(spheres().map(|s| s.center.distance(center) + s.radius))
        .fold(0.0f32, f32::max);
    Some((center, radius))
}

fn non_empty<T: Zeroable>(mut v: Vec<T>) -> Vec<T> {
    if v.is_empty() {
        v.push(T::zeroed());
    }
    v
}

/// A point photons of `light` leave from, just off its emitting side: where its medium is.
fn light_origin(scene: &Scene, light: &GpuLight) -> Vec3 {
    let (lo, hi) = scene.bounds();
    let centre = 0.5 * (lo + hi);
    let reach = (hi - lo).length().max(1.0);
    let nudge = 1e-4 * reach;
    match light.kind {
        LIGHT_TRIANGLE => scene
            .triangles
            .get(light.prim as usize)
            .map_or(centre, |t| {
                let normal = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalize_or_zero();
                (t.v[0] + t.v[1] + t.v[2]) / 3.0 + normal * nudge
            }),
        LIGHT_SPHERE => scene.spheres.get(light.prim as usize).map_or(centre, |s| {
            let out = if s.flip_normals { -1.0 } else { 1.0 };
            s.center + Vec3::Y * (s.radius + out * nudge)
        }),
        LIGHT_DIRECTIONAL => centre - Vec3::from_array(light.axis) * reach,
        LIGHT_CONSTANT | LIGHT_ENVMAP => centre + Vec3::Y * reach,
        _ => Vec3::from_array(light.position),
    }
}
