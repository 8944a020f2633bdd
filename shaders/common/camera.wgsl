#define_import_path common::camera

#import common::scene::scene_info
#import common::pixel_filter::{FILTER_BOX, filter_offset, is_signed_filter}
#import common::signed_filter::signed_filter_offset
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
