//! Wavefront OBJ meshes through tobj: triangles only (polygons are fan-triangulated), their
//! front counter-clockwise, with vertex normals (the file's or computed, as Mitsuba does) for
//! shapes that shade smoothly. Materials (`mtllib`, `usemtl`) are ignored: the scene file
//! assigns the BSDF.

use std::path::Path;

use glam::{Mat4, Vec3};

use crate::error::Location;
use crate::scene::filter::PixelFilter;
use crate::scene::mesh::{MeshData, angle_weighted_normals};
use crate::scene::{
    Camera, Integrator, Material, PointLight, Scene, SceneError, Triangle, place_triangles,
};

/// The triangles of `path` placed by `transform` (a mirroring transform keeps the front side,
/// `flip` reverses it), all with material index `material`.
pub fn load_mesh(
    path: &Path,
    transform: Mat4,
    material: u32,
    flip: bool,
) -> Result<Vec<Triangle>, SceneError> {
    let triangles = load_triangles(path)?;
    Ok(place_triangles(triangles, transform, material, flip).collect())
}

/// The triangles of `path` in the file's coordinates.
pub fn load_triangles(path: &Path) -> Result<Vec<[Vec3; 3]>, SceneError> {
    let text = crate::loaders::read_text(path)?;
    parse_triangles(path, &text)
}

/// The triangles of OBJ `text`; `path` names the file in errors.
pub fn parse_triangles(path: &Path, text: &str) -> Result<Vec<[Vec3; 3]>, SceneError> {
    parse_mesh(path, text).map(|mesh| mesh.triangles)
}

/// The mesh of OBJ file `path` with its vertex normals: the file's (`vn`) where every face
/// corner names one, otherwise computed as Mitsuba computes them, per vertex as Mitsuba's OBJ
/// loader tells vertices apart (by position and texture coordinate index).
pub fn load_mesh_data(path: &Path) -> Result<MeshData, SceneError> {
    let text = crate::loaders::read_text(path)?;
    parse_mesh(path, &text)
}

