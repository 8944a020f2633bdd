//! Every shipped pass shader composes and validates, and the GPU structs in
//! `src/gpu_scene/layout.rs` have the sizes naga computes for their WGSL twins.

use std::collections::HashMap;

use hppm::gpu::shaders::{ShaderFile, ShaderLibrary};
use hppm::gpu_scene::layout::{
    GpuLight, GpuMaterial, GpuSceneUniform, GpuSphere, GpuTriangle, GpuTriangleNormals,
    GpuTriangleUvs,
};
use hppm::passes::{builtin_kinds, common_modules};
use hppm::scene::bvh::BvhNode;
use wgpu::naga;

fn library_with(
    float_atomics: bool,
    defs: HashMap<String, naga_oil::compose::ShaderDefValue>,
) -> ShaderLibrary {
    ShaderLibrary::new(
        float_atomics,
        defs,
        &common_modules(&hppm::bsdfs::BsdfRegistry::builtin()),
    )
    .expect("modules compose")
}

fn library(float_atomics: bool) -> ShaderLibrary {
    library_with(
        float_atomics,
        hppm::passes::all_scene_defs(&hppm::bsdfs::BsdfRegistry::builtin()),
    )
}

/// Validates a composed module with every check and capability naga has; `what` names it.
fn validate(module: &naga::Module, what: &str) {
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(module)
    .unwrap_or_else(|e| panic!("{what}: {e:?}"));
}

/// Every entry file some pass kind names, once each.
fn pass_shaders() -> Vec<ShaderFile> {
    let mut files: Vec<ShaderFile> = Vec::new();
    for kind in builtin_kinds() {
        for file in kind.shaders {
            if !files.contains(file) {
                files.push(*file);
            }
        }
    }
    files
}

/// The entry file at `path`, as a pass kind names it.
fn shader(path: &str) -> ShaderFile {
    pass_shaders()
        .into_iter()
        .find(|f| f.path == path)
        .unwrap_or_else(|| panic!("no pass names {path}"))
}

/// The light defs, which guard light sampling and emission only: their sets below, against
/// pair-covering sets of the other defs.
const LIGHT_DEFS: [&str; 5] = [
    "POINT_LIGHTS",
    "SPOT_LIGHTS",
    "PROJECTORS",
    "DIRECTIONAL_LIGHTS",
    "ENVIRONMENT",
];
const LIGHT_SETS: [&[&str]; 7] = [
    &[],
    &["POINT_LIGHTS"],
    &["POINT_LIGHTS", "SPOT_LIGHTS"],
    &["POINT_LIGHTS", "PROJECTORS"],
    &["DIRECTIONAL_LIGHTS"],
    &["ENVIRONMENT"],
    &LIGHT_DEFS,
];

/// Masks over `n` defs in which every pair of defs takes each of its four on/off states, from
/// eight masks for up to 35 defs: def `i` is on in mask `r` when row `r` is in the `i`-th 4-subset
/// of rows 1..8 (Kleitman and Spencer's construction). Two 4-subsets of 7 rows always share a
/// row (both on), neither holds the other (each on alone), and row 0 is in none (both off).
fn pair_covering_masks(n: usize) -> Vec<u64> {
    let subsets: Vec<u32> = (0u32..256)
        .filter(|m| m & 1 == 0 && m.count_ones() == 4)
        .take(n)
        .collect();
    assert_eq!(subsets.len(), n, "more defs than eight masks cover");
    (0..8)
        .map(|row| {
            (0..n)
                .filter(|&i| subsets[i] & (1 << row) != 0)
                .fold(0, |mask, i| mask | 1u64 << i)
        })
        .collect()
}

