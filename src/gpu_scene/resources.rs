//! The scene on the GPU: bind group 0 of every pass kernel. The render uploads it once and
//! shares it with the passes (`Shared`), which keep a handle to its bind group.

use std::collections::HashMap;

use naga_oil::compose::ShaderDefValue;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::binding::{Access, bind_buffers_at};
use crate::gpu::layout::StructLayout;
use crate::gpu_scene::layout::{
    GpuLight, GpuMaterial, GpuScene, GpuSceneUniform, GpuSphere, GpuTriangle, GpuTriangleNormals,
    GpuTriangleUvs,
};
use crate::gpu_scene::tables::{
    Chunked, TEXTURES_BINDING, chunk_bytes, chunk_entries_override, chunked_tables, tables,
};
use crate::scene::bvh::{Bvh, BvhNode};
use crate::struct_layout;

/// Any kernel that traces rays has every scene struct.
const TRACER: crate::gpu::shaders::ShaderFile =
    crate::shader_file!("shaders/passes/path_trace.wgsl");

/// The scene's GPU structs against their WGSL twins in src/gpu_scene/scene.wgsl (checked by
/// tests/shaders.rs).
pub const LAYOUTS: &[StructLayout] = &[
    struct_layout!(GpuSceneUniform => "SceneUniform" in TRACER, {
        camera_origin, plane_step_x, camera_right, plane_step_y, camera_up, width, camera_forward,
        height, bounds_min, bounds_max, scene_radius, num_triangles, num_spheres,
        num_lights, max_depth, rr_depth, filter_kind, filter_param, sample_border, specular_center,
        specular_radius, environment, film_width, film_height, tile_x, tile_y, hide_emitters,
        plane_origin, aperture_radius, focus_distance, filter_param_b, filter_table
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
        diffuse_texture, specular_texture, alpha_u_texture, alpha_v_texture, frame_kind,
        frame_texture, frame_scale, frame_flags, children, blend_weight, blend_weight_texture,
        field_textures, field_texture_count
    }),
    struct_layout!(GpuLight => "Light" in TRACER, {
        position, kind, radiance, prim, axis, select_prob, area, table, cutoff, beam_width,
        emit_prob
    }),
];

/// Where the scene's tables are bound: every table in a storage buffer, or on a CPU adapter
/// those that fit a uniform binding in uniform buffers. lavapipe turns a divergent storage load
/// into a masked, bounds-checked scalar load per lane and a uniform load into a plain gather;
/// the traversal's node and triangle reads are most of a camera path's time there
/// (BENCHMARKS.md). GPUs serialise divergent uniform reads, so they keep storage buffers.
/// `HPPM_SCENE_TABLES=storage` or `=uniform` overrides the choice (to measure both).
///
/// A small scene whose triangles and spheres are uniform tables is also intersected without its
/// BVH, by testing every primitive in unrolled code (`EVERY_PRIM` in shaders/common/traversal.wgsl):
/// lavapipe loads a uniform entry at a constant index once for all lanes, and that beats the
/// BVH's divergent loads up to [`EVERY_PRIM_LIMIT`] primitives (BENCHMARKS.md).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TablePlacement {
    /// (binding, length in array elements of its uniform declaration) of each uniform table.
    uniform: Vec<(u32, u32)>,
    /// The scene's (triangles, spheres) when every primitive is tested instead of the BVH.
    every_prim: Option<(u32, u32)>,
    /// The BVH's nodes collapsed to fit their uniform binding ([`Bvh::collapsed_to`]), uploaded
    /// instead of the scene's; `None` when it is uploaded as built.
    collapsed_nodes: Option<Vec<BvhNode>>,
    /// Storage tables larger than one binding, split into chunks ([`Chunked`]).
    chunked: Vec<Chunked>,
}

/// How many more primitive tests per ray (by the surface area heuristic) than the tree as built
/// a BVH collapsed to fit a uniform binding may take. On water_glass, with the nodes uniform,
/// trees of 2,048, 1,500 and 1,024 nodes (0.3%, 3.9% and 11% more tests; measured before
/// references were split) rendered at one speed,
/// 20-30% faster than the 2,081 nodes in storage, and one of 600 nodes (36% more) 10-30% slower
/// than those (BENCHMARKS.md). Box tests are left out of the measure: from a uniform binding they
/// cost far less than the storage reads of a triangle.
pub const MAX_COLLAPSE_GROWTH: f32 = 0.10;

/// The most primitives a scene may have for its rays to test every one instead of walking the
/// BVH (where its triangles and spheres are uniform tables). The unrolled blocks in
/// shaders/common/traversal.wgsl go up to 127 triangles and 15 spheres.
pub const EVERY_PRIM_LIMIT: usize = 48;

