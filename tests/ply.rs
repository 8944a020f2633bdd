//! PLY meshes (Mitsuba's `ply` shape): ASCII and binary files of either byte order load the
//! same triangles as the OBJ they were written from, vertex normals and texture coordinates are
//! read, and broken files are errors naming the file (and the scene line that uses it). The
//! render check runs on whatever adapter wgpu finds (lavapipe in CI).

mod common;

use std::path::{Path, PathBuf};

use common::*;
use glam::Vec3;
use hppm::loaders::ply;
use hppm::scene::SceneError;

/// The vertices and faces of a plain OBJ (`v` and `f` records only, 1-based indices).
fn read_obj(path: &Path) -> (Vec<[f32; 3]>, Vec<Vec<u32>>) {
    let text = std::fs::read_to_string(path).expect("OBJ");
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let xyz: Vec<f32> = words.map(|w| w.parse().expect("number")).collect();
                v.push([xyz[0], xyz[1], xyz[2]]);
            }
            Some("f") => f.push(
                words
                    .map(|w| {
                        w.split('/')
                            .next()
                            .unwrap_or(w)
                            .parse::<u32>()
                            .expect("index")
                            - 1
                    })
                    .collect(),
            ),
            _ => {}
        }
    }
    (v, f)
}

#[derive(Clone, Copy, Debug)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

/// A PLY file of `v` and `f`: positions as float (or double for big-endian files, so both
/// scalar types are read), faces as `uchar`-counted `int` lists (`uint` in big-endian files).
fn write_ply(v: &[[f32; 3]], f: &[Vec<u32>], encoding: Encoding) -> Vec<u8> {
    let (format, scalar, index) = match encoding {
        Encoding::Ascii => ("ascii", "float", "int"),
        Encoding::LittleEndian => ("binary_little_endian", "float", "int"),
        Encoding::BigEndian => ("binary_big_endian", "double", "uint"),
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment written by tests/ply.rs\nelement vertex {}\n\
         property {scalar} x\nproperty {scalar} y\nproperty {scalar} z\nelement face {}\n\
         property list uchar {index} vertex_indices\nend_header\n",
        v.len(),
        f.len()
    )
    .into_bytes();
    for p in v {
        match encoding {
            Encoding::Ascii => out.extend(format!("{} {} {}\n", p[0], p[1], p[2]).bytes()),
            Encoding::LittleEndian => p.iter().for_each(|x| out.extend(x.to_le_bytes())),
            Encoding::BigEndian => p.iter().for_each(|x| out.extend((*x as f64).to_be_bytes())),
        }
    }
    for face in f {
        match encoding {
            Encoding::Ascii => {
                let list: Vec<String> = face.iter().map(u32::to_string).collect();
                out.extend(format!("{} {}\n", face.len(), list.join(" ")).bytes());
            }
            Encoding::LittleEndian => {
                out.push(face.len() as u8);
                face.iter()
                    .for_each(|i| out.extend((*i as i32).to_le_bytes()));
            }
            Encoding::BigEndian => {
                out.push(face.len() as u8);
                face.iter().for_each(|i| out.extend(i.to_be_bytes()));
            }
        }
    }
    out
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hppm-ply-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// `cornell_diffuse_obj` with its two OBJ meshes written as PLY files of `encoding`, in `dir`.
fn cornell_as_ply(dir: &Path, encoding: Encoding) -> PathBuf {
    let source = repo_path("tests/refs/scenes/cornell_diffuse_obj");
    for mesh in ["short_box", "unit_cube"] {
        let (v, f) = read_obj(&source.join(format!("{mesh}.obj")));
        std::fs::write(dir.join(format!("{mesh}.ply")), write_ply(&v, &f, encoding))
            .expect("write PLY");
    }
    let xml = std::fs::read_to_string(source.join("scene.xml")).expect("scene");
    let xml = xml
        .replace("type=\"obj\"", "type=\"ply\"")
        .replace(".obj\"", ".ply\"");
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).expect("write scene");
    path
}

