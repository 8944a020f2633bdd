//! The scene loaders on good input: the four reference Mitsuba scenes, the bundled RON scenes,
//! bare OBJ files, and the `Scene` helpers. CPU only.

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use hppm::bsdfs::conductor::Mirror;
use hppm::bsdfs::dielectric::Dielectric;
use hppm::loaders::{mitsuba, obj, ron_format};
use hppm::scene::{self, Scene};

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

fn load(relative: &str) -> Scene {
    hppm::loaders::load(&repo(relative)).unwrap_or_else(|e| panic!("{relative}: {e}"))
}

fn xml(body: &str) -> Scene {
    let text =
        format!("<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n{body}\n</scene>");
    mitsuba::parse(Path::new("inline.xml"), &text).unwrap_or_else(|e| panic!("{e}"))
}

fn normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0]).normalize()
}

fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
    (a - b).abs().max_element() <= eps
}

const CORNELL_WHITE: Vec3 = Vec3::new(0.885809, 0.698859, 0.666422);
const CORNELL_LIGHT: Vec3 = Vec3::new(18.387, 13.9873, 6.75357);

fn emitters(s: &Scene) -> Vec<Vec3> {
    s.materials
        .iter()
        .map(|m| m.emission)
        .filter(|e| e.max_element() > 0.0)
        .collect()
}

#[test]
fn cornell_diffuse_counts_camera_and_light() {
    let s = load("tests/refs/scenes/cornell_diffuse/scene.xml");
    // 6 rectangles and 2 cubes, one material each.
    assert_eq!(s.triangles.len(), 6 * 2 + 2 * 12);
    assert_eq!(s.spheres.len(), 0);
    assert_eq!(s.materials.len(), 8);
    assert_eq!(s.camera.fov_x_deg, 39.3077);
    assert_eq!(s.camera.origin, Vec3::new(0.0, 0.0, 3.9));
    assert!(close(
        (s.camera.target - s.camera.origin).normalize(),
        Vec3::NEG_Z,
        1e-6
    ));
    assert!(close(s.camera.up, Vec3::Y, 1e-6));
    assert_eq!(emitters(&s), vec![CORNELL_LIGHT]);
    let white = hppm::bsdfs::diffuse::Diffuse::bsdf(CORNELL_WHITE);
    assert_eq!(s.materials.iter().filter(|m| m.bsdf == white).count(), 5);
    assert_eq!(s.integrator.max_depth, Some(12));
    assert_eq!(s.spp_hint, Some(64));
    assert!(s.has_lights());
    assert!(s.point_lights.is_empty());
    let (lo, hi) = s.bounds();
    assert!(close(lo, Vec3::splat(-1.0), 1e-6) && close(hi, Vec3::splat(1.0), 1e-6));
}