/// Def sets that cover, with and without float atomics: every pair of the non-light defs in
/// each of its four on/off states (eight masks), each non-light def on and off with each light
/// set (no def and every def, with each light set), and each def alone and left out (with no
/// light and with every light). A def that breaks only in a combination of three or more would
/// be missed, and none has. (Every pair crossed with every light set was 784 sets and two
/// minutes of CI, every subset 14,336; these 42 take seconds.)
fn every_def_combination() -> Vec<(bool, HashMap<String, naga_oil::compose::ShaderDefValue>)> {
    let names: Vec<&str> = hppm::passes::SCENE_DEFS
        .iter()
        .copied()
        .filter(|n| !LIGHT_DEFS.contains(n))
        .collect();
    assert!(
        LIGHT_DEFS
            .iter()
            .all(|d| hppm::passes::SCENE_DEFS.contains(d)),
        "a light def is no longer a scene def"
    );
    let n = names.len();
    let all = (1u64 << n) - 1;
    let mut sets: Vec<(u64, &[&str])> = Vec::new();
    for lights in LIGHT_SETS {
        sets.extend([(0, lights), (all, lights)]);
    }
    for (row, mask) in pair_covering_masks(n).into_iter().enumerate() {
        sets.push((mask, LIGHT_SETS[row % LIGHT_SETS.len()]));
    }
    for i in 0..n {
        sets.extend([(1 << i, LIGHT_SETS[0]), (all & !(1 << i), &LIGHT_DEFS[..])]);
    }
    let mut out = Vec::new();
    for float_atomics in [true, false] {
        for &(mask, lights) in &sets {
            let defs = names
                .iter()
                .enumerate()
                .filter(|(i, _)| mask & (1 << i) != 0)
                .map(|(_, n)| *n)
                .chain(lights.iter().copied())
                .map(|n| (n.to_string(), naga_oil::compose::ShaderDefValue::Bool(true)))
                .collect();
            out.push((float_atomics, defs));
        }
    }
    out
}

/// The masks cover every pair of defs in each on/off state: would catch a construction that
/// leaves a pair out (a def combination the composition test then never tries).
#[test]
fn pair_covering_masks_cover_every_pair() {
    for n in [2, 10, 20, 35] {
        let masks = pair_covering_masks(n);
        for i in 0..n {
            for j in i + 1..n {
                for (a, b) in [(false, false), (false, true), (true, false), (true, true)] {
                    assert!(
                        masks
                            .iter()
                            .any(|m| (m >> i & 1 == 1) == a && (m >> j & 1 == 1) == b),
                        "{n} defs: pair ({i}, {j}) never ({a}, {b})"
                    );
                }
            }
        }
    }
}

#[test]
fn every_pass_shader_composes_and_validates() {
    for (float_atomics, defs) in every_def_combination() {
        let lib = library_with(float_atomics, defs);
        for file in pass_shaders() {
            let path = file.path;
            let module = lib
                .compose(&file)
                .unwrap_or_else(|e| panic!("{path} (float atomics {float_atomics}): {e}"));
            validate(&module, path);
            // One kernel per pass is `main`; multi-kernel builders (radix sort, LBVH) name theirs.
            let multi_kernel = module.entry_points.len() > 1;
            assert!(
                multi_kernel || module.entry_points.iter().any(|e| e.name == "main"),
                "{path} has no `main` entry point"
            );
        }
    }
}

/// The passes' own defs (`GLOSSY`) on top of no scene def, every scene def, and each one alone:
/// the glossy-caustic code composes with whatever the scene compiles in or out.
#[test]
fn every_pass_shader_composes_with_its_own_defs() {
    let names = hppm::passes::SCENE_DEFS;
    let mut sets: Vec<Vec<&str>> = vec![Vec::new(), names.to_vec()];
    sets.extend(names.iter().map(|n| vec![*n]));
    for float_atomics in [true, false] {
        for set in &sets {
            let lib = library_with(
                float_atomics,
                hppm::gpu::shaders::defs_of(set.iter().copied()),
            );
            for file in pass_shaders() {
                let module = lib
                    .compose_with(&file, hppm::passes::PASS_DEFS)
                    .unwrap_or_else(|e| panic!("{} with {set:?} + GLOSSY: {e}", file.path));
                validate(&module, file.path);
            }
        }
    }
}

