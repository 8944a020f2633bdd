//! Running one pass alone on a scene's shared resources, outside a render graph: prepare it
//! with hand-made inputs, execute one iteration and wait.

use std::cell::RefCell;
use std::collections::HashMap;

use glam::Vec3;
use hppm::gpu::GpuContext;
use hppm::gpu::shaders::ShaderLibrary;
use hppm::gpu_scene::SceneResources;
use hppm::gpu_scene::layout::GpuScene;
use hppm::graph::exec::{Standalone, Wiring};
use hppm::graph::pass::{Pass, PassKind, Resource, Shared};
use hppm::passes::hit_points::{
    GpuHitPoint, GpuPhotonHit, HEADER_BYTES, HIT_POINTS, HitPointsHeader, PHOTON_HITS,
    PhotonHitsHeader, tree_range_query,
};
use hppm::scene::Scene;
use hppm::scene::bvh::BvhNode;

pub struct PassHarness<'a> {
    pub gpu: &'a GpuContext,
    pub shared: Shared,
    pub shaders: ShaderLibrary,
    pub width: u32,
    pub height: u32,
    // Each prepared pass's outputs, by the pass's address, so that `run` zeroes its
    // non-persistent outputs as a graph would.
    prepared: RefCell<Vec<(usize, Standalone)>>,
}

fn address(pass: &dyn Pass) -> usize {
    pass as *const dyn Pass as *const () as usize
}

impl<'a> PassHarness<'a> {
    /// `float_atomics`: compose the kernels with `atomic<f32>` (the device must have it) or with
    /// the compare-and-swap fallback, so tests can run both paths on one device.
    pub fn new(gpu: &'a GpuContext, scene: &Scene, size: (u32, u32), float_atomics: bool) -> Self {
        let gpu_scene = GpuScene::new(scene, size.0, size.1).expect("layout");
        let mut shared = Shared::default();
        let resources = SceneResources::for_adapter(gpu, &gpu_scene).expect("scene upload");
        let shaders = hppm::passes::shader_library(float_atomics, scene, &resources.placement)
            .expect("shaders");
        shared.insert(resources);
        Self {
            gpu,
            shared,
            shaders,
            width: size.0,
            height: size.1,
            prepared: RefCell::new(Vec::new()),
        }
    }

    pub fn scene(&self) -> &SceneResources {
        self.shared.get::<SceneResources>().expect("scene")
    }

    /// Runs a test kernel (`main`, 64 invocations per workgroup, scene at group 0) that reads
    /// `input` at group 1 binding 0 and writes `outputs` vec4s at binding 1; returns them.
    pub fn run_kernel(
        &self,
        path: &'static str,
        source: &'static str,
        input: &[glam::Vec4],
        outputs: usize,
    ) -> Vec<glam::Vec4> {
        use hppm::gpu::binding::{Access, bind_buffers};
        let gpu = self.gpu;
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let input = gpu
            .create_buffer_init("kernel input", bytemuck::cast_slice(input), usage)
            .expect("kernel input");
        let output = gpu
            .create_buffer("kernel output", (outputs * 16) as u64, usage)
            .expect("kernel output");
        let (layout, group) = bind_buffers(
            gpu,
            path,
            &[(Access::Read, &input), (Access::ReadWrite, &output)],
        );
        // With HPPM_SHADER_DIR set (tests/mutation/run), every module is read from there, this
        // test's kernel too: it is written there so that the modules it imports are the ones
        // under test.
        if let Some(dir) = std::env::var_os("HPPM_SHADER_DIR") {
            let at = std::path::Path::new(&dir).join(path);
            std::fs::create_dir_all(at.parent().expect("a folder")).expect("the shader folder");
            std::fs::write(&at, source).expect("the test kernel");
        }
        let file = hppm::gpu::shaders::ShaderFile { path, source };
        let pipeline = self
            .shaders
            .compute_pipeline(gpu, &file, "main", &[&self.scene().layout, &layout])
            .expect("pipeline");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &self.scene().bind_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.dispatch_workgroups(outputs.div_ceil(64) as u32, 1, 1);
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.read_pod(&output, outputs).expect("readback")
    }

