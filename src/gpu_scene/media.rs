//! The scene's media as the GPU reads them: each medium's record in the float tables (where
//! `GpuMaterial::interior` / `exterior`, the camera's and each light's medium point), and the
//! medium each light's photons start in, found on the CPU by a ray from the light to the first
//! shape that bounds a medium.

use glam::Vec3;

use crate::scene::Scene;
use crate::scene::medium::{MEDIUM_RECORD_FLOATS, MediumInterface};

/// A medium reference the WGSL reads as "vacuum" (common::medium's NO_MEDIUM).
pub const NO_MEDIUM: u32 = u32::MAX;

/// Appends every medium's record (and its grid's values after it) to `tables`: the offset of
/// each record, by medium index.
pub fn append_records(scene: &Scene, tables: &mut Vec<f32>) -> Vec<u32> {
    scene
        .media
        .list
        .iter()
        .map(|m| {
            let offset = tables.len() as u32;
            let grid = offset + MEDIUM_RECORD_FLOATS as u32;
            tables.extend(m.gpu_record(grid));
            if let Some(d) = &m.density {
                tables.extend_from_slice(&d.grid.data);
            }
            offset
        })
        .collect()
}

/// A medium index as its record's offset (or NO_MEDIUM).
pub fn offset_of(medium: Option<u32>, offsets: &[u32]) -> u32 {
    medium
        .and_then(|m| offsets.get(m as usize).copied())
        .unwrap_or(NO_MEDIUM)
}

/// A direction no axis-aligned wall or box edge lies along.
const PROBE_DIR: Vec3 = Vec3::new(0.371_390_7, 0.848_894_2, 0.376_076_4);

/// The medium at `point`: the side it lies on of the first shape bounding a medium that a ray
/// from it meets; the camera's medium where it meets none (a medium everywhere is the camera's,
/// as Mitsuba's volpath carries the camera's medium until a shape changes it).
pub fn medium_at(scene: &Scene, point: Vec3) -> Option<u32> {
    let dir = PROBE_DIR.normalize();
    let bounds_medium = |material: u32| {
        scene
            .materials
            .get(material as usize)
            .map(|m| m.media)
            .filter(MediumInterface::is_transition)
    };
    let mut nearest: Option<(f32, Vec3, MediumInterface)> = None;
    let mut consider = |t: f32, normal: Vec3, media: MediumInterface| {
        if t > 1e-5 && nearest.is_none_or(|(best, _, _)| t < best) {
            nearest = Some((t, normal, media));
        }
    };
    for tri in &scene.triangles {
        let Some(media) = bounds_medium(tri.material) else {
            continue;
        };
        let e1 = tri.v[1] - tri.v[0];
        let e2 = tri.v[2] - tri.v[0];
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let s = point - tri.v[0];
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = dir.dot(q) / det;
        if u < 0.0 || v < 0.0 || u + v > 1.0 {
            continue;
        }
        consider(e2.dot(q) / det, e1.cross(e2), media);
    }
    for sphere in &scene.spheres {
        let Some(media) = bounds_medium(sphere.material) else {
            continue;
        };
        let oc = point - sphere.center;
        let b = oc.dot(dir);
        let c = oc.length_squared() - sphere.radius * sphere.radius;
        let disc = b * b - c;
        if disc < 0.0 {
            continue;
        }
        let root = disc.sqrt();
        for t in [-b - root, -b + root] {
            let outward = point + dir * t - sphere.center;
            let normal = if sphere.flip_normals {
                -outward
            } else {
                outward
            };
            consider(t, normal, media);
        }
    }
    match nearest {
        // The side the ray came from.
        Some((_, normal, media)) => media.target(-dir, normal),
        None => scene.media.camera,
    }
}
