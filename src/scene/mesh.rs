//! Built-in shapes as object-space triangles, counter-clockwise seen from the front (normal)
//! side: Mitsuba's `rectangle` ([-1,1]^2 at z=0, normal +z) and `cube` ([-1,1]^3, outward).

use glam::{Vec2, Vec3};

/// A mesh file's triangles in its own coordinates, with what else it has per corner.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    pub triangles: Vec<[Vec3; 3]>,
    /// Vertex normals at each triangle's corners, when the file gives one for every vertex.
    pub normals: Option<Vec<[Vec3; 3]>>,
    /// Texture coordinates at each triangle's corners, when the file gives them.
    pub uvs: Option<Vec<[Vec2; 3]>>,
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

/// Two triangles spanning the parallelogram centre +- u +- v, facing u x v.
fn quad(center: Vec3, u: Vec3, v: Vec3) -> [[Vec3; 3]; 2] {
    let (a, b, c, d) = (
        center - u - v,
        center + u - v,
        center + u + v,
        center - u + v,
    );
    [[a, b, c], [a, c, d]]
}

pub fn rectangle() -> Vec<[Vec3; 3]> {
    quad(Vec3::ZERO, Vec3::X, Vec3::Y).to_vec()
}

pub fn cube() -> Vec<[Vec3; 3]> {
    // Each face's (u, v) is ordered so that u x v points out of the cube.
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    faces.iter().flat_map(|&(n, u, v)| quad(n, u, v)).collect()
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
}
