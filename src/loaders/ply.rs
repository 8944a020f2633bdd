//! Stanford PLY meshes (ASCII and binary, either byte order) through the `ply-rs-bw` crate, read
//! as Mitsuba 3's `ply` shape reads them: a `vertex` element with `x`, `y`, `z`, optional
//! vertex normals `nx`, `ny`, `nz` and texture coordinates (`u`/`v`, `s`/`t` or
//! `texture_u`/`texture_v`), and a `face` element whose `vertex_indices` (or `vertex_index`)
//! lists are triangles (larger polygons are fan-triangulated). Without vertex normals in the
//! file they are computed as Mitsuba computes them. Other elements and properties (colours,
//! per-face attributes) are not used.

use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};

use crate::error::Location;
use crate::scene::SceneError;
use crate::scene::mesh::MeshData;

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
    let raw = match binary::read(bytes) {
        Some(raw) => raw.map_err(&fail)?,
        None => generic(path, bytes)?,
    };
    let Raw {
        positions,
        normals,
        uvs,
        faces,
    } = raw;
    let mut corners_of_triangles: Vec<[usize; 3]> = Vec::with_capacity(faces.len());
    for (f, indices) in faces.iter().enumerate() {
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
    drop(faces);
    let mesh = MeshData::from_indexed(
        &positions,
        normals.as_deref(),
        uvs.as_deref(),
        corners_of_triangles,
    );
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

/// What a PLY file holds for a mesh: vertex positions, optional normals and texture
/// coordinates (z 0), and each face's vertex indices.
struct Raw {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec3>>,
    faces: Faces,
}

/// Every face's vertex indices, one after the other.
#[derive(Default)]
struct Faces {
    /// Where each face's indices end in `indices`.
    ends: Vec<usize>,
    indices: Vec<u32>,
}

impl Faces {
    fn push(&mut self, face: impl IntoIterator<Item = u32>) {
        self.indices.extend(face);
        self.ends.push(self.indices.len());
    }

    fn len(&self) -> usize {
        self.ends.len()
    }

    fn iter(&self) -> impl Iterator<Item = &[u32]> {
        let starts = std::iter::once(0).chain(self.ends.iter().copied());
        starts.zip(&self.ends).map(|(a, &b)| &self.indices[a..b])
    }
}

/// Any PLY file, through the `ply-rs-bw` crate (every vertex a map of its properties: slow and
/// large for big meshes, which [`binary::read`] reads instead).
fn generic(path: &Path, bytes: &[u8]) -> Result<Raw, SceneError> {
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
    let mut face_indices = Faces::default();
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
        face_indices.push(indices);
    }
    Ok(Raw {
        positions,
        normals,
        uvs,
        faces: face_indices,
    })
}

/// Binary PLY files whose vertices have scalar properties only, read straight from the bytes:
/// a 16M-triangle mesh in seconds and the memory of its arrays, where the generic reader takes
/// a map per vertex (44 s and 14 GB, BENCHMARKS.md). `None` for ASCII files and any other
/// layout, which [`generic`] reads.
mod binary {
    use glam::Vec3;

    use super::{Faces, Raw};

    #[derive(Clone, Copy, PartialEq)]
    enum Scalar {
        I8,
        U8,
        I16,
        U16,
        I32,
        U32,
        F32,
        F64,
    }

    impl Scalar {
        fn parse(name: &str) -> Option<Scalar> {
            Some(match name {
                "char" | "int8" => Scalar::I8,
                "uchar" | "uint8" => Scalar::U8,
                "short" | "int16" => Scalar::I16,
                "ushort" | "uint16" => Scalar::U16,
                "int" | "int32" => Scalar::I32,
                "uint" | "uint32" => Scalar::U32,
                "float" | "float32" => Scalar::F32,
                "double" | "float64" => Scalar::F64,
                _ => return None,
            })
        }

        fn size(self) -> usize {
            match self {
                Scalar::I8 | Scalar::U8 => 1,
                Scalar::I16 | Scalar::U16 => 2,
                Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
                Scalar::F64 => 8,
            }
        }

        /// The value at the start of `b` (at least `size` bytes).
        fn read(self, b: &[u8], little: bool) -> f64 {
            macro_rules! num {
                ($t:ty, $n:expr) => {{
                    let mut a = [0u8; $n];
                    a.copy_from_slice(&b[..$n]);
                    (if little {
                        <$t>::from_le_bytes(a)
                    } else {
                        <$t>::from_be_bytes(a)
                    }) as f64
                }};
            }
            match self {
                Scalar::I8 => b[0] as i8 as f64,
                Scalar::U8 => b[0] as f64,
                Scalar::I16 => num!(i16, 2),
                Scalar::U16 => num!(u16, 2),
                Scalar::I32 => num!(i32, 4),
                Scalar::U32 => num!(u32, 4),
                Scalar::F32 => num!(f32, 4),
                Scalar::F64 => num!(f64, 8),
            }
        }
    }

