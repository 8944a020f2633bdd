//! The BSDFs, one unit each: a folder holding everything about one Mitsuba BSDF plugin, namely
//! the properties it reads and how ([`BsdfPlugin::read`], through a [`BsdfReader`] the loader
//! gives it), its model (a [`BsdfModel`](crate::scene::bsdf::BsdfModel): the CPU reference of
//! its eval, pdf and sample, its lobes as the light-transport partition sees them and its
//! packing into the GPU record), its WGSL (eval and sample with the dispatch's signatures), the
//! shader def that compiles that WGSL in, its row of the plugin table and its tests.
//!
//! One table lists them ([`BsdfRegistry`], a value like `passes::Registry`): the Mitsuba loader
//! dispatches on it, the GPU kind numbers are its order, the WGSL constants
//! (`MATERIAL_<KIND>`) and the material dispatch (`common::material`) are generated from it,
//! and so are the shader defs a scene sets, `hppm plugins` and docs/scenes.md's rows. Adding a
//! BSDF is a folder and one line of [`builtin`]; a program adds its own with
//! [`BsdfRegistry::with`] (examples/custom_bsdf), and hppm never names it.

mod plugin;
mod reader;
mod registry;
pub mod shared;

pub mod blendbsdf;
pub mod coating;
pub mod conductor;
pub mod dielectric;
pub mod difftrans;
pub mod diffuse;
pub mod hk;
pub mod mixturebsdf;
pub mod normalmap;
pub mod null;
pub mod phong;
pub mod plastic;
pub mod pplastic;
pub mod principled;
pub mod principledthin;
pub mod roughconductor;
pub mod roughdielectric;
pub mod roughdiffuse;
pub mod roughplastic;
pub mod thindielectric;
pub mod twosided;
pub mod ward;

pub use plugin::{BsdfPlugin, Glossy, GpuKind, WgslCall};
pub use reader::{BsdfReader, Sides};
pub use registry::BsdfRegistry;

/// hppm's own BSDF units, in the order of their kind numbers. A unit's WGSL may import the
/// modules of units before it (`principledthin` uses `principled`'s lobes).
pub fn builtin() -> &'static [&'static BsdfPlugin] {
    static UNITS: &[&BsdfPlugin] = &[
        &diffuse::PLUGIN,
        &dielectric::PLUGIN,
        &conductor::PLUGIN,
        &roughconductor::PLUGIN,
        &plastic::PLUGIN,
        &roughplastic::PLUGIN,
        &roughdielectric::PLUGIN,
        &thindielectric::PLUGIN,
        &blendbsdf::PLUGIN,
        &null::PLUGIN,
        &principled::PLUGIN,
        &pplastic::PLUGIN,
        &principledthin::PLUGIN,
        &twosided::PLUGIN,
        &normalmap::PLUGIN,
        &normalmap::BUMP_PLUGIN,
        &roughdiffuse::PLUGIN,
        &phong::PLUGIN,
        &ward::PLUGIN,
        &difftrans::PLUGIN,
        &mixturebsdf::PLUGIN,
        &hk::PLUGIN,
        &coating::PLUGIN,
        &coating::ROUGH_PLUGIN,
    ];
    UNITS
}
