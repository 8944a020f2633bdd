//! Texture coordinates on the GPU (for textures to come), on whatever adapter wgpu finds
//! (lavapipe in CI): rays traced by `intersect_scene` and `surface_at` report the uv that
//! Mitsuba's parameterisation gives at the hit, for a placed rectangle, an OBJ with `vt`
//! (flipped in v as Mitsuba's OBJ loader does by default), a mesh without any (the
//! barycentrics) and an unrotated sphere.

mod common;

use common::pass_harness::PassHarness;
use common::*;
use glam::{Vec2, Vec3, Vec4};

const KERNEL: &str = "#import common::scene::NO_HIT
#import common::traversal::intersect_scene
#import common::surface::surface_at
@group(1) @binding(0) var<storage, read> rays: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&out) { return; }
    let origin = rays[2u * id.x].xyz;
    let dir = rays[2u * id.x + 1u].xyz;
    let hit = intersect_scene(origin, dir);
    if hit.prim == NO_HIT {
        out[id.x] = vec4<f32>(-1.0);
        return;
    }
    let surface = surface_at(hit, origin, dir);
    out[id.x] = vec4<f32>(surface.uv, f32(hit.prim), surface.position.z);
}
";

/// The uv `surface_at` reports for each ray (origin, direction), or None on a miss.
fn gpu_uvs(scene: &hppm::scene::Scene, rays: &[(Vec3, Vec3)]) -> Vec<Option<Vec2>> {
    let gpu = gpu();
    let harness = PassHarness::new(&gpu, scene, (4, 4), false);
    let words: Vec<Vec4> = rays
        .iter()
        .flat_map(|(o, d)| [o.extend(1.0), d.normalize().extend(0.0)])
        .collect();
    harness
        .run_kernel("tests/uvs.rs (kernel)", KERNEL, &words, rays.len())
        .iter()
        .map(|v| (v.x >= 0.0).then(|| Vec2::new(v.x, v.y)))
        .collect()
}

/// Straight down (-z) onto the point (x, y, 10) above.
fn down(x: f32, y: f32) -> (Vec3, Vec3) {
    (Vec3::new(x, y, 10.0), Vec3::NEG_Z)
}

/// Each shape's uv at points of known parameterisation, to 1e-4. Would catch: uvs not reaching
/// the GPU, interpolated with the wrong barycentrics, not following a winding swap, OBJ's v not
/// flipped, the rectangle's or the sphere's parameterisation differing from Mitsuba's.
#[test]
fn surface_uvs_follow_mitsubas_parameterisations() {
    let dir = std::env::temp_dir().join(format!("hppm-uvs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    // A triangle at x in [10, 12] with its own uvs, and one (PLY, no uvs) at x in [20, 22].
    std::fs::write(
        dir.join("tri.obj"),
        "v 10 0 0\nv 12 0 0\nv 10 2 0\nvt 0.1 0.2\nvt 0.9 0.2\nvt 0.1 0.6\nf 1/1 2/2 3/3\n",
    )
    .expect("obj");
    std::fs::write(
        dir.join("tri.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         20 0 0\n22 0 0\n20 2 0\n3 0 1 2\n",
    )
    .expect("ply");
    let xml = r#"<scene version="3.0.0">
    <sensor type="perspective"/>
    <shape type="rectangle">
        <transform name="to_world"><scale x="2" y="1"/><translate x="-5"/></transform>
    </shape>
    <shape type="obj"><string name="filename" value="tri.obj"/></shape>
    <shape type="ply"><string name="filename" value="tri.ply"/></shape>
    <shape type="sphere">
        <point name="center" x="30" y="0" z="0"/>
        <float name="radius" value="2"/>
    </shape>
</scene>"#;
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).expect("scene");
    let scene = hppm::loaders::load(&path).expect("scene loads");
    let cases: Vec<((Vec3, Vec3), Vec2)> = vec![
        // Rectangle: local (x, y) in [-1, 1]^2 -> ((x + 1) / 2, (y + 1) / 2); world x = 2 lx - 5.
        (down(-5.0, 0.0), Vec2::new(0.5, 0.5)),
        (down(-6.0, 0.5), Vec2::new(0.25, 0.75)),
        (down(-3.5, -0.9), Vec2::new(0.875, 0.05)),
        // OBJ triangle: barycentrics (u, v) at (10 + 2u, 2v); uv interpolated, then v -> 1 - v.
        (down(10.5, 0.5), {
            let (b1, b2) = (0.25, 0.25);
            let uv = (1.0 - b1 - b2) * Vec2::new(0.1, 0.2)
                + b1 * Vec2::new(0.9, 0.2)
                + b2 * Vec2::new(0.1, 0.6);
            Vec2::new(uv.x, 1.0 - uv.y)
        }),
        // PLY triangle without uvs: the barycentrics.
        (down(20.6, 0.4), Vec2::new(0.3, 0.2)),
        // Sphere: theta from +z, phi from +x towards +y.
        // 30 degrees from the pole towards +x (at the pole itself phi is undefined).
        (down(31.0, 0.0), Vec2::new(0.0, 1.0 / 6.0)),
        // 60 degrees from the pole, phi 45 degrees.
        (
            down(30.0 + 3f32.sqrt() / 2f32.sqrt(), 3f32.sqrt() / 2f32.sqrt()),
            Vec2::new(0.125, 1.0 / 3.0),
        ),
        (
            (Vec3::new(40.0, 0.0, 0.0), Vec3::NEG_X),
            Vec2::new(0.0, 0.5),
        ),
        (
            (Vec3::new(30.0, 10.0, 0.0), Vec3::NEG_Y),
            Vec2::new(0.25, 0.5),
        ),
        ((Vec3::new(30.0, -10.0, 0.0), Vec3::Y), Vec2::new(0.75, 0.5)),
    ];
    let rays: Vec<(Vec3, Vec3)> = cases.iter().map(|c| c.0).collect();
    let got = gpu_uvs(&scene, &rays);
    for ((ray, expected), uv) in cases.iter().zip(got) {
        let uv = uv.unwrap_or_else(|| panic!("ray {ray:?} missed"));
        assert!(
            (uv - *expected).abs().max_element() < 1e-4,
            "ray {ray:?}: uv {uv}, expected {expected}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
