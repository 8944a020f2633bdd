#define_import_path common::environment

// The light escaping rays see: Mitsuba's `constant` (one radiance) or `envmap` (a lat-long map in
// Mitsuba 3's orientation, src/scene/emitter.rs), evaluated, sampled and given a density.
//
// A map's table in bsdf_tables, from `light.table` (EnvMap::append_gpu_table): the three rows of
// its world-to-local rotation (9), width and height (2) and one unused word, W x H texels as RGB,
// then over its W x (H - 1) cells (the patches between texel centres, over which radiance is
// bilinear): the rows' marginal CDF, each row's conditional CDF, and each cell's probability.
// A sampled cell is uniform in (u, v), and solid angle is 2 pi^2 sin(theta) du dv.

#import common::scene::{scene_info, lights, bsdf_tables, Light, LIGHT_CONSTANT}
#import common::sampling::{PI, sample_uniform_sphere}

const MAP_HEADER: u32 = 12u;

struct MapInfo {
    to_local: mat3x3<f32>,
    width: u32,
    height: u32,
    texels: u32,
    marginal: u32,
    conditional: u32,
    cells: u32,
}

fn table_vec3(i: u32) -> vec3<f32> {
    return vec3<f32>(bsdf_tables[i], bsdf_tables[i + 1u], bsdf_tables[i + 2u]);
}

fn map_info(light: Light) -> MapInfo {
    let t = light.table;
    var info: MapInfo;
    // Stored by rows, WGSL's matrices by columns: transpose so that M * d takes the rows'
    // dot products.
    info.to_local = transpose(mat3x3<f32>(table_vec3(t), table_vec3(t + 3u), table_vec3(t + 6u)));
    info.width = u32(bsdf_tables[t + 9u]);
    info.height = u32(bsdf_tables[t + 10u]);
    info.texels = t + MAP_HEADER;
    info.marginal = info.texels + 3u * info.width * info.height;
    info.conditional = info.marginal + info.height - 1u;
    info.cells = info.conditional + (info.height - 1u) * info.width;
    return info;
}

fn map_texel(info: MapInfo, x: i32, y: i32) -> vec3<f32> {
    let w = i32(info.width);
    let column = ((x % w) + w) % w;
    let row = clamp(y, 0, i32(info.height) - 1);
    return table_vec3(info.texels + 3u * u32(row * w + column));
}

// Mitsuba's (u, v) of a local direction: u = atan2(x, -z) / 2 pi in [0, 1), v = acos(y) / pi.
fn map_uv(local: vec3<f32>) -> vec2<f32> {
    let u = atan2(local.x, -local.z) / (2.0 * PI);
    return vec2<f32>(u - floor(u), acos(clamp(local.y, -1.0, 1.0)) / PI);
}

fn map_eval(info: MapInfo, uv: vec2<f32>) -> vec3<f32> {
    let x = uv.x * f32(info.width) - 0.5;
    let y = clamp(uv.y, 0.0, 1.0) * f32(info.height - 1u);
    let x0 = floor(x);
    let y0 = min(floor(y), f32(info.height - 2u));
    let f = vec2<f32>(x - x0, y - y0);
    let ix = i32(x0);
    let iy = i32(y0);
    let top = mix(map_texel(info, ix, iy), map_texel(info, ix + 1, iy), f.x);
    let bottom = mix(map_texel(info, ix, iy + 1), map_texel(info, ix + 1, iy + 1), f.x);
    return mix(top, bottom, f.y);
}

// Solid-angle density of sampling local direction `local` (at (u, v) `uv`).
fn map_pdf(info: MapInfo, local: vec3<f32>, uv: vec2<f32>) -> f32 {
    let sin_theta = sqrt(max(0.0, 1.0 - local.y * local.y));
    if sin_theta <= 0.0 {
        return 0.0;
    }
    let rows = info.height - 1u;
    let row = min(u32(uv.y * f32(rows)), rows - 1u);
    let w = i32(info.width);
    let column = u32(((i32(floor(uv.x * f32(w) - 0.5)) % w) + w) % w);
    let p = bsdf_tables[info.cells + row * info.width + column];
    return p * f32(info.width * rows) / (2.0 * PI * PI * sin_theta);
}

// The first of `count` CDF entries from `start` that exceeds u, and u's place within its
// interval (so one uniform number picks the interval and a position inside it).
struct CdfPick {
    index: u32,
    remainder: f32,
}

fn pick_in_cdf(start: u32, count: u32, u: f32) -> CdfPick {
    var lo = 0u;
    var hi = count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if u < bsdf_tables[start + mid] {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    let below = select(0.0, bsdf_tables[start + lo - 1u], lo > 0u);
    let width = bsdf_tables[start + lo] - below;
    var pick: CdfPick;
    pick.index = lo;
    pick.remainder = select(0.5, clamp((u - below) / width, 0.0, 0.99999994), width > 0.0);
    return pick;
}

struct EnvironmentSample {
    // Unit world direction towards the environment.
    dir: vec3<f32>,
    radiance: vec3<f32>,
    // Solid-angle density, without the light's selection probability.
    pdf: f32,
}

fn sample_map(light: Light, u: vec2<f32>) -> EnvironmentSample {
    let info = map_info(light);
    let rows = info.height - 1u;
    let row = pick_in_cdf(info.marginal, rows, u.x);
    let column = pick_in_cdf(info.conditional + row.index * info.width, info.width, u.y);
    let uv = vec2<f32>((f32(column.index) + 0.5 + column.remainder) / f32(info.width), (f32(row.index) + row.remainder) / f32(rows));
    let theta = uv.y * PI;
    let phi = uv.x * 2.0 * PI;
    let local = vec3<f32>(sin(phi) * sin(theta), cos(theta), -cos(phi) * sin(theta));
    var s: EnvironmentSample;
    s.dir = normalize(transpose(info.to_local) * local);
    let wrapped = vec2<f32>(uv.x - floor(uv.x), uv.y);
    s.radiance = map_eval(info, wrapped);
    let sin_theta = sin(theta);
    let p = bsdf_tables[info.cells + row.index * info.width + column.index];
    s.pdf = select(0.0, p * f32(info.width * rows) / (2.0 * PI * PI * sin_theta), sin_theta > 0.0);
    return s;
}

fn sample_environment_light(light: Light, u: vec2<f32>) -> EnvironmentSample {
    if light.kind == LIGHT_CONSTANT {
        return EnvironmentSample(sample_uniform_sphere(u), light.radiance, 1.0 / (4.0 * PI));
    }
    return sample_map(light, u);
}

// Radiance arriving from world direction `dir` (unit, away from the scene).
fn environment_light_radiance(light: Light, dir: vec3<f32>) -> vec3<f32> {
    if light.kind == LIGHT_CONSTANT {
        return light.radiance;
    }
    let info = map_info(light);
    return map_eval(info, map_uv(info.to_local * dir));
}

// Solid-angle density of sampling `dir`, without the selection probability.
fn environment_light_pdf(light: Light, dir: vec3<f32>) -> f32 {
    if light.kind == LIGHT_CONSTANT {
        return 1.0 / (4.0 * PI);
    }
    let info = map_info(light);
    let local = info.to_local * dir;
    return map_pdf(info, local, map_uv(local));
}

// What an escaping ray sees, and the density with which light sampling would have chosen its
// direction (selection included), for MIS.
struct Escape {
    radiance: vec3<f32>,
    pdf: f32,
}

fn escaped(dir: vec3<f32>) -> Escape {
    let light = lights[scene_info.environment];
    return Escape(environment_light_radiance(light, dir), light.select_prob * environment_light_pdf(light, dir));
}
