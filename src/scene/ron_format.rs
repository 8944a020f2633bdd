//! hppm's own scene format, for `scenes/*.ron`. Every struct denies unknown fields.
//!
//! ```ron
//! (
//!     camera: (origin: (0, 0, 3.9), target: (0, 0, 0), up: (0, 1, 0), fov_x: 39.3, width: 128, height: 128),
//!     integrator: (max_depth: 12, rr_depth: None),   // optional; None = unbounded / no roulette
//!     spp: 64,                                       // optional default sample count
//!     // (optional values may be written `x` or `Some(x)`)
//!     materials: {
//!         "white": Diffuse(reflectance: (0.8, 0.8, 0.8)),
//!         "glass": Dielectric(int_ior: 1.5, ext_ior: 1.0),
//!         "mirror": Mirror,
//!     },
//!     shapes: [
//!         // Rectangle: [-1,1]^2 at z=0 facing +z. Cube: [-1,1]^3 facing out. Obj: a mesh file
//!         // relative to this file. Placed by `to_world`, a list applied in order.
//!         (shape: Rectangle, material: "white", to_world: [Scale((2, 2, 1)), Translate((0, -1, 0))]),
//!         (shape: Sphere(center: (0, 0, 0), radius: 0.5), material: "glass"),
//!         (shape: Cube, material: "white", emission: Some((1, 1, 1)), flip_normals: true),
//!         (shape: Obj(path: "mesh.obj"), material: "white",
//!          to_world: [Matrix((1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1))]),  // row-major
//!     ],
//!     point_lights: [(position: (0, 2, 0), intensity: (10, 10, 10))],   // W/sr
//! )
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use glam::{Mat4, Vec3};
use serde::Deserialize;

