//! Mitsuba 3's `checkerboard` and `bitmap` textures: the CPU reference against hand-computed
//! values (Mitsuba's checker rule, Dr.Jit's bilinear lookup and wrap modes, sRGB decoding),
//! the loader's errors, the WGSL lookup against the CPU one on a table of uvs, renders of a
//! textured plane under a point light against the analytic image, and the hybrid against `pt`
//! on a box whose colours are textures.

mod common;

use common::pass_harness::PassHarness;
use common::*;
use glam::{Mat4, Vec2, Vec3, Vec4};
use hppm::scene::texture::{Bitmap, Filter, Texture, UvTransform, WrapMode, srgb_to_linear};

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("hppm-textures-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).abs().max_element() <= tolerance
}

fn checkerboard(to_uv: UvTransform) -> Texture {
    Texture::Checkerboard {
        color0: Vec3::new(0.9, 0.5, 0.1),
        color1: Vec3::new(0.1, 0.2, 0.3),
        to_uv,
    }
}

/// Mitsuba's rule: `color0` where the fractional parts of u and v are both above 1/2 or both
/// not (a half exactly is not above), `color1` elsewhere, after `to_uv` (a 4x4 transform keeps
/// its x, y block and translation). Would catch the colours swapped, `fract` of negative
/// coordinates taken towards zero, the comparison at 1/2 the wrong way, the translation lost.
#[test]
fn checkerboard_follows_mitsubas_rule() {
    let c0 = Vec3::new(0.9, 0.5, 0.1);
    let c1 = Vec3::new(0.1, 0.2, 0.3);
    let plain = checkerboard(UvTransform::IDENTITY);
    for (uv, expected) in [
        ((0.25, 0.25), c0),
        ((0.75, 0.75), c0),
        ((0.75, 0.25), c1),
        ((0.25, 0.75), c1),
        ((0.5, 0.25), c0),
        ((0.5, 0.75), c1),
        ((-0.25, -0.25), c0),
        ((-0.25, 0.25), c1),
        ((1.75, -3.75), c1),
    ] {
        let got = plain.eval(Vec2::new(uv.0, uv.1));
        assert_eq!(got, expected, "uv {uv:?}");
    }
    let scaled = checkerboard(UvTransform::from_mat4(Mat4::from_scale(Vec3::new(
        4.0, 2.0, 1.0,
    ))));
    assert_eq!(scaled.eval(Vec2::new(0.1, 0.1)), c0); // (0.4, 0.2)
    assert_eq!(scaled.eval(Vec2::new(0.15, 0.1)), c1); // (0.6, 0.2)
    assert_eq!(scaled.eval(Vec2::new(0.15, 0.3)), c0); // (0.6, 0.6)
    // As a scalar (a roughness) Mitsuba swaps the colours and takes their luminance.
    let luminance = |c: Vec3| 0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z;
    assert_eq!(plain.eval_1(Vec2::new(0.25, 0.25)), luminance(c1));
    assert_eq!(plain.eval_1(Vec2::new(0.75, 0.25)), luminance(c0));
    let moved = checkerboard(UvTransform::from_mat4(Mat4::from_translation(Vec3::new(
        0.5, 0.0, 7.0,
    ))));
    assert_eq!(moved.eval(Vec2::new(0.25, 0.25)), c1); // (0.75, 0.25)
    // Mitsuba's defaults and its scalar mean (the channel means averaged).
    let scene = scene_with_texture(
        "defaults",
        r#"<texture type="checkerboard" name="reflectance"/>"#,
    );
    let t = &scene.textures[0];
    assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Vec3::splat(0.4));
    assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Vec3::splat(0.2));
    assert!((t.mean() - 0.3).abs() < 1e-6);
}

/// A 3x2 bitmap whose texels all differ: texel (x, y) = (x, y, 1 + x + 3 y) / 8.
fn bitmap(wrap: WrapMode, filter: Filter) -> Bitmap {
    let texels = (0..2)
        .flat_map(|y| {
            (0..3).map(move |x| Vec3::new(x as f32, y as f32, (1 + x + 3 * y) as f32) / 8.0)
        })
        .collect();
    Bitmap {
        width: 3,
        height: 2,
        bytes: None,
        texels,
        wrap,
        filter,
        to_uv: UvTransform::IDENTITY,
        source: "test".into(),
    }
}

fn t(x: i32, y: i32) -> Vec3 {
    Vec3::new(x as f32, y as f32, (1 + x + 3 * y) as f32) / 8.0
}