#[test]
fn cornell_walls_and_light_face_into_the_room() {
    let s = load("tests/refs/scenes/cornell_diffuse/scene.xml");
    // Rectangles come first: floor, ceiling, back, left, right, light.
    let expected = [
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::X,
        Vec3::NEG_X,
        Vec3::NEG_Y,
    ];
    for (i, n) in expected.iter().enumerate() {
        for t in &s.triangles[2 * i..2 * i + 2] {
            assert!(close(normal(&t.v), *n, 1e-5), "rectangle {i}: {:?}", t.v);
        }
    }
    // The light is 0.46 x 0.38 at y = 0.99.
    let light: Vec<_> = s.triangles[10..12].iter().flat_map(|t| t.v).collect();
    assert!(light.iter().all(|v| (v.y - 0.99).abs() < 1e-6));
    let area: f32 = s.triangles[10..12]
        .iter()
        .map(|t| 0.5 * (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length())
        .sum();
    assert!((area - 0.46 * 0.38).abs() < 1e-5, "{area}");
    // Box faces point away from their box's centre.
    for (k, tris) in s.triangles[12..].chunks(12).enumerate() {
        let centre = tris.iter().flat_map(|t| t.v).sum::<Vec3>() / 36.0;
        for t in tris {
            let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
            assert!(
                normal(&t.v).dot(c - centre) > 0.0,
                "box {k} has an inward face"
            );
        }
    }
}

#[test]
fn cornell_glass_sphere_spheres_and_materials() {
    let s = load("tests/refs/scenes/cornell_glass_sphere/scene.xml");
    assert_eq!(s.triangles.len(), 12);
    assert_eq!(s.spheres.len(), 2);
    assert_eq!(s.materials.len(), 8);
    let glass = s.spheres[0];
    assert_eq!(glass.center, Vec3::new(0.42, -0.62, 0.42));
    assert_eq!(glass.radius, 0.38);
    assert_eq!(
        s.materials[glass.material as usize].bsdf,
        Dielectric::bsdf(1.5, 1.0)
    );
    let mirror = s.spheres[1];
    assert_eq!(mirror.radius, 0.35);
    assert_eq!(s.materials[mirror.material as usize].bsdf, Mirror::bsdf());
    assert!(!glass.flip_normals && !mirror.flip_normals);
    assert_eq!(emitters(&s), vec![CORNELL_LIGHT]);
    // rr_depth 1000 >= max_depth 12: roulette could never start, stored as "never".
    assert_eq!(s.integrator.rr_depth, None);
}

#[test]
fn point_light_caustic_light_camera_and_plane() {
    let s = load("tests/refs/scenes/point_light_caustic/scene.xml");
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.spheres.len(), 1);
    assert_eq!(s.point_lights.len(), 1);
    assert_eq!(s.point_lights[0].position, Vec3::new(-2.0, 2.8, 0.0));
    assert_eq!(s.point_lights[0].intensity, Vec3::splat(40.0));
    assert_eq!(s.camera.fov_x_deg, 40.0);
    assert_eq!(s.camera.origin, Vec3::new(0.3, 2.4, 4.2));
    let dir = (s.camera.target - s.camera.origin).normalize();
    assert!(close(
        dir,
        (Vec3::new(0.3, 0.3, 0.0) - s.camera.origin).normalize(),
        1e-6
    ));
    // The 10 x 10 plane at y = 0 faces up.
    for t in &s.triangles {
        assert!(close(normal(&t.v), Vec3::Y, 1e-6));
        assert!(
            t.v.iter()
                .all(|v| v.y == 0.0 && v.x.abs() <= 5.0 && v.z.abs() <= 5.0)
        );
    }
    assert!(s.has_lights());
    assert!(emitters(&s).is_empty());
}

