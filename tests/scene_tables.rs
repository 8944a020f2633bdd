//! The scene's tables bound as uniform buffers (what a CPU adapter gets, see
//! `src/gpu_scene/resources.rs`'s `TablePlacement`) must render exactly what storage buffers
//! render: same kernels, same arithmetic, only the address space of the loads differs. And a
//! small scene whose rays test every primitive instead of walking the BVH must render what the
//! BVH renders. Each render runs in its own `hppm` process with `HPPM_SCENE_TABLES` set, as a
//! user would measure them.
//!
//! What it would catch: a uniform table padded short or declared with a wrong length (wgpu
//! refuses the binding, or the tail reads zeros), `prim_indices` unpacked from its vec4s with the
//! wrong lane, a table bound at the wrong binding, or a uniform declaration that does not compose
//! (the render fails). Any of these changes the image or stops the render.

use std::path::PathBuf;
use std::process::{Command, Output};

use hppm::image::Image;

/// Scenes that put different tables in uniform buffers on lavapipe: everything (spheres,
/// plastics, conductors), everything with textures and an environment map, a ring mesh whose
/// nodes fit while its triangles and normals do not, and a glass of water whose BVH is collapsed
/// from 3,249 nodes to fit a uniform binding (a merged leaf that lost a triangle would show).
const SCENES: [(&str, &[&str]); 4] = [
    (
        "tests/refs/scenes/materials_cornell/scene.xml",
        &[
            "BVH_NODES_UNIFORM",
            "TRIANGLES_UNIFORM",
            "PRIM_INDICES_UNIFORM",
            "MATERIALS_UNIFORM",
        ],
    ),
    (
        "tests/refs/scenes/sun_sky_textured/scene.xml",
        &["BVH_NODES_UNIFORM", "TRIANGLES_UNIFORM", "LIGHTS_UNIFORM"],
    ),
    (
        "scenes/glossy_ring/scene.xml",
        &["BVH_NODES_UNIFORM", "PRIM_INDICES_UNIFORM"],
    ),
    (
        "tests/refs/scenes/water_glass/scene.xml",
        &["BVH_NODES_UNIFORM", "PRIM_INDICES_UNIFORM"],
    ),
];

const GRAPHS: [&str; 2] = ["graphs/pt.ron", "graphs/hybrid.ron"];

/// `pt` is deterministic, so its images must be identical. The hybrid's photon deposits are
/// float atomic adds whose order follows the threads' timing: two runs of one placement differ
/// in the last bits of a few pixels (13 of 768 on the glossy ring, on a busy machine). Its
/// bound is that of tests/shards.rs; any of the faults above is 1e-3 or more.
const HYBRID_EQUAL: f64 = 1e-9;

fn render(scene: &str, graph: &str, tables: &str, out: &PathBuf) -> Output {
    render_chunked(scene, graph, tables, None, out)
}

fn render_chunked(
    scene: &str,
    graph: &str,
    tables: &str,
    chunk_entries: Option<u64>,
    out: &PathBuf,
) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_hppm"));
    if let Some(n) = chunk_entries {
        command.env("HPPM_TABLE_CHUNK_ENTRIES", n.to_string());
    }
    let output = command
        .args([
            "render", scene, "--graph", graph, "--spp", "4", "--size", "32x24",
        ])
        .arg("--out")
        .arg(out)
        .env("HPPM_SCENE_TABLES", tables)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run hppm");
    assert!(
        output.status.success(),
        "{scene} through {graph} with {tables} tables: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// Two renders of one scene through `graph` that must be the same: `pt` bit for bit, the hybrid
/// within its atomic adds' ordering noise ([`HYBRID_EQUAL`]).
fn assert_same_render(graph: &str, a: &Image, b: &Image, what: &str) {
    if graph == "graphs/pt.ron" {
        let differing = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .filter(|(p, q)| p != q)
            .count();
        assert_eq!(differing, 0, "{what} through pt: {differing} pixels differ");
    } else {
        let error = b.relmse(a).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            error <= HYBRID_EQUAL,
            "{what} through {graph}: relMSE {error}"
        );
    }
}