/// Dr.Jit's lookup: texel centres at ((i + 1/2) / w, (j + 1/2) / h), row 0 at v = 0, bilinear
/// weights of the four neighbours, each index wrapped alone (repeat: modulo; mirror: period
/// 2n, the edge texel repeated; clamp), nearest by floor(uv * res). Values computed by hand.
/// Would catch a half-texel shift, u and v (or width and height) swapped, a wrap mode that
/// mirrors about the texel centre, weights the wrong way round.
#[test]
fn bitmap_lookups_match_hand_computed_values() {
    let repeat = bitmap(WrapMode::Repeat, Filter::Bilinear);
    let mirror = bitmap(WrapMode::Mirror, Filter::Bilinear);
    let clamp = bitmap(WrapMode::Clamp, Filter::Bilinear);
    let uv = |u: f32, v: f32| Vec2::new(u, v);
    // Texel centres are the texels.
    for (x, y) in [(0, 0), (1, 0), (2, 0), (0, 1), (2, 1)] {
        let at = uv((x as f32 + 0.5) / 3.0, (y as f32 + 0.5) / 2.0);
        assert!(close(repeat.eval(at), t(x, y), 1e-6), "texel ({x}, {y})");
    }
    // A quarter of the way from texel (0, 0) to (1, 0), and half-way down to row 1.
    let at = uv((0.5 + 0.25) / 3.0, 0.5);
    let expected =
        0.5 * (0.75 * t(0, 0) + 0.25 * t(1, 0)) + 0.5 * (0.75 * t(0, 1) + 0.25 * t(1, 1));
    assert!(close(repeat.eval(at), expected, 1e-6));
    // u = 0: half-way between texel -1 and texel 0 (row 0 centre).
    let at = uv(0.0, 0.25);
    assert!(
        close(repeat.eval(at), 0.5 * (t(2, 0) + t(0, 0)), 1e-6),
        "repeat"
    );
    assert!(close(mirror.eval(at), t(0, 0), 1e-6), "mirror");
    assert!(close(clamp.eval(at), t(0, 0), 1e-6), "clamp");
    // Texel -2 exactly: repeat reads 1, mirror reads 1 (-1 -> 0, -2 -> 1), clamp 0.
    let at = uv(-1.5 / 3.0, 0.25);
    assert!(close(repeat.eval(at), t(1, 0), 1e-6), "repeat -2");
    assert!(close(mirror.eval(at), t(1, 0), 1e-6), "mirror -2");
    assert!(close(clamp.eval(at), t(0, 0), 1e-6), "clamp -2");
    // Texel 4 (one period on): repeat 1, mirror 4 -> 6-1-4 = 1, clamp 2; texel 5: 2, 0, 2.
    let at = uv(4.5 / 3.0, 0.25);
    assert!(close(repeat.eval(at), t(1, 0), 1e-6), "repeat 4");
    assert!(close(mirror.eval(at), t(1, 0), 1e-6), "mirror 4");
    assert!(close(clamp.eval(at), t(2, 0), 1e-6), "clamp 4");
    let at = uv(5.5 / 3.0, 0.25);
    assert!(close(repeat.eval(at), t(2, 0), 1e-6), "repeat 5");
    assert!(close(mirror.eval(at), t(0, 0), 1e-6), "mirror 5");
    // Rows wrap too: v = 1.25 is row 0's centre again (repeat), row 1 mirrored.
    let at = uv(0.5 / 3.0, 1.25);
    assert!(close(repeat.eval(at), t(0, 0), 1e-6), "repeat v");
    assert!(close(mirror.eval(at), t(0, 1), 1e-6), "mirror v");
    // Nearest: floor(uv * res).
    let nearest = bitmap(WrapMode::Repeat, Filter::Nearest);
    assert_eq!(nearest.eval(uv(0.33, 0.49)), t(0, 0));
    assert_eq!(nearest.eval(uv(0.34, 0.51)), t(1, 1));
    assert_eq!(nearest.eval(uv(-0.01, 0.1)), t(2, 0));
    // to_uv applies first: scale 2 about u maps u = 0.25 to texel centre... (0.5 -> 1.5/3).
    let mut scaled = bitmap(WrapMode::Repeat, Filter::Bilinear);
    scaled.to_uv = UvTransform::from_mat4(
        Mat4::from_translation(Vec3::new(1.0 / 6.0, 0.0, 0.0))
            * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)),
    );
    assert!(close(scaled.eval(uv(1.0 / 6.0, 0.25)), t(1, 0), 1e-6));
    // Mitsuba's mean of a bitmap: its mean luminance.
    let luminance = |c: Vec3| 0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z;
    let mean = (0..2)
        .flat_map(|y| (0..3).map(move |x| luminance(t(x, y))))
        .sum::<f32>()
        / 6.0;
    // As a scalar, the luminance of the lookup.
    let at = uv((0.5 + 0.25) / 3.0, 0.5);
    let repeat = Texture::Bitmap(repeat);
    assert!((repeat.eval_1(at) - luminance(repeat.eval(at))).abs() < 1e-7);
    assert!((repeat.mean() - mean).abs() < 1e-6);
}

/// A diffuse rectangle whose reflectance is `texture` (XML), in a scene written to a temp dir
/// that also holds `files`.
fn scene_with_texture(name: &str, texture: &str) -> hppm::scene::Scene {
    let dir = temp_dir(name);
    write_test_images(&dir);
    let xml = plane_scene(&format!("<bsdf type=\"diffuse\">{texture}</bsdf>"));
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).expect("scene");
    hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A unit-square... the rectangle [-1, 1]^2 at z = 0 seen from z = 2, under a point light.
fn plane_scene(bsdf: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">{bsdf}</shape>
    <emitter type="point"><point name="position" x="0.3" y="-0.2" z="1.5"/>
        <rgb name="intensity" value="3"/></emitter>
</scene>"#
    )
}