/// [`load_mesh_data`] of OBJ `text`; `path` names the file in errors.
pub fn parse_mesh(path: &Path, text: &str) -> Result<MeshData, SceneError> {
    check_lines(path, text)?;
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
    let mut mesh = MeshData {
        normals: Some(Vec::new()),
        ..MeshData::default()
    };
    let mut uv_parts = Vec::new();
    // The vertices of triangles whose normals are computed, numbered across the file's models.
    let mut corner_vertices: Vec<Option<[usize; 3]>> = Vec::new();
    let mut computed_vertices = 0;
    for model in &models {
        let m = &model.mesh;
        let out_of_range = || SceneError::File {
            file: path.to_path_buf(),
            message: format!("mesh \"{}\" has a face index out of range", model.name),
        };
        let triple = |values: &[f32], i: u32| -> Option<Vec3> {
            let i = i as usize * 3;
            values.get(i..i + 3).map(Vec3::from_slice)
        };
        let positions = (0..m.positions.len() / 3)
            .map(|i| triple(&m.positions, i as u32).unwrap_or_default())
            .collect::<Vec<_>>();
        let mut corners = Vec::new();
        for face in m.indices.chunks_exact(3) {
            let c = [face[0], face[1], face[2]].map(|i| i as usize);
            if c.iter().any(|&i| i >= positions.len()) {
                return Err(out_of_range());
            }
            mesh.triangles.push(c.map(|i| positions[i]));
            corners.push(c);
        }
        let file_normals = !m.normals.is_empty() && m.normal_indices.len() == m.indices.len();
        let normals = if file_normals {
            m.normal_indices
                .chunks_exact(3)
                .map(|f| {
                    let n = [f[0], f[1], f[2]].map(|i| triple(&m.normals, i));
                    match n {
                        [Some(a), Some(b), Some(c)] => Ok([a, b, c]),
                        _ => Err(out_of_range()),
                    }
                })
                .collect::<Result<Vec<_>, _>>()?
        } else {
            // Mitsuba's vertices are (position, texture coordinate) pairs: a UV seam splits a
            // vertex, and its normal with it.
            let with_uv = m.texcoord_indices.len() == m.indices.len();
            let mut ids = std::collections::HashMap::new();
            let mut vertex_positions = Vec::new();
            let mut vertex_corners = Vec::with_capacity(corners.len());
            for (t, c) in corners.iter().enumerate() {
                vertex_corners.push([0, 1, 2].map(|k| {
                    let uv = if with_uv {
                        m.texcoord_indices[3 * t + k]
                    } else {
                        0
                    };
                    *ids.entry((c[k], uv)).or_insert_with(|| {
                        vertex_positions.push(positions[c[k]]);
                        vertex_positions.len() - 1
                    })
                }));
            }
            let first = computed_vertices;
            computed_vertices += vertex_positions.len();
            corner_vertices.extend(vertex_corners.iter().map(|c| Some(c.map(|v| first + v))));
            angle_weighted_normals(&vertex_positions, &vertex_corners)
        };
        if file_normals {
            corner_vertices.extend(std::iter::repeat_n(None, corners.len()));
        }
        mesh.normals.get_or_insert_with(Vec::new).extend(normals);
        // Texture coordinates where every corner of every face names one (as OBJ stores them;
        // Mitsuba's flip_tex_coords is the loader's business).
        let with_uv = !m.texcoords.is_empty() && m.texcoord_indices.len() == m.indices.len();
        let uvs = with_uv
            .then(|| {
                m.texcoord_indices
                    .chunks_exact(3)
                    .map(|f| {
                        let uv = [f[0], f[1], f[2]].map(|i| {
                            let i = i as usize * 2;
                            m.texcoords.get(i..i + 2).map(glam::Vec2::from_slice)
                        });
                        match uv {
                            [Some(a), Some(b), Some(c)] => Ok([a, b, c]),
                            _ => Err(out_of_range()),
                        }
                    })
                    .collect::<Result<Vec<_>, _>>()
            })
            .transpose()?;
        uv_parts.push((corners.len(), uvs));
    }
    // A model without texture coordinates in a file that has them takes Mitsuba's default for
    // a mesh without any: the barycentrics.
    if uv_parts.iter().any(|(_, uvs)| uvs.is_some()) {
        let barycentric = [glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y];
        mesh.uvs = Some(
            uv_parts
                .into_iter()
                .flat_map(|(n, uvs)| uvs.unwrap_or_else(|| vec![barycentric; n]))
                .collect(),
        );
    }
    if mesh.triangles.is_empty() {
        return Err(SceneError::File {
            file: path.to_path_buf(),
            message: "the OBJ file has no faces".into(),
        });
    }
    if corner_vertices.iter().any(Option::is_some) {
        mesh.computed_normal_vertices = Some(corner_vertices);
    }
    Ok(mesh)
}

/// How many `v`, `vt` and `vn` records precede the current line: what face indices may refer to.
#[derive(Default)]
struct Counts {
    positions: i64,
    texcoords: i64,
    normals: i64,
}

/// tobj reports no line numbers, so malformed `v` and `f` lines are found here first, with their
/// line: numbers that do not parse or are not finite, and face indices out of range (which also
/// keeps tobj away from indices it would have to reject without a line).
fn check_lines(path: &Path, text: &str) -> Result<(), SceneError> {
    let mut counts = Counts::default();
    for (n, line) in text.lines().enumerate() {
        let at = |message: String| SceneError::at(Location::new(path, n + 1, 1), message);
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                check_coordinates(words, 3, "vertex").map_err(at)?;
                counts.positions += 1;
            }
            Some("vt") => {
                check_coordinates(words, 1, "texture coordinate").map_err(at)?;
                counts.texcoords += 1;
            }
            Some("vn") => {
                check_coordinates(words, 3, "normal").map_err(at)?;
                counts.normals += 1;
            }
            Some("f") => check_face(words, &counts).map_err(at)?,
            _ => {}
        }
    }
    Ok(())
}

fn check_coordinates<'a>(
    words: impl Iterator<Item = &'a str>,
    needed: usize,
    what: &str,
) -> Result<(), String> {
    let mut found = 0;
    for word in words {
        match word.parse::<f32>() {
            Ok(v) if v.is_finite() => found += 1,
            _ => return Err(format!("{what}: \"{word}\" is not a finite number")),
        }
    }
    if found < needed {
        return Err(format!(
            "{what} needs at least {needed} numbers, found {found}"
        ));
    }
    Ok(())
}