    /// Prepares `pass` (of `kind`) alone with `inputs`; returns its allocated outputs.
    pub fn prepare(
        &self,
        kind: &PassKind,
        pass: &mut dyn Pass,
        inputs: &[(&'static str, &Resource)],
    ) -> HashMap<&'static str, Resource> {
        self.prepare_wired(kind, pass, inputs, &Wiring::default())
    }

    /// `prepare`, with the consumers and keeping a graph would tell the pass.
    pub fn prepare_wired(
        &self,
        kind: &PassKind,
        pass: &mut dyn Pass,
        inputs: &[(&'static str, &Resource)],
        wiring: &Wiring,
    ) -> HashMap<&'static str, Resource> {
        let size = (self.width, self.height);
        let (gpu, shaders, shared) = (self.gpu, &self.shaders, &self.shared);
        let prepared = Standalone::prepare(gpu, shaders, shared, size, kind, pass, inputs, wiring)
            .expect("prepare");
        let outputs = prepared.outputs.clone();
        let key = address(pass);
        let mut all = self.prepared.borrow_mut();
        all.retain(|(k, _)| *k != key);
        all.push((key, prepared));
        outputs
    }

    /// One iteration of a prepared pass, waited for. The pass is found by its address, so it
    /// must not move between `prepare` and `run`.
    pub fn run(&self, pass: &mut dyn Pass, iteration: u64, seed: u64) {
        let key = address(pass);
        let all = self.prepared.borrow();
        let (_, prepared) = all
            .iter()
            .find(|(k, _)| *k == key)
            .expect("run a pass prepared by this harness");
        prepared
            .run(self.gpu, pass, iteration, seed)
            .expect("execute");
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

/// A hit-points resource holding `points` after a header of one slot per pixel.
pub fn hit_point_resource(gpu: &GpuContext, points: &[GpuHitPoint]) -> Resource {
    hit_point_resource_with(gpu, 1, points)
}

/// A hit-points resource holding `points`, `slots_per_pixel` to a pixel.
pub fn hit_point_resource_with(
    gpu: &GpuContext,
    slots_per_pixel: u32,
    points: &[GpuHitPoint],
) -> Resource {
    let header = HitPointsHeader {
        slots_per_pixel,
        _pad: [0; 3],
    };
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(points));
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let buffer = gpu
        .create_buffer_init("test hit points", &bytes, usage)
        .expect("buffer");
    Resource::new(HIT_POINTS, buffer, points.len() as u64)
}

/// Overwrites the hit points of `resource` (same count).
pub fn write_hit_points(gpu: &GpuContext, resource: &Resource, points: &[GpuHitPoint]) {
    gpu.queue
        .write_buffer(&resource.buffer, HEADER_BYTES, bytemuck::cast_slice(points));
}

/// A photon-hits resource holding `hits` (room for at least one), as photon_trace writes them.
pub fn photon_hits_resource(gpu: &GpuContext, hits: &[GpuPhotonHit]) -> Resource {
    photon_hits_resource_with(gpu, hits, hits.len() as u32)
}

/// A photon-hits resource whose header counts the first `count` of `hits` (the rest lie past
/// the count, where a gather must not look).
pub fn photon_hits_resource_with(gpu: &GpuContext, hits: &[GpuPhotonHit], count: u32) -> Resource {
    let header = PhotonHitsHeader {
        count,
        ..Default::default()
    };
    let mut bytes = bytemuck::bytes_of(&header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(hits));
    bytes.resize(bytes.len().max(16 + 48), 0);
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let buffer = gpu
        .create_buffer_init("test photon hits", &bytes, usage)
        .expect("buffer");
    Resource::new(PHOTON_HITS, buffer, hits.len().max(1) as u64)
}