/// The OBJ version places one box from world-space triangles and the other from a unit cube
/// with to_world: both must be the cube scene's triangles (as a set of vertices per triangle,
/// with the same front side).
#[test]
fn cornell_obj_scene_has_the_same_triangles_as_the_cube_scene() {
    let cubes = load("tests/refs/scenes/cornell_diffuse/scene.xml");
    let objs = load("tests/refs/scenes/cornell_diffuse_obj/scene.xml");
    assert_eq!(cubes.triangles.len(), objs.triangles.len());
    assert_eq!(cubes.materials, objs.materials);
    let (lo_a, hi_a) = cubes.bounds();
    let (lo_b, hi_b) = objs.bounds();
    assert!(close(lo_a, lo_b, 1e-4) && close(hi_a, hi_b, 1e-4));
    // Triangulations may differ per face, so compare the sets of corners per box and the
    // orientation of every triangle against the face it lies in.
    let corners = |s: &Scene| {
        let mut v: Vec<[i64; 3]> = s
            .triangles
            .iter()
            .flat_map(|t| t.v)
            .map(|p| (p * 1e4).round().as_i64vec3().to_array())
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let (a, b) = (corners(&cubes), corners(&objs));
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(&b) {
        assert!(
            p.iter().zip(q).all(|(x, y)| (x - y).abs() <= 1),
            "{p:?} vs {q:?}"
        );
    }
    for t in &objs.triangles {
        let n = normal(&t.v);
        let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
        let same_face = cubes.triangles.iter().any(|u| {
            let m = normal(&u.v);
            m.dot(n) > 0.9999 && (c - u.v[0]).dot(m).abs() < 1e-4
        });
        assert!(same_face, "OBJ triangle {:?} matches no cube face", t.v);
    }
}

#[test]
fn bundled_ron_scenes_match_their_xml_originals() {
    for (ron, xml) in [
        (
            "scenes/cornell_box.ron",
            "tests/refs/scenes/cornell_glass_sphere/scene.xml",
        ),
        (
            "scenes/cornell_diffuse.ron",
            "tests/refs/scenes/cornell_diffuse/scene.xml",
        ),
    ] {
        let (r, x) = (load(ron), load(xml));
        assert_eq!(r.camera.fov_x_deg, x.camera.fov_x_deg, "{ron}");
        assert_eq!(
            (r.camera.width, r.camera.height),
            (x.camera.width, x.camera.height)
        );
        assert!(close(r.camera.origin, x.camera.origin, 1e-6));
        assert_eq!(r.triangles.len(), x.triangles.len(), "{ron}");
        for (a, b) in r.triangles.iter().zip(&x.triangles) {
            for (p, q) in a.v.iter().zip(b.v) {
                assert!(close(*p, q, 1e-5), "{ron}: {p} vs {q}");
            }
            assert_eq!(
                r.materials[a.material as usize],
                x.materials[b.material as usize]
            );
        }
        assert_eq!(r.spheres.len(), x.spheres.len());
        for (a, b) in r.spheres.iter().zip(&x.spheres) {
            assert_eq!((a.center, a.radius), (b.center, b.radius));
            assert_eq!(
                r.materials[a.material as usize],
                x.materials[b.material as usize]
            );
        }
        assert_eq!(r.integrator.max_depth, x.integrator.max_depth);
    }
}

#[test]
fn furnace_is_a_closed_inward_facing_emitting_grey_cube() {
    let s = load("scenes/furnace.ron");
    assert_eq!(s.integrator.max_depth, None);
    assert_eq!(s.integrator.rr_depth, Some(5));
    assert_eq!(s.triangles.len(), 12);
    for m in &s.materials {
        assert_eq!(
            m.bsdf,
            hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.5))
        );
        assert_eq!(m.emission, Vec3::ONE);
    }
    assert!(s.camera.origin.abs().max_element() < 1.0, "camera inside");
    for t in &s.triangles {
        let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
        assert!(normal(&t.v).dot(c) < 0.0, "faces inwards");
    }
}

#[test]
fn mitsuba_conventions() {
    // fov along y converts with the aspect ratio: tan(fx/2) = tan(fy/2) * w/h.
    let s = mitsuba::parse(
        Path::new("fov.xml"),
        r#"<scene version="3.0.0"><sensor type="perspective">
            <float name="fov" value="30"/><string name="fov_axis" value="y"/>
            <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/></film>
        </sensor></scene>"#,
    )
    .unwrap();
    let expected = 2.0 * (15f32.to_radians().tan() * 2.0).atan().to_degrees();
    assert!((s.camera.fov_x_deg - expected).abs() < 1e-4);
    // Defaults: no integrator = unbounded with roulette from depth 5.
    assert_eq!(s.integrator.max_depth, None);
    assert_eq!(s.integrator.rr_depth, Some(5));

    // A shape without a BSDF is Mitsuba's grey diffuse; BSDFs can be shared by reference.
    let s = xml(r#"<bsdf type="dielectric" id="glass"/>
        <shape type="sphere"/>
        <shape type="sphere"><ref id="glass"/><point name="center" value="1, 2, 3"/></shape>"#);
    assert_eq!(
        s.materials[0].bsdf,
        hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.5))
    );
    assert_eq!(s.materials[1].bsdf, Dielectric::bsdf(1.5046, 1.000277));
    assert_eq!(s.spheres[1].center, Vec3::new(1.0, 2.0, 3.0));

    // $name defaults, grey from one number, -1 = unbounded.
    let s = mitsuba::parse(
        Path::new("d.xml"),
        r#"<scene version="3.0.0"><default name="d" value="-1"/><default name="g" value="0.25"/>
        <integrator type="path"><integer name="max_depth" value="$d"/><integer name="rr_depth" value="3"/></integrator>
        <sensor type="perspective"/>
        <shape type="cube"><bsdf type="diffuse"><float name="reflectance" value="$g"/></bsdf></shape>
        </scene>"#,
    )
    .unwrap();
    assert_eq!(s.integrator.max_depth, None);
    assert_eq!(s.integrator.rr_depth, Some(3));
    assert_eq!(
        s.materials[0].bsdf,
        hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.25))
    );
}

