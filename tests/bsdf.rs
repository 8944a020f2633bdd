//! The BSDFs: the CPU reference (each unit's model under src/bsdfs/) against Mitsuba 3's own values, against
//! energy conservation, reciprocity and its own sampler (chi-square), and the GPU modules
//! (shaders/common/*.wgsl) against the CPU reference on a table of directions.

mod common;

use std::path::Path;

use glam::{Vec2, Vec3};
use hppm::scene::bsdf::Mode;
use hppm::scene::{Bsdf, Scene};

use common::rng::Rng;
use hppm::testing::bsdf::{chi_square, furnace, gpu_against_cpu, incident_directions};

/// The materials of tests/data/bsdf/mitsuba_table.py, written as a scene would write them, so
/// that the loader's reading of each parameter is checked too.
const MATERIALS: &[(&str, &str)] = &[
    (
        "diffuse",
        r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.8"/></bsdf>"#,
    ),
    (
        "conductor_au",
        r#"<bsdf type="conductor"><string name="material" value="Au"/></bsdf>"#,
    ),
    (
        "conductor_etak",
        r#"<bsdf type="conductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.1"/><rgb name="specular_reflectance" value="0.9, 0.8, 0.7"/></bsdf>"#,
    ),
    (
        "roughconductor_au_ggx",
        r#"<bsdf type="roughconductor"><string name="material" value="Au"/><string name="distribution" value="ggx"/><float name="alpha" value="0.18"/></bsdf>"#,
    ),
    (
        "roughconductor_cu_beckmann_aniso",
        r#"<bsdf type="roughconductor"><string name="material" value="Cu"/><string name="distribution" value="beckmann"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.35"/></bsdf>"#,
    ),
    (
        "roughconductor_ggx_aniso",
        r#"<bsdf type="roughconductor"><string name="material" value="Ag"/><string name="distribution" value="ggx"/><float name="alpha_u" value="0.4"/><float name="alpha_v" value="0.08"/></bsdf>"#,
    ),
    (
        "plastic",
        r#"<bsdf type="plastic"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><rgb name="diffuse_reflectance" value="0.1, 0.25, 0.6"/></bsdf>"#,
    ),
    (
        "plastic_nonlinear",
        r#"<bsdf type="plastic"><float name="int_ior" value="1.7"/><boolean name="nonlinear" value="true"/><rgb name="diffuse_reflectance" value="0.8, 0.5, 0.2"/><rgb name="specular_reflectance" value="0.9, 0.9, 0.6"/></bsdf>"#,
    ),
    (
        "roughplastic_ggx",
        r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.12"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><rgb name="diffuse_reflectance" value="0.6, 0.12, 0.1"/></bsdf>"#,
    ),
    (
        "roughplastic_beckmann_nonlinear",
        r#"<bsdf type="roughplastic"><string name="distribution" value="beckmann"/><float name="alpha" value="0.3"/><boolean name="nonlinear" value="true"/><rgb name="diffuse_reflectance" value="0.7, 0.7, 0.3"/></bsdf>"#,
    ),
    (
        "roughdielectric_ggx",
        r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.1"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/></bsdf>"#,
    ),
    (
        "roughdielectric_beckmann_aniso",
        r#"<bsdf type="roughdielectric"><string name="distribution" value="beckmann"/><float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.1"/><float name="int_ior" value="1.33"/><float name="ext_ior" value="1.0"/></bsdf>"#,
    ),
    (
        "thindielectric",
        r#"<bsdf type="thindielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/></bsdf>"#,
    ),
    (
        "dielectric",
        r#"<bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/></bsdf>"#,
    ),
    (
        "principled_plain",
        r#"<bsdf type="principled"><rgb name="base_color" value="0.8, 0.4, 0.2"/><float name="roughness" value="0.4"/></bsdf>"#,
    ),
    (
        "principled_every_lobe",
        r#"<bsdf type="principled"><rgb name="base_color" value="0.9, 0.6, 0.3"/><float name="metallic" value="0.3"/><float name="roughness" value="0.35"/><float name="anisotropic" value="0.5"/><float name="spec_tint" value="0.4"/><float name="sheen" value="0.3"/><float name="sheen_tint" value="0.5"/><float name="clearcoat" value="0.6"/><float name="clearcoat_gloss" value="0.3"/><float name="flatness" value="0.2"/><float name="specular" value="0.7"/></bsdf>"#,
    ),
    (
        "principled_glass",
        r#"<bsdf type="principled"><rgb name="base_color" value="0.9, 0.95, 1.0"/><float name="spec_trans" value="0.8"/><float name="roughness" value="0.25"/><float name="eta" value="1.45"/></bsdf>"#,
    ),
    (
        "dielectric_tinted",
        r#"<bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><rgb name="specular_reflectance" value="0.9, 0.6, 0.3"/><rgb name="specular_transmittance" value="0.2, 0.7, 0.95"/></bsdf>"#,
    ),
    (
        "thindielectric_tinted",
        r#"<bsdf type="thindielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><rgb name="specular_reflectance" value="0.9, 0.6, 0.3"/><rgb name="specular_transmittance" value="0.2, 0.7, 0.95"/></bsdf>"#,
    ),
    (
        "roughdielectric_tinted",
        r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><rgb name="specular_reflectance" value="0.9, 0.6, 0.3"/><rgb name="specular_transmittance" value="0.2, 0.7, 0.95"/></bsdf>"#,
    ),
    (
        "pplastic_ggx",
        r#"<bsdf type="pplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.15"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><rgb name="diffuse_reflectance" value="0.3, 0.5, 0.7"/></bsdf>"#,
    ),
    (
        "pplastic_beckmann_aniso",
        r#"<bsdf type="pplastic"><string name="distribution" value="beckmann"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/><rgb name="diffuse_reflectance" value="0.8, 0.3, 0.1"/><rgb name="specular_reflectance" value="0.9, 0.8, 0.7"/></bsdf>"#,
    ),
    (
        "principledthin_plain",
        r#"<bsdf type="principledthin"><rgb name="base_color" value="0.7, 0.3, 0.2"/><float name="roughness" value="0.4"/></bsdf>"#,
    ),
    (
        "principledthin_every_lobe",
        r#"<bsdf type="principledthin"><rgb name="base_color" value="0.8, 0.5, 0.3"/><float name="roughness" value="0.3"/><float name="anisotropic" value="0.5"/><float name="spec_trans" value="0.6"/><float name="spec_tint" value="0.4"/><float name="sheen" value="0.5"/><float name="sheen_tint" value="0.3"/><float name="flatness" value="0.3"/><float name="diff_trans" value="0.8"/><float name="eta" value="1.33"/><float name="specular_reflectance_sampling_rate" value="0.7"/><float name="specular_transmittance_sampling_rate" value="1.3"/><float name="diffuse_reflectance_sampling_rate" value="0.9"/><float name="diffuse_transmittance_sampling_rate" value="1.1"/></bsdf>"#,
    ),
    (
        "principledthin_leaf",
        r#"<bsdf type="principledthin"><rgb name="base_color" value="0.2, 0.6, 0.1"/><float name="roughness" value="0.5"/><float name="spec_trans" value="0.2"/><float name="diff_trans" value="1.2"/></bsdf>"#,
    ),
];

