#define_import_path common::sampling

const PI: f32 = 3.14159265358979323846;
const INV_PI: f32 = 0.31830988618379067154;

// Orthonormal basis around a unit normal (Duff et al. 2017, "Building an Orthonormal Basis,
// Revisited"): branch-free and stable for every direction.
fn basis_from_normal(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}

// Cosine-weighted direction around `n`; pdf = cos(theta) / pi.
fn sample_cosine_hemisphere(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let local = vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
    return normalize(basis_from_normal(n) * local);
}

// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
fn sample_uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(0.0, 1.0 - z * z));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// Uniform direction within the cone around unit `axis` whose solid angle is
// 2 pi `one_minus_cos_max`; pdf = 1 / (2 pi one_minus_cos_max). Taking 1 - cos(theta_max)
// rather than cos(theta_max) keeps narrow cones accurate.
fn sample_cone(axis: vec3<f32>, one_minus_cos_max: f32, u: vec2<f32>) -> vec3<f32> {
    let cos_t = 1.0 - u.x * one_minus_cos_max;
    let sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    let phi = 2.0 * PI * u.y;
    let local = vec3<f32>(sin_t * cos(phi), sin_t * sin(phi), cos_t);
    return normalize(basis_from_normal(axis) * local);
}

// Uniform barycentrics (b1, b2) on a triangle (square-root parametrisation).
fn sample_triangle_barycentrics(u: vec2<f32>) -> vec2<f32> {
    let su = sqrt(u.x);
    return vec2<f32>(1.0 - su, u.y * su);
}

// Veach's power heuristic with beta = 2, the weight of the strategy with density `a`.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 <= 0.0 {
        return 0.0;
    }
    return a2 / (a2 + b2);
}

fn max_component(v: vec3<f32>) -> f32 {
    return max(v.x, max(v.y, v.z));
}

// True for NaN and +-Inf: the exponent bits are all ones.
fn is_not_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u;
}

fn any_not_finite(v: vec3<f32>) -> bool {
    return is_not_finite(v.x) || is_not_finite(v.y) || is_not_finite(v.z);
}

// Shirley and Chiu's concentric map of the unit square onto the unit disk (as Mitsuba writes it).
fn square_to_disk_concentric(u: vec2<f32>) -> vec2<f32> {
    let x = 2.0 * u.x - 1.0;
    let y = 2.0 * u.y - 1.0;
    let quarter = 0.25 * PI;
    var r = 0.0;
    var phi = 0.0;
    if x == 0.0 && y == 0.0 {
        return vec2<f32>(0.0);
    } else if x * x > y * y {
        r = x;
        phi = quarter * (y / x);
    } else {
        r = y;
        phi = 2.0 * quarter - quarter * (x / y);
    }
    return vec2<f32>(r * cos(phi), r * sin(phi));
}

// Cosine-weighted local direction (z up) through the concentric map, as Mitsuba samples it;
// pdf = z / pi.
fn square_to_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let p = square_to_disk_concentric(u);
    return vec3<f32>(p.x, p.y, sqrt(max(1.0 - dot(p, p), 0.0)));
}

// Rec. 709 luminance of linear RGB (Mitsuba's luminance; src/scene/texture.rs).
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.212671, 0.715160, 0.072169));
}
