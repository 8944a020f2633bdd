//! Mitsuba's `serialized` meshes, versions 3 and 4: the zlib-compressed indexed triangle meshes
//! of Mitsuba 0.5/0.6, which Mitsuba 3 still reads (its `serialized` shape plugin,
//! src/shapes/serialized.cpp, whose documentation and reader are the source of every format fact
//! here). Mitsuba 3's own version 5 files are not read.
//!
//! A file is one or more shapes back to back, then a table of where each starts:
//!
//! - per shape, uncompressed: `u16` magic 0x041C, `u16` version (3 or 4); then one zlib stream
//!   holding a `u32` flag word, in version 4 the shape's name (NUL-terminated), `u64` vertex
//!   count V, `u64` triangle count F, V positions (3 reals), the optional V normals (3 reals),
//!   V texture coordinates (2 reals) and V colours (3 reals) that the flags announce, and 3F
//!   `u32` vertex indices; reals are `f64` under the double-precision flag, else `f32`;
//! - at the end: each shape's byte offset (`u64` in version 4, `u32` in version 3), then the
//!   `u32` number of shapes.
//!
//! Everything is little-endian. As in Mitsuba, the version of the file's first header decides
//! how the table and every shape are read, and shape 0 is read from the start of the file
//! without looking at the table.

use std::path::Path;

use flate2::{Decompress, FlushDecompress, Status};
use glam::Vec3;

use crate::scene::SceneError;
use crate::scene::mesh::MeshData;

const MAGIC: u16 = 0x041C;
const VERSION_3: u16 = 3;
const VERSION_4: u16 = 4;

// Mitsuba's TriMeshFlags. Its tangent flag (0x0004) is documented as unused and Mitsuba 3 reads
// no data for it, so neither does this reader.
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
// Mitsuba reads doubles exactly when this bit is set; the single-precision bit (0x1000) decides
// nothing.
const DOUBLE_PRECISION: u32 = 0x2000;

/// One shape of a `serialized` file.
#[derive(Debug, Clone, PartialEq)]
pub struct Serialized {
    /// The shape in the file's coordinates. `normals` is always set: the file's vertex normals,
    /// or, when it has none, Mitsuba's computed ones (with `computed_normal_vertices` set), as
    /// [`crate::loaders::ply::load`] gives them.
    pub mesh: MeshData,
    /// The shape's `FaceNormals` flag (0x0010): it was written to be shaded flat. Mitsuba 0.5/0.6
    /// honoured it; Mitsuba 3 ignores it in version 3/4 files and shades flat only for the
    /// `face_normals` property.
    pub face_normals: bool,
    /// The shape's name (version 4; `None` in version 3, which stores none). Mitsuba 3 names the
    /// shape by it.
    pub name: Option<String>,
}

/// Shape `shape_index` (0 is the first) of the `serialized` file `path`.
pub fn load(path: &Path, shape_index: u32) -> Result<Serialized, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    parse(path, &bytes, shape_index)
}

/// Shape `shape_index` of the `serialized` file in `bytes`; `path` names the file in errors.
pub fn parse(path: &Path, bytes: &[u8], shape_index: u32) -> Result<Serialized, SceneError> {
    read_shape(bytes, shape_index).map_err(|message| SceneError::File {
        file: path.to_path_buf(),
        message: format!("serialized mesh: {message}"),
    })
}

fn read_shape(bytes: &[u8], shape_index: u32) -> Result<Serialized, String> {
    let (magic, version) =
        header(bytes, 0).ok_or_else(|| format!("{} bytes, too short for a header", bytes.len()))?;
    if magic != MAGIC {
        return Err(format!(
            "the file starts with {magic:#06x}, not the serialized format's {MAGIC:#06x}"
        ));
    }
    if version != VERSION_3 && version != VERSION_4 {
        return Err(format!(
            "format version {version}: only versions 3 and 4 are read (Mitsuba 0.5/0.6 files)"
        ));
    }
    let start = if shape_index == 0 {
        0
    } else {
        let start = shape_offset(bytes, version, shape_index)?;
        match header(bytes, start) {
            Some((MAGIC, _)) => start,
            _ => {
                return Err(format!(
                    "the file's table puts shape {shape_index} at byte {start}, but no shape \
                     header is there"
                ));
            }
        }
    };
    let compressed = bytes.get(start + 4..).unwrap_or_default();
    let (data, ended) = inflate(compressed).map_err(|e| {
        format!(
            "shape {shape_index}: the compressed data from byte {} is not a valid zlib stream \
             ({e})",
            start + 4
        )
    })?;
    decode(&data, version).map_err(|e| {
        // A stream cut short is the likelier story behind data that ends too soon.
        let cut = if ended {
            ""
        } else {
            " (its zlib stream is cut short: the file is truncated)"
        };
        format!("shape {shape_index}: {e}{cut}")
    })
}

