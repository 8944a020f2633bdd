//! Built-in shapes as object-space triangles, counter-clockwise seen from the front (normal)
//! side, with Mitsuba's texture coordinates: `rectangle` ([-1,1]^2 at z=0, normal +z) and `cube`
//! ([-1,1]^3, outward); and what mesh files give per triangle corner.

use glam::{Vec2, Vec3};

/// A mesh file's triangles in its own coordinates, with what else it has per corner.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    pub triangles: Vec<[Vec3; 3]>,
    /// Vertex normals at each triangle's corners, when the file gives one for every vertex.
    pub normals: Option<Vec<[Vec3; 3]>>,
    /// Texture coordinates at each triangle's corners, when the file gives them.
    pub uvs: Option<Vec<[Vec2; 3]>>,
    /// Per triangle, the vertex of each corner where `normals` were computed from the faces
    /// (the file gave none), else `None`: placing the mesh computes those normals again from the
    /// placed positions, as Mitsuba does (under a non-uniform scale, normals averaged over the
    /// faces in the file's space and carried into the world are not the world faces' average).
    pub computed_normal_vertices: Option<Vec<Option<[usize; 3]>>>,
}

impl MeshData {
    /// An indexed mesh file's triangles (`faces` index the vertex arrays) with its values per
    /// corner; a 2D `uvs` has its z ignored. Without normals in the file, Mitsuba's computed
    /// ones, with `computed_normal_vertices` set so that placing the mesh computes them again.
    pub fn from_indexed(
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        uvs: Option<&[Vec3]>,
        faces: Vec<[usize; 3]>,
    ) -> Self {
        let per_corner = |values: &[Vec3]| -> Vec<[Vec3; 3]> {
            faces.iter().map(|c| c.map(|i| values[i])).collect()
        };
        MeshData {
            triangles: per_corner(positions),
            normals: Some(match normals {
                Some(n) => per_corner(n),
                None => angle_weighted_normals(positions, &faces),
            }),
            uvs: uvs.map(|uv| {
                faces
                    .iter()
                    .map(|c| c.map(|i| Vec2::new(uv[i].x, uv[i].y)))
                    .collect()
            }),
            computed_normal_vertices: normals
                .is_none()
                .then(|| faces.iter().map(|&c| Some(c)).collect()),
        }
    }
}

/// Vertex normals as Mitsuba 3 computes them for a mesh file that has none (Thürmer and
/// Wüthrich, "Computing Vertex Normals from Polygonal Facets", JGT 1998): each face adds its unit
/// normal to its corners' vertices, weighted by the corner's angle. `faces` index `positions`;
/// the result is per triangle corner, zero at a vertex no proper face touches (such a triangle
/// then shades flat).
pub fn angle_weighted_normals(positions: &[Vec3], faces: &[[usize; 3]]) -> Vec<[Vec3; 3]> {
    let mut sums = vec![glam::DVec3::ZERO; positions.len()];
    for face in faces {
        let p = face.map(|i| positions[i].as_dvec3());
        let Some(n) = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() else {
            continue;
        };
        for k in 0..3 {
            let (to_next, to_prev) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let angle = to_next.angle_between(to_prev);
            if angle.is_finite() {
                sums[face[k]] += n * angle;
            }
        }
    }
    let unit: Vec<Vec3> = sums
        .iter()
        .map(|s| s.try_normalize().unwrap_or_default().as_vec3())
        .collect();
    faces.iter().map(|face| face.map(|i| unit[i])).collect()
}

/// Mitsuba's `rectangle`: [-1,1]^2 at z=0 facing +z, uv = (x, y) / 2 + 1/2.
pub fn rectangle_mesh() -> MeshData {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let p = corners.map(|(x, y)| Vec3::new(x, y, 0.0));
    let uv = corners.map(|(x, y)| Vec2::new(0.5 * x + 0.5, 0.5 * y + 0.5));
    MeshData {
        triangles: vec![[p[0], p[1], p[2]], [p[0], p[2], p[3]]],
        normals: None,
        uvs: Some(vec![[uv[0], uv[1], uv[2]], [uv[0], uv[2], uv[3]]]),
        computed_normal_vertices: None,
    }
}

