//! A binned-SAH bounding volume hierarchy over axis-aligned boxes, laid out for GPU traversal.
//! Generic over boxes so the same builder serves scene primitives and photon-map hit points.
//!
//! Layout: `nodes[0]` is the root. A node with `count > 0` is a leaf holding
//! `indices[left_or_first .. left_or_first + count]`; with `count == 0` it is interior and its
//! children are `left_or_first` and `left_or_first + 1`. An empty hierarchy is one interior-looking
//! node with an inverted box (min = +f32::MAX > max = -f32::MAX) and no children. A point test
//! rejects that box, but a slab test that orders its planes does not, so ray traversals must
//! check for emptiness (the GPU checks its primitive count) before descending.
//!
//! The module also holds the CPU reference intersection of a [`Scene`] (`closest_hit`), used by
//! tests and by passes that need ground truth: primitive `i < triangles.len()` is triangle `i`,
//! the rest are spheres `i - triangles.len()` (the GPU uses the same numbering).

pub mod split_boxes;

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::Vec3;

use crate::scene::Scene;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

impl BvhNode {
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }

    /// The left child of an interior node (the right one follows it); `None` for a leaf or the
    /// empty tree's root.
    fn left_child(&self) -> Option<usize> {
        (self.count == 0 && !self.bounds().is_empty()).then_some(self.left_or_first as usize)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The identity of `union`: contains nothing, and grows to exactly what is added to it.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::MAX),
        max: Vec3::splat(-f32::MAX),
    };

    pub fn empty() -> Aabb {
        Self::EMPTY
    }

    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The box extended to contain `p`.
    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
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

    /// Closed test: points on the boundary are inside, so flat boxes still contain their points.
    pub fn contains_point(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    pub fn contains(&self, other: &Aabb) -> bool {
        other.is_empty() || (other.min.cmpge(self.min).all() && other.max.cmple(self.max).all())
    }

    /// The points in both boxes (empty if they do not overlap).
    pub fn intersection(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.max(other.min),
            max: self.max.min(other.max),
        }
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

    /// The parametric interval `[enter, exit]` in which the ray is inside the box, clipped to
    /// `[0, t_max]`, or `None` when it misses. `inv_dir` is `1 / dir` per component.
    ///
    /// `exit` is enlarged by a few ulps (PBRT's `1 + 2 gamma(3)`) so rounding in the slab
    /// arithmetic never culls a box the ray grazes: the test may visit a little too much, never
    /// too little, which keeps BVH queries equal to brute force.
    pub fn ray_interval(&self, origin: Vec3, inv_dir: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let t0 = (self.min - origin) * inv_dir;
        let t1 = (self.max - origin) * inv_dir;
        // f32::min / max ignore a NaN operand, so an axis where 0 * inf occurs (the origin on a
        // slab plane of a ray parallel to it) simply does not constrain the interval.
        let enter = t0.min(t1).max_element().max(0.0);
        let exit = (t0.max(t1).min_element() * ROUNDING_SLACK).min(t_max);
        (enter <= exit).then_some((enter, exit))
    }
}

/// `1 + 2 gamma(3)` with gamma(n) = n eps / (1 - n eps), eps = 2^-24 (PBRT 3, section 3.9).
const ROUNDING_SLACK: f32 = 1.0 + 2.0 * (3.0 * 5.960_464_5e-8) / (1.0 - 3.0 * 5.960_464_5e-8);

#[derive(Clone)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub indices: Vec<u32>,
}

/// Tests per ray that enters a tree's root ([`Bvh::expected_tests`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExpectedTests {
    /// Interior nodes entered (each tests its node's box, as the SAH counts it).
    pub boxes: f32,
    pub primitives: f32,
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
/// stack) whatever the input: at most `MAX_SAH_DEPTH + ceil(log2 n)` edges from the root to a
/// leaf, which is at most 64 for any `n` that fits the u32 indices (the shader's stack size).
pub const MAX_SAH_DEPTH: u32 = 32;
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

/// A box being sorted into the tree, with what the builder reads of it kept together: the
/// builder moves items rather than indices so each pass over a node reads memory in order.
#[derive(Clone, Copy)]
struct Item {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

/// The boxes on one side of a split: their bounds, their centroids' bounds and how many.
#[derive(Clone, Copy)]
struct Side {
    bounds: Aabb,
    centroids: Aabb,
    count: u32,
}

impl Side {
    const EMPTY: Side = Side {
        bounds: Aabb::EMPTY,
        centroids: Aabb::EMPTY,
        count: 0,
    };

