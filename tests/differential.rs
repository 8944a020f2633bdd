//! Differential tests against Mitsuba 3 on generated scenes (tests/differential/generate.py):
//! each scene of the corpus rendered by `pt` and, where it can agree with Mitsuba's path tracer,
//! by the default hybrid, several seeds each, with the bias statistic of tests/bias.rs applied
//! to every 8x8 block of the image (tests/common/differential.rs). A fault confined to one
//! direction, one material, one emitter kind or one region of one scene fails it; the faults
//! shown caught are in tests/differential_faults.rs.
//!
//! The corpus (51 scenes at 32x32, 11 of them with participating media from `generate.py
//! --media`; references rendered by Mitsuba 3.9.1 `llvm_ad_rgb` at 32,768 spp) runs in four shards so the test harness runs them side by side. A longer run over any
//! corpus the generator writes (a thousand scenes, say):
//!
//! ```text
//! python3 tests/differential/generate.py --first 1000 --count 1000 --out /tmp/corpus
//! HPPM_DIFFERENTIAL_CORPUS=/tmp/corpus cargo test --release --test differential corpus_shard
//! ```

mod common;

use common::differential::*;
use common::*;

const SEEDS: u64 = 6;
const SPP: u64 = 8;
const SHARDS: usize = 4;

/// Renders every case of `cases` through each of its graphs; returns one line per failure.
fn check(cases: &[&Case]) -> Vec<String> {
    let gpu = gpu();
    let mut failures = Vec::new();
    for case in cases {
        let scene = case.scene();
        for graph in &case.graphs {
            let file = format!("graphs/{graph}.ron");
            let images = render_seeds(&gpu, &scene, &file, 0..SEEDS, SPP);
            let (flagged, worst) = flagged(case, &images, SPP);
            eprintln!("{} {graph}: worst {worst}", case.name);
            if let Some(first) = flagged.first() {
                failures.push(format!(
                    "{} ({}) through {graph}: {} of 16 blocks biased, worst {first}",
                    case.name,
                    case.dir.display(),
                    flagged.len()
                ));
            }
        }
    }
    failures
}

/// Renders every `of`-th case of `cases` from the `k`-th; fails naming each biased one.
fn assert_unbiased(cases: &[Case], k: usize, of: usize) {
    let mine: Vec<&Case> = cases.iter().skip(k).step_by(of).collect();
    let failures = check(&mine);
    eprintln!("{} scenes, {} failures", mine.len(), failures.len());
    assert!(
        failures.is_empty(),
        "biased against Mitsuba:\n{}",
        failures.join("\n")
    );
}

/// One of the corpus's shards: the committed corpus, or the one HPPM_DIFFERENTIAL_CORPUS names
/// (written by generate.py: a longer run through the same tests).
fn shard(k: usize) {
    let cases = match std::env::var("HPPM_DIFFERENTIAL_CORPUS") {
        Ok(dir) => corpus(&dir),
        Err(_) => {
            let cases = corpus(CORPUS);
            assert!(cases.len() >= 40, "the corpus has {} scenes", cases.len());
            cases
        }
    };
    assert_unbiased(&cases, k, SHARDS);
}

#[test]
fn corpus_shard_0() {
    shard(0);
}

#[test]
fn corpus_shard_1() {
    shard(1);
}

#[test]
fn corpus_shard_2() {
    shard(2);
}

#[test]
fn corpus_shard_3() {
    shard(3);
}

/// Scenes a long run flagged (tests/differential/found, generator indices 1052 and 1061, references
/// at 16,384 spp), kept as regression tests for what they found:
///
/// - **Shading normals judged as Mitsuba does.** hppm dropped every direction that a mesh's
///   shading normal put on the other side of its geometric surface; Mitsuba judges light, BSDF
///   samples and refraction by the shading normal alone. Coarse smooth meshes of glass (a box
///   whose computed corner normals are the diagonals, a 4-ring sphere) then rendered darker than
///   Mitsuba: 1052 by 11-14% in two blocks (pt and hybrid, 2.7x and 1.9x the bound) and 1061 by
///   24% (2.5x). Caught by the long run over indices 1000-1104, where it was five of six flags.
#[test]
fn found_by_long_runs() {
    let cases = corpus("tests/differential/found");
    assert_unbiased(&cases, 0, 1);
}