/// Block sizes of the unrolled tests, largest first (shaders/common/traversal.wgsl).
const TRIANGLE_BLOCKS: [u32; 7] = [64, 32, 16, 8, 4, 2, 1];
const SPHERE_BLOCKS: [u32; 4] = [8, 4, 2, 1];

/// A table that may be bound as a uniform buffer: its binding in group 0, the shader def that
/// declares it so (src/gpu_scene/scene.wgsl, set to the array length), and its element size
/// there (the Rust twin's size: tests/shaders.rs checks the WGSL layouts match, and all are
/// multiples of 16 as a uniform array's stride must be). `prim_indices` is declared as vec4s.
/// A table is uniform whole or not at all: splitting the nodes and triangles over two bindings
/// each (an accessor choosing by index) was slower than storage buffers (BENCHMARKS.md).
struct UniformCapable {
    binding: u32,
    def: &'static str,
    stride: u64,
}

/// In the order they are worth a uniform binding: traversal reads nodes, triangles and indices
/// on every step, shading the rest once a vertex.
const UNIFORM_CAPABLE: [UniformCapable; 7] = [
    UniformCapable {
        binding: 1,
        def: "BVH_NODES_UNIFORM",
        stride: size_of::<BvhNode>() as u64,
    },
    UniformCapable {
        binding: 3,
        def: "TRIANGLES_UNIFORM",
        stride: size_of::<GpuTriangle>() as u64,
    },
    UniformCapable {
        binding: 2,
        def: "PRIM_INDICES_UNIFORM",
        stride: 16,
    },
    UniformCapable {
        binding: 5,
        def: "MATERIALS_UNIFORM",
        stride: size_of::<GpuMaterial>() as u64,
    },
    UniformCapable {
        binding: 4,
        def: "SPHERES_UNIFORM",
        stride: size_of::<GpuSphere>() as u64,
    },
    UniformCapable {
        binding: 6,
        def: "LIGHTS_UNIFORM",
        stride: size_of::<GpuLight>() as u64,
    },
    UniformCapable {
        binding: 9,
        def: "TRIANGLE_NORMALS_UNIFORM",
        stride: size_of::<GpuTriangleNormals>() as u64,
    },
];

/// Uniform bindings a stage keeps for itself beyond the scene's own uniform: the passes' params
/// (one each today; one spare).
const PASS_UNIFORMS: u32 = 2;

/// How tables are placed, from `HPPM_SCENE_TABLES` or the adapter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlacementRule {
    Storage,
    /// Uniform where tables fit, and every primitive tested in scenes small enough.
    UniformWhereFits,
    /// Uniform where tables fit, always through the BVH.
    UniformWithBvh,
}

impl PlacementRule {
    /// `HPPM_SCENE_TABLES` when set (`storage`, `uniform` or `uniform-bvh`), else uniform where
    /// tables fit on CPU adapters and storage elsewhere.
    pub fn for_adapter(gpu: &GpuContext) -> Result<Self, Error> {
        match std::env::var("HPPM_SCENE_TABLES").as_deref() {
            Ok("storage") => Ok(Self::Storage),
            Ok("uniform") => Ok(Self::UniformWhereFits),
            Ok("uniform-bvh") => Ok(Self::UniformWithBvh),
            Ok(other) => Err(Error::Other(format!(
                "HPPM_SCENE_TABLES={other}: expected `storage`, `uniform` or `uniform-bvh`"
            ))),
            Err(_) if gpu.info.device_type == wgpu::DeviceType::Cpu => Ok(Self::UniformWhereFits),
            Err(_) => Ok(Self::Storage),
        }
    }
}

impl TablePlacement {
    /// Every table in a storage buffer.
    pub fn storage() -> Self {
        Self::default()
    }

    /// Where `scene`'s tables go on `gpu`: by [`PlacementRule::for_adapter`], chunked where a
    /// table exceeds a binding (or `HPPM_TABLE_CHUNK_ENTRIES`).
    pub fn for_adapter(gpu: &GpuContext, scene: &GpuScene) -> Result<Self, Error> {
        Ok(Self::choose_chunked(
            PlacementRule::for_adapter(gpu)?,
            scene,
            &gpu.limits,
            chunk_entries_override()?,
        ))
    }

    /// Under `rule`, the tables of `scene` that fit `limits`' uniform bindings (by size, and
    /// by count after the scene uniform and the passes' own).
    pub fn choose(rule: PlacementRule, scene: &GpuScene, limits: &wgpu::Limits) -> Self {
        Self::choose_chunked(rule, scene, limits, None)
    }

