//! The scene as the GPU reads it, in one place: the records and tables built from a [`Scene`]
//! (`layout.rs`), where each table is bound and how it is uploaded (`resources.rs`), and the
//! WGSL that declares them (`scene.wgsl`, the module `common::scene` every pass imports). Knows
//! `gpu` and `scene`, nothing above them.
//!
//! [`Scene`]: crate::scene::Scene

pub mod layout;
pub mod media;
pub mod resources;
pub mod tables;

pub use layout::GpuScene;
pub use resources::{PlacementRule, SceneResources, TablePlacement};

use crate::bsdfs::BsdfRegistry;
use crate::gpu::shaders::{ShaderFile, WgslModule};

/// The scene's records and bindings as WGSL (`common::scene`), written by hand.
const WGSL: ShaderFile = crate::shader_file!("src/gpu_scene/scene.wgsl");

/// The module `common::scene`: scene.wgsl, then the chunked tables' bindings and readers
/// generated from `tables::CHUNKABLE` and the material kinds' numbers generated from `bsdfs`.
pub fn wgsl_module(bsdfs: &BsdfRegistry) -> WgslModule {
    WgslModule::FileThen(WGSL, tables::chunk_wgsl() + &bsdfs.kinds_wgsl())
}
