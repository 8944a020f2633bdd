#define_import_path common::camera

#import common::scene::scene_info
#import common::pixel_filter::{FILTER_BOX, filter_offset}

// Where on the film, in pixels, a camera sample of `pixel` lands for the uniform pair `u`:
// offset from the pixel centre with the pixel filter's density (common::pixel_filter), the
// filter cut at the film's edge unless samples may leave it (Mitsuba's sample_border).
fn film_position(pixel: vec2<u32>, u: vec2<f32>) -> vec2<f32> {
    // The box filter keeps the plain jitter: the same position for the same numbers as before.
    if scene_info.filter_kind == FILTER_BOX {
        return vec2<f32>(pixel) + u;
    }
    let size = vec2<f32>(f32(scene_info.width), f32(scene_info.height));
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

// Direction of a primary ray for a camera sample of `pixel` drawn from the uniform pair `u`
// (see film_position). Row 0 is the top of the image.
fn camera_direction(pixel: vec2<u32>, u: vec2<f32>) -> vec3<f32> {
    return camera_direction_through(film_position(pixel, u));
}

// Direction of the primary ray through film position `position` (pixels from the top left).
fn camera_direction_through(position: vec2<f32>) -> vec3<f32> {
    let size = vec2<f32>(f32(scene_info.width), f32(scene_info.height));
    let film = position / size;
    let x = (2.0 * film.x - 1.0) * scene_info.tan_half_x;
    let y = (1.0 - 2.0 * film.y) * scene_info.tan_half_y;
    return normalize(scene_info.camera_forward + x * scene_info.camera_right + y * scene_info.camera_up);
}
