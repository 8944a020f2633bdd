//! Shared helpers for GPU tests. Every GPU test prints the adapter it ran on and fails (never
//! skips) when there is none, so CI cannot pass while testing nothing.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use hppm::gpu::GpuContext;
use hppm::graph::{self, ValidGraph};
use hppm::image::Image;
use hppm::render::{Budget, Renderer};
use hppm::scene::Scene;

pub fn repo_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// The adapter named by HPPM_TEST_ADAPTER, or the best one.
pub fn gpu() -> GpuContext {
    let choice = std::env::var("HPPM_TEST_ADAPTER").ok();
    let gpu = GpuContext::new(choice.as_deref())
        .unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    eprintln!("adapter: {}", gpu.adapter_label());
    gpu
}

pub fn load_graph(relative: &str) -> ValidGraph {
    graph::load_graph(&repo_path(relative), hppm::passes::builtin_kinds())
        .unwrap_or_else(|e| panic!("{relative}: {e}"))
}

pub fn load_scene(relative: &str) -> Scene {
    hppm::loaders::load(&repo_path(relative)).unwrap_or_else(|e| panic!("{relative}: {e}"))
}

/// A scene written inline in our RON format (`name` stands for its file in errors).
pub fn ron_scene(name: &str, text: &str) -> Scene {
    hppm::loaders::ron_format::parse(Path::new(name), text).unwrap_or_else(|e| panic!("{e}"))
}

pub fn reference(name: &str) -> Image {
    Image::read_exr(&repo_path(&format!("tests/refs/images/{name}.exr")))
        .unwrap_or_else(|e| panic!("reference {name}: {e}"))
}

/// A renderer for `scene` through `graph` at the scene's film size.
pub fn renderer<'a>(
    gpu: &'a GpuContext,
    scene: &Scene,
    graph: ValidGraph,
    seed: u64,
) -> Renderer<'a> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    Renderer::new(gpu, scene, graph, w, h, seed).unwrap_or_else(|e| panic!("renderer: {e}"))
}

/// Renders until `spp` samples per pixel in total and returns the image.
pub fn render_to(renderer: &mut Renderer<'_>, spp: u64) -> Image {
    let never = AtomicBool::new(false);
    renderer
        .run(
            Budget {
                spp: Some(spp),
                seconds: None,
                photons: None,
                target_error: None,
                adaptive: false,
            },
            &never,
            |_, _| {},
        )
        .unwrap_or_else(|e| panic!("render: {e}"));
    renderer.image().unwrap_or_else(|e| panic!("readback: {e}"))
}

/// `scene` moved by the affine map `m`: triangles (with their vertex normals), spheres, point
/// lights and the camera. With a rigid `m` the picture is the same.
pub fn moved(scene: &Scene, m: glam::Affine3A) -> Scene {
    let mut out = scene.clone();
    for t in &mut out.triangles {
        t.v = t.v.map(|v| m.transform_point3(v));
        t.normals = t.normals.map(|n| n.map(|n| m.transform_vector3(n)));
    }
    for s in &mut out.spheres {
        s.center = m.transform_point3(s.center);
    }
    for p in &mut out.point_lights {
        p.position = m.transform_point3(p.position);
    }
    out.camera.origin = m.transform_point3(out.camera.origin);
    out.camera.target = m.transform_point3(out.camera.target);
    out.camera.up = m.transform_vector3(out.camera.up);
    out
}

/// Relative MSE between two images of the same size.
pub fn relmse(image: &Image, reference: &Image) -> f64 {
    image.relmse(reference).unwrap_or_else(|e| panic!("{e}"))
}
pub mod convergence;
pub mod differential;
pub mod pass_harness;
pub mod rng;
