//! Mitsuba 0.5/0.6 files (a `<scene version>` below 2.0) are read with 0.6's rules where 0.6 and
//! Mitsuba 3 differ, and the same constructs stay errors in a version 3 file. Expected values
//! come from 0.6's sources and tables (src/medium/materials.h, src/bsdfs/conductor.cpp,
//! src/textures/bitmap.cpp, src/librender/texture.cpp, src/librender/scenehandler.cpp of
//! Mitsuba 0.6), written out here rather than computed by the loader. CPU only.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};
use hppm::bsdfs::conductor::Conductor;
use hppm::bsdfs::diffuse::Diffuse;
use hppm::bsdfs::null::Null;
use hppm::loaders::{Report, mitsuba};
use hppm::scene::texture::{Filter, Texture};
use hppm::scene::{Scene, grid::Grid};

fn check_version(version: &str, body: &str) -> Report {
    check_in(Path::new("shipped.xml"), version, body)
}

fn check_in(path: &Path, version: &str, body: &str) -> Report {
    let text = format!("<scene version=\"{version}\">\n{body}\n</scene>");
    mitsuba::check_text(path, &text, &[])
}

fn scene_of(report: Report) -> Scene {
    let errors: Vec<String> = report.errors.iter().map(|e| e.to_string()).collect();
    report
        .scene
        .unwrap_or_else(|| panic!("refused: {}", errors.join("\n")))
}

fn strings(list: &[hppm::scene::SceneError]) -> Vec<String> {
    list.iter().map(|e| e.to_string()).collect()
}

/// `report`'s messages (errors or warnings) that are at `line` of shipped.xml and contain `words`.
fn has_at(list: &[String], line: usize, words: &str) -> bool {
    let place = format!("shipped.xml:{line}:");
    list.iter().any(|m| m.contains(&place) && m.contains(words))
}

const SENSOR: &str = r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>"#;

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).abs().max_element() <= tolerance * b.abs().max_element().max(1e-6)
}

/// A folder of its own under the target directory for files a test writes.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("mitsuba06")
        .join(name);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}

/// 0.6 rendered a file with a property no plugin read (a research fork's option, `alpha` on a
/// smooth dielectric, a property of the scene itself) and printed a warning; so does hppm, at
/// each place and with a did-you-mean. The same body in a version 3 file is refused at the
/// same places. Catches: 0.6 files refused for an unread property, or version 3 files no
/// longer strict.
#[test]
fn unread_properties_are_warnings_in_06_files_and_errors_in_3() {
    let body = format!(
        r#"{SENSOR}
<integer name="maxDepth" value="4"/>
<integrator type="path"><boolean name="usePathGuiding" value="true"/></integrator>
<shape type="sphere"><bsdf type="dielectric"><float name="alpha" value="0.1"/><float name="intIORr" value="1.3"/></bsdf></shape>
<emitter type="constant"/>"#
    );
    let old = check_version("0.6.0", &body);
    let said = strings(&old.warnings);
    assert!(
        has_at(&said, 3, "a property of the scene itself"),
        "{said:#?}"
    );
    assert!(has_at(&said, 4, "\"use_path_guiding\""), "{said:#?}");
    assert!(has_at(&said, 5, "\"alpha\""), "{said:#?}");
    assert!(has_at(&said, 5, "did you mean \"int_ior\"?"), "{said:#?}");
    assert!(old.rule_sets[0].legacy);
    assert_eq!(old.rule_sets[0].version.as_deref(), Some("0.6.0"));
    scene_of(old);

    let current = check_version("3.0.0", &body);
    let errors = strings(&current.errors);
    assert!(current.scene.is_none());
    assert!(has_at(&errors, 3, "unknown tag <integer>"), "{errors:#?}");
    assert!(has_at(&errors, 5, "unknown property"), "{errors:#?}");
    assert!(!current.rule_sets[0].legacy);
}