#[test]
fn mitsuba_transforms_winding_and_flips() {
    // translate, scale, rotate compose in order: scale by 2, rotate 90 degrees about z, move up.
    let s = xml(r#"<shape type="rectangle"><transform name="to_world">
        <scale value="2"/><rotate z="1" angle="90"/><translate y="5"/></transform></shape>"#);
    let m = Mat4::from_translation(Vec3::Y * 5.0)
        * Mat4::from_rotation_z(90f32.to_radians())
        * Mat4::from_scale(Vec3::splat(2.0));
    let reference = scene::mesh::rectangle();
    for (t, r) in s.triangles.iter().zip(&reference) {
        for (p, q) in t.v.iter().zip(r) {
            assert!(close(*p, m.transform_point3(*q), 1e-5));
        }
    }
    // A mirroring scale keeps the front where the mirrored normal points: +z -> -z.
    let s = xml(
        r#"<shape type="rectangle"><transform name="to_world"><scale z="-1"/></transform></shape>"#,
    );
    assert!(
        s.triangles
            .iter()
            .all(|t| close(normal(&t.v), Vec3::NEG_Z, 1e-6))
    );
    let s = xml(
        r#"<shape type="rectangle"><transform name="to_world"><scale x="-1"/></transform></shape>"#,
    );
    assert!(
        s.triangles
            .iter()
            .all(|t| close(normal(&t.v), Vec3::Z, 1e-6))
    );
    // flip_normals reverses the side, for meshes and spheres.
    let s = xml(
        r#"<shape type="rectangle"><boolean name="flip_normals" value="true"/></shape>
        <shape type="sphere"><boolean name="flip_normals" value="true"/></shape>"#,
    );
    assert!(
        s.triangles
            .iter()
            .all(|t| close(normal(&t.v), Vec3::NEG_Z, 1e-6))
    );
    assert!(s.spheres[0].flip_normals);
    // A sphere's to_world may scale uniformly and move it.
    let s = xml(r#"<shape type="sphere"><float name="radius" value="0.5"/>
        <transform name="to_world"><rotate x="1" angle="30"/><scale value="3"/><translate x="1"/></transform></shape>"#);
    assert!((s.spheres[0].radius - 1.5).abs() < 1e-5);
    assert!(close(s.spheres[0].center, Vec3::X, 1e-6));
}

#[test]
fn mitsuba_emitters() {
    let s = xml(
        r#"<shape type="cube"><emitter type="area"><rgb name="radiance" value="1 2 3"/></emitter></shape>
        <emitter type="point"><point name="position" x="1" y="2" z="3"/><float name="intensity" value="7"/></emitter>"#,
    );
    assert_eq!(s.materials[0].emission, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(s.point_lights[0].position, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(s.point_lights[0].intensity, Vec3::splat(7.0));
}

#[test]
fn obj_meshes_and_bare_obj_scenes() {
    let cube = repo("tests/refs/scenes/cornell_diffuse_obj/unit_cube.obj");
    let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)) * Mat4::from_scale(Vec3::splat(0.5));
    let tris = obj::load_mesh(&cube, m, 7, false).unwrap();
    assert_eq!(tris.len(), 12);
    assert!(tris.iter().all(|t| t.material == 7));
    let centre = Vec3::new(1.0, 2.0, 3.0);
    for t in &tris {
        let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
        assert!(normal(&t.v).dot(c - centre) > 0.0, "outward");
        assert!(
            t.v.iter()
                .all(|v| close((*v - centre).abs(), Vec3::splat(0.5), 1e-6))
        );
    }
    let flipped = obj::load_mesh(&cube, m, 0, true).unwrap();
    for (a, b) in tris.iter().zip(&flipped) {
        assert!(close(normal(&a.v), -normal(&b.v), 1e-6));
    }

    // Polygons are triangulated; negative indices count back.
    let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n";
    let tris = obj::parse_triangles(Path::new("q.obj"), quad).unwrap();
    assert_eq!(tris.len(), 2);
    assert!(tris.iter().all(|t| close(normal(t), Vec3::Z, 1e-6)));

    // A bare OBJ gets a camera on +z looking at it, a grey material and a light.
    let s = load("tests/refs/scenes/cornell_diffuse_obj/unit_cube.obj");
    assert_eq!(s.triangles.len(), 12);
    assert_eq!(
        s.materials,
        vec![scene::Material {
            media: Default::default(),
            bsdf: hppm::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.8)),
            back: None,
            emission: Vec3::ZERO,
            textures: Default::default(),
        }]
    );
    assert!(close(s.camera.target, Vec3::ZERO, 1e-6));
    assert!(s.camera.origin.z > 1.0 && s.camera.origin.x == 0.0);
    assert_eq!(s.point_lights.len(), 1);
    assert!(s.point_lights[0].position.y > s.camera.origin.y);
}