use super::{Bsdf, Camera, Integrator, Material, PointLight, Scene, SceneError, Sphere, mesh};
use crate::error::Location;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: CameraFile,
    #[serde(default)]
    integrator: IntegratorFile,
    #[serde(default)]
    spp: Option<u32>,
    materials: BTreeMap<String, MaterialFile>,
    shapes: Vec<ShapeFile>,
    #[serde(default)]
    point_lights: Vec<PointLightFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    origin: [f32; 3],
    target: [f32; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    fov_x: f32,
    width: u32,
    height: u32,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
struct IntegratorFile {
    max_depth: Option<u32>,
    rr_depth: Option<u32>,
}

impl Default for IntegratorFile {
    fn default() -> Self {
        let Integrator {
            max_depth,
            rr_depth,
        } = Integrator::default();
        Self {
            max_depth,
            rr_depth,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum MaterialFile {
    Diffuse {
        reflectance: [f32; 3],
    },
    Dielectric {
        int_ior: f32,
        #[serde(default = "one")]
        ext_ior: f32,
    },
    Mirror,
}

fn one() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum ShapeKind {
    Rectangle,
    Cube,
    Sphere { center: [f32; 3], radius: f32 },
    Obj { path: String },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum TransformStep {
    Translate([f32; 3]),
    Scale([f32; 3]),
    Rotate { axis: [f32; 3], degrees: f32 },
    Matrix([f32; 16]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeFile {
    shape: ShapeKind,
    material: String,
    #[serde(default)]
    to_world: Vec<TransformStep>,
    #[serde(default)]
    emission: Option<[f32; 3]>,
    #[serde(default)]
    flip_normals: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightFile {
    position: [f32; 3],
    intensity: [f32; 3],
}

pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    parse(path, &text)
}

/// Parses scene `text`; `path` names the file in errors and anchors relative OBJ paths.
pub fn parse(path: &Path, text: &str) -> Result<Scene, SceneError> {
    if let Some(offset) = non_finite_literal(text) {
        return Err(SceneError::at(
            Location::from_offset(path, text, offset),
            "numbers must be finite (NaN and infinity are not allowed)",
        ));
    }
    let options =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let file: SceneFile = options.from_str(text).map_err(|e| {
        SceneError::at(
            Location::new(path, e.span.start.line, e.span.start.col),
            e.code.to_string(),
        )
    })?;
    build(path, text, file)
}

/// Byte offset of the first `nan` / `inf` / `NaN` / `infinity` word outside strings and
/// comments: ron accepts them as floats, a scene must not.
fn non_finite_literal(text: &str) -> Option<usize> {
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i + 1 < bytes.len() && !(bytes[i] == b'*' && bytes[i + 1] == b'/') {
                    i += 1;
                }
                i += 2;
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = i;
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                let word = text[start..i].to_ascii_lowercase();
                if matches!(word.as_str(), "nan" | "inf" | "infinity") {
                    return Some(start);
                }
            }
            _ => i += 1,
        }
    }
    None
}

/// Location of the first occurrence of `needle` in `text` (for semantic errors serde cannot
/// place), or the start of the file.
fn locate(path: &Path, text: &str, needle: &str) -> Location {
    Location::from_offset(path, text, text.find(needle).unwrap_or(0))
}

fn to_world(steps: &[TransformStep]) -> Result<Mat4, String> {
    let mut m = Mat4::IDENTITY;
    for step in steps {
        let next = match step {
            TransformStep::Translate(t) => Mat4::from_translation(Vec3::from(*t)),
            TransformStep::Scale(s) => Mat4::from_scale(Vec3::from(*s)),
            TransformStep::Rotate { axis, degrees } => {
                let axis = Vec3::from(*axis)
                    .try_normalize()
                    .ok_or("Rotate: the axis is zero")?;
                Mat4::from_axis_angle(axis, degrees.to_radians())
            }
            TransformStep::Matrix(v) => Mat4::from_cols_slice(v).transpose(),
        };
        m = next * m;
    }
    Ok(m)
}

fn build(path: &Path, text: &str, file: SceneFile) -> Result<Scene, SceneError> {
    let names: Vec<&String> = file.materials.keys().collect();
    let mut scene = Scene {
        source: path.to_path_buf(),
        camera: Camera {
            origin: file.camera.origin.into(),
            target: file.camera.target.into(),
            up: file.camera.up.into(),
            fov_x_deg: file.camera.fov_x,
            width: file.camera.width,
            height: file.camera.height,
        },
        integrator: Integrator {
            max_depth: file.integrator.max_depth,
            rr_depth: file.integrator.rr_depth,
        },
        spp_hint: file.spp,
        materials: Vec::new(),
        triangles: Vec::new(),
        spheres: Vec::new(),
        point_lights: file
            .point_lights
            .iter()
            .map(|p| PointLight {
                position: p.position.into(),
                intensity: p.intensity.into(),
            })
            .collect(),
    };
    for shape in &file.shapes {
        let here = || locate(path, text, &format!("\"{}\"", shape.material));
        let bsdf = match file.materials.get(&shape.material) {
            Some(MaterialFile::Diffuse { reflectance }) => Bsdf::Diffuse {
                reflectance: (*reflectance).into(),
            },
            Some(MaterialFile::Dielectric { int_ior, ext_ior }) => Bsdf::Dielectric {
                int_ior: *int_ior,
                ext_ior: *ext_ior,
            },
            Some(MaterialFile::Mirror) => Bsdf::Mirror,
            None => {
                return Err(SceneError::at(
                    here(),
                    format!(
                        "unknown material \"{}\" (defined: {names:?})",
                        shape.material
                    ),
                ));
            }
        };
        let emission = Vec3::from(shape.emission.unwrap_or([0.0; 3]));
        if emission.min_element() < 0.0 {
            return Err(SceneError::at(here(), "emission must not be negative"));
        }
        let material = scene.materials.len() as u32;
        scene.materials.push(Material { bsdf, emission });
        let m = to_world(&shape.to_world).map_err(|e| SceneError::at(here(), e))?;
        let object_triangles = match &shape.shape {
            ShapeKind::Rectangle => mesh::rectangle(),
            ShapeKind::Cube => mesh::cube(),
            ShapeKind::Obj { path: obj } => {
                let obj_path = path.parent().unwrap_or(Path::new(".")).join(obj);
                super::obj::load_triangles(&obj_path).map_err(|e| match e {
                    SceneError::Io { file, source } => SceneError::at(
                        locate(path, text, obj),
                        format!("cannot read OBJ file {}: {source}", file.display()),
                    ),
                    other => other,
                })?
            }
            ShapeKind::Sphere { center, radius } => {
                if radius.is_nan() || *radius <= 0.0 {
                    return Err(SceneError::at(
                        locate(path, text, "radius"),
                        format!("sphere radius {radius}: must be positive"),
                    ));
                }
                scene.spheres.push(Sphere {
                    center: m.transform_point3(Vec3::from(*center)),
                    radius: radius * m.transform_vector3(Vec3::X).length(),
                    material,
                    flip_normals: shape.flip_normals,
                });
                continue;
            }
        };
        scene.push_mesh(object_triangles, m, material, shape.flip_normals);
    }
    scene.validate()?;
    Ok(scene)
}
