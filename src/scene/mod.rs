//! Scene description: what every loader (Mitsuba XML, OBJ, our RON format) produces and what the
//! GPU layout is built from. Geometry is flattened to world-space triangles and analytic spheres;
//! every shape owns one material entry (its BSDF plus its area emission, as in Mitsuba, where the
//! emitter is attached to the shape).

pub mod bvh;
pub mod gpu_layout;
pub mod mitsuba;
pub mod obj;
pub mod ron_format;

use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::error::Location;

/// A perspective pinhole camera. `fov_x_deg` is the full horizontal field of view; loaders that
/// read a vertical fov convert it with the film's aspect ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub origin: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_x_deg: f32,
    pub width: u32,
    pub height: u32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bsdf {
    /// Lambertian, one-sided: black when seen from the back of the surface.
    Diffuse { reflectance: Vec3 },
    /// Smooth dielectric with Fresnel-weighted reflection and refraction, no absorption.
    Dielectric { int_ior: f32, ext_ior: f32 },
    /// Perfect mirror of reflectance 1 (Mitsuba `conductor` with `material="none"`).
    Mirror,
}

impl Bsdf {
    /// Delta (specular) BSDFs are the S vertices of the light-transport partition.
    pub fn is_delta(&self) -> bool {
        !matches!(self, Bsdf::Diffuse { .. })
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    pub bsdf: Bsdf,
    /// Radiance emitted on the front (normal) side; zero for non-emitters.
    pub emission: Vec3,
}

/// A world-space triangle, counter-clockwise seen from its front (normal) side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    pub v: [Vec3; 3],
    pub material: u32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
    /// Normals point inwards (Mitsuba `flip_normals`).
    pub flip_normals: bool,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLight {
    pub position: Vec3,
    /// Radiant intensity in W/sr per RGB channel.
    pub intensity: Vec3,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Integrator {
    /// Longest path in segments (Mitsuba's rule: 1 = emitters seen directly). `None` = unbounded.
    pub max_depth: Option<u32>,
    /// Depth (in segments) from which Russian roulette starts. `None` = never.
    pub rr_depth: Option<u32>,
}

impl Default for Integrator {
    fn default() -> Self {
        Self {
            max_depth: Some(12),
            rr_depth: None,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The file the scene was loaded from (for messages).
    pub source: PathBuf,
    pub camera: Camera,
    pub integrator: Integrator,
    /// Samples per pixel the scene file suggests (Mitsuba `sample_count`), if any.
    pub spp_hint: Option<u32>,
    pub materials: Vec<Material>,
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    pub point_lights: Vec<PointLight>,
}

/// A scene that could not be loaded. Every variant names the file; parse errors carry a line and
/// column.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{location}: {message}")]
    At { location: Location, message: String },
    #[error("{file}: {message}")]
    File { file: PathBuf, message: String },
}

impl SceneError {
    pub fn at(location: Location, message: impl Into<String>) -> Self {
        SceneError::At {
            location,
            message: message.into(),
        }
    }
}

/// Loads a scene by extension: `.xml` (Mitsuba 3), `.ron` (ours) or `.obj` (a bare mesh, given a
/// default camera and light so it can be looked at).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "xml" => mitsuba::load(path),
        "ron" => ron_format::load(path),
        "obj" => obj::load_scene(path),
        _ => Err(SceneError::File {
            file: path.to_path_buf(),
            message: "unknown scene format (expected .xml, .ron or .obj)".into(),
        }),
    }
}