#[test]
fn ron_conveniences() {
    let text = r#"(
        camera: (origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8),
        integrator: (max_depth: None, rr_depth: 3),
        spp: 16,
        materials: { "m": Diffuse(reflectance: (0.5, 0.5, 0.5)), "g": Dielectric(int_ior: 1.33) },
        shapes: [
            (shape: Rectangle, material: "m", to_world: [Scale((2, 2, 1)), Rotate(axis: (1, 0, 0), degrees: -90), Translate((0, -1, 0))]),
            (shape: Sphere(center: (0, 0, 0), radius: 0.5), material: "g", to_world: [Scale((2, 2, 2)), Translate((1, 0, 0))]),
            (shape: Obj(path: "../refs/scenes/cornell_diffuse_obj/unit_cube.obj"), material: "m", flip_normals: true),
        ],
        point_lights: [(position: (0, 2, 0), intensity: (10, 10, 10))],
    )"#;
    let s = ron_format::parse(&repo("tests/data/inline.ron"), text).unwrap();
    assert_eq!(s.integrator.max_depth, None);
    assert_eq!(s.integrator.rr_depth, Some(3));
    assert_eq!(s.spp_hint, Some(16));
    assert_eq!(s.camera.up, Vec3::Y);
    // The floor: y = -1, 4 x 4, facing up.
    for t in &s.triangles[..2] {
        assert!(close(normal(&t.v), Vec3::Y, 1e-6));
        assert!(
            t.v.iter()
                .all(|v| (v.y + 1.0).abs() < 1e-6 && v.x.abs() <= 2.0 + 1e-6)
        );
    }
    assert_eq!((s.spheres[0].center, s.spheres[0].radius), (Vec3::X, 1.0));
    assert_eq!(s.materials[1].bsdf, Dielectric::bsdf(1.33, 1.0));
    assert_eq!(s.triangles.len(), 2 + 12);
    for t in &s.triangles[2..] {
        let c = (t.v[0] + t.v[1] + t.v[2]) / 3.0;
        assert!(normal(&t.v).dot(c) < 0.0, "flipped cube faces inwards");
    }
    assert_eq!(s.point_lights[0].intensity, Vec3::splat(10.0));
}