/// The magic and version at byte `at`.
fn header(bytes: &[u8], at: usize) -> Option<(u16, u16)> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some((
        u16::from_le_bytes([b[0], b[1]]),
        u16::from_le_bytes([b[2], b[3]]),
    ))
}

/// Where shape `index` (> 0) starts, from the table at the end of the file.
fn shape_offset(bytes: &[u8], version: u16, index: u32) -> Result<usize, String> {
    let len = bytes.len();
    let count = len
        .checked_sub(4)
        .and_then(|at| le_u32(bytes, at))
        .ok_or("the file is too short for its table of shapes")?;
    if index >= count {
        return Err(format!(
            "shape_index {index} is out of range: the file has {count} shape{}",
            if count == 1 { "" } else { "s" }
        ));
    }
    let from_end = (count - index) as usize;
    let offset = if version == VERSION_4 {
        from_end
            .checked_mul(8)
            .and_then(|n| n.checked_add(4))
            .and_then(|n| len.checked_sub(n))
            .and_then(|at| le_u64(bytes, at))
    } else {
        from_end
            .checked_add(1)
            .and_then(|n| n.checked_mul(4))
            .and_then(|n| len.checked_sub(n))
            .and_then(|at| le_u32(bytes, at).map(u64::from))
    };
    let Some(offset) = offset else {
        return Err(format!(
            "the file's table of {count} shapes would start before the file does (truncated or \
             not a serialized file)"
        ));
    };
    usize::try_from(offset)
        .ok()
        .filter(|&o| o < len)
        .ok_or_else(|| {
            format!("the file's table puts shape {index} at byte {offset}, past its end ({len})")
        })
}

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

fn le_u64(bytes: &[u8], at: usize) -> Option<u64> {
    let b = bytes.get(at..at.checked_add(8)?)?;
    let mut a = [0u8; 8];
    a.copy_from_slice(b);
    Some(u64::from_le_bytes(a))
}

/// The zlib stream at the start of `input` (the next shape's header follows it), and whether
/// it ended: a stream cut short gives what it holds, as Mitsuba reads only what it needs.
fn inflate(input: &[u8]) -> Result<(Vec<u8>, bool), String> {
    let mut z = Decompress::new(true);
    let mut out = Vec::with_capacity(input.len().saturating_mul(3).min(1 << 26));
    loop {
        if out.len() == out.capacity() {
            out.reserve(out.capacity().max(1 << 16));
        }
        let (before_in, before_out) = (z.total_in(), z.total_out());
        let rest = usize::try_from(before_in)
            .ok()
            .and_then(|at| input.get(at..))
            .unwrap_or_default();
        let status = z
            .decompress_vec(rest, &mut out, FlushDecompress::None)
            .map_err(|e| e.to_string())?;
        if status == Status::StreamEnd {
            return Ok((out, true));
        }
        if z.total_in() == before_in && z.total_out() == before_out {
            // With room to write, no progress means the input is spent.
            return Ok((out, false));
        }
    }
}

