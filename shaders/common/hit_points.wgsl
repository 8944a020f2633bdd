#define_import_path common::hit_points

// Hit points (camera-path vertices where photon mapping takes over), their radii, the photons
// arriving at diffuse surfaces, the BVH over hit points, and the per-iteration photon deposits.
// Layouts mirror src/passes/hit_points.rs (tests/layouts.rs checks every offset).

struct HitPoint {
    position: vec3<f32>,
    // Pixel index, or NO_PIXEL when the slot holds no hit point this iteration.
    pixel: u32,
    // Front normal of the (one-sided) diffuse surface.
    normal: vec3<f32>,
    // Search radius for this iteration's gather: the estimator's radius for this slot (its
    // `radii` output), or the `RadiusRule`'s first radius while the estimator has none.
    radius: f32,
    // Unit direction towards where the camera path came from.
    wo: vec3<f32>,
    // Path segments from the camera to this point: a photon path may add at most
    // max_depth - depth segments, so photon mapping obeys the same depth rule as path tracing.
    depth: u32,
    // Camera path throughput times the diffuse BSDF value (albedo / pi): the radiance one unit
    // of photon flux per unit area adds to the pixel.
    weight: vec3<f32>,
    // Width of one pixel at this point (distance travelled times the pixel's angle).
    footprint: f32,
}

// Written by the camera pass.
struct HitPointsHeader {
    // Hit-point slots per pixel (merge depth).
    slots_per_pixel: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

struct HitPointBuffer {
    header: HitPointsHeader,
    points: array<HitPoint>,
}

// Written by the estimator (when prepared; pppm every iteration): how the camera pass sets a
// slot's first radius.
struct RadiusRule {
    // Absolute initial radius in scene units; 0 means `radius_pixels` footprints.
    initial_radius: f32,
    radius_pixels: f32,
    // Floor relative to the scene's size, so radii never underflow.
    min_radius: f32,
    // Factor on the first radius before the floor: 1, or pppm's schedule for this iteration.
    scale: f32,
}

// The estimator's radius per hit-point slot; 0 while the slot has none yet.
struct RadiusBuffer {
    rule: RadiusRule,
    radii: array<f32>,
}

// A photon arriving at a diffuse surface where it deposits.
struct PhotonHit {
    position: vec3<f32>,
    // Camera segments the full path may still have (UNBOUNDED when the depth is unbounded).
    remaining: u32,
    // Unit direction towards where the photon came from.
    wi: vec3<f32>,
    // 1: deposited where the photon scattered in a medium (a volumetric caustic), gathered by
    // camera paths' medium vertices only; 0: on a surface.
    in_medium: u32,
    // Flux per photon of this iteration.
    flux: vec3<f32>,
    pad_b: u32,
}

// As photon_trace writes them: `count` hits were stored, `dropped` did not fit.
struct PhotonHitsOut {
    count: atomic<u32>,
    dropped: atomic<u32>,
    pad_a: u32,
    pad_b: u32,
    hits: array<PhotonHit>,
}

// The same buffer as the gathers read it.
struct PhotonHitsIn {
    count: u32,
    dropped: u32,
    pad_a: u32,
    pad_b: u32,
    hits: array<PhotonHit>,
}

const NO_PIXEL: u32 = 0xffffffffu;

// BVH over hit-point spheres. Every leaf holds exactly one hit point: `count` == 1 and
// `left_or_first` is its index. Interior nodes have `count` == 0 and their right child follows
// the left one. The GPU builder (passes/lbvh.wgsl) gives every slot a leaf and slots without a
// hit point an empty box (min > max), which no point is inside.
struct HitPointNode {
    min: vec3<f32>,
    left_or_first: u32,
    max: vec3<f32>,
    count: u32,
}

struct HitPointTree {
    node_count: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
    nodes: array<HitPointNode>,
}

const TREE_STACK_SIZE: u32 = 64u;

// Photons gathered by one hit point in one iteration. Flux is an RGB sum added with float
// atomics where the device has them, else with a compare-and-swap loop on the f32 bits.
//
// The photons within half the radius are summed again (`inner_*`): the estimate over the half
// disc against the whole one measures the kernel's bias (docs/error-estimate.md).
#ifdef FLOAT_ATOMICS
struct DepositCell {
    count: atomic<u32>,
    flux: array<atomic<f32>, 3>,
    inner_flux: array<atomic<f32>, 3>,
    inner_count: atomic<u32>,
}
#else
struct DepositCell {
    count: atomic<u32>,
    flux: array<atomic<u32>, 3>,
    inner_flux: array<atomic<u32>, 3>,
    inner_count: atomic<u32>,
}
#endif

// Radius of a slot used for the first time.
fn initial_radius(rule: RadiusRule, footprint: f32) -> f32 {
    var r = rule.initial_radius;
    if r <= 0.0 {
        r = rule.radius_pixels * footprint;
    }
    return max(r * rule.scale, rule.min_radius);
}

fn point_in_box(p: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    return all(p >= lo) && all(p <= hi);
}