/// naga_oil decorates imported names (`Triangle` becomes `TriangleX_naga_oil_mod_...`).
fn struct_size(module: &naga::Module, name: &str) -> Option<u32> {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).ok()?;
    module.types.iter().find_map(|(handle, ty)| {
        let type_name = ty.name.as_deref()?;
        let matches = type_name == name || type_name.starts_with(&format!("{name}X_naga_oil"));
        matches.then(|| layouter[handle].size)
    })
}

#[test]
fn gpu_structs_match_wgsl_layout() {
    let module = library(true)
        .compose(&shader("shaders/passes/path_trace.wgsl"))
        .expect("path_trace composes");
    let expected = [
        ("SceneUniform", std::mem::size_of::<GpuSceneUniform>()),
        ("BvhNode", std::mem::size_of::<BvhNode>()),
        ("Triangle", std::mem::size_of::<GpuTriangle>()),
        ("TriangleNormals", std::mem::size_of::<GpuTriangleNormals>()),
        ("TriangleUvs", std::mem::size_of::<GpuTriangleUvs>()),
        ("Sphere", std::mem::size_of::<GpuSphere>()),
        ("Material", std::mem::size_of::<GpuMaterial>()),
        ("Light", std::mem::size_of::<GpuLight>()),
    ];
    for (name, rust_size) in expected {
        let wgsl_size = struct_size(&module, name).unwrap_or_else(|| panic!("no struct {name}"));
        assert_eq!(
            wgsl_size as usize, rust_size,
            "size of {name}: WGSL vs Rust"
        );
    }
}

#[test]
fn a_wgsl_error_names_the_module_file_and_line() {
    // Compose a broken entry through the same composer setup the library uses.
    let broken =
        "#import common::rng::rng_next_f32\n\nfn main() {\n    let x: f32 = undefined_name;\n}\n";
    let err = library(true)
        .compose_source("shaders/passes/broken.wgsl", broken)
        .expect_err("broken shader must not compose");
    let message = err.to_string();
    assert!(message.contains("shaders/passes/broken.wgsl"), "{message}");
    assert!(message.contains(":4:"), "line 4 expected in: {message}");
}

fn function_names(module: &naga::Module) -> Vec<String> {
    module
        .functions
        .iter()
        .filter_map(|(_, f)| f.name.clone())
        .collect()
}