/// 8-bit PNGs (sRGB) and an EXR (linear) for the loader tests.
fn write_test_images(dir: &std::path::Path) {
    let levels = [0u8, 10, 128, 255];
    let png = image::RgbImage::from_fn(4, 1, |x, _| {
        let v = levels[x as usize];
        image::Rgb([v, 255 - v, v / 2])
    });
    png.save(dir.join("levels.png")).expect("png");
    let grid = image::RgbImage::from_fn(4, 4, |x, y| {
        image::Rgb([
            40 + 60 * x as u8,
            30 + 70 * y as u8,
            200 - 40 * ((x + y) % 3) as u8,
        ])
    });
    grid.save(dir.join("grid.png")).expect("png");
    image::RgbImage::from_pixel(8, 8, image::Rgb([128, 64, 200]))
        .save(dir.join("flat.jpg"))
        .expect("jpeg");
    exr::prelude::write_rgb_file(dir.join("linear.exr"), 2, 1, |x, _| {
        if x == 0 {
            (0.5f32, 2.0f32, 0.25f32)
        } else {
            (0.0, 1.0, 8.0)
        }
    })
    .expect("exr");
    std::fs::write(dir.join("broken.png"), b"\x89PNG\r\n\x1a\nnot really a png").expect("broken");
}

/// PNG and JPEG are decoded from sRGB to linear (each texel, before filtering, as Mitsuba's
/// 8-bit textures decode on lookup) unless `raw`; EXR is linear as stored. Would catch a
/// missing or doubled decode, gamma 2.2 in place of the sRGB curve, `raw` ignored.
#[test]
fn bitmaps_are_decoded_from_srgb_unless_raw() {
    assert!((srgb_to_linear(10.0 / 255.0) - 10.0 / 255.0 / 12.92).abs() < 1e-7);
    assert!((srgb_to_linear(128.0 / 255.0) - 0.215861).abs() < 1e-5);
    assert_eq!(srgb_to_linear(1.0), 1.0);
    let nearest = r#"<string name="filter_type" value="nearest"/>"#;
    let srgb = scene_with_texture(
        "srgb",
        &format!(
            r#"<texture type="bitmap" name="reflectance"><string name="filename" value="levels.png"/>{nearest}</texture>"#
        ),
    );
    let raw = scene_with_texture(
        "raw",
        &format!(
            r#"<texture type="bitmap" name="reflectance"><string name="filename" value="levels.png"/><boolean name="raw" value="true"/>{nearest}</texture>"#
        ),
    );
    let levels = [0u8, 10, 128, 255];
    for (x, v) in levels.iter().enumerate() {
        let at = Vec2::new((x as f32 + 0.5) / 4.0, 0.5);
        let enc = Vec3::new(*v as f32, (255 - v) as f32, (v / 2) as f32) / 255.0;
        let lin = Vec3::new(
            srgb_to_linear(enc.x),
            srgb_to_linear(enc.y),
            srgb_to_linear(enc.z),
        );
        assert!(
            close(srgb.textures[0].eval(at), lin, 1e-6),
            "sRGB texel {x}"
        );
        assert!(close(raw.textures[0].eval(at), enc, 1e-6), "raw texel {x}");
    }
    let exr = scene_with_texture(
        "exr",
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="linear.exr"/><string name="filter_type" value="nearest"/></texture>"#,
    );
    assert_eq!(
        exr.textures[0].eval(Vec2::new(0.25, 0.5)),
        Vec3::new(0.5, 2.0, 0.25)
    );
    assert_eq!(
        exr.textures[0].eval(Vec2::new(0.75, 0.5)),
        Vec3::new(0.0, 1.0, 8.0)
    );
    let jpeg = scene_with_texture(
        "jpeg",
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="flat.jpg"/></texture>"#,
    );
    let expected = Vec3::new(
        srgb_to_linear(128.0 / 255.0),
        srgb_to_linear(64.0 / 255.0),
        srgb_to_linear(200.0 / 255.0),
    );
    // JPEG is lossy: a flat image comes back within a few levels.
    assert!(close(
        jpeg.textures[0].eval(Vec2::splat(0.5)),
        expected,
        0.04
    ));
    // The diffuse BSDF's constant holds the texture's mean (plastic's sampling weight uses it).
    let Some(&hppm::bsdfs::diffuse::Diffuse { reflectance }) = srgb.materials[0].bsdf.get() else {
        panic!("diffuse expected");
    };
    assert_eq!(reflectance, Vec3::splat(srgb.textures[0].mean()));
}

fn load_error(name: &str, bsdf: &str) -> String {
    let dir = temp_dir(name);
    write_test_images(&dir);
    let path = dir.join("scene.xml");
    std::fs::write(&path, plane_scene(bsdf)).expect("scene");
    match hppm::loaders::load(&path) {
        Ok(_) => panic!("{name}: the scene loaded"),
        Err(e) => e.to_string(),
    }
}