/// A one-sphere Mitsuba scene per BSDF snippet, loaded through the XML loader.
fn scene_with(bsdfs: &[&str]) -> Scene {
    let shapes: String = bsdfs
        .iter()
        .enumerate()
        .map(|(i, b)| {
            format!(
                r#"<shape type="sphere"><point name="center" x="{i}" y="0" z="0"/><float name="radius" value="0.4"/>{b}</shape>"#
            )
        })
        .collect();
    let xml = format!(
        r#"<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>{shapes}</scene>"#
    );
    hppm::loaders::mitsuba::parse(Path::new("bsdf_test.xml"), &xml)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn loaded(name: &str) -> Bsdf {
    let (_, xml) = MATERIALS.iter().find(|(n, _)| *n == name).expect(name);
    scene_with(&[xml]).materials[0].bsdf.clone()
}

struct Row {
    material: String,
    wi: Vec3,
    wo: Vec3,
    u1: f32,
    u2: Vec2,
    f: Vec3,
    pdf: f32,
    s_wo: Vec3,
    s_weight: Vec3,
    s_pdf: f32,
    s_delta: bool,
}

fn mitsuba_rows() -> Vec<Row> {
    let text = std::fs::read_to_string(common::repo_path("tests/data/bsdf/mitsuba_values.csv"))
        .expect("mitsuba_values.csv");
    text.lines()
        .skip(1)
        .map(|line| {
            let mut cells = line.split(',');
            let material = cells.next().expect("material").to_string();
            let v: Vec<f32> = cells.map(|c| c.parse().expect("number")).collect();
            let v3 = |i: usize| Vec3::new(v[i], v[i + 1], v[i + 2]);
            Row {
                material,
                wi: v3(0),
                wo: v3(3),
                u1: v[6],
                u2: Vec2::new(v[7], v[8]),
                f: v3(9),
                pdf: v[12],
                s_wo: v3(13),
                s_weight: v3(16),
                s_pdf: v[19],
                s_delta: v[20] != 0.0,
            }
        })
        .collect()
}

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-5
}

