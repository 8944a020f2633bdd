//! The scene as the GPU reads it, in one place: the records and tables built from a [`Scene`]
//! (`layout.rs`), where each table is bound and how it is uploaded (`resources.rs`), and the
//! WGSL that declares them (`scene.wgsl`, the module `common::scene` every pass imports). Knows
//! `gpu` and `scene`, nothing above them.
//!
//! [`Scene`]: crate::scene::Scene

pub mod layout;
pub mod resources;

pub use layout::GpuScene;
pub use resources::{PlacementRule, SceneResources, TablePlacement};