/// Bad texture files and parameters are errors naming the file and line (the texture's own
/// file where it is the file that is bad) and what is supported.
#[test]
fn bad_textures_are_errors_naming_file_line_and_what_is_supported() {
    let bitmap = |file: &str| {
        format!(
            r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="{file}"/></texture></bsdf>"#
        )
    };
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        ("missing", bitmap("missing.png"), vec!["scene.xml:9:", "missing.png"]),
        ("broken", bitmap("broken.png"), vec!["scene.xml:9:", "broken.png"]),
        ("format", bitmap("levels.tga"), vec!["levels.tga", ".png, .jpg, .jpeg, .bmp, .exr"]),
        (
            "plugin",
            r#"<bsdf type="diffuse"><texture type="noise" name="reflectance"/></bsdf>"#.into(),
            vec!["scene.xml:9:", "\"noise\"", "checkerboard, bitmap"],
        ),
        (
            "param",
            r#"<bsdf type="diffuse"><texture type="checkerboard" name="reflectance"><float name="scale" value="2"/></texture></bsdf>"#.into(),
            vec!["scene.xml:9:", "\"scale\"", "color0, color1, to_uv"],
        ),
        (
            "wrap",
            r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="grid.png"/><string name="wrap_mode" value="border"/></texture></bsdf>"#.into(),
            vec!["scene.xml:9:", "border", "repeat, mirror, clamp"],
        ),
        (
            "alpha",
            r#"<bsdf type="roughplastic"><texture type="checkerboard" name="alpha"/></bsdf>"#.into(),
            vec!["scene.xml:9:", "takes no texture", "specular_reflectance"],
        ),
        (
            "ref",
            r#"<bsdf type="diffuse"><ref name="reflectance" id="nowhere"/></bsdf>"#.into(),
            vec!["scene.xml:9:", "nowhere"],
        ),
    ];
    for (name, bsdf, needles) in cases {
        let message = load_error(name, &bsdf);
        eprintln!("{name}: {message}");
        for needle in needles {
            assert!(
                message.contains(needle),
                "{name}: {message:?} lacks {needle:?}"
            );
        }
    }
}

const KERNEL: &str = "#import common::texture::{texture_eval, texture_eval_1}
@group(1) @binding(0) var<storage, read> queries: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&out) { return; }
    let q = queries[id.x];
    out[id.x] = vec4<f32>(texture_eval(u32(q.z), q.xy), texture_eval_1(u32(q.z), q.xy));
}
";

/// `texture_eval` and `texture_eval_1` in WGSL for each (texture index, uv).
fn gpu_lookups(scene: &hppm::scene::Scene, queries: &[(u32, Vec2)]) -> Vec<Vec4> {
    let gpu = gpu();
    let harness = PassHarness::new(&gpu, scene, (4, 4), false);
    let words: Vec<Vec4> = queries
        .iter()
        .map(|(i, uv)| Vec4::new(uv.x, uv.y, *i as f32, 0.0))
        .collect();
    harness.run_kernel("tests/textures.rs (kernel)", KERNEL, &words, queries.len())
}

