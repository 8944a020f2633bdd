//! Shading normals (interpolated vertex normals of smooth meshes) on whatever adapter wgpu finds
//! (lavapipe in CI): a smooth-shaded sphere mesh renders as the analytic sphere does, a flat one
//! visibly does not, and shading normals never create energy in a white furnace.

mod common;

use common::*;
use glam::{Mat4, Vec3};
use hppm::image::Image;
use hppm::scene::filter::PixelFilter;
use hppm::scene::mesh::MeshData;
use hppm::scene::{Camera, Integrator, Material, PointLight, Scene, Sphere};

/// A UV sphere of `rings` x `2 rings` quads on the unit sphere, counter-clockwise seen from
/// outside, with its exact (radial) vertex normals.
fn uv_sphere(rings: usize) -> MeshData {
    let segments = 2 * rings;
    let point = |i: usize, j: usize| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = 2.0 * std::f32::consts::PI * j as f32 / segments as f32;
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        )
    };
    let mut mesh = MeshData {
        normals: Some(Vec::new()),
        ..MeshData::default()
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            for t in [[a, c, b], [a, d, c]] {
                let n = (t[1] - t[0]).cross(t[2] - t[0]);
                // The pole quads have a degenerate half.
                if n.length_squared() > 1e-12 {
                    debug_assert!(n.dot(t[0] + t[1] + t[2]) > 0.0, "inward triangle");
                    mesh.triangles.push(t);
                    mesh.normals.as_mut().expect("normals").push(t);
                }
            }
        }
    }
    mesh
}

fn camera(origin: Vec3, target: Vec3, fov: f32, size: u32) -> Camera {
    Camera {
        origin,
        target,
        up: Vec3::Y,
        fov_x_deg: fov,
        width: size,
        height: size,
        filter: PixelFilter::Box,
        sample_border: false,
        crop: None,
        lens: None,
    }
}

/// A diffuse unit sphere at the origin lit by a point light from the upper right, seen from +z:
/// as an analytic sphere, or as `mesh` (smooth- or flat-shaded).
fn lit_sphere(mesh: Option<MeshData>) -> Scene {
    let mut scene = Scene {
        media: Default::default(),
        source: "lit sphere (built in the test)".into(),
        camera: camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 36.0, 48),
        // Direct light only: with a point light the image then has no noise but the pixel
        // jitter's, so the comparison measures shading alone.
        integrator: Integrator {
            max_depth: Some(2),
            rr_depth: None,
            hide_emitters: false,
        },
        spp_hint: None,
        materials: vec![Material {
            media: Default::default(),
            bsdf: hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.7)),
            emission: Vec3::ZERO,
            back: None,
            textures: Default::default(),
        }],
        triangles: vec![],
        spheres: vec![],
        point_lights: vec![PointLight {
            position: Vec3::new(3.0, 2.0, 3.0),
            intensity: Vec3::splat(20.0),
        }],
        emitters: Default::default(),
        textures: vec![],
    };
    match mesh {
        Some(mesh) => scene.push_mesh_data(mesh, Mat4::IDENTITY, 0, false),
        None => scene.spheres.push(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
            material: 0,
            flip_normals: false,
        }),
    }
    scene
}

fn render(scene: &Scene, spp: u64) -> Image {
    let gpu = gpu();
    let mut r = renderer(&gpu, scene, load_graph("graphs/pt.ron"), 9);
    render_to(&mut r, spp)
}

