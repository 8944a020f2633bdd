//! The scene on the GPU: bind group 0 of every pass kernel. The render uploads it once and
//! shares it with the passes (`Shared`), which keep a handle to its bind group.

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers};
use crate::gpu::layout::StructLayout;
use crate::scene::bvh::BvhNode;
use crate::scene::gpu_layout::{
    GpuLight, GpuMaterial, GpuScene, GpuSceneUniform, GpuSphere, GpuTriangle, GpuTriangleNormals,
    GpuTriangleUvs,
};
use crate::struct_layout;

/// Any kernel that traces rays has every scene struct.
const TRACER: crate::gpu::shaders::ShaderFile =
    crate::shader_file!("shaders/passes/path_trace.wgsl");

/// The scene's GPU structs against their WGSL twins in shaders/common/scene.wgsl (checked by
/// tests/shaders.rs).
pub const LAYOUTS: &[StructLayout] = &[
    struct_layout!(GpuSceneUniform => "SceneUniform" in TRACER, {
        camera_origin, tan_half_x, camera_right, tan_half_y, camera_up, width, camera_forward,
        height, bounds_min, bounds_max, scene_radius, num_triangles, num_spheres,
        num_lights, max_depth, rr_depth, filter_kind, filter_param, sample_border, specular_center,
        specular_radius, environment
    }),
    struct_layout!(BvhNode => "BvhNode" in TRACER, { min, left_or_first, max, count }),
    struct_layout!(GpuTriangle => "Triangle" in TRACER, {
        vertex, material, edge_a, light, edge_b, normals
    }),
    struct_layout!(GpuTriangleNormals => "TriangleNormals" in TRACER, { a, b, c }),
    struct_layout!(GpuTriangleUvs => "TriangleUvs" in TRACER, { a, b, c }),
    struct_layout!(GpuSphere => "Sphere" in TRACER, {
        center, radius, material, light, flip_normals
    }),
    struct_layout!(GpuMaterial => "Material" in TRACER, {
        albedo, kind, emission, int_ior, specular, ext_ior, eta, alpha_u, k, alpha_v,
        distribution, back, nonlinear, specular_weight, internal_reflectance, table,
        diffuse_texture, specular_texture, alpha_u_texture, alpha_v_texture
    }),
    struct_layout!(GpuLight => "Light" in TRACER, {
        position, kind, radiance, prim, axis, select_prob, area, table, cutoff, beam_width,
        emit_prob
    }),
];

pub struct SceneResources {
    pub layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
    pub uniform: GpuSceneUniform,
    /// [`GpuScene::glossy_sphere`]: what caustic photons aim at when glossy lobes are specular.
    pub glossy_sphere: [f32; 4],
    /// Some shape's BSDF has a microfacet lobe.
    /// The smallest roughness of any microfacet lobe (`GpuScene::smoothest_microfacet`).
    pub smoothest_microfacet: f32,
    _buffers: Vec<wgpu::Buffer>,
}

impl SceneResources {
    pub fn upload(gpu: &GpuContext, scene: &GpuScene) -> Result<Self, Error> {
        use bytemuck::{bytes_of, cast_slice};
        let storage = wgpu::BufferUsages::STORAGE;
        let uniform = gpu.create_buffer_init(
            "scene uniform",
            bytes_of(&scene.uniform),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let tables: [(&str, &[u8]); 10] = [
            ("scene bvh nodes", cast_slice(&scene.bvh_nodes)),
            ("scene prim indices", cast_slice(&scene.prim_indices)),
            ("scene triangles", cast_slice(&scene.triangles)),
            ("scene spheres", cast_slice(&scene.spheres)),
            ("scene materials", cast_slice(&scene.materials)),
            ("scene lights", cast_slice(&scene.lights)),
            ("scene light cdf", cast_slice(&scene.light_cdf)),
            ("scene bsdf tables", cast_slice(&scene.bsdf_tables)),
            (
                "scene triangle normals",
                cast_slice(&scene.triangle_normals),
            ),
            ("scene triangle uvs", cast_slice(&scene.triangle_uvs)),
        ];
        let mut buffers = vec![uniform];
        for (label, bytes) in tables {
            buffers.push(gpu.create_buffer_init(label, bytes, storage)?);
        }
        // Binding 11, only for a scene with textures (whose shaders are composed with
        // `TEXTURES`): untextured scenes keep their 10 storage buffers (GL allows 16 a stage).
        if !scene.textures.is_empty() {
            let words = cast_slice(&scene.textures);
            buffers.push(gpu.create_buffer_init("scene textures", words, storage)?);
        }
        let entries: Vec<_> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| {
                (
                    if i == 0 {
                        Access::Uniform
                    } else {
                        Access::Read
                    },
                    b,
                )
            })
            .collect();
        let (layout, bind_group) = bind_buffers(&gpu.device, "scene", &entries);
        Ok(Self {
            layout,
            bind_group,
            uniform: scene.uniform,
            glossy_sphere: scene.glossy_sphere,
            smoothest_microfacet: scene.smoothest_microfacet,
            _buffers: buffers,
        })
    }
}
