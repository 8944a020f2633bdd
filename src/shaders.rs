//! WGSL composition with naga_oil. Shared modules live in `shaders/common/` (each with a
//! `#define_import_path` matching its path), one entry file per pass in `shaders/passes/`. The
//! sources are compiled into the binary, so `hppm` runs from any directory.

use std::collections::HashMap;

use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderDefValue,
};
use wgpu::naga;

/// Importable modules in dependency order (a module may import only those above it).
pub const COMMON_MODULES: &[(&str, &str)] = &[
    (
        "shaders/common/rng.wgsl",
        include_str!("../shaders/common/rng.wgsl"),
    ),
    (
        "shaders/common/sampling.wgsl",
        include_str!("../shaders/common/sampling.wgsl"),
    ),
    (
        "shaders/common/scene.wgsl",
        include_str!("../shaders/common/scene.wgsl"),
    ),
    (
        "shaders/common/camera.wgsl",
        include_str!("../shaders/common/camera.wgsl"),
    ),
    (
        "shaders/common/lights.wgsl",
        include_str!("../shaders/common/lights.wgsl"),
    ),
    (
        "shaders/common/bsdf.wgsl",
        include_str!("../shaders/common/bsdf.wgsl"),
    ),
    (
        "shaders/common/hit_points.wgsl",
        include_str!("../shaders/common/hit_points.wgsl"),
    ),
    (
        "shaders/common/dispatch.wgsl",
        include_str!("../shaders/common/dispatch.wgsl"),
    ),
];

/// Entry-point files, one per pass kind that runs a kernel.
pub const PASS_SHADERS: &[(&str, &str)] = &[
    (
        "shaders/passes/path_trace.wgsl",
        include_str!("../shaders/passes/path_trace.wgsl"),
    ),
    (
        "shaders/passes/photon_trace.wgsl",
        include_str!("../shaders/passes/photon_trace.wgsl"),
    ),
    (
        "shaders/passes/merge.wgsl",
        include_str!("../shaders/passes/merge.wgsl"),
    ),
    (
        "shaders/passes/resolve.wgsl",
        include_str!("../shaders/passes/resolve.wgsl"),
    ),
    (
        "shaders/passes/radix_sort.wgsl",
        include_str!("../shaders/passes/radix_sort.wgsl"),
    ),
    (
        "shaders/passes/lbvh.wgsl",
        include_str!("../shaders/passes/lbvh.wgsl"),
    ),
];

/// The text of shader `path`: from `$HPPM_SHADER_DIR/path` when that variable is set (to edit
/// shaders without rebuilding), else the copy compiled into the binary.
fn source_of(
    path: &str,
    embedded: &'static str,
) -> Result<std::borrow::Cow<'static, str>, crate::Error> {
    match std::env::var_os("HPPM_SHADER_DIR") {
        Some(dir) => {
            let file = std::path::Path::new(&dir).join(path);
            std::fs::read_to_string(&file)
                .map(std::borrow::Cow::Owned)
                .map_err(|source| crate::Error::Io { path: file, source })
        }
        None => Ok(std::borrow::Cow::Borrowed(embedded)),
    }
}

/// Shader defs that compile in code for scene features; without them that code is left out.
pub const SCENE_DEFS: &[&str] = &["DIELECTRIC", "SPHERES", "POINT_LIGHTS"];

/// The shader defs a scene needs: `DIELECTRIC` when a shape has a dielectric BSDF, `SPHERES`
/// when it has spheres, `POINT_LIGHTS` when it has a point light.
pub fn scene_defs(scene: &crate::scene::Scene) -> HashMap<String, ShaderDefValue> {
    let features = scene.features();
    [
        ("DIELECTRIC", features.dielectric),
        ("SPHERES", features.spheres),
        ("POINT_LIGHTS", features.point_lights),
    ]
    .into_iter()
    .filter(|(_, present)| *present)
    .map(|(name, _)| (name.to_string(), ShaderDefValue::Bool(true)))
    .collect()
}

/// Every scene def set: kernels composed this way contain all the code there is.
pub fn all_scene_defs() -> HashMap<String, ShaderDefValue> {
    SCENE_DEFS
        .iter()
        .map(|name| (name.to_string(), ShaderDefValue::Bool(true)))
        .collect()
}

/// Composes pass shaders for one device and one scene (its shader defs).
pub struct ShaderLibrary {
    capabilities: naga::valid::Capabilities,
    defs: HashMap<String, ShaderDefValue>,
}

impl ShaderLibrary {
    /// `float_atomics`: the device has SHADER_FLOAT32_ATOMIC, so modules may use `atomic<f32>`.
    /// With `float_atomics` the shader def `FLOAT_ATOMICS` is set, and modules add flux with
    /// `atomic<f32>`; without it they use a compare-and-swap loop.
    pub fn new(float_atomics: bool, mut defs: HashMap<String, ShaderDefValue>) -> Self {
        let mut capabilities = naga::valid::Capabilities::default();
        if float_atomics {
            capabilities |= naga::valid::Capabilities::SHADER_FLOAT32_ATOMIC;
            defs.insert("FLOAT_ATOMICS".into(), ShaderDefValue::Bool(true));
        }
        Self { capabilities, defs }
    }

    pub fn defs(&self) -> &HashMap<String, ShaderDefValue> {
        &self.defs
    }

    fn composer(&self) -> Result<Composer, crate::Error> {
        let mut composer = Composer::default().with_capabilities(self.capabilities);
        for (path, embedded) in COMMON_MODULES {
            let source = source_of(path, embedded)?;
            let added = composer.add_composable_module(ComposableModuleDescriptor {
                source: &source,
                file_path: path,
                shader_defs: self.defs.clone(),
                ..Default::default()
            });
            if let Err(e) = added {
                return Err(crate::Error::Shader(e.emit_to_string(&composer)));
            }
        }
        Ok(composer)
    }

    /// Composes and validates the entry file `path` (one of `PASS_SHADERS`).
    pub fn compose(&self, path: &str) -> Result<naga::Module, crate::Error> {
        let source = PASS_SHADERS
            .iter()
            .find(|(p, _)| *p == path)
            .map(|(_, s)| *s)
            .ok_or_else(|| crate::Error::Shader(format!("no pass shader named {path}")))?;
        self.compose_source(path, &source_of(path, source)?)
    }

    /// Composes an entry file given as text; `path` names it in error messages.
    pub fn compose_source(&self, path: &str, source: &str) -> Result<naga::Module, crate::Error> {
        let mut composer = self.composer()?;
        composer
            .make_naga_module(NagaModuleDescriptor {
                source,
                file_path: path,
                shader_defs: self.defs.clone(),
                ..Default::default()
            })
            .map_err(|e| crate::Error::Shader(e.emit_to_string(&composer)))
    }

    /// A compute pipeline for `entry` in the pass shader `path`, with an explicit layout.
    pub fn compute_pipeline(
        &self,
        gpu: &crate::gpu::GpuContext,
        path: &str,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
    ) -> Result<wgpu::ComputePipeline, crate::Error> {
        let module = self.compose(path)?;
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(path),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(module)),
        };
        let shader = gpu.device.create_shader_module(desc);
        let layout_refs: Vec<Option<&wgpu::BindGroupLayout>> =
            layouts.iter().map(|l| Some(*l)).collect();
        let layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(path),
                bind_group_layouts: &layout_refs,
                immediate_size: 0,
            });
        let pipeline = gpu
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(path),
                layout: Some(&layout),
                module: &shader,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
        gpu.check_errors()?;
        Ok(pipeline)
    }
}
