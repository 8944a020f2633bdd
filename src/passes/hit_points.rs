//! Hit points, their radii, photon hits, the tree over hit points and photon deposits: the
//! resource kinds several passes share, their GPU layouts (mirrored in
//! `shaders/common/hit_points.wgsl`) and the CPU side of the hit-point BVH (build, range query)
//! that the SAH builder node and the tests use.

use glam::Vec3;

use crate::gpu::layout::StructLayout;
use crate::graph::pass::ResourceKind;
use crate::passes::gather::BVH_GATHER;
/// A kernel that reads the radius rule (the sppm estimator's), for its layout check.
const SPPM_SHADER: crate::gpu::shaders::ShaderFile =
    crate::shader_file!("shaders/passes/merge.wgsl");
use crate::scene::bvh::{Aabb, BvhNode, build_sah};
use crate::struct_layout;

/// `HitPoint.pixel` of a slot that holds no hit point this iteration.
pub const NO_PIXEL: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuHitPoint {
    pub position: [f32; 3],
    pub pixel: u32,
    pub normal: [f32; 3],
    pub radius: f32,
    pub wo: [f32; 3],
    pub depth: u32,
    pub weight: [f32; 3],
    pub footprint: f32,
}

impl GpuHitPoint {
    pub fn is_valid(&self) -> bool {
        self.pixel != NO_PIXEL && self.radius > 0.0
    }
}

/// What precedes the hit points in their buffer; written by the camera pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HitPointsHeader {
    /// Hit-point slots per pixel (the merge depth).
    pub slots_per_pixel: u32,
    pub _pad: [u32; 3],
}

/// How a slot's first radius is chosen; precedes the radii in their buffer, written by the
/// estimator that owns them (the camera pass applies it to a slot whose radius is still 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RadiusRule {
    /// Absolute radius in scene units; 0 means `radius_pixels` pixel footprints.
    pub initial_radius: f32,
    pub radius_pixels: f32,
    pub min_radius: f32,
    /// Factor on the first radius before the floor: 1, or pppm's schedule for the iteration.
    pub scale: f32,
}

impl RadiusRule {
    /// `initial_radius` in scene units (0: `radius_pixels` pixel footprints); the floor is
    /// `MIN_RADIUS_FRACTION` of the scene's bounding radius.
    pub fn new(initial_radius: f32, radius_pixels: f32, scene_radius: f32) -> Self {
        Self {
            initial_radius,
            radius_pixels,
            min_radius: MIN_RADIUS_FRACTION * scene_radius,
            scale: 1.0,
        }
    }
}

/// Where a photon met a diffuse surface it deposits at (written by `photon_trace`, gathered by
/// the hit-point structures).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuPhotonHit {
    pub position: [f32; 3],
    /// Camera segments the full path may still have (max_depth minus the photon's segments;
    /// `UNBOUNDED` when the depth is unbounded), so that photon mapping obeys path tracing's
    /// depth rule.
    pub remaining: u32,
    /// Unit direction towards where the photon came from.
    pub wi: [f32; 3],
    /// 1: deposited where the photon scattered in a medium (a volumetric caustic, gathered by
    /// camera paths' medium vertices only); 0: on a surface.
    pub in_medium: u32,
    /// Flux per photon of this iteration.
    pub flux: [f32; 3],
    pub _pad_b: u32,
}

/// What precedes the photon hits: how many were written, and how many did not fit.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PhotonHitsHeader {
    pub count: u32,
    pub dropped: u32,
    pub _pad: [u32; 2],
}

/// Initial search radius in pixel footprints unless the estimator says otherwise.
pub const DEFAULT_RADIUS_PIXELS: f32 = 1.0;

pub const HIT_POINT_BYTES: u64 = std::mem::size_of::<GpuHitPoint>() as u64;
/// Bytes before the first hit point in a hit-points buffer.
pub const HEADER_BYTES: u64 = std::mem::size_of::<HitPointsHeader>() as u64;
/// Photons gathered by one hit point in one iteration (`DepositCell`, added to atomically).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuDepositCell {
    pub count: u32,
    pub flux: [f32; 3],
    /// The same sums over the photons within half the radius (for the kernel-bias estimate).
    pub inner_flux: [f32; 3],
    pub inner_count: u32,
}

/// One `DepositCell`: photon count and RGB flux, and both within half the radius.
pub const DEPOSIT_BYTES: u64 = std::mem::size_of::<GpuDepositCell>() as u64;
/// Bytes before the first node in a tree buffer (the node count and padding).
pub const TREE_HEADER_BYTES: u64 = 16;

/// The output slot where a photon-mapping estimator writes its estimate's kernel bias (an image
/// like its radiance: the mean of per-iteration estimates), which the error estimate reads
/// (docs/error-estimate.md).
pub const KERNEL_BIAS: &str = "kernel_bias";