/// Mean relative error of `image` against `reference` over the pixels whose centre ray hits
/// the sphere well inside its silhouette (where a 64-gon and a circle cover the same pixels).
fn interior_error(image: &Image, reference: &Image, camera: &Camera) -> f64 {
    let forward = (camera.target - camera.origin).normalize();
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    let tan_half = (camera.fov_x_deg.to_radians() * 0.5).tan();
    let (w, h) = (camera.width as usize, camera.height as usize);
    let (mut sum, mut count) = (0.0, 0usize);
    for y in 0..h {
        for x in 0..w {
            let fx = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * tan_half;
            let fy = (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * tan_half;
            let dir = (forward + fx * right + fy * up).normalize();
            // Distance of the ray from the centre, against 0.9 of the radius.
            let closest = camera.origin - dir * camera.origin.dot(dir);
            let r = reference.pixels[y * w + x][0] as f64;
            if closest.length() < 0.9 && r > 1e-3 {
                sum += (image.pixels[y * w + x][0] as f64 - r).abs() / r;
                count += 1;
            }
        }
    }
    assert!(count > 500, "only {count} interior pixels");
    sum / count as f64
}

/// A 32-ring sphere mesh with its exact vertex normals renders within 1.5% (mean over interior
/// pixels) of the analytic sphere, and at least 4 times closer than the same mesh shaded flat
/// (whose facets are visible). A renderer that ignored the vertex normals, interpolated them
/// with the wrong barycentrics or let NEE use the face normal fails.
#[test]
fn smooth_sphere_mesh_renders_like_the_analytic_sphere() {
    let spp = 16;
    let analytic = lit_sphere(None);
    let reference = render(&analytic, spp);
    let smooth = render(&lit_sphere(Some(uv_sphere(32))), spp);
    let mut flat_mesh = uv_sphere(32);
    flat_mesh.normals = None;
    let flat = render(&lit_sphere(Some(flat_mesh)), spp);
    let smooth_error = interior_error(&smooth, &reference, &analytic.camera);
    let flat_error = interior_error(&flat, &reference, &analytic.camera);
    eprintln!(
        "mean relative error against the analytic sphere: smooth {smooth_error:.4}, flat \
         {flat_error:.4}"
    );
    assert!(smooth_error < 0.015, "smooth mesh off by {smooth_error}");
    assert!(
        smooth_error * 4.0 < flat_error,
        "smooth {smooth_error} is not clearly better than flat {flat_error}"
    );
}

/// A furnace: inside a closed, inward-facing sphere mesh of albedo 0.8 emitting 0.5, radiance
/// is 0.5 / (1 - 0.8) = 2.5 everywhere with the true normals. Its vertex normals are tilted at
/// random by up to about 20 degrees, so shading and geometry disagree everywhere: directions that
/// leave through the wall are lost, but nothing may add energy, so the image mean stays at or below 2.5
/// (within 1%, the noise at 256 spp) and, with most of the light still there (2.25 measured),
/// above 2.0. A diffuse weight of albedo times the shading over the geometric cosine (a
/// common mistake) renders 5.4 here and fails.
#[test]
fn shading_normals_create_no_energy_in_a_furnace() {
    let mut mesh = uv_sphere(12);
    let mut rng = common::rng::Rng(0x5eed);
    let tilt = |n: Vec3, rng: &mut common::rng::Rng| (n + 0.35 * rng.direction()).normalize();
    // One tilted normal per distinct vertex, so neighbouring triangles share it.
    let mut tilted: Vec<(Vec3, Vec3)> = Vec::new();
    for corners in mesh.normals.as_mut().expect("normals") {
        for n in corners.iter_mut() {
            let found = tilted
                .iter()
                .find(|(p, _)| p.distance(*n) < 1e-6)
                .map(|t| t.1);
            *n = found.unwrap_or_else(|| {
                let t = tilt(*n, &mut rng);
                tilted.push((*n, t));
                t
            });
        }
    }
    let mut scene = Scene {
        media: Default::default(),
        source: "shading-normal furnace (built in the test)".into(),
        camera: camera(
            Vec3::new(0.1, -0.1, 0.2),
            Vec3::new(0.4, 0.3, -1.0),
            70.0,
            32,
        ),
        integrator: Integrator {
            max_depth: None,
            rr_depth: Some(3),
            hide_emitters: false,
        },
        spp_hint: None,
        materials: vec![Material {
            media: Default::default(),
            bsdf: hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.8)),
            emission: Vec3::splat(0.5),
            back: None,
            textures: Default::default(),
        }],
        triangles: vec![],
        spheres: vec![],
        point_lights: vec![],
        emitters: Default::default(),
        textures: vec![],
    };
    scene.push_mesh_data(mesh, Mat4::from_scale(Vec3::splat(1.5)), 0, true);
    let image = render(&scene, 256);
    let mean = image.mean();
    eprintln!("furnace with tilted shading normals: mean {mean:?} (true normals: 2.5)");
    for c in mean {
        assert!(c <= 2.5 * 1.01, "shading normals created energy: mean {c}");
        assert!(c >= 2.0, "most of the light is lost: mean {c}");
    }
}