/// Hand-written scenes for plugins and scene forms the generator does not draw
/// (tests/differential/plugins, references by tests/differential/references.py): the analytic
/// `cylinder` (placed by p0, p1, radius and to_world; diffuse, rough metal, emitting),
/// `serialized` meshes, a shapegroup placed by three instances, colours given as spectra (wavelength lists as reflectance, emission and
/// conductor indices, a constant spectrum on an emitter, a .spd file; converted as Mitsuba's RGB
/// variants convert them), `hide_emitters` (camera rays through a rectangle and a sphere light,
/// no environment seen, both still lighting), and a camera given as the tutorials give it (Mitsuba's default 50 mm
/// lens on a film that is not square, a lookat without up). An up vector or cylinder frame
/// turned the wrong way moves whole blocks and fails; a default lens of 45 mm instead of 50
/// fails at 1.04x the bound (finer fov errors are left to tests/mitsuba_compat.rs, which
/// compares the fov with Mitsuba's to 1e-3 degrees). `normalmap` and `bumpmap`: the two
/// plugins on diffuse, glass, anisotropic rough metal and rough plastic, around and inside
/// `twosided`, on rectangles, spheres and a cube; with the perturbation switched off 6 and 11
/// of their 16 blocks fail (up to 2.3x and 5.4x the bound). `blendbsdf` (a textured weight, a
/// blend in a blend, a twosided blend, a caustic on a blended floor) and `mask` (bitmap cut-outs
/// casting shadows, a half-opaque mask in front of glass, a null panel, max_depth 6 so the
/// pass-throughs' bounces count): children picked the wrong way round fail both (1.4x and
/// 1.6x), pass-throughs weighted by MIS fail `mask` (1.4x, -76% in a block).
/// `thinlens`: two small lights far
/// off the focus plane, blurred to discs of about 18 and 7 pixels; rendered through a pinhole
/// (the aperture ignored) 6 of 16 blocks fail, at up to 5.9x the bound (correct: 0.44x). A
/// focus 30% too far (0.71x) is below what block means see: the in-focus plane's sharpness is
/// tests/camera.rs's. `crop`: a 32x24 window in the middle of a 96x64 film (Gaussian filter
/// cut at the window); `crop_thinlens`: a window on the film's right and bottom edges through
/// a lens, with a tent filter and `sample_border`, and the 50 mm default fov taken on the whole
/// film. Rendering the film's top-left corner instead fails 10 and 12 blocks (up to 14.6x and
/// 6.8x the bound; correct: 0.42x and 0.36x), the window stretched over the whole view 10 and
/// 11 (9.4x, 6.6x). Letting the Gaussian's samples leave the window (as with sample_border)
/// moves too little light for block means (0.35x, unchanged). `principled`: textured base
/// colour, roughness and metallic, every lobe on one sphere, a transmissive sphere; metallic
/// read as 0 fails (2.0x); single lobes (retro-reflection, clearcoat) move less than block
/// means see (0.49x, 0.39x) and are checked lobe by lobe against Mitsuba in tests/bsdf.rs.
/// `principled_textured`: a texture on each of the other eight parameters (spec_trans and
/// anisotropic in stripes on a dark sphere, sheen from a bitmap's luminance, clearcoat, gloss,
/// tints and flatness on a red one and the floor). Correct: 0.37x; the textures replaced by
/// their means fail (2.9x, -18% in a block), each texture written into the next parameter's
/// place fails (1.8x, -13%); which parameter each lands in is
/// tests/textures.rs's (`principled_field_textures_land_in_their_parameters`).
/// `pplastic`: a glossy sphere (GGX alpha 0.05, its reflection of the light photon mapped by
/// the hybrid) with a checkerboard base, an anisotropic cube with a tinted specular
/// reflectance, a rough floor. Correct: 0.36x/0.38x; the base without its two (1 - F) factors
/// fails both (1.65x, +13% in a block, 8 of 16 blocks).
/// `principledthin`: a leaf-like sheet seen from its back and lit through its other side, and a
/// frosted pane with a checkerboard `diff_trans`, both lit from behind. Correct: 0.45x (pt and
/// hybrid alike: a thin principled is never S); diffuse transmission dropped fails (5.98x, -55%
/// in a block), a back side that reflects and transmits nothing fails (5.6x); the transmission
/// untinted by the base colour is at the bound (1.01x), its roughness unscaled by the index, or
/// sheen left out, are below what block means see (0.61x, 0.40x) and are tests/bsdf.rs's.
/// `spot_texture` and `projector`: a spot with a projected bitmap (its frame turned by a
/// diagonal up) and a projector of a 4:3 bitmap, each lighting a floor and a cube directly and
/// through a mirror the camera cannot see, against Mitsuba's particle tracer (its path tracer
/// cannot reach a delta light through a mirror), through the hybrid only (`pt` has no such
/// caustic). Correct: 0.05x and 0.11x the bound. The spot's u mirrored fails 8 of 16 blocks
/// (8.0x), its texture ignored 16 (38.9x); the projector's v mirrored 14 (42.1x), its texture
/// ignored 16 (48.2x), its 1/cos^3 left out 12 (2.5x, -26%), its image's aspect ignored 5
/// (3.9x). Photons carrying the bare intensity (no falloff, texture or 1/cos^3; NEE right)
/// fail both (5.7x and 7.3x): the caustics are the photons'.
/// `lanczos` and `catmullrom_border`: the filters with negative lobes on a glass sphere's
/// caustic, a light seen directly and a dark cube, splatted (Lanczos) and with `sample_border`
/// (Catmull-Rom, nothing splatted). Correct: 0.45x/0.22x and 0.41x/0.27x (pt/hybrid). Hit
/// points weighted by |f / (q F_W)| (the sign dropped) fail the Lanczos hybrid (1.54x, +38% in
/// the caustic's block); samples weighted by |f / (q F_W)| fail both `sample_border` graphs
/// (163x). The filter's shape is tests/pixel_filter.rs's (edge columns against Mitsuba).
/// `tinted_glass`: dielectrics with `specular_reflectance` and `specular_transmittance` (a
/// smooth sphere tinted blue through and orange on reflection, whose caustic is blue; a rough
/// sphere; a thin panel whose transmittance is a checkerboard). Correct: 0.43x/0.34x. Photons
/// that ignore the tint fail the hybrid (2.10x, +56% in the caustic's block); the thin panel's
/// tint ignored fails it at 1.03x (+40% in a block) and `pt` at 0.66x; the tints' values are
/// checked row by row against Mitsuba in tests/bsdf.rs (swapped: 61 of 480 rows fail).
fn plugins_shard(k: usize) {
    let cases = corpus("tests/differential/plugins");
    assert_unbiased(&cases, k, 2);
}

// In two halves, so the test harness renders them side by side.
#[test]
fn plugins_match_mitsuba_0() {
    plugins_shard(0);
}

#[test]
fn plugins_match_mitsuba_1() {
    plugins_shard(1);
}