/// Camera-path vertices where photon mapping takes over: `slots_per_pixel` per pixel.
pub const HIT_POINTS: ResourceKind = ResourceKind::new("hit_points", HEADER_BYTES, HIT_POINT_BYTES);
/// Each hit-point slot's current search radius (0: not chosen yet) after a `RadiusRule`.
pub const HIT_POINT_RADII: ResourceKind = ResourceKind::new(
    "hit_point_radii",
    std::mem::size_of::<RadiusRule>() as u64,
    4,
);
/// Photons arriving at diffuse surfaces in one iteration.
pub const PHOTON_HITS: ResourceKind = ResourceKind::new(
    "photon_hits",
    std::mem::size_of::<PhotonHitsHeader>() as u64,
    std::mem::size_of::<GpuPhotonHit>() as u64,
);
/// Per-hit-point photon count and flux gathered in one iteration.
pub const DEPOSITS: ResourceKind = ResourceKind::new("deposits", 0, DEPOSIT_BYTES);
/// A BVH over hit points, in the layout the BVH gather traverses; its length is in nodes.
pub const HIT_POINT_TREE: ResourceKind = ResourceKind::new(
    "hit_point_tree",
    TREE_HEADER_BYTES,
    std::mem::size_of::<BvhNode>() as u64,
);

/// The structs above against their WGSL twins (tests/shaders.rs checks every offset).
pub const LAYOUTS: &[StructLayout] = &[
    struct_layout!(GpuHitPoint => "HitPoint" in BVH_GATHER, {
        position, pixel, normal, radius, wo, depth, weight, footprint
    }),
    struct_layout!(HitPointsHeader => "HitPointsHeader" in BVH_GATHER, { slots_per_pixel }),
    struct_layout!(RadiusRule => "RadiusRule" in SPPM_SHADER, {
        initial_radius, radius_pixels, min_radius, scale
    }),
    struct_layout!(GpuPhotonHit => "PhotonHit" in BVH_GATHER, { position, remaining, wi, flux }),
    struct_layout!(PhotonHitsHeader => "PhotonHitsIn" in BVH_GATHER, { count, dropped } head),
    struct_layout!(GpuDepositCell => "DepositCell" in BVH_GATHER, { count, flux, inner_flux, inner_count }),
    struct_layout!(BvhNode => "HitPointNode" in BVH_GATHER, { min, left_or_first, max, count }),
];

/// Minimum search radius as a fraction of the scene's bounding radius: far above f32
/// resolution of positions, far below any useful radius.
pub const MIN_RADIUS_FRACTION: f32 = 1e-5;

/// Nodes of a tree over `slots` hit-point slots (one leaf each).
pub fn tree_nodes(slots: u64) -> u64 {
    2 * slots.max(1) - 1
}

/// Size in bytes of a tree buffer able to hold a BVH over `capacity` hit points.
pub fn tree_bytes(capacity: u64) -> u64 {
    TREE_HEADER_BYTES + (2 * capacity.max(1) - 1) * std::mem::size_of::<BvhNode>() as u64
}

/// The bounding box of a hit point's search sphere, padded a little so that no point the
/// leaf's f32 distance test accepts can fall outside it by rounding.
pub fn sphere_box(hp: &GpuHitPoint) -> Aabb {
    Aabb::of_sphere(Vec3::from(hp.position), hp.radius * (1.0 + 1e-5))
}

/// A SAH BVH over the spheres of the valid hit points, in the layout the photon pass traverses:
/// one hit point per leaf, `left_or_first` its index in `hit_points`. Empty when none is valid.
pub fn build_tree(hit_points: &[GpuHitPoint]) -> Vec<BvhNode> {
    let valid: Vec<u32> = (0u32..)
        .zip(hit_points)
        .filter(|(_, hp)| hp.is_valid())
        .map(|(i, _)| i)
        .collect();
    if valid.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = valid
        .iter()
        .map(|&i| sphere_box(&hit_points[i as usize]))
        .collect();
    // With at most one box per leaf the builder splits every larger node (by count where the
    // centres coincide), so every leaf holds exactly one hit point.
    let bvh = build_sah(&boxes, 1);
    bvh.nodes
        .iter()
        .map(|n| {
            if n.count == 0 {
                *n
            } else {
                BvhNode {
                    left_or_first: valid[bvh.indices[n.left_or_first as usize] as usize],
                    count: 1,
                    ..*n
                }
            }
        })
        .collect()
}

/// The tree buffer's contents: the node count, padding, then the nodes.
pub fn tree_bytes_of(nodes: &[BvhNode]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(TREE_HEADER_BYTES as usize + std::mem::size_of_val(nodes));
    let header = [nodes.len() as u32, 0, 0, 0];
    bytes.extend_from_slice(bytemuck::cast_slice(&header));
    bytes.extend_from_slice(bytemuck::cast_slice(nodes));
    bytes
}

/// Indices of the hit points whose sphere contains `p`, found through `nodes` (a tree in the
/// GPU layout), in traversal order. The CPU twin of the photon pass's query.
pub fn tree_range_query(nodes: &[BvhNode], hit_points: &[GpuHitPoint], p: Vec3) -> Vec<u32> {
    let mut found = Vec::new();
    if nodes.is_empty() {
        return found;
    }
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let n = &nodes[i];
        let inside = Aabb {
            min: Vec3::from(n.min),
            max: Vec3::from(n.max),
        }
        .contains_point(p);
        if !inside {
            continue;
        }
        if n.count > 0 {
            let hp = &hit_points[n.left_or_first as usize];
            if Vec3::from(hp.position).distance_squared(p) <= hp.radius * hp.radius {
                found.push(n.left_or_first);
            }
        } else {
            stack.push(n.left_or_first as usize);
            stack.push(n.left_or_first as usize + 1);
        }
    }
    found
}
