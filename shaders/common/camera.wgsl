#define_import_path common::camera

#import common::scene::scene_info

// Direction of a primary ray through `pixel` + `jitter` (jitter in [0,1)^2: a box pixel filter,
// as the references use). Row 0 is the top of the image.
fn camera_direction(pixel: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let size = vec2<f32>(f32(scene_info.width), f32(scene_info.height));
    let film = (vec2<f32>(pixel) + jitter) / size;
    let x = (2.0 * film.x - 1.0) * scene_info.tan_half_x;
    let y = (1.0 - 2.0 * film.y) * scene_info.tan_half_y;
    return normalize(scene_info.camera_forward + x * scene_info.camera_right + y * scene_info.camera_up);
}