    /// As [`TablePlacement::choose`], with storage tables of more than `chunk_entries` entries
    /// (a power of two) chunked at that size even where they fit one binding
    /// ([`chunk_entries_override`]: to test and measure chunked tables on small scenes).
    pub fn choose_chunked(
        rule: PlacementRule,
        scene: &GpuScene,
        limits: &wgpu::Limits,
        chunk_entries: Option<u64>,
    ) -> Self {
        let chunked = chunked_tables(scene, limits.max_storage_buffer_binding_size, chunk_entries);
        if rule == PlacementRule::Storage {
            return Self {
                chunked,
                ..Self::storage()
            };
        }
        let mut free = limits
            .max_uniform_buffers_per_shader_stage
            .saturating_sub(1 + PASS_UNIFORMS);
        let mut uniform = Vec::new();
        let max_bytes = limits.max_uniform_buffer_binding_size;
        let mut collapsed = collapsed_to_fit(scene, max_bytes);
        for table in &UNIFORM_CAPABLE {
            let bytes = tables(scene)[table.binding as usize - 1].1.len() as u64;
            let len = match (table.binding, &collapsed) {
                (1, Some((budget, _))) => *budget as u64,
                _ => bytes.div_ceil(table.stride).max(1),
            };
            if free > 0 && len * table.stride <= max_bytes {
                uniform.push((table.binding, len as u32));
                free -= 1;
            }
        }
        if !uniform.iter().any(|&(binding, _)| binding == 1) {
            collapsed = None;
        }
        let chunked = chunked
            .into_iter()
            .filter(|c| !uniform.iter().any(|&(b, _)| b == c.table.binding))
            .collect();
        let mut placement = Self {
            uniform,
            every_prim: None,
            collapsed_nodes: collapsed.map(|(_, nodes)| nodes),
            chunked,
        };
        // The counts, not the tables' lengths: an empty table holds one zeroed entry.
        let triangles = scene.uniform.num_triangles as usize;
        let spheres = scene.uniform.num_spheres as usize;
        let small = triangles + spheres <= EVERY_PRIM_LIMIT;
        let tested_uniform =
            |binding: u32, len: usize| len == 0 || placement.uniform_len(binding).is_some();
        if rule == PlacementRule::UniformWhereFits
            && small
            && triangles <= blocks_cover(&TRIANGLE_BLOCKS)
            && spheres <= blocks_cover(&SPHERE_BLOCKS)
            && tested_uniform(3, triangles)
            && tested_uniform(4, spheres)
        {
            placement.every_prim = Some((triangles as u32, spheres as u32));
            // Binding 1 then holds the blocks' boxes, which may outnumber the BVH's nodes.
            let blocks = triangles.div_ceil(BOXED_BLOCK) as u32;
            for (binding, len) in &mut placement.uniform {
                if *binding == 1 {
                    *len = (*len).max(blocks);
                }
            }
        }
        placement
    }

    /// The shader defs that declare the uniform tables (each set to its array length).
    /// With every primitive tested, also `EVERY_PRIM` and the unrolled blocks' first indices.
    pub fn defs(&self) -> HashMap<String, ShaderDefValue> {
        let mut defs: HashMap<String, ShaderDefValue> = UNIFORM_CAPABLE
            .iter()
            .filter_map(|t| {
                self.uniform_len(t.binding)
                    .map(|len| (t.def.to_string(), ShaderDefValue::UInt(len)))
            })
            .collect();
        if let Some((triangles, spheres)) = self.every_prim {
            defs.insert("EVERY_PRIM".into(), ShaderDefValue::Bool(true));
            defs.extend(block_defs("TRIANGLES_FROM", &TRIANGLE_BLOCKS, triangles));
            defs.extend(block_defs("SPHERES_FROM", &SPHERE_BLOCKS, spheres));
        }
        for c in &self.chunked {
            let prefix = c.table.prefix;
            defs.insert(format!("{prefix}_CHUNKED"), ShaderDefValue::Bool(true));
            defs.insert(
                format!("{prefix}_CHUNK_SHIFT"),
                ShaderDefValue::UInt(c.shift),
            );
            for k in 2..c.chunks {
                defs.insert(format!("{prefix}_CHUNK_{k}"), ShaderDefValue::Bool(true));
            }
        }
        defs
    }

    /// The tables split over several bindings, as `PREFIX chunks x 2^shift` for reports.
    pub fn chunked_report(&self) -> Vec<String> {
        self.chunked
            .iter()
            .map(|c| format!("{} {}x2^{}", c.table.prefix, c.chunks, c.shift))
            .collect()
    }