/// `<lookAt>` (0.6 took either case) places the camera in a 0.6 file; Mitsuba 3 knows only
/// `<lookat>`, so a version 3 file with it is refused. Catches: the camelCase tag ignored
/// (the camera left at the origin) or accepted in version 3 files.
#[test]
fn look_at_in_either_case_places_the_camera_in_06_files() {
    let body = r#"<sensor type="perspective"><transform name="toWorld"><lookAt origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
<emitter type="constant"/>"#;
    let old = check_version("0.5.0", body);
    assert!(
        strings(&old.upgrades)
            .iter()
            .any(|u| u.contains("shipped.xml:2:") && u.contains("<lookAt> read as <lookat>"))
    );
    let scene = scene_of(old);
    assert_eq!(scene.camera.origin, Vec3::new(1.0, 2.0, 3.0));
    let forward = (scene.camera.target - scene.camera.origin).normalize();
    assert!(close(forward, Vec3::NEG_Z, 1e-6), "{forward}");
    let current = strings(&check_version("3.0.0", &body.replace("toWorld", "to_world")).errors);
    assert!(has_at(&current, 2, "<lookAt>"), "{current:#?}");
}

/// 0.6's films: `ldrfilm` and `tiledhdrfilm` give the image's size as hdrfilm does; what only
/// shaped 0.6's PNG (gamma, a non-neutral exposure, reinhard) is a warning, neutral values a
/// note; `gamma` on an hdrfilm, which 0.6 never read, is a note; `mfilm` is refused. Catches:
/// ldrfilm refused, its size lost, or a tonemap dropped without a word.
#[test]
fn films_of_06_read_their_size_and_name_what_only_their_output_used() {
    let body = r#"<sensor type="perspective"><film type="ldrfilm"><integer name="width" value="40"/><integer name="height" value="30"/>
<float name="gamma" value="2.2"/><float name="exposure" value="1"/><float name="key" value="0.5"/><string name="tonemapMethod" value="gamma"/></film></sensor>
<emitter type="constant"/>"#;
    let old = check_version("0.5.0", body);
    let said = strings(&old.warnings);
    assert!(has_at(&said, 3, "ldrfilm gamma 2.2"), "{said:#?}");
    assert!(has_at(&said, 3, "ldrfilm exposure 1"), "{said:#?}");
    assert!(!said.iter().any(|w| w.contains("key")), "{said:#?}");
    let scene = scene_of(old);
    assert_eq!((scene.camera.width, scene.camera.height), (40, 30));

    let hdr = r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><float name="gamma" value="2.2"/></film></sensor>
<emitter type="constant"/>"#;
    let old = check_version("0.5.0", hdr);
    assert!(old.warnings.is_empty(), "{:?}", strings(&old.warnings));
    assert!(
        strings(&old.upgrades)
            .iter()
            .any(|u| u.contains("hdrfilm gamma"))
    );
    scene_of(old);
    let mfilm = check_version("0.5.0", &hdr.replace("hdrfilm", "mfilm"));
    assert!(has_at(&strings(&mfilm.errors), 2, "film type \"mfilm\""));
    let ldr3 = check_version("3.0.0", body);
    assert!(has_at(&strings(&ldr3.errors), 2, "film type \"ldrfilm\""));
}

