//! Running one pass alone on a scene's shared resources, outside a render graph: prepare it
//! with hand-made inputs, execute one iteration and wait.

use std::collections::{HashMap, HashSet};

use hppm::gpu::GpuContext;
use hppm::graph::pass::{ExecCtx, Pass, PrepareCtx, Recorder, Resource, ResourceKind};
use hppm::passes::hit_points::{GpuHitPoint, HEADER_BYTES, HitPointHeader};
use hppm::render::SceneResources;
use hppm::scene::Scene;
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
    pub fn new(gpu: &'a GpuContext, scene: &Scene, size: (u32, u32)) -> Self {
        let gpu_scene = GpuScene::new(scene, size.0, size.1);
        Self {
            gpu,
            scene: SceneResources::upload(gpu, &gpu_scene).expect("scene upload"),
            shaders: ShaderLibrary::new(gpu.has_float_atomics(), hppm::shaders::scene_defs(scene)),
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

/// A `HitPoints` resource holding `points` after a header.
pub fn hit_point_resource(gpu: &GpuContext, points: &[GpuHitPoint]) -> Resource {
    let header = HitPointHeader {
        initial_radius: 0.0,
        radius_pixels: 1.0,
        min_radius: 0.0,
        slots_per_pixel: 1,
    };
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
