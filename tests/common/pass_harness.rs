//! Running one pass alone on a scene's shared resources, outside a render graph: prepare it
//! with hand-made inputs, execute one iteration and wait.

use std::collections::{HashMap, HashSet};

use glam::Vec3;
use hppm::gpu::GpuContext;
use hppm::graph::pass::{ExecCtx, Pass, PrepareCtx, Recorder, Resource, ResourceKind};
use hppm::passes::hit_points::{GpuHitPoint, HEADER_BYTES, HitPointHeader, tree_range_query};
use hppm::render::SceneResources;
use hppm::scene::Scene;
use hppm::scene::bvh::BvhNode;
use hppm::scene::gpu_layout::GpuScene;
use hppm::shaders::ShaderLibrary;

pub struct PassHarness<'a> {
    pub gpu: &'a GpuContext,
    pub scene: SceneResources,
    pub shaders: ShaderLibrary,
    pub width: u32,
    pub height: u32,
}

impl<'a> PassHarness<'a> {
    /// `float_atomics`: compose the kernels with `atomic<f32>` (the device must have it) or with
    /// the compare-and-swap fallback, so tests can run both paths on one device.
    pub fn new(gpu: &'a GpuContext, scene: &Scene, size: (u32, u32), float_atomics: bool) -> Self {
        let gpu_scene = GpuScene::new(scene, size.0, size.1);
        Self {
            gpu,
            scene: SceneResources::upload(gpu, &gpu_scene).expect("scene upload"),
            shaders: ShaderLibrary::new(float_atomics, hppm::shaders::scene_defs(scene)),
            width: size.0,
            height: size.1,
        }
    }

    pub fn prepare(
        &self,
        pass: &mut dyn Pass,
        inputs: &[(&'static str, &Resource)],
    ) -> HashMap<&'static str, Resource> {
        let ctx = PrepareCtx {
            gpu: self.gpu,
            scene: &self.scene,
            shaders: &self.shaders,
            inputs: inputs.iter().map(|(s, r)| (*s, (*r).clone())).collect(),
            consumed: HashSet::new(),
            width: self.width,
            height: self.height,
        };
        pass.prepare(ctx).expect("prepare")
    }

    pub fn run(&self, pass: &mut dyn Pass, iteration: u64, seed: u64) {
        let ctx = ExecCtx {
            gpu: self.gpu,
            scene: &self.scene,
            iteration,
            seed,
        };
        let mut recorder = Recorder::new(self.gpu);
        pass.execute(&ctx, &mut recorder).expect("execute");
        recorder.flush().expect("flush");
    }
}

/// A valid hit point (pixel 0) on an upward-facing surface, seen from above.
pub fn hit_point(position: Vec3, radius: f32) -> GpuHitPoint {
    GpuHitPoint {
        position: position.to_array(),
        pixel: 0,
        normal: [0.0, 1.0, 0.0],
        radius,
        wo: [0.0, 1.0, 0.0],
        depth: 1,
        weight: [1.0; 3],
        footprint: radius,
    }
}

/// Indices of the valid hit points whose sphere contains `p`, by checking every one.
pub fn brute_force(points: &[GpuHitPoint], p: Vec3) -> Vec<u32> {
    (0u32..)
        .zip(points)
        .filter(|(_, hp)| {
            hp.is_valid() && Vec3::from(hp.position).distance_squared(p) <= hp.radius * hp.radius
        })
        .map(|(i, _)| i)
        .collect()
}

/// Range queries through `nodes` (a tree in the GPU layout) return exactly the brute-force set.
pub fn check_range_queries(
    name: &str,
    nodes: &[BvhNode],
    points: &[GpuHitPoint],
    queries: &[Vec3],
) {
    let mut pairs = 0;
    for &q in queries {
        let mut found = tree_range_query(nodes, points, q);
        found.sort_unstable();
        let expected = brute_force(points, q);
        assert_eq!(found, expected, "{name}: query at {q}");
        pairs += expected.len();
    }
    eprintln!(
        "{name}: {} slots, {} queries, {pairs} pairs found",
        points.len(),
        queries.len()
    );
}

/// A `HitPoints` resource holding `points` after a header of one slot per pixel.
pub fn hit_point_resource(gpu: &GpuContext, points: &[GpuHitPoint]) -> Resource {
    let header = HitPointHeader {
        initial_radius: 0.0,
        radius_pixels: 1.0,
        min_radius: 0.0,
        slots_per_pixel: 1,
    };
    hit_point_resource_with(gpu, header, points)
}

/// A `HitPoints` resource holding `header`, then `points`.
pub fn hit_point_resource_with(
    gpu: &GpuContext,
    header: HitPointHeader,
    points: &[GpuHitPoint],
) -> Resource {
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(points));
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let buffer = gpu
        .create_buffer_init("test hit points", &bytes, usage)
        .expect("buffer");
    Resource::new(ResourceKind::HitPoints, buffer, points.len() as u64)
}

/// Overwrites the hit points of `resource` (same count).
pub fn write_hit_points(gpu: &GpuContext, resource: &Resource, points: &[GpuHitPoint]) {
    gpu.queue
        .write_buffer(&resource.buffer, HEADER_BYTES, bytemuck::cast_slice(points));
}