    fn add(self, other: &Side) -> Side {
        Side {
            bounds: self.bounds.union(other.bounds),
            centroids: self.centroids.union(other.centroids),
            count: self.count + other.count,
        }
    }

    fn of(items: &[Item]) -> Side {
        items.iter().fold(Side::EMPTY, |side, item| Side {
            bounds: side.bounds.union(item.bounds),
            centroids: side.centroids.grow(item.centroid),
            count: side.count + 1,
        })
    }

    /// The SAH cost of intersecting everything on this side once its box is entered.
    fn cost(&self) -> f32 {
        self.bounds.surface_area() * self.count as f32
    }
}

struct Split {
    axis: usize,
    /// Boxes whose centroid falls in bins below this one go left.
    bin: usize,
    cost: f32,
    /// What goes left and right, known from the bins (except the centroid bounds, which the
    /// partition measures): children need no extra pass.
    left: Side,
    right: Side,
}

/// Maps a centroid coordinate to its bin along one axis. Computed the same way when binning and
/// when partitioning, so both always agree on which side a box is on.
#[derive(Clone, Copy)]
struct Binning {
    min: f32,
    scale: f32,
    /// Bins in use: fewer for small nodes, where a sweep over 16 mostly empty bins would cost
    /// more than the binning itself (most nodes of a large tree are small).
    bins: usize,
}

impl Binning {
    fn along(centroid_bounds: &Aabb, axis: usize, count: usize) -> Option<Binning> {
        let bins = count.clamp(2, BINS);
        let extent = centroid_bounds.max[axis] - centroid_bounds.min[axis];
        // An extent so small that its reciprocal overflows cannot be split by position anyway.
        let scale = bins as f32 / extent;
        (extent > 0.0 && scale.is_finite()).then_some(Binning {
            min: centroid_bounds.min[axis],
            scale,
            bins,
        })
    }

