//! A binned-SAH bounding volume hierarchy over axis-aligned boxes, laid out for GPU traversal.
//! Generic over boxes so the same builder serves scene primitives and photon-map hit points.
//!
//! Layout: `nodes[0]` is the root. A node with `count > 0` is a leaf holding
//! `indices[left_or_first .. left_or_first + count]`; with `count == 0` it is interior and its
//! children are `left_or_first` and `left_or_first + 1`. An empty hierarchy is one interior-looking
//! node with an inverted box (min > max) and no children: traversals must check for emptiness
//! (the GPU checks its primitive count) before descending, since a slab test does not reject an
//! inverted box.

use glam::Vec3;

use super::Scene;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::MAX),
        max: Vec3::splat(-f32::MAX),
    };

    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.max - self.min;
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    pub fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    pub fn contains_point(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    pub fn contains(&self, other: &Aabb) -> bool {
        other.is_empty() || (other.min.cmpge(self.min).all() && other.max.cmple(self.max).all())
    }

    pub fn of_triangle(v: &[Vec3; 3]) -> Aabb {
        Aabb {
            min: v[0].min(v[1]).min(v[2]),
            max: v[0].max(v[1]).max(v[2]),
        }
    }

    pub fn of_sphere(center: Vec3, radius: f32) -> Aabb {
        Aabb {
            min: center - radius,
            max: center + radius,
        }
    }
}

pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub indices: Vec<u32>,
}

/// Boxes of every scene primitive: triangles first, then spheres. A primitive index below
/// `scene.triangles.len()` is a triangle, the rest are spheres (the GPU uses the same rule).
pub fn scene_boxes(scene: &Scene) -> Vec<Aabb> {
    let triangles = scene.triangles.iter().map(|t| Aabb::of_triangle(&t.v));
    let spheres = scene
        .spheres
        .iter()
        .map(|s| Aabb::of_sphere(s.center, s.radius));
    triangles.chain(spheres).collect()
}

const BINS: usize = 16;
/// Beyond this depth splits are by count, which bounds the depth (and so the GPU traversal
/// stack) whatever the input.
const MAX_SAH_DEPTH: u32 = 40;
/// Cost of one box test relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;

fn node_from(bounds: Aabb, left_or_first: u32, count: u32) -> BvhNode {
    BvhNode {
        min: bounds.min.to_array(),
        left_or_first,
        max: bounds.max.to_array(),
        count,
    }
}

struct Split {
    axis: usize,
    /// Boxes whose centroid falls in bins below this one go left.
    bin: usize,
    cost: f32,
}

/// The cheapest binned SAH split of `range`, if any axis has extent.
fn best_split(boxes: &[Aabb], range: &[u32], centroid_bounds: Aabb) -> Option<Split> {
    let extent = centroid_bounds.max - centroid_bounds.min;
    let mut best: Option<Split> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_counts = [0u32; BINS];
        for &i in range {
            let b = &boxes[i as usize];
            let k = bin_of(b.centroid()[axis], centroid_bounds.min[axis], scale);
            bin_bounds[k] = bin_bounds[k].union(*b);
            bin_counts[k] += 1;
        }
        // Sweep from the right to know each suffix's area and count.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for k in (1..BINS).rev() {
            acc = acc.union(bin_bounds[k]);
            n += bin_counts[k];
            right_area[k] = acc.surface_area();
            right_count[k] = n;
        }
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for k in 1..BINS {
            acc = acc.union(bin_bounds[k - 1]);
            n += bin_counts[k - 1];
            if n == 0 || right_count[k] == 0 {
                continue;
            }
            let cost = acc.surface_area() * n as f32 + right_area[k] * right_count[k] as f32;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split { axis, bin: k, cost });
            }
        }
    }
    best
}

fn bin_of(value: f32, min: f32, scale: f32) -> usize {
    (((value - min) * scale) as usize).min(BINS - 1)
}