    /// The scene's (triangles, spheres) when rays test every primitive instead of the BVH.
    pub fn every_prim(&self) -> Option<(u32, u32)> {
        self.every_prim
    }

    /// The most nodes the BVH was collapsed to so that its nodes fit a uniform binding (its
    /// declared length there).
    pub fn node_budget(&self) -> Option<usize> {
        self.collapsed_nodes.as_ref()?;
        self.uniform_len(1).map(|len| len as usize)
    }

    /// The array length of binding `binding`'s uniform declaration, if it is uniform.
    fn uniform_len(&self, binding: u32) -> Option<u32> {
        self.uniform
            .iter()
            .find(|(b, _)| *b == binding)
            .map(|(_, len)| *len)
    }

    /// The size of binding `binding`'s uniform buffer, if it is uniform: its declared length
    /// times its stride, which the buffer must cover.
    fn uniform_size(&self, binding: u32) -> Option<usize> {
        let stride = UNIFORM_CAPABLE
            .iter()
            .find(|t| t.binding == binding)?
            .stride;
        self.uniform_len(binding)
            .map(|len| (u64::from(len) * stride) as usize)
    }

    /// The defs of the tables bound as uniform buffers, in binding priority, for reports.
    pub fn uniform_defs(&self) -> Vec<&'static str> {
        UNIFORM_CAPABLE
            .iter()
            .filter(|t| self.uniform_len(t.binding).is_some())
            .map(|t| t.def)
            .collect()
    }
}

/// Blocks of four triangles whose box has less than this share of the scene box's surface area
/// are culled by their box (a random line through the scene meets a convex box inside it with
/// about the ratio of their areas); others are tested without one, since a box most rays enter
/// only costs its test (the two-wall blocks of a Cornell box: 10% slower with boxes).
const BLOCK_BOX_AREA: f32 = 0.5;

/// `count` primitives per block of the every-primitive test that binding 1's boxes cover.
const BOXED_BLOCK: usize = 4;