/// The WGSL lookup (colour and scalar) equals the CPU reference on 4000 uvs over [-3, 4]^2 for a checkerboard
/// (scaled, rotated, translated) and bitmaps with every wrap mode and both filters, sRGB and
/// raw (within 2e-5; checker cells within 1e-4 of an edge are skipped, where one rounding may
/// pick either colour). Would catch a header field out of place, rows and columns swapped,
/// a wrap mode or the half-texel offset differing, a texture index off by one, an 8-bit texel
/// (kept as its bytes on the GPU) decoded otherwise than the CPU decodes it, or a float one
/// (EXR) read as bytes.
#[test]
fn gpu_lookup_equals_cpu_reference() {
    let dir = temp_dir("gpu");
    write_test_images(&dir);
    let shape = |i: usize, bsdf: String| {
        format!(
            r#"<shape type="rectangle"><transform name="to_world"><translate x="{}"/></transform>{bsdf}</shape>"#,
            3 * i
        )
    };
    let textures = [
        r#"<texture type="checkerboard" name="reflectance"><rgb name="color0" value="0.9, 0.5, 0.1"/>
            <transform name="to_uv"><scale x="3" y="2"/><rotate z="1" angle="30"/><translate x="0.3" y="-0.1"/></transform></texture>"#,
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="grid.png"/></texture>"#,
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="grid.png"/><string name="wrap_mode" value="mirror"/>
            <transform name="to_uv"><scale x="1.7" y="0.6"/><translate x="0.1"/></transform></texture>"#,
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="levels.png"/><string name="wrap_mode" value="clamp"/><boolean name="raw" value="true"/></texture>"#,
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="grid.png"/><string name="filter_type" value="nearest"/><string name="wrap_mode" value="mirror"/></texture>"#,
        r#"<texture type="bitmap" name="reflectance"><string name="filename" value="linear.exr"/><string name="wrap_mode" value="clamp"/></texture>"#,
    ];
    let shapes: String = textures
        .iter()
        .enumerate()
        .map(|(i, t)| shape(i, format!(r#"<bsdf type="diffuse">{t}</bsdf>"#)))
        .collect();
    let xml = format!(
        r#"<scene version="3.0.0"><sensor type="perspective"/>{shapes}
        <shape type="rectangle"><transform name="to_world"><translate x="-3"/></transform>
            <bsdf type="plastic"><ref name="specular_reflectance" id="spec"/></bsdf></shape></scene>"#
    )
    .replace(
        "<sensor type=\"perspective\"/>",
        r#"<sensor type="perspective"/><texture type="checkerboard" id="spec"/>"#,
    );
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).expect("scene");
    let scene = hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.textures.len(), textures.len() + 1);
    assert!(scene.features().textures);
    let mut rng = common::rng::Rng(0x9e37_79b9_7f4a_7c15);
    let mut queries = Vec::new();
    for i in 0..scene.textures.len() as u32 {
        for _ in 0..4000 / scene.textures.len() {
            let uv = Vec2::new(-3.0 + 7.0 * rng.unit(), -3.0 + 7.0 * rng.unit());
            if let Texture::Checkerboard { to_uv, .. } = &scene.textures[i as usize] {
                let p = to_uv.apply(uv) * 2.0;
                let near_edge = |x: f32| (x - x.round()).abs() < 2e-4;
                if near_edge(p.x) || near_edge(p.y) {
                    continue;
                }
            }
            queries.push((i, uv));
        }
    }
    let gpu = gpu_lookups(&scene, &queries);
    let mut worst = 0.0f32;
    for ((i, uv), got) in queries.iter().zip(&gpu) {
        let texture = &scene.textures[*i as usize];
        let cpu = texture.eval(*uv).extend(texture.eval_1(*uv));
        let error = (cpu - *got).abs().max_element() / cpu.abs().max_element().max(1.0);
        worst = worst.max(error);
        assert!(error <= 2e-5, "texture {i} at {uv}: GPU {got}, CPU {cpu}");
    }
    eprintln!("{} lookups, largest difference {worst:.2e}", queries.len());
}

/// The analytic image of the plane in `plane_scene` with reflectance `albedo(uv)`: each pixel
/// the mean over an 8x8 grid of its area of albedo * E / pi, E = I cos / d^2 from the point
/// light; `None` where the albedo is not constant over the pixel and `constant_only`.
fn analytic_image(
    scene: &hppm::scene::Scene,
    albedo: impl Fn(Vec2) -> Vec3,
    constant_only: bool,
) -> Vec<Option<Vec3>> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let u = hppm::gpu_scene::layout::GpuScene::new(scene, w, h)
        .expect("layout")
        .uniform;
    let origin = Vec3::from_array(u.camera_origin);
    let light = scene.point_lights[0];
    let n = 8;
    let mut out = Vec::new();
    for py in 0..h {
        for px in 0..w {
            let mut sum = Vec3::ZERO;
            let mut first = None;
            let mut constant = true;
            for j in 0..n {
                for i in 0..n {
                    let fx = px as f32 + (i as f32 + 0.5) / n as f32;
                    let fy = py as f32 + (j as f32 + 0.5) / n as f32;
                    let x = u.plane_origin[0] + fx * u.plane_step_x;
                    let y = u.plane_origin[1] + fy * u.plane_step_y;
                    let dir = Vec3::from_array(u.camera_forward)
                        + x * Vec3::from_array(u.camera_right)
                        + y * Vec3::from_array(u.camera_up);
                    let p = origin - dir * (origin.z / dir.z);
                    let uv = Vec2::new((p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0);
                    let a = albedo(uv);
                    constant &= *first.get_or_insert(a) == a;
                    let to_light = light.position - p;
                    let d2 = to_light.length_squared();
                    let cos = to_light.z / d2.sqrt();
                    sum += a * light.intensity * cos / d2 / std::f32::consts::PI;
                }
            }
            out.push((constant || !constant_only).then_some(sum / (n * n) as f32));
        }
    }
    out
}

/// Each pixel's albedo on the plane of `plane_scene` where it is the same over the whole pixel
/// (an 8x8 grid of its area), else `None`.
fn pixel_albedos(scene: &hppm::scene::Scene, albedo: impl Fn(Vec2) -> Vec3) -> Vec<Option<Vec3>> {
    // With unit irradiance the analytic image is albedo / pi.
    let mut unlit = scene.clone();
    unlit.point_lights[0].position = Vec3::new(0.0, 0.0, 1e4);
    unlit.point_lights[0].intensity = Vec3::splat(1e8);
    analytic_image(&unlit, &albedo, true)
        .into_iter()
        .map(|v| v.map(|v| v * std::f32::consts::PI))
        .collect()
}

/// Renders `plane_scene` with `bsdf` through `pt` at 64 spp and compares each pixel with the
/// analytic image (where it is defined): within 1.5% plus 0.002 (the pixel jitter's noise
/// over the texture's and the light's variation inside a pixel); returns the largest relative
/// error and the mean relative difference of the whole image.
fn check_plane(name: &str, bsdf: &str, constant_only: bool) -> (f32, f64) {
    let dir = temp_dir(name);
    write_test_images(&dir);
    let path = dir.join("scene.xml");
    std::fs::write(&path, plane_scene(bsdf)).expect("scene");
    let scene = hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let texture = scene.textures[0].clone();
    let expected = analytic_image(&scene, |uv| texture.eval(uv), constant_only);
    let gpu = gpu();
    let mut r = renderer(&gpu, &scene, load_graph("graphs/pt.ron"), 3);
    let image = render_to(&mut r, 64);
    let mut worst = 0.0f32;
    let (mut sum_image, mut sum_expected, mut compared) = (0.0f64, 0.0f64, 0);
    for (pixel, e) in image.pixels.iter().zip(&expected) {
        let Some(e) = e else { continue };
        let got = Vec3::from_array(*pixel);
        let error = (got - *e).abs().max_element();
        worst = worst.max(error / e.max_element());
        assert!(
            error <= 0.015 * e.max_element() + 0.002,
            "{name}: pixel {got} against the analytic {e}"
        );
        sum_image += (got.x + got.y + got.z) as f64;
        sum_expected += (e.x + e.y + e.z) as f64;
        compared += 1;
    }
    let mean_error = sum_image / sum_expected - 1.0;
    eprintln!(
        "{name}: {compared} pixels compared, largest relative error {worst:.4}, image mean \
         {mean_error:+.5} relative"
    );
    assert!(compared >= 400, "{name}: only {compared} pixels compared");
    assert!(mean_error.abs() < 0.003, "{name}: mean off by {mean_error}");
    (worst, mean_error)
}

/// A checkerboard floor (8x8 cells over the plane, colours far apart per channel) under a
/// point light renders albedo(uv) E / pi in every pixel whose area lies in one cell, and a
/// bilinear bitmap (the 4x4 grid, repeated 1.5 times, mirrored) the filtered lookup averaged
/// over each pixel. Would catch the texture not applied (the constant is the mean: wrong in
/// every cell), looked up at the wrong uv or transposed, sRGB not decoded, a texture of the
/// other side or material.
#[test]
fn textured_plane_renders_the_analytic_image() {
    check_plane(
        "checker_render",
        r#"<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
            <rgb name="color0" value="0.8, 0.1, 0.5"/><rgb name="color1" value="0.2, 0.7, 0.3"/>
            <transform name="to_uv"><scale x="4" y="4"/></transform></texture></bsdf>"#,
        true,
    );
    check_plane(
        "bitmap_render",
        r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance">
            <string name="filename" value="grid.png"/><string name="wrap_mode" value="mirror"/>
            <transform name="to_uv"><scale x="1.5" y="1.5"/></transform></texture></bsdf>"#,
        false,
    );
}

/// On `tests/data/scenes/textured_box.xml` (a checkerboard floor, bitmap walls, a plastic
/// sphere with a textured base, copper with a bitmap `specular_reflectance`, a thin pane
/// throwing a caustic over the box) `hybrid` renders `pt`'s image: with the same seed their
/// camera paths are the same, so over 4 seeds the difference of image means must be within 4
/// standard errors plus 0.3% (the photon kernel's blur) of zero, per channel. The caustic is
/// checked to be large enough that dropping it or counting it twice would fail; a camera or
/// photon pass that treats a textured surface differently (a missing texture binding, a
/// textured plastic or conductor whose lobes differ between the passes) fails too. Whether the
/// hit points weigh the caustic with the textured albedo is too small an effect here (measured:
/// weighting with the texture's mean passes); the next test checks exactly that.
#[test]
fn hybrid_equals_pt_on_textured_surfaces() {
    let scene = load_scene("tests/data/scenes/textured_box.xml");
    assert!(scene.features().textures);
    common::convergence::hybrid_equals_pt("textured_box", "graphs/hybrid.ron", &scene);
}

/// The hit points weigh photons with the textured albedo: a checkerboard (or nearest bitmap)
/// floor lit only through a thin glass pane by a point light (all of its light a caustic, which
/// path tracing cannot render) renders through `hybrid` exactly albedo(uv) times the same
/// render of a white floor (same seed: the same photons and camera paths, which stop at the
/// floor), in every pixel inside one texture cell, within 1e-3. Fails when a hit point's
/// weight, or the photon grid's lookup, uses the untextured albedo (the texture's mean).
#[test]
fn hybrid_weighs_caustics_with_the_textured_albedo() {
    let pane = r#"<shape type="rectangle"><transform name="to_world"><scale value="1.6"/><translate z="0.75"/></transform><bsdf type="thindielectric"/></shape>"#;
    let scene_of = |name: &str, bsdf: &str| {
        let dir = temp_dir(name);
        write_test_images(&dir);
        let path = dir.join("scene.xml");
        // Camera, pane, floor: the hit points are at the second vertex.
        let xml = plane_scene(bsdf)
            .replace("</scene>", &format!("{pane}</scene>"))
            .replace(
                r#"name="max_depth" value="2""#,
                r#"name="max_depth" value="4""#,
            );
        std::fs::write(&path, xml).expect("scene");
        hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"))
    };
    let gpu = gpu();
    let render = |scene: &hppm::scene::Scene| {
        let mut r = renderer(&gpu, scene, load_graph("graphs/hybrid.ron"), 5);
        render_to(&mut r, 8)
    };
    let white = render(&scene_of(
        "white_caustic",
        r#"<bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf>"#,
    ));
    let mean = white.mean();
    assert!(mean[0] > 0.01, "no caustic on the floor: mean {mean:?}");
    for (name, bsdf) in [
        (
            "checker_caustic",
            r#"<bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
                <rgb name="color0" value="0.9, 0.3, 0.05"/><rgb name="color1" value="0.05, 0.3, 0.9"/>
                <transform name="to_uv"><scale x="2" y="2"/></transform></texture></bsdf>"#,
        ),
        (
            "bitmap_caustic",
            r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance">
                <string name="filename" value="grid.png"/><string name="filter_type" value="nearest"/></texture></bsdf>"#,
        ),
    ] {
        let scene = scene_of(name, bsdf);
        let texture = scene.textures[0].clone();
        let albedo = pixel_albedos(&scene, |uv| texture.eval(uv));
        let image = render(&scene);
        let (mut compared, mut worst) = (0, 0.0f32);
        for ((got, w), a) in image.pixels.iter().zip(&white.pixels).zip(&albedo) {
            let (Some(a), w) = (a, Vec3::from_array(*w)) else {
                continue;
            };
            if w.min_element() < 1e-3 {
                continue;
            }
            let ratio = Vec3::from_array(*got) / w;
            worst = worst.max((ratio - *a).abs().max_element());
            compared += 1;
        }
        eprintln!("{name}: {compared} pixels, largest |ratio - albedo| {worst:.2e}");
        assert!(compared >= 100, "{name}: only {compared} pixels compared");
        assert!(
            worst <= 1e-3,
            "{name}: ratio to the white floor off the albedo by {worst}"
        );
    }
}

/// A textured roughness: a rough conductor plane whose `alpha` is a checkerboard of 0.05 and
/// 0.4 renders, in every pixel inside one cell, what the same plane with that constant alpha
/// renders (same seed, so the same samples; within 1e-4 relative), where the two constant
/// renders differ by far more. Would catch the roughness texture not applied, Mitsuba's
/// swapped scalar checker rule not followed, alpha_u and alpha_v textured apart wrongly.
#[test]
fn textured_roughness_renders_each_cells_constant_roughness() {
    let conductor = |alpha: &str| {
        format!(
            r#"<bsdf type="roughconductor"><string name="material" value="Al"/><string name="distribution" value="ggx"/>{alpha}</bsdf>"#
        )
    };
    let scene_of = |name: &str, bsdf: &str| {
        let dir = temp_dir(name);
        let path = dir.join("scene.xml");
        std::fs::write(&path, plane_scene(bsdf)).expect("scene");
        hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"))
    };
    let gpu = gpu();
    let render = |scene: &hppm::scene::Scene| {
        let mut r = renderer(&gpu, scene, load_graph("graphs/pt.ron"), 11);
        render_to(&mut r, 4)
    };
    let constant = [0.05f32, 0.4].map(|a| {
        render(&scene_of(
            &format!("alpha_{a}"),
            &conductor(&format!(r#"<float name="alpha" value="{a}"/>"#)),
        ))
    });
    let scene = scene_of(
        "alpha_checker",
        &conductor(
            r#"<texture type="checkerboard" name="alpha"><float name="color0" value="0.05"/>
                <float name="color1" value="0.4"/><transform name="to_uv"><scale x="3" y="3"/></transform></texture>"#,
        ),
    );
    let texture = scene.textures[0].clone();
    let alphas = pixel_albedos(&scene, |uv| Vec3::splat(texture.eval_1(uv)));
    let image = render(&scene);
    let (mut compared, mut distinct, mut worst) = (0, 0, 0.0f32);
    for (i, a) in alphas.iter().enumerate() {
        let Some(a) = a else { continue };
        let which = usize::from((a.x - 0.4).abs() < 1e-3);
        let (got, want) = (
            Vec3::from_array(image.pixels[i]),
            Vec3::from_array(constant[which].pixels[i]),
        );
        let other = Vec3::from_array(constant[1 - which].pixels[i]);
        let scale = want.max_element().max(1e-3);
        worst = worst.max((got - want).abs().max_element() / scale);
        distinct += usize::from((other - want).abs().max_element() > 0.1 * scale);
        compared += 1;
    }
    eprintln!(
        "{compared} pixels, {distinct} where the two roughnesses differ by 10%, largest relative difference {worst:.2e}"
    );
    assert!(
        compared >= 300 && distinct >= 100,
        "{compared} pixels compared, {distinct} distinct"
    );
    assert!(
        worst <= 1e-4,
        "a cell renders off its constant roughness by {worst}"
    );
}

const MATERIAL_KERNEL: &str = "#import common::scene::materials
#import common::texture::textured_material
@group(1) @binding(0) var<storage, read> queries: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&out) / 3u { return; }
    let q = queries[id.x];
    let m = textured_material(materials[u32(q.z)], q.xy);
    out[3u * id.x] = vec4<f32>(m.specular, m.alpha_u);
    out[3u * id.x + 1u] = vec4<f32>(m.eta, m.alpha_v);
    out[3u * id.x + 2u] = vec4<f32>(m.k, m.albedo.x);
}
";

/// Each of principled's parameters that its plugin reads as a texture (besides base colour,
/// roughness and metallic) given its own checkerboard, with colours and scales unlike the
/// others', and a second material with two of them and plain floats for the rest: the WGSL
/// material at 500 uvs carries in each parameter's place (`specular`, `eta`, `k`, in
/// `PRINCIPLED_TEXTURED`'s order; `k.z` keeps eta) exactly the CPU lookup of that parameter's
/// texture, and the untextured ones keep their floats. Would catch a parameter written into
/// another's place, a texture list read from the wrong offset of `bsdf_tables` (the second
/// material's list follows the first's), or a scalar taken from the wrong channel.
#[test]
fn principled_field_textures_land_in_their_parameters() {
    let checker = |name, i| checker_texture(name, i);
    let some = format!(
        r#"{}{}<float name="anisotropic" value="0.3"/><float name="clearcoat" value="0.7"/><float name="eta" value="1.7"/>"#,
        checker("sheen", 3),
        checker("clearcoat_gloss", 7)
    );
    let floats = [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.4],
        [0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.7, 0.0, 1.7],
    ];
    let all = r#"<float name="eta" value="1.4"/>"#;
    field_textures_land(
        "principled",
        &hppm::bsdfs::principled::TEXTURED,
        all,
        &some,
        floats,
    );
}