/// The tables the render reported as uniform.
fn uniform_tables(output: &Output) -> Vec<String> {
    String::from_utf8_lossy(&output.stderr)
        .lines()
        .find_map(|l| l.strip_prefix("scene tables in uniform buffers: "))
        .map(|l| l.split_whitespace().map(str::to_string).collect())
        .unwrap_or_default()
}

#[test]
fn uniform_scene_tables_render_the_same_image_as_storage_tables() {
    let dir = std::env::temp_dir().join(format!("hppm-tables-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    for (scene, expected) in SCENES {
        for graph in GRAPHS {
            let name = format!("{}-{}", scene.replace('/', "_"), graph.replace('/', "_"));
            let storage_out = dir.join(format!("{name}-storage.exr"));
            let uniform_out = dir.join(format!("{name}-uniform.exr"));
            let storage = render(scene, graph, "storage", &storage_out);
            let uniform = render(scene, graph, "uniform-bvh", &uniform_out);
            assert!(
                uniform_tables(&storage).is_empty(),
                "{scene}: storage run bound uniforms"
            );
            let bound = uniform_tables(&uniform);
            let collapsed =
                String::from_utf8_lossy(&uniform.stderr).contains("scene BVH collapsed");
            assert_eq!(
                collapsed,
                scene.contains("water_glass"),
                "{scene}: BVH collapsed or not as expected"
            );
            for table in expected {
                assert!(
                    bound.iter().any(|b| b == table),
                    "{scene}: {table} not uniform (bound: {bound:?})"
                );
            }
            let a = Image::read_exr(&storage_out).unwrap_or_else(|e| panic!("{e}"));
            let b = Image::read_exr(&uniform_out).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!((a.width, a.height), (b.width, b.height));
            let mean: f64 =
                a.pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / a.pixels.len() as f64;
            assert!(mean > 0.0, "{scene} through {graph}: black image");
            assert_same_render(graph, &a, &b, scene);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Small scenes (every primitive tested on lavapipe) with each block size of the unrolled tests
/// in shaders/common/traversal.wgsl: 36 triangles (32 + 4; the cubes' blocks culled by their boxes),
/// 12 and 2 spheres (8 + 4 and 2), 24 and 3 (16 + 8 and 2 + 1), 2 and 1 (a point light's
/// caustic: photons' coplanar tie rule).
const SMALL_SCENES: [&str; 4] = [
    "tests/refs/scenes/cornell_diffuse/scene.xml",
    "tests/refs/scenes/cornell_glass_sphere/scene.xml",
    "tests/refs/scenes/materials_cornell/scene.xml",
    "tests/refs/scenes/point_light_caustic/scene.xml",
];

/// Rays that meet two primitives at exactly one distance may keep the other one when the
/// primitives are tested in index order instead of the BVH's; such a pixel's path then differs.
/// At most this share of pixels may differ by more than the hybrid's ordering noise. A
/// primitive no block tests (a wall or sphere missing), a sphere given a wrong index (its
/// material or light swapped) or a block starting at the wrong index changes a tenth of the
/// image or more.
const TIE_PIXELS: f64 = 0.01;

#[test]
fn testing_every_primitive_renders_what_the_bvh_renders() {
    let dir = std::env::temp_dir().join(format!("hppm-every-prim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    for scene in SMALL_SCENES {
        for graph in GRAPHS {
            let name = format!("{}-{}", scene.replace('/', "_"), graph.replace('/', "_"));
            let bvh_out = dir.join(format!("{name}-bvh.exr"));
            let every_out = dir.join(format!("{name}-every.exr"));
            let bvh = render(scene, graph, "uniform-bvh", &bvh_out);
            let every = render(scene, graph, "uniform", &every_out);
            let tests_every = |output: &Output| {
                String::from_utf8_lossy(&output.stderr)
                    .contains("rays test every primitive instead of the BVH")
            };
            assert!(
                !tests_every(&bvh),
                "{scene}: uniform-bvh tested every primitive"
            );
            assert!(
                tests_every(&every),
                "{scene}: uniform did not test every primitive"
            );
            let a = Image::read_exr(&bvh_out).unwrap_or_else(|e| panic!("{e}"));
            let b = Image::read_exr(&every_out).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!((a.width, a.height), (b.width, b.height));
            let differing = a
                .pixels
                .iter()
                .zip(&b.pixels)
                .filter(|(p, q)| {
                    p.iter().zip(q.iter()).any(|(x, y)| {
                        f64::from((x - y).abs()) > 1e-4 * f64::from(x.abs().max(y.abs())).max(1e-6)
                    })
                })
                .count();
            let share = differing as f64 / a.pixels.len() as f64;
            assert!(
                share <= TIE_PIXELS,
                "{scene} through {graph}: {differing} of {} pixels differ",
                a.pixels.len()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Tables split over several bindings (what a mesh of millions of triangles gets on an adapter
/// that binds 128 MiB) must render what one binding per table renders: the same loads, only
/// the binding an entry is read from differs. water_glass's tables chunked at 512 entries:
/// nodes, indices, triangles, normals and texture coordinates in 2 to 8 chunks each. Would catch
/// an accessor that picks the wrong chunk or drops the index's high bits (a wrong triangle, a
/// hole or a garbled glass), a chunk bound at another binding than its declaration, or chunks
/// cut at another size than the shader's shift.
#[test]
fn chunked_scene_tables_render_the_same_image_as_whole_tables() {
    let dir = std::env::temp_dir().join(format!("hppm-chunks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = "tests/refs/scenes/water_glass/scene.xml";
    for graph in GRAPHS {
        let name = graph.replace('/', "_");
        let whole_out = dir.join(format!("{name}-whole.exr"));
        let chunked_out = dir.join(format!("{name}-chunked.exr"));
        render(scene, graph, "storage", &whole_out);
        let chunked = render_chunked(scene, graph, "storage", Some(512), &chunked_out);
        let report = String::from_utf8_lossy(&chunked.stderr)
            .lines()
            .find_map(|l| {
                l.strip_prefix("scene tables larger than one binding, in chunks: ")
                    .map(str::to_string)
            })
            .unwrap_or_default();
        for table in ["BVH_NODES", "PRIM_INDICES", "TRIANGLES", "TRIANGLE_UVS"] {
            assert!(
                report.contains(&format!("{table} ")),
                "{table} not chunked: {report:?}"
            );
        }
        let a = Image::read_exr(&whole_out).unwrap_or_else(|e| panic!("{e}"));
        let b = Image::read_exr(&chunked_out).unwrap_or_else(|e| panic!("{e}"));
        assert_same_render(graph, &a, &b, "water_glass chunked");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A texture table split over bindings (ten 2048x2048 bitmaps are 480 MiB; lavapipe binds 128)
/// renders what one binding renders: a textured plane whose table of 28 words is cut into
/// chunks of 16. Would catch a texel read from the wrong chunk (a shifted or garbled grid).
#[test]
fn chunked_textures_render_the_same_image_as_one_table() {
    let dir = std::env::temp_dir().join(format!("hppm-texture-chunks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = "tests/data/textures/textured_plane.xml";
    let graph = "graphs/pt.ron";
    let (whole_out, chunked_out) = (dir.join("whole.exr"), dir.join("chunked.exr"));
    render(scene, graph, "storage", &whole_out);
    let chunked = render_chunked(scene, graph, "storage", Some(16), &chunked_out);
    let stderr = String::from_utf8_lossy(&chunked.stderr);
    assert!(
        stderr.contains("TEXTURES "),
        "textures not chunked: {stderr}"
    );
    let a = Image::read_exr(&whole_out).unwrap_or_else(|e| panic!("{e}"));
    let b = Image::read_exr(&chunked_out).unwrap_or_else(|e| panic!("{e}"));
    assert_same_render(graph, &a, &b, "textured plane chunked");
    let _ = std::fs::remove_dir_all(&dir);
}