/// One `BvhNode` per four consecutive triangles (shapes are consecutive in the table, so a
/// block usually lies within one or two shapes): its box, a little larger than its corners so
/// that rounding cannot move a hit outside it, and `count` 1 where the box is worth testing
/// ([`BLOCK_BOX_AREA`]), else 0.
fn block_boxes(triangles: &[GpuTriangle], scene: &GpuSceneUniform) -> Vec<BvhNode> {
    let area = |lo: glam::Vec3, hi: glam::Vec3| {
        let d = (hi - lo).max(glam::Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    };
    let scene_area = area(scene.bounds_min.into(), scene.bounds_max.into());
    triangles
        .chunks(BOXED_BLOCK)
        .map(|block| {
            let mut lo = glam::Vec3::splat(f32::INFINITY);
            let mut hi = glam::Vec3::splat(f32::NEG_INFINITY);
            for t in block {
                let v = glam::Vec3::from(t.vertex);
                for p in [
                    v,
                    v + glam::Vec3::from(t.edge_a),
                    v + glam::Vec3::from(t.edge_b),
                ] {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
            let pad = (hi - lo).max_element() * 1e-4 + lo.abs().max(hi.abs()).max_element() * 1e-5;
            let (lo, hi) = (lo - pad, hi + pad);
            BvhNode {
                min: lo.to_array(),
                left_or_first: 0,
                max: hi.to_array(),
                count: u32::from(area(lo, hi) < BLOCK_BOX_AREA * scene_area),
            }
        })
        .collect()
}

/// The most primitives blocks of these sizes can test (each size used at most once).
fn blocks_cover(blocks: &[u32]) -> usize {
    blocks.iter().sum::<u32>() as usize
}

/// `count` primitives split into blocks of the sizes in `blocks` (powers of two, largest first),
/// as defs `PREFIX_<size>` = the block's first index: the binary digits of `count`.
fn block_defs(prefix: &str, blocks: &[u32], count: u32) -> Vec<(String, ShaderDefValue)> {
    let mut first = 0;
    let mut defs = Vec::new();
    for &size in blocks {
        if count & size != 0 {
            defs.push((format!("{prefix}_{size}"), ShaderDefValue::UInt(first)));
            first += size;
        }
    }
    defs
}

/// The BVH as built, as a [`Bvh`].
fn scene_bvh(scene: &GpuScene) -> Bvh {
    Bvh {
        nodes: scene.bvh_nodes.clone(),
        indices: scene.prim_indices.clone(),
    }
}

/// The node count a uniform binding of `max_bytes` holds and the scene's BVH nodes collapsed
/// to it, when they do not fit as built and the collapsed tree takes at most
/// [`MAX_COLLAPSE_GROWTH`] more primitive tests per ray.
fn collapsed_to_fit(scene: &GpuScene, max_bytes: u64) -> Option<(usize, Vec<BvhNode>)> {
    let budget = (max_bytes / size_of::<BvhNode>() as u64) as usize;
    // A tree many times the budget cannot lose that many nodes for a few more tests; trying
    // would copy and walk a large mesh's whole tree (millions of nodes) for nothing.
    if scene.bvh_nodes.len() <= budget || budget == 0 || scene.bvh_nodes.len() > 16 * budget {
        return None;
    }
    let built = scene_bvh(scene);
    let tests = |bvh: &Bvh| bvh.expected_tests().primitives;
    let built_tests = tests(&built);
    // A little past the bound, so that the merges' running sum (another order of additions
    // than expected_tests') cannot refuse a tree the final check below would take.
    let collapsed = built.collapsed_within(budget, built_tests * MAX_COLLAPSE_GROWTH * 1.01)?;
    (collapsed.nodes.len() <= budget
        && tests(&collapsed) <= built_tests * (1.0 + MAX_COLLAPSE_GROWTH))
        .then_some((budget, collapsed.nodes))
}

pub struct SceneResources {
    pub layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
    pub uniform: GpuSceneUniform,
    /// [`GpuScene::glossy_sphere`]: what caustic photons aim at when glossy lobes are specular.
    pub glossy_sphere: [f32; 4],
    /// Some shape's BSDF has a microfacet lobe.
    /// The smallest roughness of any microfacet lobe (`GpuScene::smoothest_microfacet`).
    pub smoothest_microfacet: f32,
    /// The scene has participating media (`GpuScene::media`).
    pub media: bool,
    /// Which tables are uniform buffers (the shader library must be composed with its defs).
    pub placement: TablePlacement,
    /// The bound buffers (the uniform first) with their binding and access: a band of the
    /// image binds the same tables with its own uniform ([`SceneResources::with_uniform`]).
    bound: Vec<(u32, Access, wgpu::Buffer)>,
}

impl SceneResources {
    /// Uploads `scene` with its tables placed as the adapter prefers ([`PlacementRule`]); compose
    /// the shader library with `placement`'s defs.
    pub fn for_adapter(gpu: &GpuContext, scene: &GpuScene) -> Result<Self, Error> {
        Self::upload(gpu, scene, &TablePlacement::for_adapter(gpu, scene)?)
    }

    /// Uploads `scene` with its tables where `placement` puts them (the shader library must
    /// have been composed with `placement.defs()`).
    pub fn upload(
        gpu: &GpuContext,
        scene: &GpuScene,
        placement: &TablePlacement,
    ) -> Result<Self, Error> {
        use bytemuck::{bytes_of, cast_slice};
        let uniform = gpu.create_buffer_init(
            "scene uniform",
            bytes_of(&scene.uniform),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let mut buffers = vec![uniform];
        let mut access = vec![Access::Uniform];
        // Chunks past the first of the tables too large for one binding: (binding, buffer).
        let mut chunk_buffers = Vec::new();
        // Testing every primitive, binding 1 holds the boxes of its blocks instead of the BVH.
        let block_boxes = placement.every_prim.map(|(triangles, _)| {
            block_boxes(&scene.triangles[..triangles as usize], &scene.uniform)
        });
        // Or the BVH collapsed to fit its uniform binding.
        for (binding, (label, bytes)) in (1u32..).zip(tables(scene)) {
            let bytes = match (&block_boxes, &placement.collapsed_nodes, binding) {
                (Some(boxes), _, 1) => bytemuck::cast_slice(boxes),
                (None, Some(nodes), 1) => bytemuck::cast_slice(nodes),
                _ => bytes,
            };
            match placement.uniform_size(binding) {
                Some(size) => {
                    buffers.push(uniform_buffer(gpu, label, bytes, size)?);
                    access.push(Access::Uniform);
                }
                None => {
                    let (first, rest) = storage_table(gpu, placement, binding, label, bytes)?;
                    buffers.push(first);
                    access.push(Access::Read);
                    chunk_buffers.extend(rest);
                }
            }
        }
        // Binding 11, only for a scene with textures (whose shaders are composed with
        // `TEXTURES`): untextured scenes keep their 10 storage buffers (GL allows 16 a stage).
        if !scene.textures.is_empty() {
            let words = cast_slice(&scene.textures);
            let (first, rest) =
                storage_table(gpu, placement, TEXTURES_BINDING, "scene textures", words)?;
            buffers.push(first);
            chunk_buffers.extend(rest);
        }
        access.resize(buffers.len(), Access::Read);
        let mut entries: Vec<_> = (0u32..)
            .zip(access.iter().copied().zip(&buffers))
            .map(|(binding, (access, buffer))| (binding, access, buffer))
            .collect();
        entries.extend(
            chunk_buffers
                .iter()
                .map(|(binding, buffer)| (*binding, Access::Read, buffer)),
        );
        let (layout, bind_group) = bind_buffers_at(gpu, "scene", &entries);
        let bound = entries
            .into_iter()
            .map(|(binding, access, buffer)| (binding, access, buffer.clone()))
            .collect();
        Ok(Self {
            layout,
            bind_group,
            uniform: scene.uniform,
            glossy_sphere: scene.glossy_sphere,
            smoothest_microfacet: scene.smoothest_microfacet,
            media: scene.media,
            placement: placement.clone(),
            bound,
        })
    }

    /// The same tables (the very buffers, not copies) with another scene uniform: each band of
    /// an image rendered in bands has its own pixel grid, and one copy of a large mesh.
    pub fn with_uniform(
        &self,
        gpu: &GpuContext,
        uniform: &crate::gpu_scene::layout::GpuSceneUniform,
    ) -> Result<Self, Error> {
        let own = gpu.create_buffer_init(
            "scene uniform",
            bytemuck::bytes_of(uniform),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let mut bound = self.bound.clone();
        if let Some(first) = bound.first_mut() {
            first.2 = own;
        }
        let entries: Vec<_> = bound
            .iter()
            .map(|(b, a, buffer)| (*b, *a, buffer))
            .collect();
        let (layout, bind_group) = bind_buffers_at(gpu, "scene", &entries);
        Ok(Self {
            layout,
            bind_group,
            uniform: *uniform,
            glossy_sphere: self.glossy_sphere,
            smoothest_microfacet: self.smoothest_microfacet,
            media: self.media,
            placement: self.placement.clone(),
            bound,
        })
    }
}

/// A storage table's buffer for `binding` and, when `placement` chunks it, the buffers of its
/// other chunks with their bindings.
fn storage_table(
    gpu: &GpuContext,
    placement: &TablePlacement,
    binding: u32,
    label: &str,
    bytes: &[u8],
) -> Result<(wgpu::Buffer, Vec<(u32, wgpu::Buffer)>), Error> {
    let storage = wgpu::BufferUsages::STORAGE;
    let Some(c) = placement
        .chunked
        .iter()
        .find(|c| c.table.binding == binding)
    else {
        return Ok((gpu.create_buffer_init(label, bytes, storage)?, Vec::new()));
    };
    let mut chunks = chunk_bytes(c, bytes, label)?.into_iter();
    let first = gpu.create_buffer_init(label, chunks.next().unwrap_or(bytes), storage)?;
    let mut rest = Vec::new();
    for (k, chunk) in (1u32..).zip(chunks) {
        let label = format!("{label}, chunk {k}");
        rest.push((
            c.table.base + k - 1,
            gpu.create_buffer_init(&label, chunk, storage)?,
        ));
    }
    Ok((first, rest))
}

/// A uniform buffer holding `bytes` zero-padded to `size`.
fn uniform_buffer(
    gpu: &GpuContext,
    label: &str,
    bytes: &[u8],
    size: usize,
) -> Result<wgpu::Buffer, Error> {
    let mut padded = bytes.to_vec();
    padded.resize(size.max(bytes.len()), 0);
    Ok(gpu.create_buffer_init(label, &padded, wgpu::BufferUsages::UNIFORM)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu_scene::layout::GpuScene;

    fn glass_sphere() -> GpuScene {
        scene_at("tests/refs/scenes/cornell_glass_sphere/scene.xml")
    }

    fn scene_at(relative: &str) -> GpuScene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
        GpuScene::new(&crate::loaders::load(&path).expect("scene"), 16, 16).expect("layout")
    }

    /// water_glass's BVH has 3,249 nodes (2,081 before its references were split): more than a
    /// 64 KiB binding holds. Merging leaves fits it for 5% more primitive tests, so its nodes go
    /// uniform (and are uploaded collapsed); a binding of 512 nodes would take a tree with far
    /// more tests, so they stay in storage. Would catch a collapse whose result overflows its
    /// declaration, a budget kept when the nodes end up in storage, or a collapse at any cost.
    #[test]
    fn bvh_nodes_collapse_into_a_uniform_binding_only_when_cheap() {
        let scene = scene_at("tests/refs/scenes/water_glass/scene.xml");
        let node = size_of::<BvhNode>() as u64;
        let built = scene_bvh(&scene);
        let tests = |bvh: &Bvh| bvh.expected_tests().primitives;
        assert!(
            scene.bvh_nodes.len() > 2048,
            "the test needs nodes past 64 KiB"
        );
        let rule = PlacementRule::UniformWhereFits;
        let placement = TablePlacement::choose(rule, &scene, &limits(65536, 12));
        assert_eq!(placement.node_budget(), Some(2048));
        assert_eq!(placement.uniform_len(1), Some(2048));
        let fitted = built.collapsed_to(2048);
        assert!(fitted.nodes.len() <= 2048);
        assert!(tests(&fitted) <= tests(&built) * (1.0 + MAX_COLLAPSE_GROWTH));
        let small = TablePlacement::choose(rule, &scene, &limits(512 * node, 12));
        assert!(tests(&built.collapsed_to(512)) > tests(&built) * (1.0 + MAX_COLLAPSE_GROWTH));
        assert_eq!((small.node_budget(), small.uniform_len(1)), (None, None));
        // No uniform binding left for the nodes: no collapse either.
        let none = TablePlacement::choose(rule, &scene, &limits(65536, 1 + PASS_UNIFORMS));
        assert_eq!((none.node_budget(), none.uniform_len(1)), (None, None));
        let storage = TablePlacement::choose(PlacementRule::Storage, &scene, &limits(65536, 12));
        assert_eq!(storage.node_budget(), None);
    }

    fn limits(uniform_binding: u64, uniform_buffers: u32) -> wgpu::Limits {
        wgpu::Limits {
            max_uniform_buffer_binding_size: uniform_binding,
            max_uniform_buffers_per_shader_stage: uniform_buffers,
            ..wgpu::Limits::default()
        }
    }

    /// Catches a table declared longer or shorter than its data (the binding would not cover
    /// the declaration, or the tail would be lost) and the storage rule binding anything uniform.
    #[test]
    fn every_table_that_fits_is_uniform_with_its_length() {
        let scene = glass_sphere();
        assert!(
            TablePlacement::choose(PlacementRule::Storage, &scene, &limits(65536, 12))
                .defs()
                .is_empty()
        );
        let placement =
            TablePlacement::choose(PlacementRule::UniformWithBvh, &scene, &limits(65536, 12));
        let defs = placement.defs();
        assert_eq!(defs.len(), UNIFORM_CAPABLE.len(), "{defs:?}");
        let expect = |def: &str, len: usize| {
            assert_eq!(
                defs.get(def),
                Some(&ShaderDefValue::UInt(len as u32)),
                "{def}"
            );
        };
        expect("BVH_NODES_UNIFORM", scene.bvh_nodes.len());
        expect("TRIANGLES_UNIFORM", scene.triangles.len());
        expect("PRIM_INDICES_UNIFORM", scene.prim_indices.len().div_ceil(4));
        expect("MATERIALS_UNIFORM", scene.materials.len());
        expect("LIGHTS_UNIFORM", scene.lights.len());
    }

    /// Catches a table bound uniform past the adapter's binding size or past its count of
    /// uniform bindings (wgpu would refuse the pipeline layout).
    #[test]
    fn tables_stay_in_storage_past_the_adapters_uniform_limits() {
        let scene = glass_sphere();
        let triangles = (scene.triangles.len() * size_of::<GpuTriangle>()) as u64;
        let nodes = (scene.bvh_nodes.len() * size_of::<BvhNode>()) as u64;
        assert!(
            triangles > nodes,
            "the test needs the triangles to be the larger table"
        );
        let small =
            TablePlacement::choose(PlacementRule::UniformWhereFits, &scene, &limits(nodes, 12));
        let names = small.uniform_defs();
        assert!(names.contains(&"BVH_NODES_UNIFORM") && !names.contains(&"TRIANGLES_UNIFORM"));
        // The scene uniform, the passes' own and two tables: the two first in priority.
        let few = TablePlacement::choose(
            PlacementRule::UniformWhereFits,
            &scene,
            &limits(65536, 1 + PASS_UNIFORMS + 2),
        );
        assert_eq!(
            few.uniform_defs(),
            ["BVH_NODES_UNIFORM", "TRIANGLES_UNIFORM"]
        );
    }

    /// Catches a primitive no unrolled block tests (a wall missing from every image) or one
    /// tested twice, for every count the blocks allow, and a block size the WGSL lacks.
    #[test]
    fn unrolled_blocks_cover_every_primitive_once() {
        for (blocks, most) in [(&TRIANGLE_BLOCKS[..], 127), (&SPHERE_BLOCKS[..], 15)] {
            assert_eq!(blocks_cover(blocks), most as usize);
            for count in 0..=most {
                let mut next = 0;
                let mut defs = block_defs("B", blocks, count);
                defs.sort_by_key(|(_, first)| match first {
                    ShaderDefValue::UInt(first) => *first,
                    _ => u32::MAX,
                });
                for (name, first) in defs {
                    let size: u32 = name["B_".len()..].parse().expect("block size");
                    assert!(blocks.contains(&size), "{name}");
                    assert_eq!(first, ShaderDefValue::UInt(next), "count {count}: {name}");
                    next += size;
                }
                assert_eq!(next, count, "blocks of {count} primitives");
            }
        }
    }

    /// Catches the every-primitive test chosen where it would read tables from storage (its
    /// loads are only cheap from uniform buffers), under the rules that exclude it, or with its
    /// block defs missing; and a large scene losing its BVH.
    #[test]
    fn only_small_scenes_with_uniform_geometry_test_every_primitive() {
        let scene = glass_sphere();
        let (triangles, spheres) = (scene.uniform.num_triangles, scene.uniform.num_spheres);
        assert_eq!((triangles, spheres), (12, 2));
        let every =
            TablePlacement::choose(PlacementRule::UniformWhereFits, &scene, &limits(65536, 12));
        assert_eq!(every.every_prim(), Some((12, 2)));
        let defs = every.defs();
        for (def, first) in [
            ("TRIANGLES_FROM_8", 0),
            ("TRIANGLES_FROM_4", 8),
            ("SPHERES_FROM_2", 0),
        ] {
            assert_eq!(defs.get(def), Some(&ShaderDefValue::UInt(first)), "{def}");
        }
        assert!(defs.contains_key("EVERY_PRIM"));
        assert_eq!(
            defs.keys().filter(|k| k.contains("_FROM_")).count(),
            3,
            "{defs:?}"
        );
        for rule in [PlacementRule::Storage, PlacementRule::UniformWithBvh] {
            let bvh = TablePlacement::choose(rule, &scene, &limits(65536, 12));
            assert_eq!(bvh.every_prim(), None, "{rule:?}");
            assert!(!bvh.defs().contains_key("EVERY_PRIM"), "{rule:?}");
        }
        let triangle_bytes = (scene.triangles.len() * size_of::<GpuTriangle>()) as u64;
        let storage_triangles = TablePlacement::choose(
            PlacementRule::UniformWhereFits,
            &scene,
            &limits(triangle_bytes - 16, 12),
        );
        assert_eq!(storage_triangles.every_prim(), None);
        let mut large = glass_sphere();
        large.uniform.num_triangles = EVERY_PRIM_LIMIT as u32;
        let large =
            TablePlacement::choose(PlacementRule::UniformWhereFits, &large, &limits(65536, 12));
        assert_eq!(
            large.every_prim(),
            None,
            "{EVERY_PRIM_LIMIT} triangles and 2 spheres"
        );
    }

    /// Catches a block box that misses one of its triangles' corners (hits there would be
    /// lost), boxes for the wrong runs of triangles, a box worth testing left untested or the
    /// reverse, and binding 1 declared shorter than the boxes.
    #[test]
    fn block_boxes_hold_their_triangles_and_cull_only_small_ones() {
        let scene = scene_at("tests/refs/scenes/cornell_diffuse/scene.xml");
        let triangles = &scene.triangles[..scene.uniform.num_triangles as usize];
        assert_eq!(triangles.len(), 36);
        let boxes = block_boxes(triangles, &scene.uniform);
        assert_eq!(boxes.len(), 9);
        for (block, b) in triangles.chunks(BOXED_BLOCK).zip(&boxes) {
            for t in block {
                let v = glam::Vec3::from(t.vertex);
                for p in [
                    v,
                    v + glam::Vec3::from(t.edge_a),
                    v + glam::Vec3::from(t.edge_b),
                ] {
                    assert!(
                        p.cmpge(b.min.into()).all() && p.cmple(b.max.into()).all(),
                        "{p} outside {b:?}"
                    );
                }
            }
        }
        // Walls and light (12 triangles: blocks 0-2) span the box; the two cubes do not.
        let culled: Vec<u32> = boxes.iter().map(|b| b.count).collect();
        assert_eq!(culled, [0, 0, 0, 1, 1, 1, 1, 1, 1]);
        let placement =
            TablePlacement::choose(PlacementRule::UniformWhereFits, &scene, &limits(65536, 12));
        assert!(placement.every_prim().is_some());
        assert!(
            placement
                .uniform_len(1)
                .is_some_and(|len| len as usize >= boxes.len())
        );
    }
}