/// The Cornell box with PLY meshes (ASCII, binary little- and big-endian; float and double
/// positions; int and uint indices) is the same scene as with the OBJ meshes, triangle for
/// triangle: a reader that dropped a face, swapped a winding or misread a byte order fails.
#[test]
fn ply_meshes_load_the_same_triangles_as_their_obj() {
    let obj_scene = load_scene("tests/refs/scenes/cornell_diffuse_obj/scene.xml");
    for encoding in [Encoding::Ascii, Encoding::LittleEndian, Encoding::BigEndian] {
        let dir = temp_dir(&format!("{encoding:?}"));
        let ply_scene = hppm::loaders::load(&cornell_as_ply(&dir, encoding))
            .unwrap_or_else(|e| panic!("{encoding:?}: {e}"));
        assert_eq!(ply_scene.triangles, obj_scene.triangles, "{encoding:?}");
        assert_eq!(ply_scene.materials, obj_scene.materials, "{encoding:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// And it renders the same image (same seed, through `pt`): the loader's triangles reach the
/// GPU the same way whatever file they came from.
#[test]
fn ply_scene_renders_what_the_obj_scene_renders() {
    let gpu = gpu();
    let dir = temp_dir("render");
    let mut images = Vec::new();
    for path in [
        repo_path("tests/refs/scenes/cornell_diffuse_obj/scene.xml"),
        cornell_as_ply(&dir, Encoding::LittleEndian),
    ] {
        let mut scene = hppm::loaders::load(&path).expect("scene");
        scene.camera.width = 32;
        scene.camera.height = 32;
        let mut r = renderer(&gpu, &scene, load_graph("graphs/pt.ron"), 5);
        images.push(render_to(&mut r, 4));
    }
    assert!(images[0].mean()[0] > 0.0, "the Cornell box is lit");
    assert_eq!(images[0].pixels, images[1].pixels);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Vertex normals and texture coordinates (in each of the spellings Mitsuba reads) are read per
/// triangle corner, quads are split into two triangles, and colours are ignored.
#[test]
fn ply_normals_and_texture_coordinates_are_read() {
    for (u, v) in [("u", "v"), ("s", "t"), ("texture_u", "texture_v")] {
        let text = format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
             property float {u}\nproperty float {v}\nproperty uchar red\nelement face 1\n\
             property list uchar int vertex_index\nend_header\n\
             0 0 0 0 0 1 0 0 255\n1 0 0 0 0.6 0.8 1 0 255\n1 1 0 0 0 1 1 1 255\n\
             0 1 0 0.6 0 0.8 0 1 255\n4 0 1 2 3\n"
        );
        let mesh = ply::parse(Path::new("quad.ply"), text.as_bytes()).expect("quad");
        assert_eq!(mesh.triangles.len(), 2, "{u}/{v}");
        assert_eq!(mesh.triangles[1][2], Vec3::new(0.0, 1.0, 0.0));
        let normals = mesh.normals.expect("normals");
        assert_eq!(normals[0][1], Vec3::new(0.0, 0.6, 0.8));
        assert_eq!(normals[1][2], Vec3::new(0.6, 0.0, 0.8));
        let uvs = mesh.uvs.expect("uvs");
        assert_eq!(uvs[0][2], glam::Vec2::new(1.0, 1.0), "{u}/{v}");
    }
}

/// Broken PLY files are errors that name the file and say what is wrong, never a panic or an
/// empty mesh: a bad header, a truncated binary payload, an index past the vertices, a missing
/// element, non-finite numbers, and a scene naming a missing file (at the scene's line).
#[test]
fn malformed_ply_files_name_the_file_and_the_problem() {
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                  property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                  end_header\n";
    let (v, f) = (
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![vec![0, 1, 2]],
    );
    let binary = write_ply(&v, &f, Encoding::LittleEndian);
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        ("not_ply.ply", b"OFF\n3 1 0\n".to_vec(), &["invalid PLY"]),
        (
            "bad_format.ply",
            header.replace("ascii", "binary_middle_endian").into_bytes(),
            &["invalid PLY"],
        ),
        (
            "truncated.ply",
            binary[..binary.len() - 3].to_vec(),
            &["invalid PLY"],
        ),
        (
            "bad_index.ply",
            format!("{header}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").into_bytes(),
            &["face 0", "vertex 7", "3 vertices"],
        ),
        (
            "no_faces.ply",
            header
                .replace("element face 1", "element face 0")
                .into_bytes()
                .into_iter()
                .chain(b"0 0 0\n1 0 0\n0 1 0\n".iter().copied())
                .collect(),
            &["0 faces"],
        ),
        (
            "nan_ascii.ply",
            format!("{header}0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n").into_bytes(),
            &["nan_ascii.ply:11:", "invalid PLY"],
        ),
        (
            "nan_binary.ply",
            write_ply(
                &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
                &f,
                Encoding::LittleEndian,
            ),
            &["vertex 1", "x", "finite"],
        ),
        (
            "no_z.ply",
            header
                .replace("property float z\n", "")
                .into_bytes()
                .into_iter()
                .chain(b"0 0\n1 0\n0 1\n3 0 1 2\n".iter().copied())
                .collect(),
            &["x, y, z"],
        ),
    ];
    for (name, bytes, words) in cases {
        let err = match ply::parse(Path::new(name), &bytes) {
            Ok(mesh) => panic!(
                "{name} loaded ({} triangles), but it is broken",
                mesh.triangles.len()
            ),
            Err(e) => e.to_string(),
        };
        assert!(
            err.contains(name),
            "{name}: the error does not name the file: {err}"
        );
        for word in words {
            assert!(err.contains(word), "{name}: expected {word:?} in: {err}");
        }
        eprintln!("{err}");
    }
    // Through a scene: the file's error, then the scene line that uses it.
    let dir = temp_dir("errors");
    std::fs::write(
        dir.join("bad.ply"),
        b"ply\nformat ascii 1.0\nbogus\nend_header\n",
    )
    .expect("write");
    let scene_xml = |file: &str| {
        format!(
            "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n\
             <shape type=\"ply\">\n<string name=\"filename\" value=\"{file}\"/>\n</shape>\n</scene>\n"
        )
    };
    for (file, words) in [
        ("bad.ply", &["bad.ply", "scene.xml:3"][..]),
        (
            "missing.ply",
            &["missing.ply", "scene.xml:3", "cannot read PLY"][..],
        ),
    ] {
        let path = dir.join("scene.xml");
        std::fs::write(&path, scene_xml(file)).expect("write scene");
        let err = hppm::loaders::load(&path)
            .map(drop)
            .expect_err("broken PLY");
        let text = err.to_string();
        for word in words {
            assert!(text.contains(word), "expected {word:?} in: {text}");
        }
        assert!(matches!(
            err,
            SceneError::At { .. } | SceneError::File { .. }
        ));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `serialized` mesh file that is not there is an error at the shape's line naming the file
/// (the format itself: src/loaders/serialized.rs and tests/mitsuba_compat.rs).
#[test]
fn a_missing_serialized_file_is_named_at_its_shape() {
    let xml = "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"/>\n\
               <shape type=\"serialized\">\n<string name=\"filename\" value=\"m.serialized\"/>\n\
               </shape>\n</scene>\n";
    let err = hppm::loaders::mitsuba::parse(Path::new("s.xml"), xml)
        .map(drop)
        .expect_err("serialized");
    let text = err.to_string();
    for word in ["s.xml:3:", "m.serialized"] {
        assert!(text.contains(word), "expected {word:?} in: {text}");
    }
}

/// A bare `.ply` is a scene as a bare `.obj` is: the same framing camera and light around the
/// same triangles.
#[test]
fn a_bare_ply_frames_like_a_bare_obj() {
    let dir = temp_dir("bare");
    let obj = repo_path("tests/refs/scenes/cornell_diffuse_obj/short_box.obj");
    let (v, f) = read_obj(&obj);
    let ply_path = dir.join("short_box.ply");
    std::fs::write(&ply_path, write_ply(&v, &f, Encoding::Ascii)).expect("write");
    let from_obj = hppm::loaders::load(&obj).expect("obj");
    let from_ply = hppm::loaders::load(&ply_path).expect("ply");
    assert_eq!(from_ply.triangles, from_obj.triangles);
    assert_eq!(from_ply.camera, from_obj.camera);
    assert_eq!(from_ply.point_lights, from_obj.point_lights);
    let _ = std::fs::remove_dir_all(&dir);
}
