//! Wavefront OBJ meshes through tobj: triangles only (polygons are fan-triangulated), positions
//! only (flat normals from the winding, counter-clockwise seen from outside).

use std::path::Path;

use glam::{Vec3, Vec4};

use super::{Bsdf, Camera, Integrator, Material, PointLight, Scene, SceneError, Triangle};
use crate::error::Location;

/// The triangles of `path` in the file's coordinates.
pub fn load_triangles(path: &Path) -> Result<Vec<[Vec3; 3]>, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    check_lines(path, &text)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _materials) =
        tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| Ok(Default::default())).map_err(
            |e| SceneError::File {
                file: path.to_path_buf(),
                message: format!("invalid OBJ: {e}"),
            },
        )?;
    let mut triangles = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let vertex = |i: u32| -> Option<Vec3> {
            let i = i as usize * 3;
            Some(Vec3::new(
                *mesh.positions.get(i)?,
                *mesh.positions.get(i + 1)?,
                *mesh.positions.get(i + 2)?,
            ))
        };
        for face in mesh.indices.chunks_exact(3) {
            let corners = [vertex(face[0]), vertex(face[1]), vertex(face[2])];
            let [Some(a), Some(b), Some(c)] = corners else {
                return Err(SceneError::File {
                    file: path.to_path_buf(),
                    message: format!("mesh \"{}\" has a face index out of range", model.name),
                });
            };
            triangles.push([a, b, c]);
        }
    }
    if triangles.is_empty() {
        return Err(SceneError::File {
            file: path.to_path_buf(),
            message: "the OBJ file has no faces".into(),
        });
    }
    Ok(triangles)
}

/// tobj reports no line numbers, so malformed `v` and `f` lines are found here first, with their
/// line: numbers that do not parse or are not finite, and face indices out of range.
fn check_lines(path: &Path, text: &str) -> Result<(), SceneError> {
    let mut vertices = 0i64;
    for (n, line) in text.lines().enumerate() {
        let at = |message: String| SceneError::at(Location::new(path, n + 1, 1), message);
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let coords: Vec<&str> = words.collect();
                if coords.len() < 3 {
                    return Err(at(format!("vertex needs 3 coordinates: \"{line}\"")));
                }
                for c in &coords[..3] {
                    match c.parse::<f32>() {
                        Ok(v) if v.is_finite() => {}
                        _ => {
                            return Err(at(format!(
                                "vertex coordinate \"{c}\" is not a finite number"
                            )));
                        }
                    }
                }
                vertices += 1;
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err(at(format!("face needs at least 3 vertices: \"{line}\"")));
                }
                for corner in corners {
                    let index = corner.split('/').next().unwrap_or("");
                    let i: i64 = index
                        .parse()
                        .map_err(|_| at(format!("face index \"{corner}\" is not a number")))?;
                    // Negative indices count back from the latest vertex.
                    let resolved = if i < 0 { vertices + i + 1 } else { i };
                    if resolved < 1 || resolved > vertices {
                        return Err(at(format!(
                            "face index {i} is out of range ({vertices} vertices so far)"
                        )));
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// A bare OBJ as a scene: a grey diffuse mesh seen from +z (looking at its bounding box centre,
/// framing it), lit by a point light above and behind the camera, so it can be looked at
/// without writing a scene file.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let triangles = load_triangles(path)?;
    let (lo, hi) = triangles.iter().flatten().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let center = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(f32::MIN_POSITIVE);
    let fov_x_deg: f32 = 40.0;
    let distance = radius / (fov_x_deg.to_radians() * 0.5).sin();
    let origin = center + Vec3::Z * distance;
    let light = origin + Vec4::new(0.0, radius, radius, 0.0).truncate();
    let scene = Scene {
        source: path.to_path_buf(),
        camera: Camera {
            origin,
            target: center,
            up: Vec3::Y,
            fov_x_deg,
            width: 512,
            height: 512,
        },
        integrator: Integrator::default(),
        spp_hint: None,
        materials: vec![Material {
            bsdf: Bsdf::Diffuse {
                reflectance: Vec3::splat(0.8),
            },
            emission: Vec3::ZERO,
        }],
        triangles: triangles
            .into_iter()
            .map(|v| Triangle { v, material: 0 })
            .collect(),
        spheres: Vec::new(),
        point_lights: vec![PointLight {
            position: light,
            intensity: Vec3::splat((light - center).length_squared()),
        }],
    };
    scene.validate()?;
    Ok(scene)
}