/// The decompressed data of one shape.
struct Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// The next `n` bytes, which hold `what`.
    fn take(&mut self, n: Option<usize>, what: &str) -> Result<&'a [u8], String> {
        let end = n.and_then(|n| self.at.checked_add(n));
        let bytes = end
            .and_then(|end| self.data.get(self.at..end))
            .ok_or_else(|| {
                format!(
                    "the data ends ({} bytes decompressed) before the end of its {what}",
                    self.data.len()
                )
            })?;
        self.at += bytes.len();
        Ok(bytes)
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b = self.take(Some(4), what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let b = self.take(Some(8), what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }

    /// The NUL-terminated string next.
    fn c_string(&mut self, what: &str) -> Result<String, String> {
        let rest = self.data.get(self.at..).unwrap_or_default();
        let len = rest
            .iter()
            .position(|&b| b == 0)
            .ok_or_else(|| format!("the data ends before the end of its {what}"))?;
        let text = String::from_utf8_lossy(&rest[..len]).into_owned();
        self.at += len + 1;
        Ok(text)
    }

    /// `count` vectors of `N` reals (the rest of a `Vec3` zero), which must be finite.
    fn vectors<const N: usize>(
        &mut self,
        count: usize,
        double: bool,
        what: &str,
    ) -> Result<Vec<Vec3>, String> {
        let size = if double { 8 } else { 4 };
        let bytes = self.take(count.checked_mul(N * size), what)?;
        let mut out = Vec::with_capacity(count);
        for (i, record) in bytes.chunks_exact(N * size).enumerate() {
            let mut v = [0.0f32; 3];
            for (slot, b) in v.iter_mut().zip(record.chunks_exact(size)) {
                // As Mitsuba does, doubles are rounded to single precision.
                *slot = match *b {
                    [a, b, c, d] => f32::from_le_bytes([a, b, c, d]),
                    [a, b, c, d, e, f, g, h] => f64::from_le_bytes([a, b, c, d, e, f, g, h]) as f32,
                    // Chunks are 4 or 8 bytes; NaN would be reported below.
                    _ => f32::NAN,
                };
            }
            if v.iter().any(|x| !x.is_finite()) {
                return Err(format!(
                    "vertex {i}: its {what} are {v:?}, not all finite numbers"
                ));
            }
            out.push(Vec3::from_array(v));
        }
        Ok(out)
    }

    /// `count` skipped values of `size` bytes.
    fn skip(&mut self, count: usize, size: usize, what: &str) -> Result<(), String> {
        self.take(count.checked_mul(size), what).map(|_| ())
    }
}