    fn bin(&self, value: f32) -> usize {
        // `as usize` saturates (and maps NaN to 0), so this never leaves 0..bins.
        (((value - self.min) * self.scale) as usize).min(self.bins - 1)
    }
}

/// The cheapest binned SAH split of `items` over all three axes, if any axis has extent.
fn best_split(items: &[Item], centroid_bounds: &Aabb) -> Option<(Split, Binning)> {
    let binnings = [0, 1, 2].map(|axis| Binning::along(centroid_bounds, axis, items.len()));
    if binnings.iter().all(Option::is_none) {
        return None;
    }
    let mut bins = [[Side::EMPTY; BINS]; 3];
    for &Item {
        bounds: b,
        centroid: c,
        ..
    } in items
    {
        for (axis, binning) in binnings.iter().enumerate() {
            if let Some(binning) = binning {
                // Bins leave `centroids` empty: the partition measures them, once, on one axis.
                let bin = &mut bins[axis][binning.bin(c[axis])];
                bin.bounds = bin.bounds.union(b);
                bin.count += 1;
            }
        }
    }
    let mut best: Option<(Split, Binning)> = None;
    for (axis, binning) in binnings.iter().enumerate() {
        let Some(binning) = binning else {
            continue;
        };
        if let Some(split) = sweep(axis, &bins[axis][..binning.bins])
            && best.as_ref().is_none_or(|(b, _)| split.cost < b.cost)
        {
            best = Some((split, *binning));
        }
    }
    best
}

/// The cheapest split between bins along one axis (area-weighted counts of both sides).
fn sweep(axis: usize, bins: &[Side]) -> Option<Split> {
    // From the right first, to know each suffix.
    let mut right = [Side::EMPTY; BINS];
    let mut acc = Side::EMPTY;
    for k in (1..bins.len()).rev() {
        acc = acc.add(&bins[k]);
        right[k] = acc;
    }
    let mut best: Option<Split> = None;
    let mut left = Side::EMPTY;
    for k in 1..bins.len() {
        left = left.add(&bins[k - 1]);
        if left.count == 0 || right[k].count == 0 {
            continue;
        }
        let cost = left.cost() + right[k].cost();
        if best.as_ref().is_none_or(|b| cost < b.cost) {
            best = Some(Split {
                axis,
                bin: k,
                cost,
                left,
                right: right[k],
            });
        }
    }
    best
}

/// A node still to be built: `nodes[node]` covers `indices[start..end]`, described by `side`.
struct Task {
    node: usize,
    start: usize,
    side: Side,
    depth: u32,
}

/// Builds a BVH over `boxes` with at most `max_leaf_size` boxes per leaf (0 is taken as 1).
/// Smaller leaves are made where the surface area heuristic says splitting pays.
///
/// Boxes whose centroids coincide are split in half by count, and past [`MAX_SAH_DEPTH`] every
/// split is by count, so no leaf is more than `MAX_SAH_DEPTH + ceil(log2 len)` edges below the
/// root for any input. The build is iterative (no recursion) and O(n log n).
pub fn build_sah(boxes: &[Aabb], max_leaf_size: usize) -> Bvh {
    let max_leaf_size = max_leaf_size.max(1);
    let mut nodes = vec![node_from(Aabb::EMPTY, 0, 0)];
    if boxes.is_empty() {
        return Bvh {
            nodes,
            indices: Vec::new(),
        };
    }
    let mut items: Vec<Item> = boxes
        .iter()
        .zip(0u32..)
        .map(|(b, index)| Item {
            bounds: *b,
            centroid: b.centroid(),
            index,
        })
        .collect();
    nodes.reserve(2 * boxes.len().div_ceil(max_leaf_size));
    let mut stack = vec![Task {
        node: 0,
        start: 0,
        side: Side::of(&items),
        depth: 0,
    }];
    while let Some(task) = stack.pop() {
        let Side {
            bounds,
            centroids: centroid_bounds,
            count,
        } = task.side;
        let range = &mut items[task.start..task.start + count as usize];
        let split = if task.depth < MAX_SAH_DEPTH {
            best_split(range, &centroid_bounds)
        } else {
            None
        };
        let split_pays = split.as_ref().is_some_and(|(s, _)| {
            s.cost + TRAVERSAL_COST * bounds.surface_area() < task.side.cost()
        });
        if count as usize <= max_leaf_size && !split_pays {
            nodes[task.node] = node_from(bounds, task.start as u32, count);
            continue;
        }
        let (left_side, right_side) = match split {
            Some((s, binning)) => {
                let [left_centroids, right_centroids] =
                    partition(range, |c| binning.bin(c[s.axis]) < s.bin);
                (
                    Side {
                        centroids: left_centroids,
                        ..s.left
                    },
                    Side {
                        centroids: right_centroids,
                        ..s.right
                    },
                )
            }
            None => {
                let half = median_split(range, &centroid_bounds);
                let (l, r) = range.split_at(half);
                (Side::of(l), Side::of(r))
            }
        };
        let left = nodes.len();
        nodes.push(node_from(Aabb::EMPTY, 0, 0));
        nodes.push(node_from(Aabb::EMPTY, 0, 0));
        nodes[task.node] = node_from(bounds, left as u32, 0);
        let depth = task.depth + 1;
        stack.push(Task {
            node: left + 1,
            start: task.start + left_side.count as usize,
            side: right_side,
            depth,
        });
        stack.push(Task {
            node: left,
            start: task.start,
            side: left_side,
            depth,
        });
    }
    let indices = items.iter().map(|item| item.index).collect();
    Bvh { nodes, indices }
}

/// Halves `items` by count along the widest centroid axis; for coincident centroids (or a
/// node past the SAH depth limit). Returns the size of the left half, always in 1..len.
fn median_split(items: &mut [Item], centroid_bounds: &Aabb) -> usize {
    let axis = widest_axis(centroid_bounds);
    let half = items.len() / 2;
    items.select_nth_unstable_by(half, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    half
}

pub(super) fn widest_axis(b: &Aabb) -> usize {
    let d = b.max - b.min;
    if d.x >= d.y && d.x >= d.z {
        0
    } else if d.y >= d.z {
        1
    } else {
        2
    }
}

/// Moves the items whose centroid satisfies `goes_left` to the front, and returns the bounds of
/// the centroids that went left and right.
fn partition(items: &mut [Item], goes_left: impl Fn(Vec3) -> bool) -> [Aabb; 2] {
    let mut centroids = [Aabb::EMPTY; 2];
    let mut first_right = 0;
    for i in 0..items.len() {
        let c = items[i].centroid;
        if goes_left(c) {
            centroids[0] = centroids[0].grow(c);
            items.swap(i, first_right);
            first_right += 1;
        } else {
            centroids[1] = centroids[1].grow(c);
        }
    }
    centroids
}

impl Bvh {
    /// The surface area heuristic's expected cost of a ray that enters the root, in primitive
    /// tests (a box test costs `TRAVERSAL_COST` of one).
    pub fn sah_cost(&self) -> f32 {
        let tests = self.expected_tests();
        TRAVERSAL_COST * tests.boxes + tests.primitives
    }

    /// The box and primitive tests a ray that enters the root is expected to make, by the
    /// surface area heuristic: each node's tests weighted by the chance (its area over the
    /// root's) that the ray enters it.
    pub fn expected_tests(&self) -> ExpectedTests {
        let root_area = self.node_box(0).surface_area();
        let mut tests = ExpectedTests::default();
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let chance = if root_area > 0.0 {
                self.node_box(i).surface_area() / root_area
            } else {
                1.0
            };
            if let Some(left) = self.nodes[i].left_child() {
                tests.boxes += chance;
                stack.extend([left, left + 1]);
            } else {
                tests.primitives += chance * self.nodes[i].count as f32;
            }
        }
        tests
    }

    /// This tree with sibling leaves merged, the cheapest merge by the surface area heuristic
    /// first, until at most `max_nodes` nodes remain (or the root is one leaf). Sibling leaves
    /// hold adjacent ranges of `indices`, so a merged leaf holds their union and `indices` is
    /// unchanged. On lavapipe nodes in a uniform binding read so much faster than in a storage
    /// buffer that a few larger leaves pay for fitting them in one (BENCHMARKS.md).
    pub fn collapsed_to(&self, max_nodes: usize) -> Bvh {
        // No merge adds more than infinitely many tests, so this never falls back.
        self.collapsed_within(max_nodes, f32::INFINITY)
            .unwrap_or_else(|| self.clone())
    }

    /// [`Bvh::collapsed_to`], or `None` as soon as the merges add more than
    /// `max_added_primitive_tests` to the [`Bvh::expected_tests`] primitives (merges only ever
    /// add some, cheapest first, so a tree that cannot fit within the bound is given up without
    /// merging it all the way: a 400,000-triangle scene spent a third of a second there).
    pub fn collapsed_within(
        &self,
        max_nodes: usize,
        max_added_primitive_tests: f32,
    ) -> Option<Bvh> {
        let root_area = self.node_box(0).surface_area();
        let mut added = 0.0f32;
        let mut nodes = self.nodes.clone();
        let mut parent = vec![None; nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            if let Some(left) = node.left_child() {
                parent[left] = Some(i);
                parent[left + 1] = Some(i);
            }
        }
        let mut heap: BinaryHeap<Reverse<(CostKey, usize)>> = (0..nodes.len())
            .filter_map(|i| merge_cost(&nodes, i).map(|c| Reverse((CostKey(c), i))))
            .collect();
        let mut live = nodes.len();
        while live > max_nodes.max(1) {
            let Some(Reverse((CostKey(cost), i))) = heap.pop() else {
                break;
            };
            // The merge's primitive tests: its SAH cost plus the box test it removes.
            if root_area > 0.0 {
                added += (cost + TRAVERSAL_COST * nodes[i].bounds().surface_area()) / root_area;
                if added > max_added_primitive_tests {
                    return None;
                }
            }
            let left = nodes[i].left_or_first as usize;
            let (l, r) = (nodes[left], nodes[left + 1]);
            nodes[i].count = l.count + r.count;
            // The left child's range comes first (build_sah partitions in place).
            nodes[i].left_or_first = l.left_or_first;
            live -= 2;
            if let Some(p) = parent[i]
                && let Some(c) = merge_cost(&nodes, p)
            {
                heap.push(Reverse((CostKey(c), p)));
            }
        }
        Some(Bvh {
            nodes: reachable_in_order(&nodes),
            indices: self.indices.clone(),
        })
    }

    pub fn node_box(&self, i: usize) -> Aabb {
        self.nodes[i].bounds()
    }

    fn leaf_primitives(&self, node: &BvhNode) -> &[u32] {
        let first = node.left_or_first as usize;
        self.indices
            .get(first..first + node.count as usize)
            .unwrap_or(&[])
    }

    /// Calls `visit` with every primitive in a leaf whose box contains `p` (a superset of the
    /// primitives whose own box contains `p`: callers filter).
    pub fn point_query(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            if !self.node_box(i).contains_point(p) {
                continue;
            }
            let n = self.nodes[i];
            if n.count > 0 {
                self.leaf_primitives(&n)
                    .iter()
                    .for_each(|&prim| visit(prim));
            } else {
                stack.push(n.left_or_first as usize);
                stack.push(n.left_or_first as usize + 1);
            }
        }
    }