/// Vertex normals as Mitsuba makes them: a mesh file without normals gets angle-weighted ones
/// (at a cube's corner, whichever way its faces are split, the diagonal: each face meets the
/// corner with 90 degrees in all), an OBJ's own `vn` are kept, `face_normals` drops both, and a
/// `flip_normals` or mirroring `to_world` keeps them on the front side.
#[test]
fn vertex_normals_follow_mitsuba() {
    let cube = hppm::loaders::obj::load_mesh_data(&repo_path(
        "tests/refs/scenes/cornell_diffuse_obj/unit_cube.obj",
    ))
    .expect("cube");
    for (corners, normals) in cube
        .triangles
        .iter()
        .zip(cube.normals.as_ref().expect("normals"))
    {
        for (p, n) in corners.iter().zip(normals) {
            assert!(
                (*n - p.normalize()).length() < 1e-5,
                "corner {p}: normal {n}"
            );
        }
    }
    let with_vn = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0.6 0.8\nvn 0 0 1\nvn 0.6 0 0.8\n\
                   f 1//1 2//2 3//3\n";
    let mesh = hppm::loaders::obj::parse_mesh(std::path::Path::new("vn.obj"), with_vn).expect("vn");
    assert_eq!(
        mesh.normals.as_deref(),
        Some(&[[Vec3::new(0.0, 0.6, 0.8), Vec3::Z, Vec3::new(0.6, 0.0, 0.8)]][..])
    );
    for (flip, mirror) in [(false, false), (true, false), (false, true), (true, true)] {
        let mut scene = lit_sphere(None);
        let to_world = if mirror {
            Mat4::from_scale(Vec3::new(-2.0, 1.0, 1.0))
        } else {
            Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0))
        };
        scene.push_mesh_data(mesh.clone(), to_world, 0, flip);
        let t = scene.triangles[0];
        let face = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).normalize();
        for n in t.normals.expect("placed normals") {
            assert!((n.length() - 1.0).abs() < 1e-5);
            assert!(
                n.dot(face) > 0.5,
                "flip {flip}, mirror {mirror}: {n} against face {face}"
            );
        }
    }
    let dir = std::env::temp_dir().join(format!("hppm-normals-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("vn.obj"), with_vn).expect("write");
    for (face_normals, smooth) in [
        ("", true),
        ("<boolean name=\"face_normals\" value=\"true\"/>", false),
    ] {
        let xml = format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"/><shape type=\"obj\">\
             <string name=\"filename\" value=\"vn.obj\"/>{face_normals}</shape></scene>"
        );
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).expect("write");
        let scene = hppm::loaders::load(&path).expect("scene");
        assert_eq!(
            scene.triangles[0].normals.is_some(),
            smooth,
            "{face_normals}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Against Mitsuba itself: a 16-ring sphere PLY with its vertex normals, lit by a point light
/// (tests/data/mitsuba/smooth_sphere.xml, rendered by Mitsuba 3.9.1 at 1024 spp), renders within
/// relMSE 2e-4 of Mitsuba's image (measured 4.5e-5; the mean relative error on lit pixels is
/// 0.6%), while the same mesh with `face_normals` (set through `-D`) is off by more than 5x that
/// (measured 1.4e-3): vertex normals read from the PLY and interpolated as Mitsuba does, with
/// its one-sidedness and NEE cosine. Without normals in the file, computed as Mitsuba computes
/// them, the same bound holds against Mitsuba's render of that (measured 4.5e-5).
#[test]
fn smooth_ply_sphere_matches_mitsuba() {
    let path = repo_path("tests/data/mitsuba/smooth_sphere.xml");
    let reference = Image::read_exr(&repo_path("tests/data/mitsuba/smooth_sphere.exr"))
        .expect("Mitsuba's image");
    let mut errors = Vec::new();
    for face_normals in ["false", "true"] {
        let defines = [("face_normals".to_string(), face_normals.to_string())];
        let scene = hppm::loaders::load_with(&path, &defines).expect("scene");
        let error = relmse(&render(&scene, 256), &reference);
        eprintln!("face_normals={face_normals}: relMSE against Mitsuba {error:.2e}");
        errors.push(error);
    }
    assert!(
        errors[0] < 2e-4,
        "smooth sphere: relMSE {} against Mitsuba",
        errors[0]
    );
    assert!(
        errors[1] > 5.0 * 2e-4,
        "flat shading is not distinguishable from smooth ({} vs {})",
        errors[1],
        errors[0]
    );
    // The same mesh without normals in the file: Mitsuba computes them, and so must we (a
    // loader that shaded it flat would be off by the 1.4e-3 above).
    let defines = [("mesh".to_string(), "computed_normals.ply".to_string())];
    let scene = hppm::loaders::load_with(&path, &defines).expect("scene");
    let reference = Image::read_exr(&repo_path("tests/data/mitsuba/computed_normals.exr"))
        .expect("Mitsuba's image");
    let error = relmse(&render(&scene, 256), &reference);
    eprintln!("computed normals: relMSE against Mitsuba {error:.2e}");
    assert!(
        error < 2e-4,
        "computed normals: relMSE {error} against Mitsuba"
    );
}

/// `cornell_glass_sphere` with its glass sphere as the 16-ring smooth PLY
/// (tests/data/mitsuba/glass_mesh.xml, 32x32), against Mitsuba 3.9.1 at 32768 spp: `pt` and the
/// hybrid (whose caustic comes from photons refracted by the shading normals, with their adjoint
/// correction) at 256 spp are within 1.5x Mitsuba's own 256-spp relMSE (0.0093; measured 0.0117
/// and 0.0070), and fall at least 3x by 1024 spp (measured 4.9x and 4.6x), as an unbiased
/// estimator's error does; a bias, e.g. refraction by the face normals or energy lost at the
/// guards, would flatten it.
#[test]
fn glass_mesh_converges_to_mitsuba() {
    let scene = load_scene("tests/data/mitsuba/glass_mesh.xml");
    let read = |name: &str| {
        Image::read_exr(&repo_path(&format!("tests/data/mitsuba/{name}.exr"))).expect(name)
    };
    let reference = read("glass_mesh");
    let mitsuba_256 = relmse(&read("glass_mesh_256"), &reference);
    let gpu = gpu();
    for graph in ["graphs/pt.ron", "graphs/hybrid.ron"] {
        let mut r = renderer(&gpu, &scene, load_graph(graph), 3);
        let at_256 = relmse(&render_to(&mut r, 256), &reference);
        let at_1024 = relmse(&render_to(&mut r, 1024), &reference);
        eprintln!(
            "{graph}: relMSE {at_256:.4} at 256 spp (Mitsuba {mitsuba_256:.4}), {at_1024:.4} at \
             1024"
        );
        assert!(
            at_256 < 1.5 * mitsuba_256,
            "{graph}: relMSE {at_256} at 256 spp, Mitsuba's {mitsuba_256}"
        );
        assert!(
            at_256 / at_1024 > 3.0,
            "{graph}: relMSE fell only {:.2}x from 256 to 1024 spp",
            at_256 / at_1024
        );
    }
}

/// Found by the differential corpus (tests/differential/corpus/0020: a PLY box without normals
/// under a non-uniform scale, its glossy highlight 15% off Mitsuba's in one block and 45% in
/// another; block relMSE 2.9e-2, after the fix 2.8e-5 at 4,096 spp). Mitsuba computes the
/// normals of a mesh file that has none from the placed faces; hppm computed them in the file's
/// space and carried them into the world by the inverse transpose, which under a non-uniform
/// scale tilts them. A unit cube stretched 3x along x keeps its right angles, so each corner's
/// normal is the diagonal (+-1, +-1, +-1) / sqrt(3) in the world, where the carried normal was
/// (1/3, 1, 1) normalised; mirrored, it must still point out. Would catch normals computed
/// before placing, or not turned outward under a mirror.
#[test]
fn computed_vertex_normals_follow_the_placed_faces() {
    let dir = std::env::temp_dir().join(format!("hppm-placed-normals-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut obj = String::new();
    for c in 0..8 {
        let s = |bit: u32| if c & bit != 0 { 1.0 } else { -1.0 };
        obj += &format!("v {} {} {}\n", s(1), s(2), s(4));
    }
    // Counter-clockwise seen from outside; OBJ indices from 1.
    for [a, b, c, d] in [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ] {
        obj += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
    }
    std::fs::write(dir.join("box.obj"), obj).expect("obj");
    for (sx, label) in [(3.0f32, "stretched"), (-3.0, "stretched and mirrored")] {
        let xml = format!(
            r#"<scene version="3.0.0"><sensor type="perspective"/>
            <shape type="obj"><string name="filename" value="box.obj"/>
                <transform name="to_world"><scale x="{sx}" y="1" z="1"/></transform></shape>
            </scene>"#
        );
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).expect("xml");
        let scene = hppm::loaders::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut corners = 0;
        for t in &scene.triangles {
            let normals = t.normals.expect("computed vertex normals");
            for (p, n) in t.v.iter().zip(normals) {
                let expected = (p.signum()).normalize();
                assert!(
                    (n - expected).length() < 1e-5,
                    "{label}: normal {n} at corner {p}, expected {expected}"
                );
                corners += 1;
            }
            // Outward: the face's own normal agrees with its corners'.
            let face = (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]);
            assert!(
                face.dot(normals[0]) > 0.0,
                "{label}: winding against the normals"
            );
        }
        assert_eq!(corners, 36);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