/// The shape in its decompressed `data`.
fn decode(data: &[u8], version: u16) -> Result<Serialized, String> {
    let mut r = Reader { data, at: 0 };
    let flags = r.u32("flags")?;
    let name = if version == VERSION_4 {
        Some(r.c_string("name")?)
    } else {
        None
    };
    let counts = |n: u64, what: &str| {
        usize::try_from(n).map_err(|_| format!("{n} {what} is more than this machine can address"))
    };
    let vertex_count = counts(r.u64("vertex count")?, "vertices")?;
    let face_count = counts(r.u64("triangle count")?, "triangles")?;
    let double = flags & DOUBLE_PRECISION != 0;
    let real = if double { 8 } else { 4 };

    let positions = r.vectors::<3>(vertex_count, double, "positions")?;
    let normals = if flags & HAS_NORMALS != 0 {
        Some(r.vectors::<3>(vertex_count, double, "normals")?)
    } else {
        None
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        Some(r.vectors::<2>(vertex_count, double, "texture coordinates")?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        r.skip(vertex_count, 3 * real, "vertex colours")?;
    }
    let index_bytes = r.take(face_count.checked_mul(12), "triangles")?;
    let mut faces: Vec<[usize; 3]> = Vec::with_capacity(face_count);
    for (f, b) in index_bytes.chunks_exact(12).enumerate() {
        let mut face = [0usize; 3];
        for (slot, i) in face.iter_mut().zip(b.chunks_exact(4)) {
            let i = u32::from_le_bytes([i[0], i[1], i[2], i[3]]);
            if i as usize >= vertex_count {
                return Err(format!(
                    "triangle {f} refers to vertex {i}, but there are {vertex_count} vertices"
                ));
            }
            *slot = i as usize;
        }
        faces.push(face);
    }
    if faces.is_empty() {
        return Err(format!(
            "{vertex_count} vertices and no triangles: a mesh needs triangles"
        ));
    }

    let mesh = MeshData::from_indexed(&positions, normals.as_deref(), uvs.as_deref(), faces);
    Ok(Serialized {
        mesh,
        face_normals: flags & FACE_NORMALS != 0,
        name,
    })
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use glam::Vec2;

    use super::*;
    use crate::scene::mesh::angle_weighted_normals;

    /// A shape for the test writer; reals are written as `f64` or `f32` by `double`.
    #[derive(Clone, Default)]
    struct Shape {
        name: &'static str,
        positions: Vec<[f64; 3]>,
        normals: Option<Vec<[f64; 3]>>,
        uvs: Option<Vec<[f64; 2]>>,
        colors: bool,
        faces: Vec<[u32; 3]>,
        double: bool,
        face_normals: bool,
    }

    /// The shape's uncompressed data.
    fn body(version: u16, s: &Shape) -> Vec<u8> {
        let mut flags = if s.double { 0x2000 } else { 0x1000 };
        for (set, bit) in [
            (s.normals.is_some(), 0x1),
            (s.uvs.is_some(), 0x2),
            (s.colors, 0x8),
            (s.face_normals, 0x10),
        ] {
            if set {
                flags |= bit;
            }
        }
        let mut out = Vec::new();
        out.extend(u32::to_le_bytes(flags));
        if version == 4 {
            out.extend(s.name.as_bytes());
            out.push(0);
        }
        out.extend((s.positions.len() as u64).to_le_bytes());
        out.extend((s.faces.len() as u64).to_le_bytes());
        let mut reals = |values: &mut dyn Iterator<Item = f64>| {
            for x in values {
                if s.double {
                    out.extend(x.to_le_bytes());
                } else {
                    out.extend((x as f32).to_le_bytes());
                }
            }
        };
        reals(&mut s.positions.iter().flatten().copied());
        if let Some(n) = &s.normals {
            reals(&mut n.iter().flatten().copied());
        }
        if let Some(uv) = &s.uvs {
            reals(&mut uv.iter().flatten().copied());
        }
        if s.colors {
            reals(&mut (0..s.positions.len() * 3).map(|i| i as f64 * 0.1));
        }
        for i in s.faces.iter().flatten() {
            out.extend(i.to_le_bytes());
        }
        out
    }

    /// A file of shapes given by their uncompressed data, with its table of offsets.
    fn file_of(version: u16, bodies: &[Vec<u8>]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for b in bodies {
            offsets.push(out.len() as u64);
            out.extend(MAGIC.to_le_bytes());
            out.extend(version.to_le_bytes());
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
            z.write_all(b).expect("in memory");
            out.extend(z.finish().expect("in memory"));
        }
        for o in offsets {
            if version == 4 {
                out.extend(o.to_le_bytes());
            } else {
                out.extend((o as u32).to_le_bytes());
            }
        }
        out.extend((bodies.len() as u32).to_le_bytes());
        out
    }

    fn file(version: u16, shapes: &[Shape]) -> Vec<u8> {
        let bodies: Vec<Vec<u8>> = shapes.iter().map(|s| body(version, s)).collect();
        file_of(version, &bodies)
    }

    /// A square of two triangles with normals, texture coordinates and colours, in single
    /// precision.
    fn square() -> Shape {
        Shape {
            name: "square",
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
            uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
            colors: true,
            faces: vec![[0, 1, 2], [0, 2, 3]],
            ..Shape::default()
        }
    }

    /// A tetrahedron without normals in double precision, one coordinate not a float.
    fn tetra() -> Shape {
        Shape {
            name: "tétra",
            positions: vec![
                [0.1, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
            double: true,
            face_normals: true,
            colors: true,
            ..Shape::default()
        }
    }

    fn v3(p: [f64; 3]) -> Vec3 {
        Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
    }

    fn parse_ok(bytes: &[u8], index: u32) -> Serialized {
        match parse(Path::new("t.serialized"), bytes, index) {
            Ok(s) => s,
            Err(e) => panic!("shape {index}: {e}"),
        }
    }

    fn parse_err(bytes: &[u8], index: u32) -> String {
        match parse(Path::new("t.serialized"), bytes, index) {
            Ok(_) => panic!("shape {index} read, an error expected"),
            Err(e) => e.to_string(),
        }
    }

    /// Both shapes of a version 4 file, each exactly: the first with its normals and texture
    /// coordinates (colours read past), the second, in double precision, with computed normals.
    /// Would catch a field read out of order, colours not skipped, the u64 table misread, or
    /// doubles read as floats.
    #[test]
    fn reads_both_shapes_of_a_version_4_file() {
        let bytes = file(4, &[square(), tetra()]);

        let first = parse_ok(&bytes, 0);
        assert_eq!(first.name.as_deref(), Some("square"));
        assert!(!first.face_normals);
        let s = square();
        let p = s.positions.iter().map(|&p| v3(p)).collect::<Vec<_>>();
        let uv = |i: usize| {
            Vec2::new(
                s.uvs.as_ref().expect("uvs")[i][0] as f32,
                s.uvs.as_ref().expect("uvs")[i][1] as f32,
            )
        };
        assert_eq!(
            first.mesh,
            MeshData {
                triangles: vec![[p[0], p[1], p[2]], [p[0], p[2], p[3]]],
                normals: Some(vec![[Vec3::Z; 3]; 2]),
                uvs: Some(vec![[uv(0), uv(1), uv(2)], [uv(0), uv(2), uv(3)]]),
                computed_normal_vertices: None,
            }
        );

        let second = parse_ok(&bytes, 1);
        assert_eq!(second.name.as_deref(), Some("tétra"));
        assert!(second.face_normals);
        let t = tetra();
        let p: Vec<Vec3> = t.positions.iter().map(|&p| v3(p)).collect();
        assert_eq!(p[0].x, 0.1f32, "a double rounded to the nearest float");
        let faces: Vec<[usize; 3]> = t.faces.iter().map(|f| f.map(|i| i as usize)).collect();
        assert_eq!(
            second.mesh,
            MeshData {
                triangles: faces.iter().map(|f| f.map(|i| p[i])).collect(),
                normals: Some(angle_weighted_normals(&p, &faces)),
                uvs: None,
                computed_normal_vertices: Some(faces.iter().map(|&f| Some(f)).collect()),
            }
        );
    }

    /// Version 3 files have no names and a u32 table. Would catch the table read with u64
    /// entries or a name expected.
    #[test]
    fn reads_a_version_3_file() {
        let bytes = file(3, &[tetra(), square(), tetra()]);
        let square = parse_ok(&bytes, 1);
        assert_eq!(square.name, None);
        assert_eq!(square.mesh.triangles[1][2], Vec3::Y);
        assert!(square.mesh.uvs.is_some());
        let last = parse_ok(&bytes, 2);
        assert_eq!(last, parse_ok(&bytes, 0));
        assert_eq!(last.mesh.triangles.len(), 4);
    }

    /// Every error says what is wrong; none panics.
    #[test]
    fn errors_name_what_is_wrong() {
        let good = file(4, &[square(), tetra()]);
        let cases: Vec<(Vec<u8>, u32, &str)> = vec![
            (b"PLY\n".to_vec(), 0, "not the serialized format's 0x041c"),
            (vec![0x1C], 0, "too short for a header"),
            (
                {
                    let mut b = good.clone();
                    b[2] = 5;
                    b
                },
                0,
                "format version 5",
            ),
            (
                good.clone(),
                2,
                "shape_index 2 is out of range: the file has 2 shapes",
            ),
            (good[..good.len() / 3].to_vec(), 0, "the file is truncated"),
            (
                {
                    let mut b = good.clone();
                    b[4..20].fill(0xAB);
                    b
                },
                0,
                "not a valid zlib stream",
            ),
            (
                {
                    let mut s = square();
                    s.faces[1][2] = 4;
                    file(4, &[s])
                },
                0,
                "triangle 1 refers to vertex 4, but there are 4 vertices",
            ),
            (
                {
                    let mut b = good.clone();
                    let n = b.len();
                    b[n - 12..n - 4].copy_from_slice(&7u64.to_le_bytes());
                    b
                },
                1,
                "puts shape 1 at byte 7, but no shape header is there",
            ),
            (
                {
                    let mut b = body(4, &square());
                    // The vertex count, after the flags and the name "square\0".
                    b[11..19].copy_from_slice(&u64::MAX.to_le_bytes());
                    file_of(4, &[b])
                },
                0,
                "before the end of its positions",
            ),
        ];
        for (bytes, index, expected) in cases {
            let message = parse_err(&bytes, index);
            assert!(
                message.starts_with("t.serialized: serialized mesh: ")
                    && message.contains(expected),
                "{message:?} should say {expected:?}"
            );
        }
        let missing = load(Path::new("/nonexistent/t.serialized"), 0);
        assert!(matches!(missing, Err(SceneError::Io { .. })));
    }

    /// Cut, flipped or overwritten bytes, in the file and in the data before compression, give
    /// a mesh or an error, never a panic (nor an allocation sized by a corrupt count).
    #[test]
    fn corrupted_files_never_panic() {
        let shapes = [square(), tetra()];
        let good = file(4, &shapes);
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut random = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for len in 0..good.len() {
            for index in 0..3 {
                let _ = parse(Path::new("t"), &good[..len], index);
            }
        }
        for _ in 0..3000 {
            let mut bytes = good.clone();
            for _ in 0..1 + random() % 3 {
                let at = (random() % bytes.len() as u64) as usize;
                bytes[at] = random() as u8;
            }
            for index in 0..3 {
                let _ = parse(Path::new("t"), &bytes, index);
            }
        }
        let bodies: Vec<Vec<u8>> = shapes.iter().map(|s| body(4, s)).collect();
        for _ in 0..3000 {
            let mut bodies = bodies.clone();
            let b = &mut bodies[(random() % 2) as usize];
            match random() % 3 {
                0 => {
                    let at = (random() % b.len() as u64) as usize;
                    b[at] = random() as u8;
                }
                1 => {
                    let at = (random() % b.len() as u64) as usize;
                    b.truncate(at);
                }
                _ => {
                    let at = (random() % (b.len() as u64 - 8)) as usize;
                    b[at..at + 8].copy_from_slice(&random().to_le_bytes());
                }
            }
            let bytes = file_of(if random() % 2 == 0 { 3 } else { 4 }, &bodies);
            for index in 0..3 {
                let _ = parse(Path::new("t"), &bytes, index);
            }
        }
    }

    /// What Mitsuba 3.9.1 itself reads from two files (tests/data/serialized, made and read in
    /// Mitsuba by make_fixture.py there): per triangle corner, the same positions, normals
    /// (the file's, or those Mitsuba computes) and texture coordinates, to 1e-6. Would catch any
    /// misread field, and computed normals that are not Mitsuba's.
    #[test]
    fn agrees_with_mitsuba() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/serialized");
        let text = std::fs::read_to_string(dir.join("mitsuba_3.9.1.txt")).expect("the fixture");
        let mut shapes = Vec::new();
        let mut current: Option<std::collections::HashMap<String, String>> = None;
        for line in text.lines().filter(|l| !l.starts_with('#')) {
            let (key, value) = line.split_once(' ').unwrap_or((line, ""));
            if key == "file" {
                shapes.extend(current.take());
                current = Some(Default::default());
            }
            if let Some(fields) = current.as_mut() {
                fields.insert(key.to_string(), value.to_string());
            }
        }
        shapes.extend(current);
        assert_eq!(shapes.len(), 4, "two shapes in each of two files");
        for fields in shapes {
            let numbers = |key: &str| -> Vec<f32> {
                fields[key]
                    .split_whitespace()
                    .map(|x| x.parse().expect("a number"))
                    .collect()
            };
            let index: u32 = fields["shape"].parse().expect("an index");
            let file = &fields["file"];
            let shape = load(&dir.join(file), index).expect("readable");
            let at = format!("{file} shape {index}");
            if file.contains("v4") {
                assert_eq!(shape.name.as_deref(), Some(fields["name"].as_str()), "{at}");
            } else {
                assert_eq!(shape.name, None, "{at}");
            }
            let faces: Vec<usize> = numbers("faces").iter().map(|&i| i as usize).collect();
            let (positions, normals, uvs) = (
                numbers("vertex_positions"),
                numbers("vertex_normals"),
                numbers("vertex_texcoords"),
            );
            let mesh = &shape.mesh;
            assert_eq!(mesh.triangles.len() * 3, faces.len(), "{at}");
            assert!(!normals.is_empty(), "{at}: Mitsuba gives normals");
            assert_eq!(mesh.uvs.is_some(), !uvs.is_empty(), "{at}");
            let near = |a: &[f32], b: &[f32], what: &str| {
                let close = a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-6);
                assert!(close, "{at}: {what} {a:?}, Mitsuba's {b:?}");
            };
            let mesh_normals = mesh.normals.as_ref().expect("normals");
            for (t, corners) in faces.chunks_exact(3).enumerate() {
                for (k, &v) in corners.iter().enumerate() {
                    let slice3 = |values: &[f32]| values[3 * v..3 * v + 3].to_vec();
                    near(
                        &mesh.triangles[t][k].to_array(),
                        &slice3(&positions),
                        "position",
                    );
                    near(&mesh_normals[t][k].to_array(), &slice3(&normals), "normal");
                    if let Some(mesh_uvs) = &mesh.uvs {
                        near(&mesh_uvs[t][k].to_array(), &uvs[2 * v..2 * v + 2], "uv");
                    }
                }
            }
        }
    }
}