/// Writes a 2x1 8-bit PNG: texel 0 grey 128, texel 1 grey 64.
fn write_png(path: &Path) {
    let image = image::RgbImage::from_raw(2, 1, vec![128, 128, 128, 64, 64, 64])
        .unwrap_or_else(|| panic!("image"));
    image
        .save(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

fn bitmap(scene: &Scene) -> &hppm::scene::texture::Bitmap {
    match scene.textures.first() {
        Some(Texture::Bitmap(b)) => b,
        other => panic!("expected a bitmap, got {other:?}"),
    }
}

/// A 0.6 bitmap: `filterType` trilinear (0.6's MIP-mapping) is read bilinear with a note;
/// `uscale`/`vscale`/`uoffset` map uv as 0.6's Texture2D does (uv * scale + offset);
/// `gamma` 1 reads the bytes as linear, 2.2 as a power law, -1 as sRGB; a file name in
/// another case is found with a warning; differing `wrapModeU`/`wrapModeV` are refused. The
/// expected texels are 128/255 and 64/255 through each curve. Catches: trilinear refused, the
/// uv transform ignored or inverted, gamma ignored, a missing file on a case mismatch.
#[test]
fn bitmaps_of_06_take_their_uv_scale_gamma_and_filter() {
    let dir = scratch("bitmaps");
    write_png(&dir.join("Grey.png"));
    let scene_with = |props: &str| {
        let body = format!(
            r#"{SENSOR}
<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="grey.png"/>{props}</texture></bsdf></shape>
<emitter type="constant"/>"#
        );
        check_in(&dir.join("scene.xml"), "0.5.0", &body)
    };
    let report = scene_with(
        r#"<string name="filterType" value="trilinear"/><float name="uscale" value="2"/><float name="uoffset" value="0.25"/><float name="gamma" value="1"/>"#,
    );
    let said = strings(&report.warnings);
    assert!(
        said.iter()
            .any(|w| w.contains("no file") && w.contains("Grey.png")),
        "{said:#?}"
    );
    assert!(
        strings(&report.upgrades)
            .iter()
            .any(|u| u.contains("MIP-mapping"))
    );
    let scene = scene_of(report);
    let b = bitmap(&scene);
    assert_eq!(b.filter, Filter::Bilinear);
    let linear = |x: f32| x / 255.0;
    // uv (0.125, 0.5) -> u' = 0.125 * 2 + 0.25 = 0.5: between the two texels' centres (0.25,
    // 0.75), halfway: the mean of 128 and 64.
    let mid = b.eval(Vec2::new(0.125, 0.5));
    assert!(close(mid, Vec3::splat(linear(96.0)), 1e-3), "{mid}");
    // u = 0.0 -> u' = 0.25: texel 0's centre exactly.
    let first = b.eval(Vec2::new(0.0, 0.5));
    assert!(close(first, Vec3::splat(linear(128.0)), 1e-3), "{first}");

    let power = scene_of(scene_with(r#"<float name="gamma" value="2.2"/>"#));
    let t = bitmap(&power).texels[0];
    assert!(
        close(t, Vec3::splat((128.0f32 / 255.0).powf(2.2)), 1e-4),
        "{t}"
    );
    let srgb = scene_of(scene_with(r#"<float name="gamma" value="-1"/>"#));
    let t = bitmap(&srgb).texels[0];
    // sRGB's curve at 128/255: ((x + 0.055) / 1.055)^2.4.
    let expected = ((128.0f32 / 255.0 + 0.055) / 1.055).powf(2.4);
    assert!(close(t, Vec3::splat(expected), 1e-4), "{t}");

    let wraps = scene_with(
        r#"<string name="wrapModeU" value="clamp"/><string name="wrapModeV" value="repeat"/>"#,
    );
    let errors = strings(&wraps.errors);
    assert!(
        errors.iter().any(|e| e.contains("wrap_mode_v")),
        "{errors:#?}"
    );
}

/// 0.6's conductor defaults to copper (Mitsuba 3's to a perfect mirror), lets `eta` or `k`
/// replace the material's, and divides both by `extEta` (a number or a named dielectric).
/// Copper's values are Mitsuba's table at RGB, as hppm's `Cu`. Catches: a 0.6 conductor
/// without a material rendered as a mirror, extEta refused or ignored, eta and material
/// together refused.
#[test]
fn conductors_of_06_default_to_copper_and_divide_by_ext_eta() {
    let (cu_eta, cu_k) =
        hppm::bsdfs::conductor::named_conductor("Cu").unwrap_or_else(|| panic!("Cu"));
    let conductor_of = |version: &str, props: &str| {
        let body = format!(
            r#"{SENSOR}<shape type="sphere"><bsdf type="conductor">{props}</bsdf></shape><emitter type="constant"/>"#
        );
        let scene = scene_of(check_version(version, &body));
        scene.materials[0].bsdf.get::<Conductor>().copied()
    };
    let plain = conductor_of("0.6.0", "").unwrap_or_else(|| panic!("a conductor"));
    assert!(close(plain.eta, cu_eta / 1.000277, 1e-6) && close(plain.k, cu_k / 1.000277, 1e-6));
    let water = conductor_of("0.6.0", r#"<string name="extEta" value="water"/>"#)
        .unwrap_or_else(|| panic!("a conductor"));
    assert!(close(water.eta, cu_eta / 1.333, 1e-5), "{water:?}");
    let given = conductor_of(
        "0.6.0",
        r#"<string name="material" value="Cu"/><rgb name="eta" value="0.2, 0.3, 0.4"/><float name="extEta" value="2"/>"#,
    )
    .unwrap_or_else(|| panic!("a conductor"));
    assert!(
        close(given.eta, Vec3::new(0.1, 0.15, 0.2), 1e-6),
        "{given:?}"
    );
    assert!(close(given.k, cu_k / 2.0, 1e-6), "{given:?}");
    // Mitsuba 3: no material is a perfect mirror, which is not a `Conductor`.
    assert!(conductor_of("3.0.0", "").is_none());
}

/// A homogeneous medium in a 0.6 file: a `material` preset is 0.6's table (mm^-1) times 100
/// times `scale`; with no coefficient the default is `skin1`; `sigmaT` alone takes skin1's
/// albedo; a preset with coefficients, or sigma_s with sigma_t, is refused as 0.6 refuses it.
/// Values from 0.6's src/medium/materials.h. Catches: presets refused or off by the unit
/// factor, Mitsuba 3's defaults (sigma_t 1, albedo 0.75) applied to 0.6 files.
#[test]
fn homogeneous_media_of_06_take_presets_and_its_defaults() {
    let medium_of = |props: &str| {
        let body = format!(
            r#"{SENSOR}<medium type="homogeneous" id="m">{props}</medium>
<shape type="sphere"><ref name="interior" id="m"/></shape><emitter type="constant"/>"#
        );
        let report = check_version("0.5.0", &body);
        (strings(&report.errors), report.scene)
    };
    let medium = |props: &str| {
        let (errors, scene) = medium_of(props);
        let scene = scene.unwrap_or_else(|| panic!("{errors:#?}"));
        scene.media.list[0].clone()
    };
    let milk = medium(
        r#"<string name="material" value="Regular Milk"/><float name="scale" value="0.5"/>"#,
    );
    let (ss, sa) = (
        Vec3::new(18.2052, 20.3826, 22.3698),
        Vec3::new(0.00153, 0.00460, 0.01993),
    );
    assert!(
        close(milk.sigma_t, (ss + sa) * 100.0 * 0.5, 1e-5),
        "{milk:?}"
    );
    assert!(close(milk.albedo, ss / (ss + sa), 1e-5), "{milk:?}");

    let (skin_s, skin_a) = (Vec3::new(0.74, 0.88, 1.01), Vec3::new(0.032, 0.17, 0.48));
    let default = medium("");
    assert!(
        close(default.sigma_t, (skin_s + skin_a) * 100.0, 1e-5),
        "{default:?}"
    );
    let thin = medium(r#"<float name="sigmaT" value="0.5"/>"#);
    assert!(close(thin.sigma_t, Vec3::splat(0.5), 1e-6), "{thin:?}");
    assert!(
        close(thin.albedo, skin_s / (skin_s + skin_a), 1e-5),
        "{thin:?}"
    );
    let explicit =
        medium(r#"<rgb name="sigmaS" value="1, 2, 3"/><rgb name="sigmaA" value="1, 0, 1"/>"#);
    assert!(close(explicit.sigma_t, Vec3::new(2.0, 2.0, 4.0), 1e-6));
    assert!(close(explicit.albedo, Vec3::new(0.5, 1.0, 0.75), 1e-6));

    let (both, _) =
        medium_of(r#"<string name="material" value="Ketchup"/><float name="sigmaT" value="1"/>"#);
    assert!(
        has_at(&both, 2, "either a preset material or coefficients"),
        "{both:#?}"
    );
    let (mixed, _) =
        medium_of(r#"<float name="sigmaS" value="1"/><float name="sigmaT" value="1"/>"#);
    assert!(
        has_at(&mixed, 2, "give sigma_s and sigma_a, or sigma_t"),
        "{mixed:#?}"
    );
    let (unknown, _) = medium_of(r#"<string name="material" value="Orange Soda"/>"#);
    assert!(has_at(&unknown, 2, "Regular Milk"), "{unknown:#?}");
}

/// A 0.6 heterogeneous medium's `density` grid is its extinction, placed in the box its file
/// states (0.6 has no unit-cube default) with the first and last voxels' values on the box's
/// faces: a 2-voxel axis over [2, 4] maps x = 2 to the first voxel's centre (0.25 of Mitsuba
/// 3's unit cube) and x = 4 to the last's (0.75). Catches: `density` refused, the file's box
/// ignored (Mitsuba 3's default), or half a voxel off.
#[test]
fn heterogeneous_media_of_06_place_their_density_grid_as_06_does() {
    let dir = scratch("grid");
    let mut grid = Grid::new([2, 2, 2], 1, vec![1.0; 8]);
    (grid.bbox_min, grid.bbox_max) = (Vec3::splat(2.0), Vec3::splat(4.0));
    hppm::loaders::vol::write_vol(&dir.join("smoke.vol"), &grid).unwrap_or_else(|e| panic!("{e}"));
    let body = format!(
        r#"{SENSOR}<medium type="heterogeneous" id="smoke"><volume name="density" type="gridvolume"><string name="filename" value="smoke.vol"/></volume>
<float name="scale" value="3"/><string name="method" value="woodcock"/></medium>
<shape type="cube"><ref name="interior" id="smoke"/></shape><emitter type="constant"/>"#
    );
    let scene = scene_of(check_in(&dir.join("scene.xml"), "0.5.0", &body));
    let medium = &scene.media.list[0];
    assert!(close(medium.sigma_t, Vec3::splat(3.0), 1e-6));
    let density = medium.density.as_ref().unwrap_or_else(|| panic!("a grid"));
    let at = |p: f32| (density.to_local * Vec4::new(p, p, p, 1.0)).truncate();
    assert!(close(at(2.0), Vec3::splat(0.25), 1e-6), "{}", at(2.0));
    assert!(close(at(4.0), Vec3::splat(0.75), 1e-6), "{}", at(4.0));
}

/// 0.6's RGB build reads `<spectrum value="8 4 2">` (as many plain values as it has spectral
/// samples) as that colour; Mitsuba 3 refuses it. Catches: the values refused, or read as
/// wavelength pairs or a grey.
#[test]
fn three_plain_spectrum_values_are_rgb_in_06_files() {
    let body = format!(
        r#"{SENSOR}<shape type="sphere"><emitter type="area"><spectrum name="radiance" value="8 4 2"/></emitter></shape>"#
    );
    let scene = scene_of(check_version("0.5.0", &body));
    assert_eq!(scene.materials[0].emission, Vec3::new(8.0, 4.0, 2.0));
    assert!(!check_version("3.0.0", &body).errors.is_empty());
}

/// A shape without a BSDF: Mitsuba 3 (and 0.6) give an area light a black diffuse surface and
/// other shapes diffuse 0.5; 0.6 makes a medium boundary without a BSDF index-matched (null),
/// Mitsuba 3 diffuse. A nameless `<ref>` to a medium is refused with what it needs. Catches:
/// lights reflecting light (the default BSDF of old), a 0.6 fog boundary rendered as a wall.
#[test]
fn default_bsdfs_follow_each_version() {
    let body = format!(
        r#"{SENSOR}<medium type="homogeneous" id="fog"><float name="sigmaT" value="1"/><float name="albedo" value="0.5"/></medium>
<shape type="sphere"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
<shape type="sphere"><ref name="interior" id="fog"/></shape>
<shape type="sphere"/>"#
    );
    for version in ["0.6.0", "3.0.0"] {
        let body = if version == "3.0.0" {
            body.replace("sigmaT", "sigma_t")
        } else {
            body.clone()
        };
        let scene = scene_of(check_version(version, &body));
        let diffuse = |i: usize| {
            scene.materials[i]
                .bsdf
                .get::<Diffuse>()
                .map(|d| d.reflectance)
        };
        assert_eq!(diffuse(0), Some(Vec3::ZERO), "{version}: the light");
        assert_eq!(
            diffuse(2),
            Some(Vec3::splat(0.5)),
            "{version}: the plain shape"
        );
        let boundary_null = scene.materials[1].bsdf.get::<Null>().is_some();
        assert_eq!(boundary_null, version == "0.6.0", "{version}: the boundary");
    }
    // A BSDF by reference and a medium by reference on one shape: both taken.
    let both = format!(
        r#"{SENSOR}<medium type="homogeneous" id="milk"><string name="material" value="Wholemilk"/></medium>
<bsdf type="dielectric" id="glass"/>
<shape type="sphere"><ref id="glass"/><ref name="interior" id="milk"/></shape><emitter type="constant"/>"#
    );
    let scene = scene_of(check_version("0.6.0", &both));
    let glass = &scene.materials[0];
    assert!(
        glass
            .bsdf
            .get::<hppm::bsdfs::dielectric::Dielectric>()
            .is_some()
    );
    assert_eq!(glass.media.interior, Some(0));
    let nameless = check_version(
        "0.6.0",
        &body.replace(r#"<ref name="interior" id="fog"/>"#, r#"<ref id="fog"/>"#),
    );
    assert!(has_at(
        &strings(&nameless.errors),
        4,
        "needs name=\"interior\""
    ));
}

/// An include's file name may use a `<default>` (research scenes choose their integrator that
/// way: `$integrator.xml`), and properties under an included `<scene>` of a 0.6 file are
/// warnings. Catches: the include not found because `$name` was not substituted.
#[test]
fn include_names_take_defaults() {
    let dir = scratch("includes");
    let part = "<scene version=\"0.6.0\"><integer name=\"maxDepth\" value=\"3\"/><integrator type=\"path\"><integer name=\"maxDepth\" value=\"$depth\"/></integrator></scene>";
    std::fs::write(dir.join("path.xml"), part).unwrap_or_else(|e| panic!("{e}"));
    let body = format!(
        r#"<default name="integrator" value="path"/><default name="depth" value="5"/>
<include filename="$integrator.xml"/>
{SENSOR}<emitter type="constant"/>"#
    );
    let report = check_in(&dir.join("scene.xml"), "0.6.0", &body);
    assert!(
        strings(&report.warnings)
            .iter()
            .any(|w| w.contains("path.xml") && w.contains("a property of the scene itself"))
    );
    assert_eq!(report.rule_sets.len(), 2);
    let scene = scene_of(report);
    assert_eq!(scene.integrator.max_depth, Some(5));
}

/// Radiance files whose first line is `#?RGBE` (as many tools write it) load as `#?RADIANCE`
/// ones do, as the floats they store: a flat 2x1 scanline of (128, 64, 32, e = 129) is
/// (1, 0.5, 0.25) (mantissa times 2^(e - 136)). Catches: such environment maps refused, and
/// HDR files read tonemapped to 8 bits (what the image crate's generic decoder returns: 0.5
/// became 55/255).
#[test]
fn radiance_files_signed_rgbe_load() {
    let dir = scratch("rgbe");
    let mut bytes = b"#?RGBE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
    bytes.extend_from_slice(&[128, 64, 32, 129, 128, 64, 32, 129]);
    let path = dir.join("sky.hdr");
    std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{e}"));
    let (w, h, texels) =
        hppm::scene::texture::read_image(&path, false).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((w, h), (2, 1));
    assert!(
        close(texels[0], Vec3::new(1.0, 0.5, 0.25), 1e-6),
        "{}",
        texels[0]
    );
}

/// The public 0.4-0.6 scenes kept as shipped under tests/data/mitsuba06 (README.md there says
/// where each is from).
const CORPUS: &[&str] = &[
    "nlvrl/FBD15ALVRL_box/box.xml",
    "nlvrl/FBD15ALVRL_glass/glass/glass.xml",
    "nlvrl/cbox_v040/cbox.xml",
    "redner/teapot/teapot.xml",
    "redner/teapot_specular/teapot_specular.xml",
    "sdmm/cornell-box/cornell-box.xml",
    "sdmm/volumetric-caustic/volumetric-caustic.xml",
    "optixrenderer/sphere/sphere.xml",
    "lajolla/veach_mi/mi.xml",
    "lajolla/matpreview/matpreview.xml",
    "lajolla/vol_cbox/vol_cbox.xml",
    "gpu_raytracer/cornellbox/scene.xml",
];

#[path = "common/mod.rs"]
mod common;

/// Every corpus scene loads with no error, read with 0.6's rules, and renders: `pt` at a
/// sixteenth of its film's size for 2 samples gives finite pixels and some light; the two
/// that cannot render are refused once each, at their place ([`REFUSED`]). Catches: any construct of these files that
/// stops the reader again, and a scene that loads but renders black or NaN (a medium preset
/// off by its units, an HDR environment read as zero).
#[test]
fn public_06_scenes_load_and_render_as_shipped() {
    let gpu = common::gpu();
    let graph = || common::load_graph("graphs/pt.ron");
    for file in CORPUS {
        let path = common::repo_path(&format!("tests/data/mitsuba06/{file}"));
        let report = hppm::loaders::check_with(&path, &[]);
        let errors = strings(&report.errors);
        assert!(errors.is_empty(), "{file}: {errors:#?}");
        assert!(report.rule_sets.iter().all(|r| r.legacy), "{file}");
        let mut scene = scene_of(report);
        let camera = &mut scene.camera;
        (camera.width, camera.height) = ((camera.width / 16).max(8), (camera.height / 16).max(8));
        let mut renderer = common::renderer(&gpu, &scene, graph(), 1);
        let image = common::render_to(&mut renderer, 2);
        let finite = image.pixels.iter().flatten().all(|v| v.is_finite());
        let mean = image
            .pixels
            .iter()
            .flatten()
            .map(|&v| v as f64)
            .sum::<f64>()
            / (3 * image.pixels.len()) as f64;
        eprintln!(
            "{file}: {}x{} mean {mean:.4}",
            scene.camera.width, scene.camera.height
        );
        assert!(
            finite && mean > 1e-4,
            "{file}: finite {finite}, mean {mean}"
        );
    }
    for (file, place, why) in REFUSED {
        let path = common::repo_path(&format!("tests/data/mitsuba06/{file}"));
        let errors = strings(&hppm::loaders::check_with(&path, &[]).errors);
        assert!(
            errors.len() == 1 && errors[0].contains(place) && errors[0].contains(why),
            "{file}: {errors:#?}"
        );
    }
}

/// Corpus files that neither 0.6 nor hppm renders, each refused once at its place: a moving
/// sphere (motion blur, which 0.6 rendered and hppm does not), and an id given to two shapes
/// (which 0.6's scene handler refused as well).
const REFUSED: &[(&str, &str, &str)] = &[
    (
        "sdmm/cornell-box-motion/cornell-box-motion.xml",
        "cornell-box-motion.xml:137:",
        "motion blur",
    ),
    (
        "nlvrl/TestScene/TestScene.xml",
        "TestScene.xml:81:",
        "id \"Ceiling_mesh\" is declared already",
    ),
];

/// A corpus scene's Mitsuba 3 reference (tests/refs/mitsuba06: render.py made it from the
/// scene after the hand edits it lists, at the reduced film `size`), and Mitsuba's figures
/// there: relMSE of one of its own 256-spp renders against the reference on 8x8 block means
/// (median over 16 passes) and on pixels, and the reference's own noise on blocks.
struct Reference {
    name: &'static str,
    file: &'static str,
    size: (u32, u32),
    /// hppm's samples per pixel: 256, or more where Mitsuba's own 256 spp are less noisy than
    /// hppm's (its `ldsampler` against hppm's independent samples; its sampling of sphere
    /// lights by solid angle), so that the comparison measures agreement, not efficiency.
    spp: u64,
    blocks_256: f64,
    noise_blocks: f64,
    pixels_256: f64,
}

#[rustfmt::skip]
const REFERENCES: &[Reference] = &[
    Reference { name: "nlvrl_box", file: "nlvrl/FBD15ALVRL_box/box.xml", size: (64, 64), spp: 256, blocks_256: 6.033e-04, noise_blocks: 3.613e-05, pixels_256: 4.022e-02 },
    Reference { name: "nlvrl_glass", file: "nlvrl/FBD15ALVRL_glass/glass/glass.xml", size: (48, 72), spp: 256, blocks_256: 4.775e-03, noise_blocks: 1.119e-03, pixels_256: 2.756e-01 },
    Reference { name: "nlvrl_cbox040", file: "nlvrl/cbox_v040/cbox.xml", size: (64, 64), spp: 2048, blocks_256: 5.482e-06, noise_blocks: 3.303e-07, pixels_256: 1.557e-04 },
    Reference { name: "redner_teapot", file: "redner/teapot/teapot.xml", size: (64, 64), spp: 256, blocks_256: 3.403e-05, noise_blocks: 2.000e-06, pixels_256: 2.002e-03 },
    Reference { name: "redner_teapot_specular", file: "redner/teapot_specular/teapot_specular.xml", size: (64, 64), spp: 256, blocks_256: 3.915e-05, noise_blocks: 2.330e-06, pixels_256: 2.146e-03 },
    Reference { name: "sdmm_cornell", file: "sdmm/cornell-box/cornell-box.xml", size: (128, 72), spp: 256, blocks_256: 8.554e-05, noise_blocks: 5.348e-06, pixels_256: 2.778e-04 },
    Reference { name: "sdmm_volumetric_caustic", file: "sdmm/volumetric-caustic/volumetric-caustic.xml", size: (64, 64), spp: 256, blocks_256: 4.001e-03, noise_blocks: 2.492e-04, pixels_256: 4.203e-03 },
    Reference { name: "optix_sphere", file: "optixrenderer/sphere/sphere.xml", size: (64, 64), spp: 256, blocks_256: 4.875e-04, noise_blocks: 3.218e-05, pixels_256: 2.658e-03 },
    Reference { name: "lajolla_veach", file: "lajolla/veach_mi/mi.xml", size: (96, 64), spp: 2048, blocks_256: 1.973e-04, noise_blocks: 1.370e-05, pixels_256: 8.228e-04 },
    Reference { name: "lajolla_matpreview", file: "lajolla/matpreview/matpreview.xml", size: (96, 72), spp: 256, blocks_256: 3.231e-04, noise_blocks: 2.112e-05, pixels_256: 6.629e-03 },
    Reference { name: "lajolla_vol_cbox", file: "lajolla/vol_cbox/vol_cbox.xml", size: (64, 64), spp: 256, blocks_256: 5.545e-04, noise_blocks: 3.164e-05, pixels_256: 1.100e-02 },
    Reference { name: "gpu_cornell", file: "gpu_raytracer/cornellbox/scene.xml", size: (64, 64), spp: 256, blocks_256: 1.248e-05, noise_blocks: 7.752e-07, pixels_256: 3.876e-04 },
];

/// The shipped file with only its film's width and height changed to `size`, read as hppm
/// reads any file of its version.
fn shipped_at(file: &str, (width, height): (u32, u32)) -> Scene {
    let path = common::repo_path(&format!("tests/data/mitsuba06/{file}"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
    let sized = |text: &str, name: &str, value: u32| {
        let key = format!("name=\"{name}\" value=\"");
        let start = text
            .find(&key)
            .unwrap_or_else(|| panic!("{file}: no {name}"))
            + key.len();
        let end = start + text[start..].find('"').unwrap_or_else(|| panic!("{file}"));
        format!("{}{value}{}", &text[..start], &text[end..])
    };
    let text = sized(&sized(&text, "width", width), "height", height);
    scene_of(mitsuba::check_text(&path, &text, &[]))
}

/// Each corpus scene Mitsuba 3 renders after hand edits agrees with Mitsuba's render of the
/// edited file: hppm's `pt` renders the file as shipped (0.6's rules doing what the edits did
/// by hand) for 256 spp (more on two scenes: [`Reference::spp`]), and its 8x8 block means are within 2x Mitsuba's own 256-spp block
/// relMSE plus twice the reference's block noise. Catches: any 0.6 rule that renders a
/// different scene than 0.6 meant (Mitsuba 3's defaults for a preset, a mirror for copper, a
/// wall for a medium boundary, tonemapped HDR light), which shows as a bias far above noise.
#[test]
fn public_06_scenes_agree_with_mitsuba_3_after_hand_edits() {
    let gpu = common::gpu();
    let mut failed = Vec::new();
    for r in REFERENCES {
        let scene = shipped_at(r.file, r.size);
        let reference = hppm::image::Image::read_exr(&common::repo_path(&format!(
            "tests/refs/mitsuba06/images/{}.exr",
            r.name
        )))
        .unwrap_or_else(|e| panic!("{}: {e}", r.name));
        let graph = common::load_graph("graphs/pt.ron");
        let image = common::render_to(&mut common::renderer(&gpu, &scene, graph, 7), r.spp);
        let blocks = |i: &hppm::image::Image| common::convergence::block_means(i, 8);
        let e_blocks = common::relmse(&blocks(&image), &blocks(&reference));
        let e_pixels = common::relmse(&image, &reference);
        let bound = 2.0 * r.blocks_256 + 2.0 * r.noise_blocks;
        eprintln!(
            "{}: 8x8 blocks relMSE {e_blocks:.3e} (bound {bound:.3e}; Mitsuba's own \
             {:.3e}), pixels {e_pixels:.3e} (Mitsuba's own {:.3e}), mean {:?} vs {:?}",
            r.name,
            r.blocks_256,
            r.pixels_256,
            image.mean(),
            reference.mean()
        );
        if e_blocks > bound {
            failed.push(format!("{}: {e_blocks:.3e} > {bound:.3e}", r.name));
        }
    }
    assert!(failed.is_empty(), "{failed:#?}");
}
