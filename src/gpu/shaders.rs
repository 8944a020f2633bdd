//! WGSL composition with naga_oil. A library is built once per device and scene: it adds every
//! importable module (this layer's own under `shaders/gpu/`, then the caller's) to one composer
//! with one set of shader defs, and composes entry files against it on demand. Sources are
//! compiled into the binary, so `hppm` runs from any directory; `$HPPM_SHADER_DIR` overrides
//! them to edit shaders without rebuilding.

use std::borrow::Cow;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::Mutex;

use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderDefValue,
};
use wgpu::naga;

use super::pipeline_cache::PipelineKey;
use super::{GpuContext, GpuError};

/// A WGSL file: its path relative to the crate root (how errors and `$HPPM_SHADER_DIR` name it)
/// and the text compiled into the binary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShaderFile {
    pub path: &'static str,
    pub source: &'static str,
}

/// `shader_file!("shaders/passes/x.wgsl")`: the file with its text embedded at compile time.
#[macro_export]
macro_rules! shader_file {
    ($path:literal) => {
        $crate::gpu::shaders::ShaderFile {
            path: $path,
            source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/", $path)),
        }
    };
}

/// This layer's importable modules (`gpu::*`), added before any caller's module.
pub const GPU_MODULES: &[ShaderFile] = &[
    crate::shader_file!("shaders/gpu/dispatch.wgsl"),
    crate::shader_file!("shaders/gpu/sample_mask.wgsl"),
];

impl ShaderFile {
    /// The text to compile: from `$HPPM_SHADER_DIR/path` when that variable is set, else the
    /// embedded copy.
    pub fn text(&self) -> Result<Cow<'static, str>, GpuError> {
        match std::env::var_os("HPPM_SHADER_DIR") {
            Some(dir) => {
                let file = std::path::Path::new(&dir).join(self.path);
                std::fs::read_to_string(&file)
                    .map(Cow::Owned)
                    .map_err(|e| GpuError::Shader(format!("{}: {e}", file.display())))
            }
            None => Ok(Cow::Borrowed(self.source)),
        }
    }
}

/// A module a library composes: a WGSL file, a file with generated text after it, or text
/// generated whole. Generated text comes from a table in Rust (the scene's chunked bindings, the
/// BSDFs' kind numbers and dispatch), so that nothing is written by hand in two places.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum WgslModule {
    File(ShaderFile),
    /// The file's text (which declares the module's import path), then `generated`.
    FileThen(ShaderFile, String),
    /// Text generated whole; `path` names it in errors (it has no file).
    Generated {
        path: String,
        text: String,
    },
}

impl From<ShaderFile> for WgslModule {
    fn from(file: ShaderFile) -> Self {
        WgslModule::File(file)
    }
}

impl WgslModule {
    /// How errors name it: its file's path, or the generated module's.
    pub fn path(&self) -> &str {
        match self {
            WgslModule::File(file) | WgslModule::FileThen(file, _) => file.path,
            WgslModule::Generated { path, .. } => path,
        }
    }

    /// The text to compose (a file's from `$HPPM_SHADER_DIR` when that is set).
    pub fn text(&self) -> Result<Cow<'_, str>, GpuError> {
        match self {
            WgslModule::File(file) => file.text(),
            WgslModule::FileThen(file, generated) => {
                Ok(Cow::Owned(format!("{}\n{generated}", file.text()?)))
            }
            WgslModule::Generated { text, .. } => Ok(Cow::Borrowed(text)),
        }
    }
}

/// Shader defs as naga_oil takes them, from the names of the defs that are set.
pub fn defs_of<'a>(names: impl IntoIterator<Item = &'a str>) -> HashMap<String, ShaderDefValue> {
    names
        .into_iter()
        .map(|name| (name.to_string(), ShaderDefValue::Bool(true)))
        .collect()
}

/// Composes entry files for one device and one set of shader defs.
pub struct ShaderLibrary {
    defs: HashMap<String, ShaderDefValue>,
    /// The modules' paths and text, the defs and the device features, hashed: what a composed
    /// module depends on besides its entry file (the pipeline cache's key).
    fingerprint: u64,
    // `make_naga_module` needs `&mut`; passes compose through a shared reference.
    composer: Mutex<Composer>,
}