fn close3(a: Vec3, b: Vec3, rel: f32) -> bool {
    close(a.x, b.x, rel) && close(a.y, b.y, rel) && close(a.z, b.z, rel)
}

/// The CPU reference reproduces Mitsuba 3.9.1's own `eval`, `pdf` and `sample` (same random
/// numbers, so the same direction) for every BSDF of tests/data/bsdf/mitsuba_table.py on 24
/// direction pairs each, including directions from inside a dielectric and below a one-sided
/// surface. Catches any formula that
/// differs from Mitsuba's: a wrong Fresnel term, a missing 1/eta^2, Mitsuba's internal-reflection
/// and specular-sampling-weight handling in plastic, the rough plastic's transmittance table,
/// pplastic's two smooth refractions and fixed lobe probabilities,
/// the named conductors' RGB eta/k, an anisotropy swapped between u and v, or a sampler that
/// maps random numbers differently (which would still be unbiased, but is not Mitsuba's).
#[test]
fn cpu_reference_matches_mitsuba_values() {
    let rows = mitsuba_rows();
    assert!(rows.len() >= 330, "the table has {} rows", rows.len());
    let mut failures = Vec::new();
    let mut prepared_cache: Vec<(String, Bsdf)> = Vec::new();
    for row in &rows {
        if !prepared_cache.iter().any(|(n, _)| *n == row.material) {
            prepared_cache.push((row.material.clone(), loaded(&row.material)));
        }
        let p = &prepared_cache
            .iter()
            .find(|(n, _)| *n == row.material)
            .expect("cached")
            .1;
        let f = p.eval(row.wi, row.wo, Mode::Radiance);
        let pdf = p.pdf(row.wi, row.wo);
        if !close3(f, row.f, 3e-3) || !close(pdf, row.pdf, 3e-3) {
            failures.push(format!(
                "{}: eval {f} pdf {pdf}, Mitsuba {} {} (wi {}, wo {})",
                row.material, row.f, row.pdf, row.wi, row.wo
            ));
        }
        let s = p.sample(row.wi, row.u1, row.u2, Mode::Radiance);
        match s {
            None if row.s_pdf == 0.0 || row.s_weight.max_element() == 0.0 => {}
            None => failures.push(format!("{}: no sample, Mitsuba has one", row.material)),
            Some(s) if row.s_pdf == 0.0 => {
                if s.weight.max_element() > 0.0 {
                    failures.push(format!("{}: a sample where Mitsuba has none", row.material))
                }
            }
            Some(mut s) => {
                // A narrow lobe sampled near the edge of its disc (u near 0 or 1) is
                // ill-conditioned: float rounding moves wo by 1e-4 and the density there by a
                // few tenths of a percent (principledthin's transmission, alpha 0.02). With the
                // direction agreeing, judge the density and weight at Mitsuba's direction.
                if s.wo.dot(row.s_wo) >= 0.9999 && !s.delta && !close(s.pdf, row.s_pdf, 3e-3) {
                    s.pdf = p.pdf(row.wi, row.s_wo);
                    s.weight = p.eval(row.wi, row.s_wo, Mode::Radiance) / s.pdf;
                }
                if s.wo.dot(row.s_wo) < 0.9999
                    || !close3(s.weight, row.s_weight, 3e-3)
                    || !close(s.pdf, row.s_pdf, 3e-3)
                    || s.delta != row.s_delta
                {
                    failures.push(format!(
                        "{}: sample wo {} weight {} pdf {} delta {}, Mitsuba {} {} {} {}",
                        row.material,
                        s.wo,
                        s.weight,
                        s.pdf,
                        s.delta,
                        row.s_wo,
                        row.s_weight,
                        row.s_pdf,
                        row.s_delta
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} rows differ from Mitsuba:\n{}",
        failures.len(),
        rows.len(),
        failures.join("\n")
    );
}

/// BSDFs for the statistical tests: every kind and both distributions, the roughness
/// anisotropic where Mitsuba allows it.
fn test_bsdfs() -> Vec<(&'static str, Bsdf)> {
    [
        "diffuse",
        "roughconductor_au_ggx",
        "roughconductor_cu_beckmann_aniso",
        "roughconductor_ggx_aniso",
        "plastic",
        "plastic_nonlinear",
        "roughplastic_ggx",
        "roughplastic_beckmann_nonlinear",
        "roughdielectric_ggx",
        "roughdielectric_beckmann_aniso",
        "principled_plain",
        "principled_every_lobe",
        "principled_glass",
        "roughdielectric_tinted",
        "pplastic_ggx",
        "pplastic_beckmann_aniso",
        "principledthin_plain",
        "principledthin_every_lobe",
        "principledthin_leaf",
    ]
    .iter()
    .map(|n| (*n, loaded(n)))
    .collect()
}

fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Each sampler draws directions with the density `pdf` says: 400,000 samples per incident
/// direction histogrammed over 20 x 40 cells of (cos theta, phi) (equal solid angle) plus one
/// cell for delta and failed samples, against the pdf integrated over each cell (32 x 32 points: with 8 x 8 or 16 x 16 the
/// integration error of the peaked anisotropic lobes alone fails the test);
/// cells expecting under 5 are pooled. The chi-square's z-score must stay under 5 (p ~ 3e-7 per
/// test). Catches a pdf that is not the sampler's (a missing lobe probability, a Jacobian off by
/// a factor, a swapped anisotropy), which MIS would turn into bias.
#[test]
fn samplers_match_their_pdf_chi_square() {
    let mut rng = hppm::testing::bsdf::Rng(0x5eed);
    let mut report = Vec::new();
    for (name, b) in test_bsdfs() {
        // Mitsuba 3.9.1's principled with spec_trans picks its lobe by the Fresnel of the
        // sampled specular normal but reports a pdf that takes it at the half vector of the
        // pair: its sampler does not follow its pdf (chi-square z 17 at wi.z 0.95), and hppm
        // samples as it does (tests/data/bsdf/mitsuba_values.csv's rows agree). The sample
        // weights' mean then falls 0.3-1.9% below the albedo eval integrates to (measured at
        // wi.z 0.95, 0.6, 0.2, -0.6 over 2M samples; docs/mitsuba-scenes.md).
        if name == "principled_glass" {
            continue;
        }
        for wi in incident_directions(b.transmits()) {
            let chi = chi_square(&b, wi, 400_000, &mut rng);
            report.push(format!(
                "{name} wi.z {:.2}: chi2 {:.0} dof {} z {:.2}",
                wi.z, chi.chi2, chi.dof, chi.z
            ));
            assert!(
                chi.z < 5.0,
                "{name}, wi {wi}: the sampler does not follow its pdf ({chi:?})\n{}",
                report.join("\n")
            );
        }
    }
    eprintln!("{}", report.join("\n"));
}

/// Energy: with white parameters (reflectance 1; conductors of eta 0 and k 1, which reflect
/// everything), the mean sample weight (the directional albedo) is at most 1 within noise (and
/// 0.2%, Mitsuba's plastic's own excess), and equals the integral of `eval` over the sphere (uniform directions)
/// within 4 standard errors plus the delta lobes' share. Catches a sample weight that is not
/// eval / pdf (the furnace would gain or lose energy) and any lobe that creates energy.
#[test]
fn white_furnace_albedo_at_most_one_and_weights_match_eval() {
    let white = [
        r#"<bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf>"#,
        r#"<bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/></bsdf>"#,
        r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.5"/></bsdf>"#,
        r#"<bsdf type="plastic"><rgb name="diffuse_reflectance" value="1"/></bsdf>"#,
        r#"<bsdf type="plastic"><rgb name="diffuse_reflectance" value="1"/><boolean name="nonlinear" value="true"/></bsdf>"#,
        r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/><rgb name="diffuse_reflectance" value="1"/></bsdf>"#,
        r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>"#,
        r#"<bsdf type="roughdielectric"><float name="alpha_u" value="0.4"/><float name="alpha_v" value="0.1"/><float name="int_ior" value="2.4"/></bsdf>"#,
        r#"<bsdf type="thindielectric"/>"#,
        r#"<bsdf type="conductor"/>"#,
        r#"<bsdf type="principledthin"><rgb name="base_color" value="1"/><float name="roughness" value="0.2"/><float name="spec_trans" value="0.5"/><float name="diff_trans" value="1"/><float name="anisotropic" value="0.4"/></bsdf>"#,
    ];
    let scene = scene_with(&white);
    let mut rng = hppm::testing::bsdf::Rng(7);
    for (m, xml) in scene.materials.iter().zip(white) {
        for wi in incident_directions(m.bsdf.transmits()) {
            // Photons (importance) conserve energy across a refraction; radiance does not.
            let f = furnace(&m.bsdf, wi, 200_000, &mut rng);
            let (a, sm, i) = (f.albedo, f.continuous_albedo, f.eval_integral);
            // Mitsuba's plastic with a white base reflects up to 0.12% more than it receives
            // at normal incidence (its fits of the coating's diffuse reflectance); we match it.
            assert!(
                a.mean <= 1.0 + 4.0 * a.error + 2e-3,
                "{xml} wi {wi}: albedo {a:?} > 1"
            );
            assert!(
                (sm.mean - i.mean).abs() <= 4.0 * (sm.error + i.error) + 2e-3,
                "{xml} wi {wi}: sampled non-delta albedo {sm:?} but eval integrates to {i:?}"
            );
            if xml.contains("thindielectric") || xml.contains("\"conductor\"") {
                assert!(
                    (a.mean - 1.0).abs() < 1e-4,
                    "{xml}: a lossless delta BSDF has albedo {a:?}"
                );
            }
        }
    }
}

/// Reciprocity (Helmholtz, and its adjoint form across a refraction): for reflection,
/// f(wi, wo) = f(wo, wi); for the rough dielectric, the photon (importance) BSDF is the adjoint
/// of the radiance one, f_importance(wi, wo) = f_radiance(wo, wi). Checked on 2,000 random
/// pairs per BSDF. Catches an asymmetric Fresnel or shadowing term and a (eta_t/eta_i)^2 factor
/// on the wrong side.
///
/// principledthin's specular transmission is left out: Mitsuba 3.9.1's is not reciprocal (its
/// micro/macro-surface and shadowing masks test wo against the half vector of wi and wo's mirror
/// image, which is not symmetric in the pair: at wi (0.147, -0.984, 0.102), wo (0.200, 0.501,
/// -0.842) with spec_trans 1 Mitsuba's own f is 0.0026 one way and 0 the other), and hppm
/// follows Mitsuba (tests/data/bsdf/mitsuba_values.csv). Its reflection and diffuse transmission
/// are checked.
#[test]
fn bsdfs_are_reciprocal() {
    let mut rng = Rng(11);
    for (name, b) in test_bsdfs() {
        let p = b.clone();
        let one_way_transmission = b
            .get::<hppm::bsdfs::principledthin::PrincipledThin>()
            .is_some_and(|t| t.spec_trans > 0.0);
        let mut checked = 0;
        for _ in 0..2000 {
            let wi = uniform_sphere(Vec2::new(rng.unit(), rng.unit()));
            let wo = uniform_sphere(Vec2::new(rng.unit(), rng.unit()));
            if wi.z.abs() < 0.05 || wo.z.abs() < 0.05 {
                continue;
            }
            if one_way_transmission && wi.z * wo.z < 0.0 {
                continue;
            }
            let forward = p.eval(wi, wo, Mode::Importance) / wo.z.abs();
            let backward = p.eval(wo, wi, Mode::Radiance) / wi.z.abs();
            assert!(
                close3(forward, backward, 2e-3),
                "{name}: f*(wi {wi}, wo {wo}) = {forward} but f(wo, wi) = {backward}"
            );
            checked += (forward.max_element() > 0.0) as u32;
        }
        assert!(checked > 50, "{name}: only {checked} pairs with a value");
    }
}

/// The named conductors are Mitsuba's spectra at RGB: gold's figures as Mitsuba 3's RGB mode
/// computes them (close to the eta (0.143, 0.374, 1.442), k (3.983, 2.385, 1.603) that pbrt and
/// Mitsuba 0.6 list), every name in Mitsuba's data/ior resolves, and an unknown name is an error
/// naming the line and the names there are.
#[test]
fn named_conductors_are_mitsubas() {
    let (eta, k) = hppm::bsdfs::conductor::named_conductor("Au").expect("Au");
    assert!(
        close3(eta, Vec3::new(0.143, 0.3753, 1.442), 2e-3),
        "Au eta {eta}"
    );
    assert!(
        close3(k, Vec3::new(3.983, 2.3856, 1.6034), 2e-3),
        "Au k {k}"
    );
    assert!(hppm::bsdfs::conductor::NAMED_CONDUCTORS.len() >= 70);
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"/>
<shape type="sphere"><bsdf type="conductor"><string name="material" value="Gold"/></bsdf></shape></scene>"#;
    let err = hppm::loaders::mitsuba::parse(Path::new("named.xml"), xml)
        .expect_err("Gold is not a Mitsuba name")
        .to_string();
    assert!(err.starts_with("named.xml:2:"), "{err}");
    assert!(err.contains("\"Gold\"") && err.contains("Au"), "{err}");
}

/// Malformed BSDF parameters are errors at their line: both alpha and alpha_u, one of
/// alpha_u/alpha_v, anisotropic roughplastic, a dielectric nested in twosided, an unknown
/// distribution, an unknown parameter (whose message lists the parameters the BSDF takes), and
/// what Mitsuba's pplastic refuses too (equal indices, a textured alpha, an `eta` it never
/// reads).
#[test]
fn bad_bsdf_parameters_are_errors_at_their_line() {
    let cases = [
        (
            r#"<bsdf type="roughconductor"><float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.1"/></bsdf>"#,
            "not both",
        ),
        (
            r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/></bsdf>"#,
            "both be given",
        ),
        (
            r#"<bsdf type="roughplastic"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.2"/></bsdf>"#,
            "anisotropic",
        ),
        (
            r#"<bsdf type="twosided"><bsdf type="dielectric"/></bsdf>"#,
            "transmission",
        ),
        (
            r#"<bsdf type="twosided"><bsdf type="diffuse"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            "at most two",
        ),
        (
            r#"<bsdf type="roughdielectric"><string name="distribution" value="phong"/></bsdf>"#,
            "phong",
        ),
        (
            r#"<bsdf type="plastic"><float name="roughness" value="0.1"/></bsdf>"#,
            "unknown property \"roughness\" for <bsdf type=\"plastic\"> (it takes int_ior, ext_ior, diffuse_reflectance",
        ),
        (r#"<bsdf type="blend"/>"#, "roughplastic"),
        (
            r#"<bsdf type="pplastic"><float name="int_ior" value="1.2"/><float name="ext_ior" value="1.2"/></bsdf>"#,
            "must differ",
        ),
        (
            r#"<bsdf type="pplastic"><texture name="alpha" type="checkerboard"/></bsdf>"#,
            "takes no texture",
        ),
        (
            r#"<bsdf type="pplastic"><float name="eta" value="1.5"/></bsdf>"#,
            "unknown property \"eta\" for <bsdf type=\"pplastic\">",
        ),
        (
            r#"<bsdf type="principledthin"><float name="eta" value="0"/></bsdf>"#,
            "eta 0: must be positive",
        ),
        (
            r#"<bsdf type="principledthin"><float name="metallic" value="0.5"/></bsdf>"#,
            "unknown property \"metallic\" for <bsdf type=\"principledthin\">",
        ),
        (
            r#"<bsdf type="principledthin"><float name="diff_tran" value="0.5"/></bsdf>"#,
            "did you mean \"diff_trans\"",
        ),
        (
            r#"<bsdf type="twosided"><bsdf type="principledthin"/></bsdf>"#,
            "transmission",
        ),
    ];
    for (bsdf, expected) in cases {
        let xml = format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"/>\n<shape type=\"sphere\">{bsdf}</shape></scene>"
        );
        let err = hppm::loaders::mitsuba::parse(Path::new("bad.xml"), &xml)
            .expect_err(bsdf)
            .to_string();
        assert!(err.starts_with("bad.xml:2:"), "{bsdf}: {err}");
        assert!(err.contains(expected), "{bsdf}: {err}");
    }
}

/// twosided: one BSDF is seen from both sides, two are front and back; the back of a material
/// that is not twosided is black.
#[test]
fn twosided_gives_the_back_its_bsdf() {
    let scene = scene_with(&[
        r#"<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf></bsdf>"#,
        r#"<bsdf type="twosided"><bsdf type="diffuse"/><bsdf type="plastic"/></bsdf>"#,
        r#"<bsdf type="diffuse"/>"#,
    ]);
    let m = &scene.materials;
    assert_eq!(m[0].back, Some(m[0].bsdf.clone()));
    assert!(m[1].bsdf.kind() == "diffuse");
    assert!(m[1].back.as_ref().is_some_and(|b| b.kind() == "plastic"));
    assert_eq!(m[2].back, None);
    let f = scene.features();
    assert!(f.has_bsdf("diffuse") && f.has_bsdf("plastic") && f.delta);
    assert!(!f.has_bsdf("conductor"));
}

/// The GPU modules (the generated material dispatch and every unit's WGSL, every kind compiled
/// in) give the CPU reference's eval, pdf and sample (same random numbers) for every BSDF of the
/// Mitsuba table the dispatch handles (the Lambertian and the smooth dielectric are the passes'
/// own) on 600 random direction pairs each, in radiance and importance mode. Catches a WGSL port
/// that differs from the reference (and so from Mitsuba): a sign, a swapped argument, a wrong
/// table lookup, a lobe left out of the dispatch.
#[test]
fn gpu_bsdfs_match_the_cpu_reference() {
    let gpu = common::gpu();
    let xmls: Vec<&str> = MATERIALS.iter().map(|(_, x)| *x).collect();
    let scene = scene_with(&xmls);
    let registry = hppm::passes::Registry::builtin();
    let mut rng = hppm::testing::bsdf::Rng(99);
    let report =
        gpu_against_cpu(&gpu, &registry, &scene, 600, 2e-3, &mut rng).expect("bsdf kernel");
    assert!(
        report.eval_failures.is_empty(),
        "{} evals differ:\n{}",
        report.eval_failures.len(),
        report.eval_failures.join("\n")
    );
    // A random number within a few ulps of a lobe's threshold, or a grazing direction, may
    // fall either way in f32 on the two sides; anything beyond a handful is a real difference.
    eprintln!(
        "{} samples compared, {} differ",
        report.samples_compared, report.sample_mismatches
    );
    assert!(
        report.samples_compared > report.queries / 2,
        "only {} samples compared",
        report.samples_compared
    );
    assert!(
        report.sample_mismatches * 200 <= report.queries,
        "{} of {} GPU samples differ from the CPU's",
        report.sample_mismatches,
        report.queries
    );
}
