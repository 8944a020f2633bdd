//! Triangles whose boxes fit them badly, split into several references with tighter boxes
//! before the BVH is built (early split clipping: Ernst and Greiner, "Early Split Clipping for
//! Bounding Volume Hierarchies", 2007). A long thin triangle, or a wedge of a fan from a disk's
//! centre to its rim, has a box far larger than itself: rays that pass near it enter its leaf
//! and test it, and its box overlaps its neighbours'. Each reference is the same primitive with
//! the box of the part of the triangle inside a smaller box, so traversal is unchanged; a
//! primitive may then sit in several leaves, which a closest-hit or any-hit query tolerates.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::Vec3;

use super::{Aabb, CostKey, scene_boxes, widest_axis};
use crate::scene::Scene;

/// Boxes to build the BVH over, and the primitive each stands for (`prims[i]` for `boxes[i]`).
pub struct References {
    pub boxes: Vec<Aabb>,
    pub prims: Vec<u32>,
}

/// The scene's primitive boxes, with the largest triangle references split in two at the middle
/// of their box's longest axis, largest first, until there are `1 + extra` references per
/// primitive (spheres are never split; their boxes fit). A reference is split only where both
/// halves hold part of the triangle and its box is worth splitting (`worth_splitting`).
pub fn split_references(scene: &Scene, extra: f32) -> References {
    let boxes = scene_boxes(scene);
    let prims: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut refs = References { boxes, prims };
    let limit = ((1.0 + extra.max(0.0)) * refs.boxes.len() as f32) as usize;
    let triangles = scene.triangles.len();
    let scene_area = refs
        .boxes
        .iter()
        .fold(Aabb::EMPTY, |a, b| a.union(*b))
        .surface_area();
    // Largest box first; of equal boxes, the lowest reference.
    let mut queue: BinaryHeap<(CostKey, Reverse<usize>)> = (0..triangles)
        .filter(|&i| worth_splitting(&refs.boxes[i], &scene.triangles[i].v, scene_area))
        .map(|i| (CostKey(refs.boxes[i].surface_area()), Reverse(i)))
        .collect();
    while refs.boxes.len() < limit {
        let Some((_, Reverse(reference))) = queue.pop() else {
            break;
        };
        let prim = refs.prims[reference] as usize;
        let corners = &scene.triangles[prim].v;
        let Some([low, high]) = split_in_half(corners, refs.boxes[reference]) else {
            continue;
        };
        refs.boxes[reference] = low;
        refs.boxes.push(high);
        refs.prims.push(prim as u32);
        for (r, b) in [(reference, low), (refs.boxes.len() - 1, high)] {
            if worth_splitting(&b, corners, scene_area) {
                queue.push((CostKey(b.surface_area()), Reverse(r)));
            }
        }
    }
    refs
}

/// A reference box is worth splitting when it is a noticeable part of the scene (rays often
/// enter it) and far larger than the triangle it bounds (most rays that enter it miss the
/// triangle).
fn worth_splitting(bounds: &Aabb, corners: &[Vec3; 3], scene_area: f32) -> bool {
    // Twice the triangle's area, as a flat box around a flat triangle has both faces. A
    // degenerate triangle is never hit, so its references are left alone.
    let both_faces = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .length();
    let area = bounds.surface_area();
    both_faces > 0.0 && area > 1e-4 * scene_area && area > 4.0 * both_faces
}

/// The boxes of the parts of the triangle on each side of the middle of `bounds`' longest
/// axis, each within `bounds`; `None` when one side holds none of it.
fn split_in_half(corners: &[Vec3; 3], bounds: Aabb) -> Option<[Aabb; 2]> {
    let axis = widest_axis(&bounds);
    let middle = 0.5 * (bounds.min[axis] + bounds.max[axis]);
    let mut low = bounds;
    low.max[axis] = middle;
    let mut high = bounds;
    high.min[axis] = middle;
    let low = clipped_box(corners, low)?.intersection(bounds);
    let high = clipped_box(corners, high)?.intersection(bounds);
    Some([low, high])
}

/// The box of the part of the triangle inside `bounds` (Sutherland-Hodgman against its six
/// planes), widened by a few roundoffs of its coordinates so that rounding in the clipping never
/// leaves a sliver of the triangle outside every reference; `None` if nothing is inside.
fn clipped_box(corners: &[Vec3; 3], bounds: Aabb) -> Option<Aabb> {
    let mut polygon: Vec<Vec3> = corners.to_vec();
    for axis in 0..3 {
        polygon = clip(&polygon, axis, bounds.min[axis], 1.0);
        polygon = clip(&polygon, axis, bounds.max[axis], -1.0);
        if polygon.is_empty() {
            return None;
        }
    }
    let clipped = polygon.iter().fold(Aabb::EMPTY, |b, &p| b.grow(p));
    let slack = Vec3::splat(4.0 * f32::EPSILON) * clipped.min.abs().max(clipped.max.abs());
    Some(Aabb {
        min: clipped.min - slack,
        max: clipped.max + slack,
    })
}

/// The part of a convex polygon on the side `side * (p[axis] - plane) >= 0`.
fn clip(polygon: &[Vec3], axis: usize, plane: f32, side: f32) -> Vec<Vec3> {
    let inside = |p: &Vec3| side * (p[axis] - plane) >= 0.0;
    let mut out = Vec::with_capacity(polygon.len() + 1);
    for (i, a) in polygon.iter().enumerate() {
        let b = &polygon[(i + 1) % polygon.len()];
        if inside(a) {
            out.push(*a);
        }
        if inside(a) != inside(b) {
            let t = (plane - a[axis]) / (b[axis] - a[axis]);
            let mut p = *a + (*b - *a) * t;
            p[axis] = plane;
            out.push(p);
        }
    }
    out
}