/// A face's corners are `v`, `v/vt`, `v//vn` or `v/vt/vn`, each index 1-based or negative
/// (counting back from the latest record).
fn check_face<'a>(corners: impl Iterator<Item = &'a str>, counts: &Counts) -> Result<(), String> {
    let mut n = 0;
    for corner in corners {
        n += 1;
        let mut parts = corner.split('/');
        let limits = [
            ("vertex", counts.positions, true),
            ("texture coordinate", counts.texcoords, false),
            ("normal", counts.normals, false),
        ];
        for (what, available, required) in limits {
            match parts.next() {
                Some("") | None if !required => {}
                Some(index) => check_index(index, what, available)?,
                None => return Err(format!("face corner \"{corner}\" has no vertex index")),
            }
        }
        if parts.next().is_some() {
            return Err(format!("face corner \"{corner}\" has more than 3 indices"));
        }
    }
    if n < 3 {
        return Err(format!("a face needs at least 3 corners, found {n}"));
    }
    Ok(())
}

fn check_index(index: &str, what: &str, available: i64) -> Result<(), String> {
    let i: i64 = index
        .parse()
        .map_err(|_| format!("face {what} index \"{index}\" is not a whole number"))?;
    let resolved = if i < 0 { available + i + 1 } else { i };
    if resolved < 1 || resolved > available {
        return Err(format!(
            "face {what} index {i} is out of range ({available} defined so far)"
        ));
    }
    Ok(())
}

/// Field of view of the default camera of a bare OBJ.
const OBJ_FOV_X_DEG: f32 = 40.0;

/// A bare OBJ as a scene, so a mesh can be looked at without writing a scene file:
///
/// - one material, diffuse with reflectance 0.8, no emission;
/// - a 512x512 camera on the +z side of the mesh's bounding sphere, looking at its centre with
///   +y up, far enough back that the whole bounding sphere fits in the 40 degree field of view;
/// - a point light one bounding radius above and one behind the camera, whose intensity
///   (distance to the centre squared) makes the irradiance at the centre about 1;
/// - the default integrator (max depth 12, no Russian roulette).
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    framed_scene(path, load_triangles(path)?)
}

/// The scene of [`load_scene`] around `triangles` (a bare mesh file's, `path` naming it).
pub fn framed_scene(path: &Path, triangles: Vec<[Vec3; 3]>) -> Result<Scene, SceneError> {
    let (lo, hi) = triangles.iter().flatten().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let center = 0.5 * (lo + hi);
    // A lower bound on the radius keeps the camera off the target for a mesh that is a point.
    let min_radius = 1e-3 * center.abs().max_element().max(1.0);
    let radius = (0.5 * (hi - lo).length()).max(min_radius);
    let distance = radius / (OBJ_FOV_X_DEG.to_radians() * 0.5).sin();
    let origin = center + Vec3::Z * distance;
    let light = origin + Vec3::new(0.0, radius, radius);
    let scene = Scene {
        media: Default::default(),
        source: path.to_path_buf(),
        camera: Camera {
            origin,
            target: center,
            up: Vec3::Y,
            fov_x_deg: OBJ_FOV_X_DEG,
            width: 512,
            height: 512,
            filter: PixelFilter::Box,
            sample_border: false,
            crop: None,
            lens: None,
        },
        integrator: Integrator::default(),
        spp_hint: None,
        materials: vec![Material {
            media: Default::default(),
            bsdf: crate::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.8)),
            back: None,
            emission: Vec3::ZERO,
            textures: Default::default(),
        }],
        triangles: place_triangles(triangles, Mat4::IDENTITY, 0, false).collect(),
        spheres: Vec::new(),
        point_lights: vec![PointLight {
            position: light,
            intensity: Vec3::splat((light - center).length_squared()),
        }],
        emitters: Default::default(),
        textures: Vec::new(),
    };
    scene.validate()?;
    Ok(scene)
}