#[test]
fn scene_helpers() {
    let s = load("tests/refs/scenes/point_light_caustic/scene.xml");
    let (lo, hi) = s.bounds();
    assert!(close(lo, Vec3::new(-5.0, 0.0, -5.0), 1e-6));
    assert!(
        close(hi, Vec3::new(5.0, 2.8, 5.0), 1e-6),
        "the light is inside the bounds"
    );

    let big = s.scaled(1000.0);
    assert_eq!(
        big.point_lights[0].intensity,
        s.point_lights[0].intensity * 1e6
    );
    assert_eq!(
        big.point_lights[0].position,
        s.point_lights[0].position * 1000.0
    );
    assert_eq!(big.spheres[0].radius, s.spheres[0].radius * 1000.0);
    assert_eq!(big.camera.target, s.camera.target * 1000.0);
    assert_eq!(big.camera.fov_x_deg, s.camera.fov_x_deg);
    let (blo, bhi) = big.bounds();
    assert!(close(blo, lo * 1000.0, 1e-3) && close(bhi, hi * 1000.0, 1e-3));
    big.validate().unwrap();

    let mut dark = s.clone();
    dark.point_lights.clear();
    assert!(!dark.has_lights());

    let mut broken = s.clone();
    broken.spheres[0].material = 99;
    assert!(
        broken
            .validate()
            .unwrap_err()
            .to_string()
            .contains("sphere 0")
    );
    let mut broken = s.clone();
    broken.triangles[1].v[2].x = f32::NAN;
    assert!(
        broken
            .validate()
            .unwrap_err()
            .to_string()
            .contains("triangle 1")
    );
    let mut broken = s.clone();
    broken.camera.target = broken.camera.origin;
    assert!(broken.validate().is_err());
    let mut broken = s;
    broken.camera.up = Vec3::ZERO;
    assert!(broken.validate().is_err());
}

/// The features the graph pruning and the shader defs read: only kinds some shape (or a point
/// light) uses count, so an unused material or a zero-radiance emitter adds nothing.
#[test]
fn scene_features_list_what_the_scene_uses() {
    use hppm::scene::SceneFeatures;
    let diffuse = load("tests/refs/scenes/cornell_diffuse/scene.xml").features();
    assert_eq!(
        diffuse,
        SceneFeatures {
            bsdfs: vec!["diffuse"],
            area_lights: true,
            triangles: true,
            ..SceneFeatures::default()
        }
    );
    assert!(!diffuse.has_specular_surface());
    assert_eq!(
        diffuse.to_string(),
        "materials diffuse, lights area, shapes triangles"
    );
    let glass = load("tests/refs/scenes/cornell_glass_sphere/scene.xml").features();
    assert!(glass.has_bsdf("dielectric") && glass.has_bsdf("mirror"));
    assert!(glass.spheres && glass.has_specular_surface());
    assert!(!glass.point_lights);
    let point = load("tests/refs/scenes/point_light_caustic/scene.xml").features();
    assert!(point.point_lights && point.has_lights());

    let unused = xml(r#"
        <bsdf type="dielectric" id="unused"/>
        <shape type="rectangle">
            <bsdf type="diffuse"/>
            <emitter type="area"><rgb name="radiance" value="0, 0, 0"/></emitter>
        </shape>"#)
    .features();
    assert!(
        !unused.has_bsdf("dielectric"),
        "an unreferenced BSDF is not a feature"
    );
    assert!(!unused.has_lights(), "a zero-radiance emitter is no light");
}