/// Mitsuba 3's `cube` (`[-1,1]^3`, outward), triangle for triangle: each face maps onto `[0,1]^2`
/// in uv space the way Mitsuba's does (its faces' corner tables, src/shapes/cube.cpp).
pub fn cube_mesh() -> MeshData {
    // Corner c is at (+-1, +-1, +-1), bit k of c giving the sign of axis k; each face lists its
    // four corners, which take the uvs below in order.
    const FACES: [[usize; 4]; 6] = [
        [1, 5, 4, 0],
        [3, 2, 6, 7],
        [1, 3, 7, 5],
        [5, 7, 6, 4],
        [4, 6, 2, 0],
        [3, 1, 0, 2],
    ];
    const FACE_UV: [(f32, f32); 4] = [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)];
    let corner = |c: usize| {
        let sign = |bit: usize| if c & bit != 0 { 1.0 } else { -1.0 };
        Vec3::new(sign(1), sign(2), sign(4))
    };
    let uv = FACE_UV.map(|(u, v)| Vec2::new(u, v));
    let mut mesh = MeshData {
        uvs: Some(Vec::new()),
        ..MeshData::default()
    };
    for face in FACES {
        let p = face.map(corner);
        for [i, j, k] in [[0, 1, 2], [3, 0, 2]] {
            mesh.triangles.push([p[i], p[j], p[k]]);
            if let Some(uvs) = mesh.uvs.as_mut() {
                uvs.push([uv[i], uv[j], uv[k]]);
            }
        }
    }
    mesh
}

pub fn rectangle() -> Vec<[Vec3; 3]> {
    rectangle_mesh().triangles
}

pub fn cube() -> Vec<[Vec3; 3]> {
    cube_mesh().triangles
}

/// Segments around the tube that stands for Mitsuba's analytic `cylinder`.
pub const CYLINDER_SEGMENTS: usize = 256;

/// Mitsuba's `cylinder` (an open tube of radius 1 around the z axis from z = 0 to z = 1, normals
/// outward) as [`CYLINDER_SEGMENTS`] quads whose radius is pushed out so that the tube's area is
/// exactly 2 pi: an emitting tube keeps its power. Vertex normals are the exact radial ones, so
/// it shades as the round tube; its outline moves by at most 0.01% of the radius. Texture
/// coordinates are Mitsuba's (phi / 2 pi, z).
pub fn cylinder_mesh() -> MeshData {
    let n = CYLINDER_SEGMENTS;
    let step = 2.0 * std::f64::consts::PI / n as f64;
    // n quads of width 2 r sin(step / 2) and height 1 sum to 2 pi.
    let r = std::f64::consts::PI / (n as f64 * (0.5 * step).sin());
    let around = |k: usize| {
        let phi = step * k as f64;
        (phi.cos() as f32, phi.sin() as f32)
    };
    let mut mesh = MeshData {
        normals: Some(Vec::with_capacity(2 * n)),
        uvs: Some(Vec::with_capacity(2 * n)),
        ..MeshData::default()
    };
    for k in 0..n {
        let ((c0, s0), (c1, s1)) = (around(k), around(k + 1));
        let at = |c: f32, s: f32, z: f32| Vec3::new(r as f32 * c, r as f32 * s, z);
        let (a, b, c, d) = (
            at(c0, s0, 0.0),
            at(c1, s1, 0.0),
            at(c1, s1, 1.0),
            at(c0, s0, 1.0),
        );
        let (n0, n1) = (Vec3::new(c0, s0, 0.0), Vec3::new(c1, s1, 0.0));
        let (u0, u1) = (
            (k as f64 / n as f64) as f32,
            ((k + 1) as f64 / n as f64) as f32,
        );
        let uv = |u: f32, v: f32| Vec2::new(u, v);
        mesh.triangles.push([a, b, c]);
        mesh.triangles.push([a, c, d]);
        if let (Some(normals), Some(uvs)) = (&mut mesh.normals, &mut mesh.uvs) {
            normals.push([n0, n1, n1]);
            normals.push([n0, n1, n0]);
            uvs.push([uv(u0, 0.0), uv(u1, 0.0), uv(u1, 1.0)]);
            uvs.push([uv(u0, 0.0), uv(u1, 1.0), uv(u0, 1.0)]);
        }
    }
    mesh
}

