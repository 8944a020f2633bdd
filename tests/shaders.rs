//! Every shipped pass shader composes and validates, and the GPU structs in
//! `src/scene/gpu_layout.rs` have the sizes naga computes for their WGSL twins.

use std::collections::HashMap;

use hppm::scene::bvh::BvhNode;
use hppm::scene::gpu_layout::{GpuLight, GpuMaterial, GpuSceneUniform, GpuSphere, GpuTriangle};
use hppm::shaders::{PASS_SHADERS, ShaderLibrary};
use wgpu::naga;

fn library(float_atomics: bool) -> ShaderLibrary {
    ShaderLibrary::new(float_atomics, HashMap::new())
}

#[test]
fn every_pass_shader_composes_and_validates() {
    for float_atomics in [true, false] {
        let lib = library(float_atomics);
        for (path, _) in PASS_SHADERS {
            let module = lib
                .compose(path)
                .unwrap_or_else(|e| panic!("{path} (float atomics {float_atomics}): {e}"));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::all(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{path}: {e:?}"));
            assert!(
                module.entry_points.iter().any(|e| e.name == "main"),
                "{path} has no `main` entry point"
            );
        }
    }
}

/// naga_oil decorates imported names (`Triangle` becomes `TriangleX_naga_oil_mod_...`).
fn struct_size(module: &naga::Module, name: &str) -> Option<u32> {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).ok()?;
    module.types.iter().find_map(|(handle, ty)| {
        let type_name = ty.name.as_deref()?;
        let matches = type_name == name || type_name.starts_with(&format!("{name}X_naga_oil"));
        matches.then(|| layouter[handle].size)
    })
}

#[test]
fn gpu_structs_match_wgsl_layout() {
    let module = library(true)
        .compose("shaders/passes/path_trace.wgsl")
        .expect("path_trace composes");
    let expected = [
        ("SceneUniform", std::mem::size_of::<GpuSceneUniform>()),
        ("BvhNode", std::mem::size_of::<BvhNode>()),
        ("Triangle", std::mem::size_of::<GpuTriangle>()),
        ("Sphere", std::mem::size_of::<GpuSphere>()),
        ("Material", std::mem::size_of::<GpuMaterial>()),
        ("Light", std::mem::size_of::<GpuLight>()),
    ];
    for (name, rust_size) in expected {
        let wgsl_size = struct_size(&module, name).unwrap_or_else(|| panic!("no struct {name}"));
        assert_eq!(
            wgsl_size as usize, rust_size,
            "size of {name}: WGSL vs Rust"
        );
    }
}

#[test]
fn a_wgsl_error_names_the_module_file_and_line() {
    // Compose a broken entry through the same composer setup the library uses.
    let broken =
        "#import common::rng::rng_next_f32\n\nfn main() {\n    let x: f32 = undefined_name;\n}\n";
    let err = library(true)
        .compose_source("shaders/passes/broken.wgsl", broken)
        .expect_err("broken shader must not compose");
    let message = err.to_string();
    assert!(message.contains("shaders/passes/broken.wgsl"), "{message}");
    assert!(message.contains(":4:"), "line 4 expected in: {message}");
}
