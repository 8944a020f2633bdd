//! hppm: a GPU renderer that combines path tracing with progressive photon mapping, built as a
//! render graph of wgpu compute passes described in RON.
//!
//! Path tracing renders every light path except caustics (`L S+ D`), which photon mapping
//! renders at the camera paths' diffuse vertices; each path is counted once
//! (docs/design.md). A graph file names the passes and wires their slots; the registry
//! ([`passes::Registry`]) says which pass kinds exist, and a program may add its own.
//!
//! Render the bundled Cornell box through the bundled hybrid graph, into memory:
//!
//! ```
//! use hppm::render::Renderer;
//! use hppm::passes::Registry;
//!
//! # fn main() -> Result<(), hppm::Error> {
//! let gpu = hppm::gpu::GpuContext::new(None)?;
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell_box.ron");
//! let scene = hppm::loaders::load(std::path::Path::new(path))?;
//! let registry = Registry::builtin();
//! let graph = registry.bundled_graph("hybrid")?;
//! let mut renderer = Renderer::builder(&gpu, &scene, graph)
//!     .registry(registry)
//!     .size(16, 16)
//!     .build()?;
//! renderer.iterate()?;
//! let image = renderer.image()?;
//! assert_eq!(image.pixels.len(), 16 * 16);
//! # Ok(())
//! # }
//! ```
//!
//! Layers point one way: `gpu` (device, buffers, shader composition, radix sort) knows nothing
//! above it; `graph` (schema, validation, pruning, schedule, allocation, execution) knows `gpu`
//! only; `scene` (the model and the BSDF interface) knows neither graph nor passes; `bsdfs`
//! (one unit per BSDF and their registry) and `loaders` (Mitsuba XML, RON, OBJ, PLY) build on
//! it; `gpu_scene` is the scene as the GPU reads it; `passes` knows all of those; `render` (the
//! renderer, budgets, the error estimate, checkpoints), `app` (render jobs, compare, bench, the
//! live view) and `cli` (the command line, behind the default `cli` feature) are clients of
//! them. docs/library.md lists the calls a program uses, docs/writing-a-pass.md and
//! docs/writing-a-bsdf.md how a pass or a BSDF is added from another crate.

pub mod app;
pub mod bsdfs;
#[cfg(feature = "cli")]
pub mod cli;
pub mod error;
pub mod gpu;
pub mod gpu_scene;
pub mod graph;
pub mod image;
pub mod loaders;
pub mod passes;
pub mod render;
pub mod ron_span;
pub mod scene;
pub mod testing;

pub use error::Location;

/// Every error a user can cause or meet, each with enough context to act on.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Gpu(#[from] gpu::GpuError),
    #[error(transparent)]
    Graph(#[from] graph::GraphErrors),
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    #[error("{0}")]
    Shader(String),
    #[error("{path}: {source}")]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("{0}")]
    Other(String),
    /// An error of one node, placed at the node in its graph file.
    #[error("{place}: {source}")]
    InNode { place: String, source: Box<Error> },
}

impl Error {
    /// A buffer larger than the adapter binds or allocates: a smaller image (or tile) may fit.
    pub fn is_too_large(&self) -> bool {
        match self {
            Error::Gpu(gpu::GpuError::BufferTooLarge { .. }) => true,
            Error::InNode { source, .. } => source.is_too_large(),
            _ => false,
        }
    }
}
