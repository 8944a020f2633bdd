#define_import_path common::camera

#import common::scene::scene_info
#import common::pixel_filter::{FILTER_BOX, filter_offset, filter_radius, filter_weight, is_signed_filter}
#import common::sampling::square_to_disk_concentric

// A dispatch covers a grid of scene_info.width x height pixels: the image, or a tile of it
// at (tile_x, tile_y). Rays and random streams follow image pixels, so a tile renders exactly
// what the whole image would have there. The image may itself be a crop window of the film
// the camera projects: scene_info's plane_origin and plane_step place it.

// The image pixel of grid pixel `pixel`.
fn film_pixel(pixel: vec2<u32>) -> vec2<u32> {
    return pixel + vec2<u32>(scene_info.tile_x, scene_info.tile_y);
}

// The image's index (row-major over the whole image) of grid pixel `pixel_index`: what random
// streams are keyed by. Equal to `pixel_index` when the grid is the image.
fn film_index(pixel_index: u32) -> u32 {
    let pixel = film_pixel(vec2<u32>(pixel_index % scene_info.width, pixel_index / scene_info.width));
    return pixel.y * scene_info.film_width + pixel.x;
}

// The image's size: where samples keep to unless sample_border (a crop window's samples keep
// to the window, as Mitsuba's do).
fn film_size() -> vec2<f32> {
    return vec2<f32>(f32(scene_info.film_width), f32(scene_info.film_height));
}

// A camera sample's place in the image (pixels from the top left) and the weight it counts:
// 1, or for a filter with negative lobes f / (q F_W) (src/scene/filter.rs).
struct FilmSample {
    position: vec2<f32>,
    weight: f32,
}

// Where in the image, in pixels, a camera sample of image pixel `pixel` lands for the uniform
// pair `u`: offset from the pixel centre with the pixel filter's density (common::pixel_filter),
// the filter cut at the image's edge unless samples may leave it (Mitsuba's sample_border).
fn film_position(pixel: vec2<u32>, u: vec2<f32>) -> FilmSample {
    // The box filter keeps the plain jitter: the same position for the same numbers as before.
    if scene_info.filter_kind == FILTER_BOX {
        return FilmSample(vec2<f32>(pixel) + u, 1.0);
    }
    let size = film_size();
    let center = vec2<f32>(pixel) + 0.5;
    var lo = -center;
    var hi = size - center;
    if scene_info.sample_border != 0u {
        lo = vec2<f32>(-1e30);
        hi = vec2<f32>(1e30);
    }
    let kind = scene_info.filter_kind;
    if is_signed_filter(kind) {
        let drawn = signed_filter_offset(u, lo, hi);
        return FilmSample(center + drawn.xy, drawn.z);
    }
    let param = scene_info.filter_param;
    return FilmSample(center + vec2<f32>(filter_offset(kind, param, u.x, lo.x, hi.x), filter_offset(kind, param, u.y, lo.y, hi.y)), 1.0);
}

// A signed filter's offset from a pixel's centre in the window [lo, hi] (offsets) for the uniform pair `u`, and the sample's weight: (offset, weight).
fn signed_filter_offset(u: vec2<f32>, lo: vec2<f32>, hi: vec2<f32>) -> vec3<f32> {
    let x = film_offset(u.x, lo.x, hi.x);
    let y = film_offset(u.y, lo.y, hi.y);
    return vec3<f32>(x.x, y.x, x.y * y.y);
}

// The density, per unit image area, of the signed filter's draws of all pixels at image
// position `position` (each pixel draws one sample from its table density q_p, cut to its
// window on the film): sum_p q_p(position - centre_p), separable in x and y. A sample drawn
// this way and splatted with f / density estimates what a uniformly placed one does
// (path_trace.wgsl `splat`).
fn signed_draw_density(position: vec2<f32>) -> f32 {
    let size = film_size();
    return draw_density_1d(position.x, size.x) * draw_density_1d(position.y, size.y);
}

fn draw_density_1d(t: f32, size: f32) -> f32 {
    let r = scene_filter_radius();
    let first = max(i32(floor(t - r - 0.5)), 0);
    let last = min(i32(ceil(t + r - 0.5)), i32(size) - 1);
    var total = 0.0;
    for (var p = first; p <= last; p++) {
        let center = f32(p) + 0.5;
        total += table_density(t - center, -center, size - center);
    }
    return total;
}

// The table's piecewise-constant density of |f| at `offset`, normalised on the window
// [lo, hi] cut to the support (0 outside it): what film_offset draws from.
fn table_density(offset: f32, window_lo: f32, window_hi: f32) -> f32 {
    let r = scene_filter_radius();
    let lo = max(window_lo, -r);
    let hi = min(window_hi, r);
    if offset < lo || offset > hi {
        return 0.0;
    }
    let per_pixel = filter_nodes_per_pixel();
    let bins = per_pixel * u32(r);
    let j = min(u32(abs(offset) * f32(per_pixel)), bins - 1u);
    let mass = filter_node(j + 1u).x - filter_node(j).x;
    return mass * f32(per_pixel) / (filter_cumulative(hi, 0u) - filter_cumulative(lo, 0u));
}