    enum Property {
        Scalar(String, Scalar),
        List(String, Scalar, Scalar),
    }

    struct Element {
        name: String,
        count: usize,
        properties: Vec<Property>,
    }

    impl Element {
        /// Bytes of one record of its scalar properties (all of a vertex's, which has no lists).
        fn record_size(&self) -> usize {
            self.properties
                .iter()
                .map(|p| match p {
                    Property::Scalar(_, s) => s.size(),
                    Property::List(..) => 0,
                })
                .sum()
        }
    }

    /// The header's elements, the byte order and where the data starts; `None` unless binary.
    fn header(bytes: &[u8]) -> Option<(Vec<Element>, bool, usize)> {
        let end = bytes.windows(11).position(|w| w == b"end_header\n")? + 11;
        let text = std::str::from_utf8(&bytes[..end]).ok()?;
        let mut little = None;
        let mut elements: Vec<Element> = Vec::new();
        for line in text.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            match words.as_slice() {
                ["format", "binary_little_endian", _] => little = Some(true),
                ["format", "binary_big_endian", _] => little = Some(false),
                ["format", ..] => return None,
                ["element", name, count] => elements.push(Element {
                    name: name.to_string(),
                    count: count.parse().ok()?,
                    properties: Vec::new(),
                }),
                ["property", "list", count, item, name] => {
                    elements.last_mut()?.properties.push(Property::List(
                        name.to_string(),
                        Scalar::parse(count)?,
                        Scalar::parse(item)?,
                    ))
                }
                ["property", kind, name] => elements
                    .last_mut()?
                    .properties
                    .push(Property::Scalar(name.to_string(), Scalar::parse(kind)?)),
                _ => {}
            }
        }
        Some((elements, little?, end))
    }

    /// The mesh, or `None` to leave the file to the generic reader; an error names what is
    /// wrong with the data.
    pub(super) fn read(bytes: &[u8]) -> Option<Result<Raw, String>> {
        let (elements, little, mut at) = header(bytes)?;
        // Elements other than the faces must have fixed-size records to be skipped or read.
        if elements.iter().any(|e| {
            e.name != "face" && e.properties.iter().any(|p| matches!(p, Property::List(..)))
        }) {
            return None;
        }
        let mut raw = Raw {
            positions: Vec::new(),
            normals: None,
            uvs: None,
            faces: Faces::default(),
        };
        let truncated = || Err("invalid PLY: the file ends before its data does".to_string());
        for element in &elements {
            match element.name.as_str() {
                "vertex" => {
                    let record = element.record_size();
                    let Some(data) =
                        bytes.get(at..at.saturating_add(record.saturating_mul(element.count)))
                    else {
                        return Some(truncated());
                    };
                    let columns = |names: &[&str]| -> Option<Vec<(usize, Scalar)>> {
                        names
                            .iter()
                            .map(|n| {
                                let mut offset = 0;
                                for p in &element.properties {
                                    if let Property::Scalar(name, s) = p {
                                        if name == n {
                                            return Some((offset, *s));
                                        }
                                        offset += s.size();
                                    }
                                }
                                None
                            })
                            .collect()
                    };
                    let read = |names: &[&str]| -> Result<Option<Vec<Vec3>>, String> {
                        let Some(cols) = columns(names) else {
                            return Ok(None);
                        };
                        let mut out = Vec::with_capacity(element.count);
                        for (i, r) in data.chunks_exact(record).enumerate() {
                            let mut v = [0.0f32; 3];
                            for (k, &(offset, s)) in cols.iter().enumerate() {
                                let x = s.read(&r[offset..], little) as f32;
                                if !x.is_finite() {
                                    return Err(format!(
                                        "vertex {i}: {} is {x}, not a finite number",
                                        names[k]
                                    ));
                                }
                                v[k] = x;
                            }
                            out.push(Vec3::from_array(v));
                        }
                        Ok(Some(out))
                    };
                    let result = (|| -> Result<(), String> {
                        raw.positions = read(&["x", "y", "z"])?
                            .ok_or("the PLY vertices have no x, y, z properties")?;
                        raw.normals = read(&["nx", "ny", "nz"])?;
                        for names in [["u", "v"], ["s", "t"], ["texture_u", "texture_v"]] {
                            if let Some(uv) = read(&names)? {
                                raw.uvs = Some(uv);
                                break;
                            }
                        }
                        Ok(())
                    })();
                    if let Err(e) = result {
                        return Some(Err(e));
                    }
                    at = at.saturating_add(record.saturating_mul(element.count));
                }
                "face" => {
                    for f in 0..element.count {
                        let mut kept = false;
                        for p in &element.properties {
                            match p {
                                Property::Scalar(_, s) => at += s.size(),
                                Property::List(name, count, item) => {
                                    let Some(b) = bytes.get(at..at + count.size()) else {
                                        return Some(truncated());
                                    };
                                    let n = count.read(b, little);
                                    if n.is_nan() || n < 0.0 {
                                        return Some(Err(format!("face {f}: a list of {n} items")));
                                    }
                                    at += count.size();
                                    let len = n as usize * item.size();
                                    let Some(items) = bytes.get(at..at + len) else {
                                        return Some(truncated());
                                    };
                                    let indices = (name == "vertex_indices"
                                        || name == "vertex_index")
                                        && !kept;
                                    if indices {
                                        let mut face = Vec::with_capacity(n as usize);
                                        for i in items.chunks_exact(item.size()) {
                                            let v = item.read(i, little);
                                            if !(v >= 0.0
                                                && v <= u32::MAX as f64
                                                && v.fract() == 0.0)
                                            {
                                                return Some(Err(format!(
                                                    "face {f}: vertex_indices is not a list of \
                                                     non-negative integers"
                                                )));
                                            }
                                            face.push(v as u32);
                                        }
                                        raw.faces.push(face);
                                        kept = true;
                                    }
                                    at += len;
                                }
                            }
                        }
                        if !kept {
                            return Some(Err("the PLY faces have no vertex_indices list".into()));
                        }
                    }
                }
                _ => {
                    let record = element.record_size();
                    at = at.saturating_add(record.saturating_mul(element.count));
                }
            }
        }
        if raw.positions.is_empty() || raw.faces.len() == 0 {
            return Some(Err(format!(
                "the PLY file has {} vertices and {} faces: a mesh needs both (elements \
                 \"vertex\" and \"face\")",
                raw.positions.len(),
                raw.faces.len()
            )));
        }
        Some(Ok(raw))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A binary PLY of two quads with extra properties the mesh does not use (a colour byte per
    /// vertex, a scalar before the face list, a second element), in either byte order.
    fn two_quads(little: bool) -> Vec<u8> {
        let format = if little {
            "binary_little_endian"
        } else {
            "binary_big_endian"
        };
        let mut bytes = format!(
            "ply\nformat {format} 1.0\ncomment extras\nelement vertex 6\nproperty double x\n\
             property float y\nproperty float z\nproperty uchar red\nproperty float nx\n\
             property float ny\nproperty float nz\nproperty float u\nproperty float v\n\
             element face 2\nproperty short flags\nproperty list uchar uint vertex_indices\n\
             element camera 1\nproperty float view\nend_header\n"
        )
        .into_bytes();
        let f32b = |x: f32| {
            if little {
                x.to_le_bytes()
            } else {
                x.to_be_bytes()
            }
        };
        for i in 0..6 {
            let (x, y) = ((i % 3) as f64, (i / 3) as f32);
            bytes.extend(if little {
                x.to_le_bytes()
            } else {
                x.to_be_bytes()
            });
            bytes.extend(f32b(y));
            bytes.extend(f32b(0.5));
            bytes.push(200);
            for n in [0.0, 0.0, 1.0, x as f32 / 2.0, y] {
                bytes.extend(f32b(n));
            }
        }
        for face in [[0u32, 1, 4, 3], [1, 2, 5, 4]] {
            bytes.extend(if little {
                7i16.to_le_bytes()
            } else {
                7i16.to_be_bytes()
            });
            bytes.push(4);
            for i in face {
                bytes.extend(if little {
                    i.to_le_bytes()
                } else {
                    i.to_be_bytes()
                });
            }
        }
        bytes.extend(f32b(1.0));
        bytes
    }

    /// The direct binary reader reads what the generic reader reads, in both byte orders, past
    /// properties and elements it skips. Would catch a record size or an offset off by a skipped
    /// property, a byte order mixed up, or faces lost.
    #[test]
    fn the_binary_reader_agrees_with_the_generic_one() {
        for little in [true, false] {
            let bytes = two_quads(little);
            let fast = binary::read(&bytes)
                .expect("a binary layout it reads")
                .expect("valid");
            let slow = generic(Path::new("quads.ply"), &bytes).expect("valid");
            assert_eq!(fast.positions, slow.positions);
            assert_eq!(fast.normals, slow.normals);
            assert_eq!(fast.uvs, slow.uvs);
            let faces = |f: &Faces| f.iter().map(<[u32]>::to_vec).collect::<Vec<_>>();
            assert_eq!(faces(&fast.faces), faces(&slow.faces));
            assert_eq!(faces(&fast.faces), vec![vec![0, 1, 4, 3], vec![1, 2, 5, 4]]);
            assert!(fast.normals.is_some() && fast.uvs.is_some());
        }
        let ascii = b"ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
        assert!(
            binary::read(ascii).is_none(),
            "ASCII goes to the generic reader"
        );
    }
}