impl ShaderLibrary {
    /// `modules`: the caller's importable modules in dependency order (a module may import only
    /// those before it, and this layer's `gpu::*`). With `float_atomics` (the device has
    /// SHADER_FLOAT32_ATOMIC) the def `FLOAT_ATOMICS` is set and modules may use `atomic<f32>`;
    /// without it they use a compare-and-swap loop.
    pub fn new(
        float_atomics: bool,
        mut defs: HashMap<String, ShaderDefValue>,
        modules: &[WgslModule],
    ) -> Result<Self, GpuError> {
        let mut capabilities = naga::valid::Capabilities::default();
        if float_atomics {
            capabilities |= naga::valid::Capabilities::SHADER_FLOAT32_ATOMIC;
            defs.insert("FLOAT_ATOMICS".into(), ShaderDefValue::Bool(true));
        }
        let mut composer = Composer::default().with_capabilities(capabilities);
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        let mut sorted: Vec<String> = defs.iter().map(|(k, v)| format!("{k}={v:?}")).collect();
        sorted.sort_unstable();
        (float_atomics, sorted).hash(&mut hasher);
        let own = GPU_MODULES.iter().map(|&file| WgslModule::File(file));
        for module in own.chain(modules.iter().cloned()) {
            let source = module.text()?;
            (module.path(), &source).hash(&mut hasher);
            let added = composer.add_composable_module(ComposableModuleDescriptor {
                source: &source,
                file_path: module.path(),
                shader_defs: defs.clone(),
                ..Default::default()
            });
            if let Err(e) = added {
                return Err(GpuError::Shader(e.emit_to_string(&composer)));
            }
        }
        Ok(Self {
            defs,
            fingerprint: hasher.finish(),
            composer: Mutex::new(composer),
        })
    }

    pub fn defs(&self) -> &HashMap<String, ShaderDefValue> {
        &self.defs
    }

    /// Composes and validates the entry file `file`.
    pub fn compose(&self, file: &ShaderFile) -> Result<naga::Module, GpuError> {
        self.compose_source(file.path, &file.text()?)
    }

    /// Composes `file` with `extra` defs set on top of the library's (a pass's own, from its
    /// params); the modules it imports see them too.
    pub fn compose_with(
        &self,
        file: &ShaderFile,
        extra: &[&str],
    ) -> Result<naga::Module, GpuError> {
        self.compose_source_with(file.path, &file.text()?, extra)
    }

    /// Composes an entry file given as text; `path` names it in error messages.
    pub fn compose_source(&self, path: &str, source: &str) -> Result<naga::Module, GpuError> {
        self.compose_source_with(path, source, &[])
    }

    fn compose_source_with(
        &self,
        path: &str,
        source: &str,
        extra: &[&str],
    ) -> Result<naga::Module, GpuError> {
        let mut defs = self.defs.clone();
        defs.extend(defs_of(extra.iter().copied()));
        let mut composer = self
            .composer
            .lock()
            .map_err(|_| GpuError::Shader("shader composer poisoned by a panic".into()))?;
        composer
            .make_naga_module(NagaModuleDescriptor {
                source,
                file_path: path,
                shader_defs: defs,
                ..Default::default()
            })
            .map_err(|e| GpuError::Shader(e.emit_to_string(&composer)))
    }

    /// A compute pipeline for `entry` in `file`, with an explicit layout.
    pub fn compute_pipeline(
        &self,
        gpu: &GpuContext,
        file: &ShaderFile,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        self.compute_pipeline_with(gpu, file, entry, layouts, &[])
    }

    /// As [`ShaderLibrary::compute_pipeline`], composed with `extra` defs (see
    /// [`ShaderLibrary::compose_with`]).
    pub fn compute_pipeline_with(
        &self,
        gpu: &GpuContext,
        file: &ShaderFile,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
        extra: &[&str],
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let source = file.text()?;
        let key = PipelineKey {
            library: self.fingerprint,
            path: file.path.to_string(),
            source: source.to_string(),
            extra: extra.iter().map(|e| e.to_string()).collect(),
            entry: entry.to_string(),
            layouts: layouts.iter().map(|l| (*l).clone()).collect(),
        };
        gpu.cache.pipeline(key, || {
            self.build_pipeline(gpu, file.path, &source, entry, layouts, extra)
        })
    }

    /// Composes the entry file at `path` (its text `source`) and compiles `entry` of it.
    fn build_pipeline(
        &self,
        gpu: &GpuContext,
        path: &'static str,
        source: &str,
        entry: &str,
        layouts: &[&wgpu::BindGroupLayout],
        extra: &[&str],
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let module = self.compose_source_with(path, source, extra)?;
        let shader = gpu
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(path),
                source: wgpu::ShaderSource::Naga(Cow::Owned(module)),
            });
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