/// Code for what a scene lacks is compiled out: a diffuse-only scene's kernels have no
/// dielectric function, a scene without spheres no sphere intersection, a scene without rough
/// or plastic BSDFs none of their modules, a scene without textures no texture lookup.
#[test]
fn scene_features_compile_code_in_and_out() {
    let load = |p: &str| {
        hppm::loaders::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(p))
            .unwrap_or_else(|e| panic!("{p}: {e}"))
    };
    let has = |lib: &ShaderLibrary, path: &str, name: &str| {
        let module = lib
            .compose(&shader(path))
            .unwrap_or_else(|e| panic!("{path}: {e}"));
        function_names(&module).iter().any(|f| f.contains(name))
    };
    let diffuse = library_with(
        true,
        hppm::passes::scene_defs(
            &load("tests/refs/scenes/cornell_diffuse/scene.xml").features(),
            &hppm::bsdfs::BsdfRegistry::builtin(),
        ),
    );
    let glass = library_with(
        true,
        hppm::passes::scene_defs(
            &load("tests/refs/scenes/cornell_glass_sphere/scene.xml").features(),
            &hppm::bsdfs::BsdfRegistry::builtin(),
        ),
    );
    for path in [
        "shaders/passes/path_trace.wgsl",
        "shaders/passes/photon_trace.wgsl",
    ] {
        assert!(
            !has(&diffuse, path, "sample_dielectric"),
            "{path}: diffuse scene"
        );
        assert!(
            !has(&diffuse, path, "fresnel_dielectric"),
            "{path}: diffuse scene"
        );
        assert!(
            !has(&diffuse, path, "intersect_sphere"),
            "{path}: no spheres"
        );
        assert!(
            has(&glass, path, "sample_dielectric"),
            "{path}: glass scene"
        );
        assert!(
            has(&glass, path, "intersect_sphere"),
            "{path}: glass scene has spheres"
        );
    }
    // The BSDF kinds: each module only where the scene has its kind.
    let materials = library_with(
        true,
        hppm::passes::scene_defs(
            &load("tests/refs/scenes/materials_cornell/scene.xml").features(),
            &hppm::bsdfs::BsdfRegistry::builtin(),
        ),
    );
    for path in [
        "shaders/passes/path_trace.wgsl",
        "shaders/passes/photon_trace.wgsl",
    ] {
        for function in [
            "roughconductor_sample",
            "rough_plastic_sample",
            "plastic_sample",
            "rough_dielectric_sample",
            "microfacet_sample",
        ] {
            assert!(
                !has(&diffuse, path, function),
                "{path}: diffuse scene has {function}"
            );
            assert!(
                !has(&glass, path, function),
                "{path}: glass scene has {function}"
            );
            assert!(
                has(&materials, path, function),
                "{path}: materials_cornell lacks {function}"
            );
        }
        // materials_cornell has no smooth or thin dielectric.
        assert!(
            !has(&materials, path, "sample_thin_dielectric"),
            "{path}: materials scene"
        );
    }
    // Texture lookups only where a material has a texture.
    let textured = library_with(
        true,
        hppm::passes::scene_defs(
            &load("tests/data/scenes/textured_box.xml").features(),
            &hppm::bsdfs::BsdfRegistry::builtin(),
        ),
    );
    for path in [
        "shaders/passes/path_trace.wgsl",
        "shaders/passes/photon_trace.wgsl",
    ] {
        for lib in [&diffuse, &glass, &materials] {
            assert!(
                !has(lib, path, "texture_lookup"),
                "{path}: untextured scene"
            );
        }
        assert!(
            has(&textured, path, "texture_lookup"),
            "{path}: textured scene"
        );
    }
    let point_light = library_with(
        true,
        hppm::passes::scene_defs(
            &load("tests/refs/scenes/point_light_caustic/scene.xml").features(),
            &hppm::bsdfs::BsdfRegistry::builtin(),
        ),
    );
    for (path, function) in [
        ("shaders/passes/path_trace.wgsl", "sample_point_light"),
        ("shaders/passes/photon_trace.wgsl", "emit_point_photon"),
    ] {
        assert!(
            !has(&glass, path, function),
            "{path}: no point light in the glass scene"
        );
        assert!(
            has(&point_light, path, function),
            "{path}: point-light scene"
        );
    }
}

/// Every Rust struct uploaded to a WGSL struct (scene tables, hit points, photon hits, deposits,
/// tree nodes, each pass's params) has the composed module's size and each named field's
/// offset, and a size that keeps arrays of it at the same stride. A field added, reordered or
/// retyped on one side only fails here instead of rendering garbage.
#[test]
fn every_uploaded_struct_matches_its_wgsl_layout() {
    let checked = hppm::passes::Registry::builtin()
        .check_layouts()
        .unwrap_or_else(|problems| panic!("{}", problems.join("\n")));
    eprintln!("checked {} layouts: {}", checked.len(), checked.join(", "));
    for name in [
        "PathTraceUniform",
        "PhotonUniform",
        "MergeUniform",
        "HitPoint",
        "PhotonHit",
    ] {
        assert!(checked.contains(&name), "{name} is not checked");
    }
}