    /// Visits the primitives of every leaf the ray (origin, dir) enters in `[0, t_max]`;
    /// `hit(prim, &mut t_max)` may shorten the ray (closest-hit queries). Near children are not
    /// ordered first: this is a reference, not the fast path.
    pub fn ray_query(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut hit: impl FnMut(u32, &mut f32),
    ) {
        let inv_dir = dir.recip();
        let mut t_max = t_max;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let b = self.node_box(i);
            if b.is_empty() || b.ray_interval(origin, inv_dir, t_max).is_none() {
                continue;
            }
            let n = self.nodes[i];
            if n.count > 0 {
                for &prim in self.leaf_primitives(&n) {
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
            if let Some(left) = self.nodes[i].left_child() {
                stack.push((left, d + 1));
                stack.push((left + 1, d + 1));
            }
        }
        deepest
    }
}

/// A cost ordered totally (for heaps of costs or areas).
#[derive(Clone, Copy, PartialEq)]
pub(super) struct CostKey(pub f32);

impl Eq for CostKey {}

impl PartialOrd for CostKey {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for CostKey {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// What merging interior node `i`'s two children adds to the tree's cost (times the root's
/// area), if both are leaves: its primitives are then tested whenever its box is entered, and
/// neither its box test nor its children's primitive tests remain.
fn merge_cost(nodes: &[BvhNode], i: usize) -> Option<f32> {
    let n = nodes[i];
    let left = n.left_child()?;
    let (l, r) = (nodes.get(left)?, nodes.get(left + 1)?);
    if l.count == 0 || r.count == 0 {
        return None;
    }
    let area = |node: &BvhNode| node.bounds().surface_area();
    Some(
        area(&n) * ((l.count + r.count) as f32 - TRAVERSAL_COST)
            - area(l) * l.count as f32
            - area(r) * r.count as f32,
    )
}

/// The nodes reachable from the root, numbered as `build_sah` numbers them: a node's two
/// children are placed together when it is reached, and the left subtree is walked first.
fn reachable_in_order(nodes: &[BvhNode]) -> Vec<BvhNode> {
    let mut order = vec![nodes[0]];
    // (index in `nodes`, index in `order`) of nodes whose children are still to be placed.
    let mut stack = vec![(0usize, 0usize)];
    while let Some((old, new)) = stack.pop() {
        if let Some(left) = nodes[old].left_child() {
            let placed = order.len();
            order[new].left_or_first = placed as u32;
            order.extend([nodes[left], nodes[left + 1]]);
            stack.push((left + 1, placed + 1));
            stack.push((left, placed));
        }
    }
    order
}

/// Möller–Trumbore: the distance along `dir` (in units of `dir`) at which the ray meets the
/// triangle, if it does at t > 0. Both sides count (culling is the shader's business), and a
/// degenerate triangle or a ray in its plane never hits.
pub fn intersect_triangle(v: &[Vec3; 3], origin: Vec3, dir: Vec3) -> Option<f32> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = origin - v[0];
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let w = dir.dot(q) * inv_det;
    if w < 0.0 || u + w > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t > 0.0 && t.is_finite()).then_some(t)
}

/// The nearest t > 0 at which the ray meets the sphere (from outside or inside).
pub fn intersect_sphere(center: Vec3, radius: f32, origin: Vec3, dir: Vec3) -> Option<f32> {
    let oc = origin - center;
    let a = dir.length_squared();
    let half_b = oc.dot(dir);
    let c = oc.length_squared() - radius * radius;
    let discriminant = half_b * half_b - a * c;
    if discriminant.is_nan() || discriminant < 0.0 || a == 0.0 {
        return None;
    }
    // The cancellation-free form of the quadratic's roots (Numerical Recipes 5.6).
    let q = -(half_b + discriminant.sqrt().copysign(half_b));
    if q == 0.0 {
        return None;
    }
    let (r0, r1) = (q / a, c / q);
    let (near, far) = (r0.min(r1), r0.max(r1));
    [near, far].into_iter().find(|&t| t > 0.0 && t.is_finite())
}

/// The hit distance of the ray with primitive `prim` of `scene` (triangles first, then spheres).
pub fn intersect_primitive(scene: &Scene, prim: u32, origin: Vec3, dir: Vec3) -> Option<f32> {
    let i = prim as usize;
    match scene.triangles.get(i) {
        Some(t) => intersect_triangle(&t.v, origin, dir),
        None => {
            let s = scene.spheres.get(i - scene.triangles.len())?;
            intersect_sphere(s.center, s.radius, origin, dir)
        }
    }
}

/// CPU reference closest hit: `(t, primitive)` of the nearest intersection at t > 0, with `bvh`
/// built over [`scene_boxes`]. `t` is in units of `dir` (which need not be normalised).
pub fn closest_hit(scene: &Scene, bvh: &Bvh, origin: Vec3, dir: Vec3) -> Option<(f32, u32)> {
    let mut best = None;
    bvh.ray_query(origin, dir, f32::INFINITY, |prim, t_max| {
        if let Some(t) = intersect_primitive(scene, prim, origin, dir)
            && t < *t_max
        {
            *t_max = t;
            best = Some((t, prim));
        }
    });
    best
}
