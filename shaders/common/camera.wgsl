#define_import_path common::camera

#import common::scene::scene_info
#import common::pixel_filter::{FILTER_BOX, filter_offset}

// A dispatch covers a grid of scene_info.width x height pixels: the whole film, or a tile of it
// at (tile_x, tile_y). Rays and random streams follow film pixels, so a tile renders exactly
// what the whole film would have there.

// The film pixel of grid pixel `pixel`.
fn film_pixel(pixel: vec2<u32>) -> vec2<u32> {
    return pixel + vec2<u32>(scene_info.tile_x, scene_info.tile_y);
}

// The film's index (row-major over the whole image) of grid pixel `pixel_index`: what random
// streams are keyed by. Equal to `pixel_index` when the grid is the film.
fn film_index(pixel_index: u32) -> u32 {
    let pixel = film_pixel(vec2<u32>(pixel_index % scene_info.width, pixel_index / scene_info.width));
    return pixel.y * scene_info.film_width + pixel.x;
}

fn film_size() -> vec2<f32> {
    return vec2<f32>(f32(scene_info.film_width), f32(scene_info.film_height));
}

// Where on the film, in pixels, a camera sample of film pixel `pixel` lands for the uniform
// pair `u`: offset from the pixel centre with the pixel filter's density (common::pixel_filter),
// the filter cut at the film's edge unless samples may leave it (Mitsuba's sample_border).
fn film_position(pixel: vec2<u32>, u: vec2<f32>) -> vec2<f32> {
    // The box filter keeps the plain jitter: the same position for the same numbers as before.
    if scene_info.filter_kind == FILTER_BOX {
        return vec2<f32>(pixel) + u;
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
    let param = scene_info.filter_param;
    return center + vec2<f32>(filter_offset(kind, param, u.x, lo.x, hi.x), filter_offset(kind, param, u.y, lo.y, hi.y));
}

// Direction of a primary ray for a camera sample of film pixel `pixel` drawn from the uniform
// pair `u` (see film_position). Row 0 is the top of the image.
fn camera_direction(pixel: vec2<u32>, u: vec2<f32>) -> vec3<f32> {
    return camera_direction_through(film_position(pixel, u));
}

// Direction of the primary ray through film position `position` (pixels from the top left).
fn camera_direction_through(position: vec2<f32>) -> vec3<f32> {
    let film = position / film_size();
    let x = (2.0 * film.x - 1.0) * scene_info.tan_half_x;
    let y = (1.0 - 2.0 * film.y) * scene_info.tan_half_y;
    return normalize(scene_info.camera_forward + x * scene_info.camera_right + y * scene_info.camera_up);
}