/// The check itself finds a wrong offset and a wrong size (so the test above can fail).
#[test]
fn a_layout_that_differs_is_reported() {
    #[repr(C)]
    struct Shifted {
        _pad: u32,
        position: [f32; 3],
        pixel: u32,
    }
    let file = shader("shaders/passes/gather_bvh.wgsl");
    let module = library(true).compose(&file).expect("compose");
    let layout = hppm::struct_layout!(Shifted => "HitPoint" in file, { position, pixel });
    let err = layout.check(&module).expect_err("must differ");
    assert!(
        err.contains("HitPoint (Rust Shifted): 64 bytes in WGSL, 20 in Rust"),
        "{err}"
    );
    assert!(
        err.contains("position: offset 0 in WGSL, 4 in Rust"),
        "{err}"
    );
}

/// Every pass shader composes and validates with the scene's tables declared as uniform
/// buffers (what CPU adapters get), all at once and each alone on top of every scene def. Would
/// catch a uniform declaration whose array stride is not a multiple of 16, an access that only
/// storage arrays allow, or a kernel that reads a table without going through its accessor.
#[test]
fn every_pass_shader_composes_with_uniform_scene_tables() {
    use hppm::gpu_scene::{PlacementRule, TablePlacement};
    let scene = hppm::loaders::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/refs/scenes/cornell_glass_sphere/scene.xml"
    )))
    .expect("scene");
    let gpu_scene = hppm::gpu_scene::layout::GpuScene::new(&scene, 8, 8).expect("layout");
    let limits = wgpu::Limits::default();
    let uniform = TablePlacement::choose(PlacementRule::UniformWithBvh, &gpu_scene, &limits);
    let all = uniform.defs();
    assert_eq!(all.len(), 7, "every table of a small scene fits: {all:?}");
    let mut sets: Vec<HashMap<_, _>> = vec![all.clone()];
    sets.extend(all.iter().map(|(k, v)| HashMap::from([(k.clone(), *v)])));
    for tables in sets {
        let mut defs = hppm::passes::all_scene_defs(&hppm::bsdfs::BsdfRegistry::builtin());
        defs.extend(tables.clone());
        let lib = library_with(true, defs);
        for file in pass_shaders() {
            let module = lib
                .compose(&file)
                .unwrap_or_else(|e| panic!("{} with {tables:?}: {e}", file.path));
            validate(&module, &format!("{} with {tables:?}", file.path));
        }
    }
}

/// Every pass kernel composes and validates with the every-primitive test and every block of
/// it present (127 triangles and 15 spheres), over uniform tables. Would catch a block whose
/// function is missing or misnamed, or a def substituted where WGSL wants another type.
#[test]
fn every_pass_shader_composes_testing_every_primitive() {
    use hppm::gpu_scene::{PlacementRule, TablePlacement};
    use naga_oil::compose::ShaderDefValue;
    let scene = hppm::loaders::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/refs/scenes/cornell_glass_sphere/scene.xml"
    )))
    .expect("scene");
    let gpu_scene = hppm::gpu_scene::layout::GpuScene::new(&scene, 8, 8).expect("layout");
    let uniform = TablePlacement::choose(
        PlacementRule::UniformWithBvh,
        &gpu_scene,
        &wgpu::Limits::default(),
    );
    let mut defs = hppm::passes::all_scene_defs(&hppm::bsdfs::BsdfRegistry::builtin());
    defs.extend(uniform.defs());
    defs.insert("EVERY_PRIM".into(), ShaderDefValue::Bool(true));
    for (size, first) in [
        (64, 0),
        (32, 64),
        (16, 96),
        (8, 112),
        (4, 120),
        (2, 124),
        (1, 126),
    ] {
        defs.insert(
            format!("TRIANGLES_FROM_{size}"),
            ShaderDefValue::UInt(first),
        );
    }
    for (size, first) in [(8, 0), (4, 8), (2, 12), (1, 14)] {
        defs.insert(format!("SPHERES_FROM_{size}"), ShaderDefValue::UInt(first));
    }
    let lib = library_with(true, defs);
    for file in pass_shaders() {
        let module = lib
            .compose(&file)
            .unwrap_or_else(|e| panic!("{} testing every primitive: {e}", file.path));
        validate(&module, &format!("{} testing every primitive", file.path));
    }
}
