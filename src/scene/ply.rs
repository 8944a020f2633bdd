//! Stanford PLY meshes (ASCII and binary, either byte order) through the `ply-rs-bw` crate, read
//! as Mitsuba 3's `ply` shape reads them: a `vertex` element with `x`, `y`, `z`, optional
//! vertex normals `nx`, `ny`, `nz` and texture coordinates (`u`/`v`, `s`/`t` or
//! `texture_u`/`texture_v`), and a `face` element whose `vertex_indices` (or `vertex_index`)
//! lists are triangles (larger polygons are fan-triangulated). Without vertex normals in the
//! file they are computed as Mitsuba computes them. Other elements and properties (colours,
//! per-face attributes) are not used.

use std::path::Path;

use glam::{Vec2, Vec3};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};

use super::SceneError;
use super::mesh::{MeshData, angle_weighted_normals};
use crate::error::Location;

/// The mesh of PLY file `path`, in the file's coordinates.
pub fn load(path: &Path) -> Result<MeshData, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    parse(path, &bytes)
}

/// The mesh in PLY `bytes`; `path` names the file in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<MeshData, SceneError> {
    let fail = |message: String| SceneError::File {
        file: path.to_path_buf(),
        message,
    };
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .map_err(|e| {
            // The crate's message spans lines (and starts with "Line N:" when it has a line,
            // which the location says): one line here.
            let text = e.to_string();
            let text = match e.line() {
                Some(line) => text
                    .trim_start_matches(&format!("Line {line}: "))
                    .to_string(),
                None => text,
            };
            let message = format!(
                "invalid PLY: {}",
                text.split_whitespace().collect::<Vec<_>>().join(" ")
            );
            match e.line() {
                Some(line) => SceneError::at(Location::new(path, line, 1), message),
                None => fail(message),
            }
        })?;
    let empty = Vec::new();
    let vertices = ply.payload.get("vertex").unwrap_or(&empty);
    let faces = ply.payload.get("face").unwrap_or(&empty);
    if vertices.is_empty() || faces.is_empty() {
        return Err(fail(format!(
            "the PLY file has {} vertices and {} faces: a mesh needs both (elements \"vertex\" \
             and \"face\")",
            vertices.len(),
            faces.len()
        )));
    }
    let positions = vertex_vectors(vertices, ["x", "y", "z"])
        .map_err(&fail)?
        .ok_or_else(|| fail("the PLY vertices have no x, y, z properties".into()))?;
    let normals = vertex_vectors(vertices, ["nx", "ny", "nz"]).map_err(&fail)?;
    let uvs = [["u", "v"], ["s", "t"], ["texture_u", "texture_v"]]
        .iter()
        .find_map(|names| vertex_vectors(vertices, *names).transpose())
        .transpose()
        .map_err(&fail)?;
    let mut corners_of_triangles: Vec<[usize; 3]> = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let indices = face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
            .ok_or_else(|| fail("the PLY faces have no vertex_indices list".into()))?;
        let indices = indices.to_u32_list().ok_or_else(|| {
            fail(format!(
                "face {f}: vertex_indices is not a list of non-negative integers"
            ))
        })?;
        if indices.len() < 3 {
            return Err(fail(format!(
                "face {f} has {} vertices: a face needs at least 3",
                indices.len()
            )));
        }
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(fail(format!(
                "face {f} refers to vertex {bad}, but there are {} vertices",
                positions.len()
            )));
        }
        for k in 1..indices.len() - 1 {
            corners_of_triangles.push([indices[0], indices[k], indices[k + 1]].map(|i| i as usize));
        }
    }
    let per_corner = |values: &[Vec3]| -> Vec<[Vec3; 3]> {
        corners_of_triangles
            .iter()
            .map(|c| c.map(|i| values[i]))
            .collect()
    };
    let mesh = MeshData {
        triangles: per_corner(&positions),
        // Mitsuba computes vertex normals for a mesh file that has none.
        normals: Some(match &normals {
            Some(n) => per_corner(n),
            None => angle_weighted_normals(&positions, &corners_of_triangles),
        }),
        uvs: uvs.as_ref().map(|uv| {
            per_corner(uv)
                .into_iter()
                .map(|c| c.map(|t| Vec2::new(t.x, t.y)))
                .collect()
        }),
        computed_normal_vertices: normals
            .is_none()
            .then(|| corners_of_triangles.iter().map(|&c| Some(c)).collect()),
    };
    Ok(mesh)
}

/// The vertices' values of the scalar properties `names` (2 or 3 of them; a 2D result has z
/// 0), `None` when the vertices lack any of them; an error for a list or a non-finite number.
fn vertex_vectors<const N: usize>(
    vertices: &[DefaultElement],
    names: [&str; N],
) -> Result<Option<Vec<Vec3>>, String> {
    let Some(first) = vertices.first() else {
        return Ok(None);
    };
    if !names.iter().all(|n| first.contains_key(*n)) {
        return Ok(None);
    }
    let mut out = Vec::with_capacity(vertices.len());
    for (i, vertex) in vertices.iter().enumerate() {
        let mut v = [0.0f32; 3];
        for (slot, name) in v.iter_mut().zip(names) {
            let value = vertex.get(name).and_then(Property::to_f32_lossy);
            match value {
                Some(x) if x.is_finite() => *slot = x,
                Some(x) => return Err(format!("vertex {i}: {name} is {x}, not a finite number")),
                None => return Err(format!("vertex {i}: {name} is missing or not a number")),
            }
        }
        out.push(Vec3::from_array(v));
    }
    Ok(Some(out))
}