/// Builds a BVH over `boxes` with at most `max_leaf_size` boxes per leaf (more only when boxes
/// cannot be told apart, which cannot happen: coincident boxes are split by count).
pub fn build_sah(boxes: &[Aabb], max_leaf_size: usize) -> Bvh {
    let max_leaf_size = max_leaf_size.max(1);
    let mut indices: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut nodes = vec![node_from(Aabb::EMPTY, 0, 0)];
    if boxes.is_empty() {
        return Bvh { nodes, indices };
    }
    // (node, start, end, depth)
    let mut stack = vec![(0usize, 0usize, boxes.len(), 0u32)];
    while let Some((node, start, end, depth)) = stack.pop() {
        let range = &mut indices[start..end];
        let (bounds, centroid_bounds) =
            range.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), &i| {
                let bx = boxes[i as usize];
                let p = bx.centroid();
                (b.union(bx), c.union(Aabb { min: p, max: p }))
            });
        let count = end - start;
        let split = if depth < MAX_SAH_DEPTH {
            best_split(boxes, range, centroid_bounds)
        } else {
            None
        };
        let leaf_cost = bounds.surface_area() * count as f32;
        let split_pays = split
            .as_ref()
            .is_some_and(|s| s.cost + TRAVERSAL_COST * bounds.surface_area() < leaf_cost);
        if count <= max_leaf_size && !split_pays {
            nodes[node] = node_from(bounds, start as u32, count as u32);
            continue;
        }
        let mid = match split {
            Some(s) => {
                let scale =
                    BINS as f32 / (centroid_bounds.max[s.axis] - centroid_bounds.min[s.axis]);
                let min = centroid_bounds.min[s.axis];
                let left = partition(range, |i| {
                    bin_of(boxes[i as usize].centroid()[s.axis], min, scale) < s.bin
                });
                start + left
            }
            None => {
                // No usable SAH split (coincident centroids, or too deep): halve by count along
                // the widest centroid axis.
                let axis = widest_axis(centroid_bounds);
                let half = count / 2;
                range.select_nth_unstable_by(half, |&a, &b| {
                    let ca = boxes[a as usize].centroid()[axis];
                    let cb = boxes[b as usize].centroid()[axis];
                    ca.total_cmp(&cb)
                });
                start + half
            }
        };
        let left = nodes.len();
        nodes.push(node_from(Aabb::EMPTY, 0, 0));
        nodes.push(node_from(Aabb::EMPTY, 0, 0));
        nodes[node] = node_from(bounds, left as u32, 0);
        stack.push((left + 1, mid, end, depth + 1));
        stack.push((left, start, mid, depth + 1));
    }
    Bvh { nodes, indices }
}

fn widest_axis(b: Aabb) -> usize {
    let d = b.max - b.min;
    if d.x >= d.y && d.x >= d.z {
        0
    } else if d.y >= d.z {
        1
    } else {
        2
    }
}

/// Moves the elements satisfying `left` to the front; returns how many there are.
fn partition(items: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut first_right = 0;
    for i in 0..items.len() {
        if left(items[i]) {
            items.swap(i, first_right);
            first_right += 1;
        }
    }
    first_right
}

impl Bvh {
    fn node_box(&self, i: usize) -> Aabb {
        let n = &self.nodes[i];
        Aabb {
            min: Vec3::from(n.min),
            max: Vec3::from(n.max),
        }
    }

    /// Calls `visit` with every primitive in a leaf whose box contains `p`.
    pub fn point_query(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            if !self.node_box(i).contains_point(p) {
                continue;
            }
            let n = self.nodes[i];
            if n.count > 0 {
                let first = n.left_or_first as usize;
                for &prim in &self.indices[first..first + n.count as usize] {
                    visit(prim);
                }
            } else {
                stack.push(n.left_or_first as usize);
                stack.push(n.left_or_first as usize + 1);
            }
        }
    }

    /// Visits the primitives of every leaf the ray (origin, dir) enters before `t_max`;
    /// `hit(prim, &mut t_max)` may shorten the ray (closest-hit queries).
    pub fn ray_query(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut hit: impl FnMut(u32, &mut f32),
    ) {
        let inv = dir.recip();
        let mut t_max = t_max;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let b = self.node_box(i);
            let t0 = (b.min - origin) * inv;
            let t1 = (b.max - origin) * inv;
            let enter = t0.min(t1).max_element().max(0.0);
            let exit = t0.max(t1).min_element().min(t_max);
            if enter > exit || b.is_empty() {
                continue;
            }
            let n = self.nodes[i];
            if n.count > 0 {
                let first = n.left_or_first as usize;
                for &prim in &self.indices[first..first + n.count as usize] {
                    hit(prim, &mut t_max);
                }
            } else {
                stack.push(n.left_or_first as usize);
                stack.push(n.left_or_first as usize + 1);
            }
        }
    }

    /// Depth of the deepest leaf (the root alone is depth 1).
    pub fn depth(&self) -> u32 {
        let mut deepest = 0;
        let mut stack = vec![(0usize, 1u32)];
        while let Some((i, d)) = stack.pop() {
            deepest = deepest.max(d);
            let n = self.nodes[i];
            if n.count == 0 && !self.node_box(i).is_empty() {
                stack.push((n.left_or_first as usize, d + 1));
                stack.push((n.left_or_first as usize + 1, d + 1));
            }
        }
        deepest
    }
}