/// The same for principledthin, whose `eta` (`k.y`) may be a texture too and whose `k.x` is
/// `diff_trans`.
#[test]
fn principled_thin_field_textures_land_in_their_parameters() {
    let some = format!(
        r#"{}{}<float name="anisotropic" value="0.3"/><float name="diff_trans" value="0.7"/>"#,
        checker_texture("sheen", 3),
        checker_texture("eta", 7)
    );
    let floats = [[0.0; 9], [0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.7, 0.0, 0.0]];
    let names = &hppm::bsdfs::principledthin::TEXTURED;
    field_textures_land("principledthin", names, "", &some, floats);
}

/// A checkerboard for parameter `name`, its colours and scales set by `i`.
fn checker_texture(name: &str, i: usize) -> String {
    format!(
        r#"<texture type="checkerboard" name="{name}"><float name="color0" value="{}"/><float name="color1" value="{}"/>
            <transform name="to_uv"><scale x="{}" y="{}"/></transform></texture>"#,
        0.05 + 0.1 * i as f32,
        0.9 - 0.07 * i as f32,
        1 + i,
        2 + i % 3
    )
}

/// Two rectangles of `plugin`: the first with every parameter of `names` textured (and
/// `all_extra`), the second with `some`. At 500 uvs the WGSL material's nine field components
/// (`specular`, `eta`, `k`) hold each textured parameter's CPU lookup in the place of its index
/// in `names`, and `floats` (per material) elsewhere.
fn field_textures_land(
    plugin: &str,
    names: &[&str],
    all_extra: &str,
    some: &str,
    floats: [[f32; 9]; 2],
) {
    let all: String = names
        .iter()
        .enumerate()
        .map(|(i, name)| checker_texture(name, i))
        .collect();
    let dir = temp_dir(&format!("{plugin}_fields"));
    let path = dir.join("scene.xml");
    let xml = format!(
        r#"<scene version="3.0.0"><sensor type="perspective"/>
        <shape type="rectangle"><bsdf type="{plugin}">{all_extra}{all}</bsdf></shape>
        <shape type="rectangle"><transform name="to_world"><translate x="3"/></transform><bsdf type="{plugin}">{some}</bsdf></shape>
        </scene>"#
    );
    std::fs::write(&path, xml).expect("scene");
    let scene = hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"));
    // The loader kept each parameter's texture in its own slot: the checkerboard made for
    // index i sits at component i.
    for material in &scene.materials {
        for (i, slot) in material.textures.front.fields.iter().enumerate() {
            if let Some(t) = slot {
                let Texture::Checkerboard { color0, .. } = scene.textures[*t as usize] else {
                    panic!("{plugin}: slot {i} holds a bitmap");
                };
                let expected = 0.05 + 0.1 * i as f32;
                assert!(
                    (color0.x - expected).abs() < 1e-6,
                    "{plugin}: slot {i} holds {color0}"
                );
            }
        }
    }
    let mut rng = common::rng::Rng(0x2545_f491_4f6c_dd1d);
    let queries: Vec<Vec4> = (0..500)
        .map(|i| {
            Vec4::new(
                -2.0 + 5.0 * rng.unit(),
                -2.0 + 5.0 * rng.unit(),
                (i % 2) as f32,
                0.0,
            )
        })
        .filter(|q| {
            // Checker cells within 1e-4 of an edge may round either way.
            scene.textures.iter().all(|t| match t {
                Texture::Checkerboard { to_uv, .. } => {
                    let p = to_uv.apply(q.truncate().truncate()) * 2.0;
                    (p.x - p.x.round()).abs() > 2e-4 && (p.y - p.y.round()).abs() > 2e-4
                }
                _ => true,
            })
        })
        .collect();
    let gpu = gpu();
    let harness = PassHarness::new(&gpu, &scene, (4, 4), false);
    let out = harness.run_kernel(
        "tests/textures.rs (material kernel)",
        MATERIAL_KERNEL,
        &queries,
        3 * queries.len(),
    );
    for (q, got) in queries.iter().zip(out.chunks(3)) {
        let material = q.z as usize;
        let fields = [got[0].truncate(), got[1].truncate(), got[2].truncate()];
        let fields: Vec<f32> = fields.iter().flat_map(|v| v.to_array()).collect();
        let textures = scene.materials[material].textures.front.fields;
        for (i, got) in fields.iter().enumerate() {
            let want = match textures.get(i).copied().flatten() {
                Some(t) => scene.textures[t as usize].eval_1(q.truncate().truncate()),
                None => floats[material][i],
            };
            let what = names.get(i).unwrap_or(&"unused");
            assert!(
                (got - want).abs() <= 1e-6,
                "{plugin} {material}, {what} at {:?}: GPU {got}, expected {want}",
                q.truncate().truncate()
            );
        }
    }
    eprintln!("{plugin}: {} lookups", queries.len());
}
