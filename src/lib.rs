//! hppm: a GPU renderer that combines path tracing with progressive photon mapping, built as a
//! render graph of wgpu compute passes described in RON.

pub mod bench;
pub mod bench_hybrid;
pub mod bench_lbvh;
pub mod compare;
pub mod error;
pub mod gpu;
pub mod graph;
pub mod image;
pub mod passes;
pub mod plot;
pub mod render;
pub mod ron_span;
pub mod scene;
pub mod shaders;

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
}