/// Segments of the triangle fan that stands for Mitsuba's analytic `disk`.
pub const DISK_SEGMENTS: usize = 256;

/// Mitsuba's `disk` (radius 1 at z=0 facing +z) as a fan of [`DISK_SEGMENTS`] triangles whose
/// rim is pushed out so that the fan's area is exactly pi: an emitting disk keeps its power and
/// its image moves by at most 0.01% of the radius. Texture coordinates are Mitsuba's polar ones,
/// (r, phi / 2 pi), with the centre at each triangle's middle angle.
pub fn disk_mesh() -> MeshData {
    let n = DISK_SEGMENTS;
    let step = 2.0 * std::f64::consts::PI / n as f64;
    // n triangles of area r^2 sin(step) / 2 sum to pi.
    let rim = (2.0 * std::f64::consts::PI / (n as f64 * step.sin())).sqrt();
    let corner = |k: usize| {
        let phi = step * k as f64;
        Vec3::new((rim * phi.cos()) as f32, (rim * phi.sin()) as f32, 0.0)
    };
    let mut mesh = MeshData {
        uvs: Some(Vec::with_capacity(n)),
        ..MeshData::default()
    };
    for k in 0..n {
        mesh.triangles.push([Vec3::ZERO, corner(k), corner(k + 1)]);
        let v = |k: f64| (k / n as f64) as f32;
        if let Some(uvs) = &mut mesh.uvs {
            uvs.push([
                Vec2::new(0.0, v(k as f64 + 0.5)),
                Vec2::new(1.0, v(k as f64)),
                Vec2::new(1.0, v(k as f64 + 1.0)),
            ]);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normal(t: &[Vec3; 3]) -> Vec3 {
        (t[1] - t[0]).cross(t[2] - t[0]).normalize()
    }

    #[test]
    fn rectangle_faces_plus_z() {
        for t in rectangle() {
            assert!((normal(&t) - Vec3::Z).length() < 1e-6);
        }
    }

    #[test]
    fn cube_faces_point_outwards_and_cover_area_24() {
        let tris = cube();
        assert_eq!(tris.len(), 12);
        let mut area = 0.0;
        for t in &tris {
            let centroid = (t[0] + t[1] + t[2]) / 3.0;
            assert!(normal(t).dot(centroid) > 0.0, "inward face {t:?}");
            area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        }
        assert!((area - 24.0).abs() < 1e-5);
    }

    /// Each cube face maps onto the unit uv square (two triangles of uv area 1/2 whose corners
    /// are its four corners), the way Mitsuba's cube does; the rectangle's uvs are (x, y)/2 + 1/2.
    #[test]
    fn built_in_uvs_cover_the_unit_square() {
        let cube = cube_mesh();
        let uvs = cube.uvs.expect("cube uvs");
        for (t, uv) in cube.triangles.iter().zip(&uvs) {
            let area = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
            assert!(
                (area.abs() - 0.5).abs() < 1e-6,
                "triangle {t:?}: uv area {area}"
            );
            for c in uv {
                assert!(c.x == 0.0 || c.x == 1.0, "{c}");
                assert!(c.y == 0.0 || c.y == 1.0, "{c}");
            }
        }
        let rect = rectangle_mesh();
        for (t, uv) in rect.triangles.iter().zip(rect.uvs.expect("rectangle uvs")) {
            for (p, c) in t.iter().zip(uv) {
                assert_eq!(c, Vec2::new(0.5 * p.x + 0.5, 0.5 * p.y + 0.5));
            }
        }
    }

    /// The fan's area is the disk's (pi): an emitting disk keeps Mitsuba's power.
    #[test]
    fn the_disk_fan_has_the_disks_area_and_faces_up() {
        let mesh = disk_mesh();
        let area: f64 = mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| v.as_dvec3());
                let n = (b - a).cross(c - a);
                assert!(n.z > 0.0, "a triangle faces down");
                0.5 * n.length()
            })
            .sum();
        assert!((area - std::f64::consts::PI).abs() < 1e-5, "area {area}");
    }
}