// Node j of the signed filter's table: (integral of |f|, integral of f) from 0 to its x.
fn filter_node(j: u32) -> vec2<f32> {
    let v = scene_info.filter_table[j / 2u];
    return select(v.xy, v.zw, (j & 1u) == 1u);
}

fn filter_nodes_per_pixel() -> u32 {
    return 2u * (127u / (2u * u32(scene_filter_radius())));
}

fn scene_filter_radius() -> f32 {
    return filter_radius(scene_info.filter_kind, scene_info.filter_param);
}

// The table's cumulative |f| (k 0) or f (k 1) from 0 to `x`, odd, linear between nodes.
fn filter_cumulative(x: f32, k: u32) -> f32 {
    let per_pixel = filter_nodes_per_pixel();
    let r = scene_filter_radius();
    let bins = per_pixel * u32(r);
    let a = min(abs(x), r) * f32(per_pixel);
    let j = min(u32(a), bins - 1u);
    let t = a - f32(j);
    let here = filter_node(j)[k];
    let next = filter_node(j + 1u)[k];
    let value = here + t * (next - here);
    return select(value, -value, x < 0.0);
}

// A signed filter's offset for `u` in [lo, hi] (cut to its support), drawn from the table's
// piecewise-constant |f|, and its weight f / (q F_W): (offset, weight). The CPU mirror is
// WeightedSampler::sample in src/scene/filter.rs.
fn film_offset(u: f32, window_lo: f32, window_hi: f32) -> vec2<f32> {
    let r = scene_filter_radius();
    let per_pixel = filter_nodes_per_pixel();
    let lo = max(window_lo, -r);
    let hi = min(window_hi, r);
    let c_lo = filter_cumulative(lo, 0u);
    let c_hi = filter_cumulative(hi, 0u);
    let target_value = c_lo + u * (c_hi - c_lo);
    let s = abs(target_value);
    var first = 0u;
    var last = per_pixel * u32(r);
    while last - first > 1u {
        let mid = (first + last) / 2u;
        if filter_node(mid).x <= s {
            first = mid;
        } else {
            last = mid;
        }
    }
    let mass = max(filter_node(first + 1u).x - filter_node(first).x, 1.17549435e-38);
    let a = (f32(first) + (s - filter_node(first).x) / mass) / f32(per_pixel);
    let x = clamp(select(a, -a, target_value < 0.0), lo, hi);
    let density = mass * f32(per_pixel) / (c_hi - c_lo);
    let window = filter_cumulative(hi, 1u) - filter_cumulative(lo, 1u);
    let f = filter_weight(scene_info.filter_kind, vec2<f32>(scene_info.filter_param, scene_info.filter_param_b), x);
    return vec2<f32>(x, f / (density * window));
}

// Whether camera rays need a lens sample (a thin lens): then two more numbers per ray.
fn has_lens() -> bool {
    return scene_info.aperture_radius > 0.0;
}

struct CameraRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
    // What the sample counts in its pixel (FilmSample's weight; 1 for a splatted sample).
    weight: f32,
    // Where it crosses the image, in pixels from the top left.
    film_position: vec2<f32>,
}

// The primary ray for a camera sample of image pixel `pixel` drawn from the uniform pair `u`
// (see film_position), through the lens point `lens_u` picks (unused for a pinhole).
fn camera_ray(pixel: vec2<u32>, u: vec2<f32>, lens_u: vec2<f32>) -> CameraRay {
    let sample = film_position(pixel, u);
    var ray = camera_ray_through(sample.position, lens_u);
    ray.weight = sample.weight;
    return ray;
}

// The primary ray through image position `position` (pixels from the top left). A thin lens
// (Mitsuba's thinlens) starts it at a uniform point of the aperture disc and aims it at where
// the pinhole ray meets the focus plane, so only that plane is sharp.
fn camera_ray_through(position: vec2<f32>, lens_u: vec2<f32>) -> CameraRay {
    let plane = scene_info.plane_origin + position * vec2<f32>(scene_info.plane_step_x, scene_info.plane_step_y);
    let toward = scene_info.camera_forward + plane.x * scene_info.camera_right + plane.y * scene_info.camera_up;
    if !has_lens() {
        return CameraRay(scene_info.camera_origin, normalize(toward), 1.0, position);
    }
    let disc = scene_info.aperture_radius * square_to_disk_concentric(lens_u);
    let offset = disc.x * scene_info.camera_right + disc.y * scene_info.camera_up;
    return CameraRay(scene_info.camera_origin + offset, normalize(toward * scene_info.focus_distance - offset), 1.0, position);
}
