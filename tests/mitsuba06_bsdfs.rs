//! Mitsuba 0.6's `roughdiffuse`, `phong` and `ward` (src/bsdfs/roughdiffuse/, phong/, ward/):
//! their CPU models against values worked out from 0.6's own formulas (src/bsdfs/roughdiffuse.cpp,
//! phong.cpp, ward.cpp of mitsuba-renderer/mitsuba), their WGSL through the generated dispatch
//! against the CPU models, their samplers against their pdfs, their energy, how the partition
//! sees them, and how they are read from 0.5/0.6 files (and refused in version 3 ones). The last
//! sections do the same for `difftrans`, `mixturebsdf` and `hk`, and for `coating` and
//! `roughcoating`.
//!
//! The expected values are not computed by the code under test: the closed forms are written
//! out below as arithmetic on the parameters, and the others come from a separate double
//! precision transcription of 0.6's formulas (Python with numpy, run when these tests were
//! written: f at fixed directions, and directional albedos integrated on a 1600 x 3200 midpoint
//! grid over (cos theta, phi), which agrees with a 800 x 1600 grid to 1e-5).

mod common;

use std::path::Path;

use bytemuck::Zeroable;
use glam::{Vec2, Vec3};
use hppm::bsdfs::phong::Phong;
use hppm::bsdfs::roughdiffuse::RoughDiffuse;
use hppm::bsdfs::ward::{Variant, Ward};
use hppm::scene::bsdf::{BsdfModel, GpuMaterial, Mode};
use hppm::scene::{Bsdf, Scene};
use hppm::testing::bsdf::{Rng, chi_square, furnace, gpu_against_cpu, incident_directions};

const PI: f32 = std::f32::consts::PI;

/// A scene of one sphere per BSDF snippet in a file of `version`, through the XML loader.
fn scene_with(version: &str, bsdfs: &[&str]) -> Result<Scene, hppm::scene::SceneError> {
    let shapes: String = bsdfs
        .iter()
        .enumerate()
        .map(|(i, b)| {
            format!(
                r#"<shape type="sphere"><point name="center" x="{i}" y="0" z="0"/><float name="radius" value="0.4"/>{b}</shape>"#
            )
        })
        .collect();
    let xml =
        format!("<scene version=\"{version}\"><sensor type=\"perspective\"/>\n{shapes}</scene>");
    hppm::loaders::mitsuba::parse(Path::new("m06.xml"), &xml)
}

fn loaded(version: &str, bsdfs: &[&str]) -> Vec<Bsdf> {
    scene_with(version, bsdfs)
        .unwrap_or_else(|e| panic!("{e}"))
        .materials
        .iter()
        .map(|m| m.bsdf.clone())
        .collect()
}

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-7
}

fn assert_close(what: &str, got: f32, expected: f32, rel: f32) {
    assert!(
        close(got, expected, rel),
        "{what}: {got}, expected {expected}"
    );
}

fn unit(x: f32, y: f32, z: f32) -> Vec3 {
    let v = Vec3::new(x, y, z);
    assert!((v.length() - 1.0).abs() < 1e-6, "{v} is not a unit vector");
    v
}

/// The test directions: wi 37 degrees off the normal, wo elsewhere in the hemisphere.
fn wi() -> Vec3 {
    unit(0.48, 0.36, 0.8)
}
fn wo_across() -> Vec3 {
    unit(-0.6, 0.0, 0.8)
}
fn wo_beside() -> Vec3 {
    unit(0.0, 0.28, 0.96)
}
fn wo_near_mirror() -> Vec3 {
    Vec3::new(-0.4, -0.3, 0.75f32.sqrt())
}
const N: Vec3 = Vec3::Z;

// ---------------------------------------------------------------- roughdiffuse

/// Oren-Nayar as 0.6 writes it, reflectance 0.8: at normal incidence and exitance (both sin
/// theta 0, so cos(phi_o - phi_i) is taken as 0 and alpha = beta = 0) the full model is
/// (rho C1 + rho^2 C4) / pi and the fast one rho A / pi, with sigma^2 = alpha^2 / 2 (0.6's
/// conversion), C1 = A = 1 - sigma^2 / (2 (sigma^2 + 0.33)), C4 = 0.17 sigma^2 / (sigma^2 +
/// 0.13); at oblique pairs (both orders: it is reciprocal) the values of 0.6's formulas in
/// double precision. Catches a wrong alpha-to-sigma conversion (sigma = alpha would change
/// every value by 2-10%), a swapped alpha/beta (the order of wi and wo), a lost
/// inter-reflection term (rho^2 C4) or sign in C2, and the fast model mixed up with the full.
#[test]
fn roughdiffuse_eval_is_oren_nayar_as_mitsuba06_writes_it() {
    let rho = 0.8f32;
    for alpha in [0.3f32, 0.7] {
        let s2 = alpha * alpha / 2.0;
        let c1 = 1.0 - 0.5 * s2 / (s2 + 0.33);
        let c4 = 0.17 * s2 / (s2 + 0.13);
        let full = RoughDiffuse::new(Vec3::splat(rho), alpha, false);
        let fast = RoughDiffuse::new(Vec3::splat(rho), alpha, true);
        let f_full = full.eval(N, N, Mode::Radiance).x;
        assert_close(
            &format!("full, alpha {alpha}, normal"),
            f_full,
            (rho * c1 + rho * rho * c4) / PI,
            1e-5,
        );
        let f_fast = fast.eval(N, N, Mode::Radiance).x;
        assert_close(
            &format!("fast, alpha {alpha}, normal"),
            f_fast,
            rho * c1 / PI,
            1e-5,
        );
    }
    // (alpha, fast, wi, wo, f |cos wo|) from 0.6's formulas.
    let table = [
        (0.3, false, wi(), wo_across(), 0.18987168871133075),
        (0.3, true, wi(), wo_across(), 0.1914952275281685),
        (0.7, false, wi(), wo_across(), 0.15955708774106034),
        (0.7, true, wi(), wo_across(), 0.16031746615447967),
        (0.3, false, wi(), wo_beside(), 0.24203746058054143),
        (0.3, true, wi(), wo_beside(), 0.23364454941708132),
        (0.7, false, wi(), wo_beside(), 0.2221489228102984),
        (0.7, true, wi(), wo_beside(), 0.20082858070391338),
        (0.3, false, wo_beside(), wi(), 0.20169788381711787),
        (0.3, true, wo_beside(), wi(), 0.19470379118090111),
        (0.7, false, wo_beside(), wi(), 0.18512410234191534),
        (0.7, true, wo_beside(), wi(), 0.16735715058659448),
    ];
    for (alpha, fast, a, b, expected) in table {
        let model = RoughDiffuse::new(Vec3::splat(rho), alpha, fast);
        let f = model.eval(a, b, Mode::Radiance);
        assert_close(
            &format!("alpha {alpha} fast {fast} wi {a} wo {b}"),
            f.x,
            expected as f32,
            2e-5,
        );
        assert_eq!(f.x, f.z, "a grey reflectance gives grey");
        assert_close("pdf", model.pdf(a, b), b.z / PI, 1e-6);
    }
    // One-sided.
    let model = RoughDiffuse::new(Vec3::splat(rho), 0.3, false);
    assert_eq!(model.eval(-wi(), wo_across(), Mode::Radiance), Vec3::ZERO);
    assert_eq!(model.eval(wi(), -wo_across(), Mode::Radiance), Vec3::ZERO);
}

/// alpha 0 is Lambert's law, reflectance / pi |cos wo|, at random pairs in both models (sigma
/// 0 zeroes every term but C1 = 1), and a white one reflects exactly what it receives. Catches
/// a roughness term that does not vanish at alpha 0.
#[test]
fn roughdiffuse_with_alpha_0_is_lambertian() {
    let mut rng = Rng(3);
    for fast in [false, true] {
        let model = RoughDiffuse::new(Vec3::new(0.9, 0.5, 0.1), 0.0, fast);
        for _ in 0..1000 {
            let (mut a, mut b) = (rng.direction(), rng.direction());
            a.z = a.z.abs();
            b.z = b.z.abs();
            let f = model.eval(a, b, Mode::Radiance);
            let lambert = Vec3::new(0.9, 0.5, 0.1) * (b.z / PI);
            assert!(
                (f - lambert).abs().max_element() <= 1e-6,
                "{f} vs {lambert}"
            );
        }
        let white = Bsdf::new(RoughDiffuse::new(Vec3::ONE, 0.0, fast));
        for wi in incident_directions(false) {
            let f = furnace(&white, wi, 20_000, &mut rng);
            assert!((f.albedo.mean - 1.0).abs() < 1e-5, "{:?}", f.albedo);
        }
    }
}

/// White furnace (reflectance 1, 200,000 samples per incident direction): the mean sample
/// weight equals the directional albedo of 0.6's formulas integrated numerically (within 4
/// standard errors + 0.2%), and the integral of eval. The albedo is at most 1 at cos theta_i
/// 0.95 and 0.6; at grazing incidence 0.6's full model, whose inter-reflection term is not
/// energy-bounded, reflects more than it receives (alpha 0.2, cos 0.2: 1.0123; up to 1.033 at
/// alpha 0.3, cos 0.05), and hppm keeps that rather than differ from 0.6. Catches weights that
/// are not eval / pdf and a model that differs from 0.6's in energy.
#[test]
fn roughdiffuse_white_furnace_is_mitsuba06s_albedo() {
    // (alpha, fast, albedo at cos theta_i 0.95, 0.6, 0.2).
    let table = [
        (0.2f32, false, [0.9942f64, 0.9992, 1.0123]),
        (0.7, false, [0.89862, 0.91845, 0.97114]),
        (0.7, true, [0.8099, 0.86988, 0.92772]),
    ];
    let mut rng = Rng(21);
    for (alpha, fast, albedos) in table {
        let bsdf = Bsdf::new(RoughDiffuse::new(Vec3::ONE, alpha, fast));
        for (wi, expected) in incident_directions(false).into_iter().zip(albedos) {
            let f = furnace(&bsdf, wi, 200_000, &mut rng);
            let (a, i) = (f.albedo, f.eval_integral);
            let what = format!("alpha {alpha} fast {fast} cos {}", wi.z);
            assert!(
                (a.mean - expected).abs() <= 4.0 * a.error + 2e-3,
                "{what}: albedo {a:?}, 0.6's {expected}"
            );
            assert!(
                (a.mean - i.mean).abs() <= 4.0 * (a.error + i.error) + 2e-3,
                "{what}: albedo {a:?} but eval integrates to {i:?}"
            );
            if wi.z >= 0.6 {
                assert!(a.mean <= 1.0 + 4.0 * a.error, "{what}: albedo {a:?} > 1");
            }
        }
    }
}

// ---------------------------------------------------------------- phong

/// 0.6's modified Phong: at normal incidence and exitance (cos alpha = 1) f = kd / pi + ks (n +
/// 2) / (2 pi), and the pdf w (n + 1) / (2 pi) + (1 - w) / pi with w = ks / (kd + ks) (grey
/// reflectances: luminance is the value); with kd 0.8 + ks 0.5 > 1 both are scaled by 0.99 /
/// 1.3 (0.6's ensureEnergyConservation) and w is unchanged; at two oblique pairs the values of
/// 0.6's formulas. Catches a wrong normalisation ((n + 1) for (n + 2) in f, or the reverse in
/// the pdf), a lobe about the wrong direction, a lobe weight not 0.6's, and reflectances not
/// scaled as 0.6 scales them.
#[test]
fn phong_eval_and_pdf_are_mitsuba06s() {
    let (kd, ks, n) = (0.5f32, 0.2f32, 30.0f32);
    let model = Phong::new(Vec3::splat(kd), Vec3::splat(ks), n);
    let w = ks / (kd + ks);
    assert_close("weight", model.lobes.specular_weight, w, 1e-6);
    assert_close(
        "f normal",
        model.eval(N, N, Mode::Radiance).x,
        kd / PI + ks * (n + 2.0) / (2.0 * PI),
        1e-5,
    );
    assert_close(
        "pdf normal",
        model.pdf(N, N),
        w * (n + 1.0) / (2.0 * PI) + (1.0 - w) / PI,
        1e-5,
    );
    // (wo, f |cos wo|, pdf) at wi from 0.6's formulas.
    for (wo, f, pdf) in [
        (wo_across(), 0.2139262450892011, 0.331705593951353),
        (wo_near_mirror(), 0.8484736079344224, 1.3325245007090158),
    ] {
        assert_close(
            &format!("f at {wo}"),
            model.eval(wi(), wo, Mode::Radiance).y,
            f as f32,
            2e-5,
        );
        assert_close(
            &format!("pdf at {wo}"),
            model.pdf(wi(), wo),
            pdf as f32,
            2e-5,
        );
    }
    let scaled = Phong::new(Vec3::splat(0.8), Vec3::splat(0.5), n);
    let scale = 0.99 / 1.3;
    assert_close("scale", scaled.lobes.scale, scale, 1e-6);
    assert_close(
        "scaled weight",
        scaled.lobes.specular_weight,
        0.5 / 1.3,
        1e-6,
    );
    assert_close(
        "scaled f normal",
        scaled.eval(N, N, Mode::Radiance).x,
        scale * (0.8 / PI + 0.5 * (n + 2.0) / (2.0 * PI)),
        1e-5,
    );
    // The lobe's weight is the luminance of the means (Rec. 709 weights, as 0.6's RGB mode).
    let coloured = Phong::new(Vec3::new(0.2, 0.5, 0.8), Vec3::splat(0.2), n);
    let lum_d = 0.212671 * 0.2 + 0.715160 * 0.5 + 0.072169 * 0.8;
    assert_close(
        "coloured weight",
        coloured.lobes.specular_weight,
        0.2 / (lum_d + 0.2),
        1e-5,
    );
    assert_eq!(model.eval(-wi(), N, Mode::Radiance), Vec3::ZERO);
    assert_eq!(model.pdf(wi(), -N), 0.0);
}

/// The Phong lobe alone (kd 0, ks 1) reflects exactly cos theta_i wherever the lobe lies above
/// the horizon (its f |cos wo| averages to cos alpha times wi's mirror direction's z, and (n + 2)
/// / (2 pi) normalises cos^(n + 1)): 0.95 and 0.6 at n = 30, 0.2119 at cos 0.2 where the horizon
/// cuts it (numerically). With kd 0.5, ks 0.5 it is 0.5 + half that. The mean sample weight
/// must equal these (4 standard errors + 0.2%) and the integral of eval, and never exceed 1.
/// Catches a normalisation or sample weight that gains or loses energy.
#[test]
fn phong_white_furnace_is_cos_theta_for_the_lobe() {
    let lobe_albedo = [0.95f64, 0.6, 0.21191];
    let mut rng = Rng(8);
    for (kd, ks) in [(0.0f32, 1.0f32), (0.5, 0.5)] {
        let bsdf = Bsdf::new(Phong::new(Vec3::splat(kd), Vec3::splat(ks), 30.0));
        for (wi, lobe) in incident_directions(false).into_iter().zip(lobe_albedo) {
            let expected = kd as f64 + ks as f64 * lobe;
            let f = furnace(&bsdf, wi, 200_000, &mut rng);
            let (a, i) = (f.albedo, f.eval_integral);
            let what = format!("kd {kd} ks {ks} cos {}", wi.z);
            assert!(
                (a.mean - expected).abs() <= 4.0 * a.error + 2e-3,
                "{what}: albedo {a:?}, expected {expected}"
            );
            assert!(
                (a.mean - i.mean).abs() <= 4.0 * (a.error + i.error) + 2e-3,
                "{what}: albedo {a:?} but eval integrates to {i:?}"
            );
            assert!(a.mean <= 1.0 + 4.0 * a.error, "{what}: albedo {a:?} > 1");
        }
    }
}

// ---------------------------------------------------------------- ward

/// 0.6's Ward variants with kd 0.5, ks 0.2, alpha_u 0.1, alpha_v 0.3: at normal incidence and
/// exitance (h = 2z, no exponential decay) every variant's lobe is 1 / (4 pi alpha_u alpha_v),
/// the pdf w / (4 pi alpha_u alpha_v) + (1 - w) / pi; at two oblique pairs the values of 0.6's
/// formulas, which differ per variant while the pdf is the same for all three. Catches a
/// variant's normalisation mixed up with another's, alpha_u and alpha_v swapped (the pairs are
/// not symmetric in x and y), h normalised where 0.6 keeps it unnormalised (balanced), and a
/// pdf that is not 0.6's.
#[test]
fn ward_eval_and_pdf_are_mitsuba06s_per_variant() {
    let (kd, ks, au, av) = (0.5f32, 0.2f32, 0.1f32, 0.3f32);
    let w = ks / (kd + ks);
    // (variant, f |cos wo| at wo_near_mirror, at wo_across).
    let table = [
        (Variant::Ward, 0.5698703279527539, 0.29955743769705484),
        (Variant::WardDuer, 0.6568852677885209, 0.34261580850293943),
        (Variant::Balanced, 0.6579371483291298, 0.3547259752920946),
    ];
    for (variant, near, across) in table {
        let model = Ward::new(variant, Vec3::splat(kd), Vec3::splat(ks), au, av);
        assert_close(
            &format!("{variant:?} f normal"),
            model.eval(N, N, Mode::Radiance).x,
            kd / PI + ks / (4.0 * PI * au * av),
            1e-5,
        );
        assert_close(
            &format!("{variant:?} pdf normal"),
            model.pdf(N, N),
            w / (4.0 * PI * au * av) + (1.0 - w) / PI,
            1e-5,
        );
        for (wo, f, pdf) in [
            (wo_near_mirror(), near, 0.9115869437338181),
            (wo_across(), across, 0.5067513932744208),
        ] {
            let what = format!("{variant:?} at {wo}");
            assert_close(
                &what,
                model.eval(wi(), wo, Mode::Radiance).x,
                f as f32,
                2e-5,
            );
            assert_close(&what, model.pdf(wi(), wo), pdf as f32, 2e-5);
        }
        let swapped = Ward::new(variant, Vec3::splat(kd), Vec3::splat(ks), av, au);
        assert!(
            !close(
                swapped.eval(wi(), wo_near_mirror(), Mode::Radiance).x,
                near as f32,
                1e-2
            ),
            "{variant:?}: swapping alpha_u and alpha_v changes nothing at an anisotropic pair"
        );
    }
}

/// White furnace of the Ward lobe alone (kd 0, ks 1, alpha_u 0.1, alpha_v 0.3): the mean sample
/// weight equals the albedo of 0.6's formulas integrated numerically (4 standard errors +
/// 0.3%) and the integral of eval. `ward` loses energy away from the normal, `balanced` keeps
/// its albedo bounded, `ward-duer` stays below 1 at these angles (0.6's docs warn that it
/// exceeds 1 at grazing angles: 1.46 at cos theta_i 0.05 by the same integration, which hppm
/// keeps). Catches a variant's normalisation or weight that differs from 0.6's.
#[test]
fn ward_white_furnace_is_mitsuba06s_albedo_per_variant() {
    // (variant, albedo at cos theta_i 0.95, 0.6, 0.2).
    let table = [
        (Variant::Ward, [0.83427f64, 0.53328, 0.22237]),
        (Variant::WardDuer, [0.91549, 0.91036, 0.8858]),
        (Variant::Balanced, [0.94763, 0.91251, 0.80534]),
    ];
    let mut rng = Rng(13);
    for (variant, albedos) in table {
        let bsdf = Bsdf::new(Ward::new(variant, Vec3::ZERO, Vec3::ONE, 0.1, 0.3));
        for (wi, expected) in incident_directions(false).into_iter().zip(albedos) {
            let f = furnace(&bsdf, wi, 200_000, &mut rng);
            let (a, i) = (f.albedo, f.eval_integral);
            let what = format!("{variant:?} cos {}", wi.z);
            assert!(
                (a.mean - expected).abs() <= 4.0 * a.error + 3e-3,
                "{what}: albedo {a:?}, 0.6's {expected}"
            );
            assert!(
                (a.mean - i.mean).abs() <= 4.0 * (a.error + i.error) + 3e-3,
                "{what}: albedo {a:?} but eval integrates to {i:?}"
            );
            assert!(a.mean <= 1.0 + 4.0 * a.error, "{what}: albedo {a:?} > 1");
        }
    }
}

// ---------------------------------------------------------------- all three

/// Each sampler draws what its pdf says: chi-square over 20 x 40 cells of (cos theta, phi),
/// 200,000 samples per incident direction (cos 0.95, 0.6, 0.2), z under 5 (p ~ 3e-7 per test);
/// lost samples (a Phong or Ward lobe direction below the horizon, which 0.6 returns as 0) are
/// the extra cell. Catches a pdf that is not the sampler's (a lobe probability, a Jacobian
/// 1 / (4 wo.h) off, a Phong lobe sampled about the wrong axis, Ward's azimuth quadrants),
/// which MIS would turn into bias.
#[test]
fn samplers_match_their_pdf_chi_square() {
    let models: Vec<(String, Bsdf)> = vec![
        (
            "roughdiffuse".into(),
            Bsdf::new(RoughDiffuse::new(Vec3::splat(0.7), 0.5, false)),
        ),
        (
            "phong n 30".into(),
            Bsdf::new(Phong::new(Vec3::splat(0.5), Vec3::splat(0.2), 30.0)),
        ),
        (
            "phong lobe n 1".into(),
            Bsdf::new(Phong::new(Vec3::ZERO, Vec3::ONE, 1.0)),
        ),
        (
            "phong n 300".into(),
            Bsdf::new(Phong::new(Vec3::splat(0.3), Vec3::splat(0.6), 300.0)),
        ),
        (
            "ward balanced 0.1 0.3".into(),
            Bsdf::new(Ward::new(
                Variant::Balanced,
                Vec3::splat(0.5),
                Vec3::splat(0.2),
                0.1,
                0.3,
            )),
        ),
        (
            "ward lobe 0.4 0.05".into(),
            Bsdf::new(Ward::new(Variant::Ward, Vec3::ZERO, Vec3::ONE, 0.4, 0.05)),
        ),
        (
            "ward-duer 0.2".into(),
            Bsdf::new(Ward::new(
                Variant::WardDuer,
                Vec3::splat(0.3),
                Vec3::splat(0.6),
                0.2,
                0.2,
            )),
        ),
    ];
    let mut rng = Rng(0x5eed);
    let mut report = Vec::new();
    for (name, bsdf) in &models {
        for wi in incident_directions(false) {
            let chi = chi_square(bsdf, wi, 200_000, &mut rng);
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

/// Reciprocity f(wi, wo) = f(wo, wi) on 2,000 random pairs each: Oren-Nayar, the modified
/// Phong lobe and all three Ward variants are symmetric in their two directions. Catches an
/// asymmetric term (a cos_i where 0.6 has cos_o, tan beta from the wrong direction).
#[test]
fn the_three_are_reciprocal() {
    let models = [
        Bsdf::new(RoughDiffuse::new(Vec3::new(0.9, 0.6, 0.3), 0.4, false)),
        Bsdf::new(RoughDiffuse::new(Vec3::new(0.9, 0.6, 0.3), 0.4, true)),
        Bsdf::new(Phong::new(Vec3::splat(0.4), Vec3::splat(0.5), 12.0)),
        Bsdf::new(Ward::new(
            Variant::Ward,
            Vec3::splat(0.4),
            Vec3::splat(0.5),
            0.2,
            0.3,
        )),
        Bsdf::new(Ward::new(
            Variant::WardDuer,
            Vec3::splat(0.4),
            Vec3::splat(0.5),
            0.2,
            0.3,
        )),
        Bsdf::new(Ward::new(
            Variant::Balanced,
            Vec3::splat(0.4),
            Vec3::splat(0.5),
            0.2,
            0.3,
        )),
    ];
    let mut rng = Rng(11);
    for b in &models {
        for _ in 0..2000 {
            let (mut a, mut c) = (rng.direction(), rng.direction());
            a.z = a.z.abs().max(0.05);
            c.z = c.z.abs().max(0.05);
            let (a, c) = (a.normalize(), c.normalize());
            let forward = b.eval(a, c, Mode::Radiance) / c.z;
            let backward = b.eval(c, a, Mode::Radiance) / a.z;
            assert!(
                (forward - backward).abs().max_element() <= 2e-3 * forward.max_element() + 1e-6,
                "{}: f(wi {a}, wo {c}) = {forward} but f(wo, wi) = {backward}",
                b.kind()
            );
        }
    }
}

/// The WGSL of the three (through the generated material dispatch, every kind compiled in)
/// gives the CPU models' eval, pdf and sample on 600 random direction pairs per material, in
/// radiance and importance mode: both models of roughdiffuse, its alpha 0 and a reflectance
/// scaled down by 0.6's energy check; phong at several exponents, coloured and scaled; each Ward
/// variant, anisotropic both ways. Materials are read from a 0.6.0 file. Catches a WGSL port
/// that differs from the reference: a slot of the GPU record read wrong (the exponent, the
/// scale, the variant), a sign, Mitsuba 0.6's frame about the mirror direction built
/// differently, a dispatch entry missing.
#[test]
fn gpu_matches_the_cpu_models() {
    let gpu = common::gpu();
    let bsdfs = [
        r#"<bsdf type="roughdiffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf>"#,
        r#"<bsdf type="roughdiffuse"><float name="alpha" value="0.6"/><boolean name="use_fast_approx" value="true"/></bsdf>"#,
        r#"<bsdf type="roughdiffuse"><float name="alpha" value="0"/><rgb name="reflectance" value="0.3, 0.6, 0.9"/></bsdf>"#,
        r#"<bsdf type="roughdiffuse"><float name="alpha" value="0.9"/><rgb name="reflectance" value="1.3, 0.7, 0.2"/></bsdf>"#,
        r#"<bsdf type="phong"/>"#,
        r#"<bsdf type="phong"><float name="exponent" value="5"/><rgb name="diffuse_reflectance" value="0.2, 0.5, 0.7"/><rgb name="specular_reflectance" value="0.6, 0.4, 0.2"/></bsdf>"#,
        r#"<bsdf type="phong"><float name="exponent" value="300"/><float name="diffuse_reflectance" value="0.8"/><float name="specular_reflectance" value="0.5"/></bsdf>"#,
        r#"<bsdf type="phong"><float name="exponent" value="0"/><float name="diffuse_reflectance" value="0"/><float name="specular_reflectance" value="1"/></bsdf>"#,
        r#"<bsdf type="ward"/>"#,
        r#"<bsdf type="ward"><string name="variant" value="ward"/><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/></bsdf>"#,
        r#"<bsdf type="ward"><string name="variant" value="ward-duer"/><float name="alpha_u" value="0.4"/><float name="alpha_v" value="0.1"/><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/><rgb name="specular_reflectance" value="0.5, 0.3, 0.1"/></bsdf>"#,
        r#"<bsdf type="ward"><string name="variant" value="Balanced"/><float name="alpha" value="0.25"/><float name="specular_reflectance" value="0.9"/></bsdf>"#,
    ];
    let scene = scene_with("0.6.0", &bsdfs).unwrap_or_else(|e| panic!("{e}"));
    let registry = hppm::passes::Registry::builtin();
    let report =
        gpu_against_cpu(&gpu, &registry, &scene, 600, 2e-3, &mut Rng(99)).expect("bsdf kernel");
    assert_eq!(report.evals, 600 * bsdfs.len());
    assert!(
        report.eval_failures.is_empty(),
        "{} evals differ:\n{}",
        report.eval_failures.len(),
        report.eval_failures.join("\n")
    );
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

/// How the light-transport partition sees them: roughdiffuse is continuous (path traced) with
/// no microfacet lobe; phong's lobe is glossy with the Beckmann-equivalent roughness
/// sqrt(2 / (n + 2)) (0.25 at n = 30), ward's with its larger alpha, and each packs that
/// roughness where the GPU's glossy split compares it with the threshold (alpha_u, alpha_v).
/// Catches a lobe classification that would photon-map a non-Lambertian vertex or never let
/// the hybrid's glossy threshold see phong and ward, and a roughness the CPU and the GPU
/// disagree on.
#[test]
fn the_partition_sees_glossy_phong_and_ward_and_a_continuous_roughdiffuse() {
    let b = loaded(
        "0.6.0",
        &[
            r#"<bsdf type="roughdiffuse"/>"#,
            r#"<bsdf type="phong"/>"#,
            r#"<bsdf type="ward"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.2"/></bsdf>"#,
        ],
    );
    let lobes = b[0].lobes();
    assert!(lobes.continuous && !lobes.microfacet && !lobes.delta && !lobes.transmits);
    assert_eq!(b[0].microfacet_roughness(), None);
    for (bsdf, roughness) in [(&b[1], (2.0f32 / 32.0).sqrt()), (&b[2], 0.2)] {
        let lobes = bsdf.lobes();
        assert!(lobes.continuous && lobes.microfacet && !lobes.delta && !lobes.transmits);
        assert_close(
            bsdf.kind(),
            bsdf.microfacet_roughness().expect("roughness"),
            roughness,
            1e-6,
        );
        let mut record = GpuMaterial::zeroed();
        bsdf.pack(&mut record, &Default::default(), &mut Vec::new());
        assert_close(
            "packed",
            record.alpha_u.max(record.alpha_v),
            roughness,
            1e-6,
        );
    }
    assert_close(
        "phong alpha 0.25",
        b[1].microfacet_roughness().unwrap(),
        0.25,
        1e-6,
    );
    let registry = hppm::bsdfs::BsdfRegistry::builtin();
    for (kind, glossy) in [("roughdiffuse", false), ("phong", true), ("ward", true)] {
        let (_, k) = registry.kind(kind).expect(kind);
        assert_eq!(
            matches!(k.glossy, hppm::bsdfs::Glossy::Split { .. }),
            glossy,
            "{kind}"
        );
    }
}

// ---------------------------------------------------------------- reading

/// A Mitsuba 0.5.0 file with 0.5's camelCase names (upgraded to snake_case as hppm upgrades
/// every pre-2.0 file) loads, each value where it belongs: phong's exponent 50 and
/// diffuseReflectance/specularReflectance, ward's variant and alphaU/alphaV (and `alpha` as
/// their default), roughdiffuse's useFastApprox, alpha and diffuseReflectance (0.6's other name
/// for its reflectance), ensureEnergyConservation; defaults where nothing is given; a textured
/// diffuse reflectance (checkerboard 0.9/0.1, mean 0.5, maximum 0.9) weighs and scales the lobes
/// by its mean and maximum as 0.6's getAverage and getMaximum do (0.9 + 0.2 > 1: scale 0.99 /
/// 1.1; weight 0.2 / 0.7). Catches a property read under the wrong name, a default that is not
/// 0.6's, the energy check or the lobe weight taken from the wrong statistics of a texture.
#[test]
fn a_mitsuba_05_file_with_camel_case_names_loads() {
    let b = loaded(
        "0.5.0",
        &[
            r#"<bsdf type="phong"><float name="exponent" value="50"/></bsdf>"#,
            r#"<bsdf type="phong"><rgb name="diffuseReflectance" value="0.1, 0.2, 0.3"/><rgb name="specularReflectance" value="0.4, 0.4, 0.4"/></bsdf>"#,
            r#"<bsdf type="ward"><string name="variant" value="ward-duer"/><float name="alphaU" value="0.05"/><float name="alphaV" value="0.2"/><float name="diffuseReflectance" value="0.3"/></bsdf>"#,
            r#"<bsdf type="ward"><float name="alpha" value="0.25"/><float name="alphaV" value="0.4"/><float name="diffuseReflectance" value="0.9"/><float name="specularReflectance" value="0.9"/><boolean name="ensureEnergyConservation" value="false"/></bsdf>"#,
            r#"<bsdf type="roughdiffuse"><boolean name="useFastApprox" value="true"/><float name="alpha" value="0.4"/><rgb name="diffuseReflectance" value="0.7, 0.6, 0.5"/></bsdf>"#,
            r#"<bsdf type="roughdiffuse"/>"#,
            r#"<bsdf type="phong"><texture name="diffuseReflectance" type="checkerboard"><rgb name="color0" value="0.9, 0.9, 0.9"/><rgb name="color1" value="0.1, 0.1, 0.1"/></texture></bsdf>"#,
        ],
    );
    let phong = |i: usize| *b[i].get::<Phong>().expect("phong");
    let ward = |i: usize| *b[i].get::<Ward>().expect("ward");
    let rough = |i: usize| *b[i].get::<RoughDiffuse>().expect("roughdiffuse");

    let p = phong(0);
    assert_eq!(p.exponent, 50.0);
    assert_eq!(
        (p.lobes.diffuse, p.lobes.specular),
        (Vec3::splat(0.5), Vec3::splat(0.2))
    );
    assert_eq!(p.lobes.scale, 1.0);
    let p = phong(1);
    assert_eq!(p.exponent, 30.0);
    assert_eq!(p.lobes.diffuse, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(p.lobes.specular, Vec3::splat(0.4));

    let w = ward(2);
    assert_eq!(w.variant, Variant::WardDuer);
    assert_eq!((w.alpha_u, w.alpha_v), (0.05, 0.2));
    assert_eq!(
        (w.lobes.diffuse, w.lobes.specular),
        (Vec3::splat(0.3), Vec3::splat(0.2))
    );
    let w = ward(3);
    assert_eq!(w.variant, Variant::Balanced);
    assert_eq!((w.alpha_u, w.alpha_v), (0.25, 0.4));
    assert_eq!(
        w.lobes.scale, 1.0,
        "ensureEnergyConservation false keeps 0.9 + 0.9"
    );

    let r = rough(4);
    assert!(r.fast_approx);
    assert_eq!((r.alpha, r.reflectance), (0.4, Vec3::new(0.7, 0.6, 0.5)));
    let r = rough(5);
    assert!(!r.fast_approx);
    assert_eq!(
        (r.alpha, r.reflectance, r.scale),
        (0.2, Vec3::splat(0.5), 1.0)
    );

    let t = phong(6);
    assert_close("textured scale", t.lobes.scale, 0.99 / 1.1, 1e-6);
    assert_close("textured weight", t.lobes.specular_weight, 0.2 / 0.7, 1e-6);

    // Textures where 0.6 takes them: phong's exponent (into the record's field 3, eta.x, with
    // the texture's mean as the model's value), ward's alphaU and alphaV, roughdiffuse's alpha
    // (the roughness slots) and reflectance.
    let checker = |name: &str, a: f32, b: f32| {
        format!(
            r#"<texture name="{name}" type="checkerboard"><float name="color0" value="{a}"/><float name="color1" value="{b}"/></texture>"#
        )
    };
    let scene = scene_with(
        "0.5.0",
        &[
            &format!(
                r#"<bsdf type="phong">{}</bsdf>"#,
                checker("exponent", 10.0, 50.0)
            ),
            &format!(
                r#"<bsdf type="ward">{}{}</bsdf>"#,
                checker("alphaU", 0.1, 0.3),
                checker("alphaV", 0.2, 0.4)
            ),
            &format!(
                r#"<bsdf type="roughdiffuse">{}{}</bsdf>"#,
                checker("alpha", 0.0, 0.6),
                checker("reflectance", 0.2, 0.8)
            ),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let m = &scene.materials;
    assert!(m[0].textures.front.fields[3].is_some());
    assert_eq!(m[0].bsdf.get::<Phong>().unwrap().exponent, 30.0);
    let mut record = GpuMaterial::zeroed();
    let mut tables = Vec::new();
    m[0].bsdf
        .pack(&mut record, &m[0].textures.front, &mut tables);
    assert_eq!(record.field_texture_count, 1);
    assert_eq!(tables[record.field_textures as usize], 3.0, "eta.x");
    let t = &m[1].textures.front;
    assert!(t.alpha_u.is_some() && t.alpha_v.is_some() && t.alpha_u != t.alpha_v);
    let t = &m[2].textures.front;
    assert!(t.alpha_u.is_some() && t.diffuse.is_some());
}

/// The three are Mitsuba 0.6 plugins: a version 3 file (Mitsuba 3 has none of them) is refused
/// at the element's line with the version named, as is a file without a version (read with
/// Mitsuba 3's rules); 0.6.0 loads.
/// Catches a file Mitsuba 3 would refuse loading silently as if it were a 0.6 one.
#[test]
fn version_3_files_refuse_them() {
    for kind in ["roughdiffuse", "phong", "ward"] {
        let bsdf = format!(r#"<bsdf type="{kind}"/>"#);
        let err = scene_with("3.0.0", &[&bsdf]).expect_err(kind).to_string();
        assert!(err.starts_with("m06.xml:2:"), "{err}");
        assert!(
            err.contains(&format!(
                "{kind} is a Mitsuba 0.6 plugin; this file is version 3.0.0"
            )),
            "{err}"
        );
        assert!(scene_with("2.1.0", &[&bsdf]).is_err(), "{kind} in 2.1.0");
        scene_with("0.6.0", &[&bsdf]).unwrap_or_else(|e| panic!("{e}"));
        // A file without a version is read with Mitsuba 3's rules.
        let xml = format!(
            "<scene><sensor type=\"perspective\"/>\n<shape type=\"sphere\">{bsdf}</shape></scene>"
        );
        let err = hppm::loaders::mitsuba::parse(Path::new("m06.xml"), &xml)
            .expect_err("no version")
            .to_string();
        assert!(err.contains("this file is version not given"), "{err}");
    }
}

/// Malformed parameters are errors at their line (line 2 of the file) saying what is wrong: a
/// negative exponent, alpha, alphaU or reflectance; a value of the wrong type (a string
/// exponent, a float useFastApprox); a variant 0.6 does not know; both of roughdiffuse's names
/// for its reflectance. A misspelt name is a warning with a did-you-mean, as 0.6 warned.
/// Catches a value accepted that 0.6 would misrender (a negative alpha divides by a negative
/// roughness) or an error without its place.
#[test]
fn bad_parameters_are_errors_at_their_line() {
    let cases = [
        (
            r#"<bsdf type="phong"><float name="exponent" value="-1"/></bsdf>"#,
            "must not be negative",
        ),
        (
            r#"<bsdf type="phong"><string name="exponent" value="high"/></bsdf>"#,
            "exponent",
        ),
        (
            r#"<bsdf type="phong"><rgb name="diffuseReflectance" value="-0.1, 0.5, 0.5"/></bsdf>"#,
            "must not be negative",
        ),
        (
            r#"<bsdf type="ward"><float name="alphaU" value="-0.1"/></bsdf>"#,
            "must not be negative",
        ),
        (
            r#"<bsdf type="ward"><float name="alpha" value="-0.1"/></bsdf>"#,
            "must not be negative",
        ),
        (
            r#"<bsdf type="ward"><string name="variant" value="duer"/></bsdf>"#,
            "variant \"duer\": expected \"ward\", \"ward-duer\" or \"balanced\"",
        ),
        (
            r#"<bsdf type="roughdiffuse"><float name="alpha" value="-0.2"/></bsdf>"#,
            "must not be negative",
        ),
        (
            r#"<bsdf type="roughdiffuse"><float name="useFastApprox" value="1"/></bsdf>"#,
            "<float name=\"useFastApprox\">: expected <boolean>",
        ),
        (
            r#"<bsdf type="roughdiffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/><rgb name="diffuseReflectance" value="0.5, 0.5, 0.5"/></bsdf>"#,
            "not both",
        ),
    ];
    for (bsdf, expected) in cases {
        let err = scene_with("0.5.0", &[bsdf]).expect_err(bsdf).to_string();
        assert!(err.starts_with("m06.xml:2:"), "{bsdf}: {err}");
        assert!(err.contains(expected), "{bsdf}: {err}");
    }
    // A misspelt name: 0.6 warned of an unqueried property and rendered; so does hppm, with a
    // did-you-mean at its line.
    let xml = "<scene version=\"0.5.0\"><sensor type=\"perspective\"/>\n<shape type=\"sphere\"><bsdf type=\"phong\"><float name=\"exponet\" value=\"20\"/></bsdf></shape></scene>";
    let report = hppm::loaders::mitsuba::check_text(Path::new("m06.xml"), xml, &[]);
    let said: Vec<String> = report.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        said.iter()
            .any(|w| w.starts_with("m06.xml:2:") && w.contains("did you mean \"exponent\"")),
        "{said:#?}"
    );
    assert!(report.errors.is_empty());
}

/// Sampling through the unit models is what `sample_from_eval` makes of the direction: a
/// sample's weight is eval / pdf at its direction, for the three, at fixed random numbers,
/// with the lobe picked by u1 against the specular weight. Catches a sampler whose weight is
/// not its own eval over its own pdf (what the GPU's sample weight is compared with).
#[test]
fn sample_weights_are_eval_over_pdf() {
    let models = [
        Bsdf::new(RoughDiffuse::new(Vec3::splat(0.6), 0.3, false)),
        Bsdf::new(Phong::new(Vec3::splat(0.4), Vec3::splat(0.5), 20.0)),
        Bsdf::new(Ward::new(
            Variant::Balanced,
            Vec3::splat(0.4),
            Vec3::splat(0.5),
            0.2,
            0.3,
        )),
    ];
    let mut rng = Rng(5);
    for b in &models {
        let mut drawn = 0;
        for _ in 0..500 {
            let u = Vec2::new(rng.unit(), rng.unit());
            let Some(s) = b.sample(wi(), rng.unit(), u, Mode::Radiance) else {
                continue;
            };
            drawn += 1;
            let expected = b.eval(wi(), s.wo, Mode::Radiance) / b.pdf(wi(), s.wo);
            assert!(!s.delta);
            assert!((s.weight - expected).abs().max_element() <= 1e-5 * expected.max_element());
            assert!(s.wo.z > 0.0);
        }
        assert!(drawn > 400, "{}: only {drawn} samples", b.kind());
    }
}

/// The glossy split of phong and ward (their lobe's f |cos wo| and its share, which a graph's
/// `glossy_threshold` uses through `GLOSSY`) composes and validates in every pass shader with
/// every scene and BSDF def on, and its functions are in the composed kernels. Catches a split
/// function that does not compile or is not imported (the GPU check above composes without
/// `GLOSSY`, so it never compiles them).
#[test]
fn the_glossy_split_composes_into_the_tracing_kernels() {
    let registry = hppm::bsdfs::BsdfRegistry::builtin();
    let lib = hppm::gpu::shaders::ShaderLibrary::new(
        false,
        hppm::passes::all_scene_defs(&registry),
        &hppm::passes::common_modules(&registry),
    )
    .expect("modules compose");
    let mut seen = Vec::new();
    for kind in hppm::passes::builtin_kinds() {
        for file in kind.shaders {
            let module = lib
                .compose_with(file, hppm::passes::PASS_DEFS)
                .unwrap_or_else(|e| panic!("{} + GLOSSY: {e}", file.path));
            wgpu::naga::valid::Validator::new(
                wgpu::naga::valid::ValidationFlags::all(),
                wgpu::naga::valid::Capabilities::all(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}: {e:?}", file.path));
            for (_, f) in module.functions.iter() {
                if let Some(name) = &f.name {
                    seen.push(name.clone());
                }
            }
        }
    }
    for function in [
        "phong_specular_share",
        "ward_specular_share",
        "phong_specular",
        "ward_specular",
    ] {
        assert!(
            // naga_oil names an imported function `<name>X_naga_oil_mod_...`.
            seen.iter()
                .any(|n| n == function || n.starts_with(&format!("{function}X"))),
            "no kernel calls {function}"
        );
    }
}

/// What `GLOSSY` kernels ask of a material: its glossy lobe's f |cos wo| and that lobe's share
/// of a sample's weight, per channel, when the lobe counts as specular.
const GLOSSY_KERNEL: &str = r#"
#import common::scene::materials
#import common::bsdf::BsdfSample
#import common::material::{material_eval, material_specular_eval, material_specular_share}

@group(1) @binding(0) var<storage, read> queries: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> answers: array<vec4<f32>>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if 2u * id.x >= arrayLength(&queries) {
        return;
    }
    let a = queries[2u * id.x];
    let b = queries[2u * id.x + 1u];
    let m = materials[u32(a.w)];
    let full = material_eval(m, a.xyz, b.xyz, true);
    let spec = material_specular_eval(m, a.xyz, b.xyz, full, b.w);
    let s = BsdfSample(b.xyz, full.value / max(full.pdf, 1e-20), full.pdf, false, true);
    let share = material_specular_share(m, a.xyz, s, b.w);
    answers[2u * id.x] = vec4<f32>(spec, 0.0);
    answers[2u * id.x + 1u] = vec4<f32>(share, 0.0);
}
"#;

/// A glossy-split query: the material's index, wi and wo.
type SplitQuery = (usize, Vec3, Vec3);

/// Runs GLOSSY_KERNEL (the dispatch's glossy split under `GLOSSY`) on `per_material` random
/// (wi, wo) pairs for each of `materials` of `scene`, half of them near the mirror direction
/// where a lobe has most of f; returns the pairs and the kernel's answers (two per pair).
fn glossy_split_on_gpu(
    gpu: &hppm::gpu::GpuContext,
    scene: &Scene,
    materials: &[usize],
    per_material: usize,
    seed: u64,
    threshold: f32,
) -> (Vec<SplitQuery>, Vec<[f32; 4]>) {
    use hppm::gpu::binding::{Access, bind_buffers};
    use hppm::gpu::shaders::ShaderFile;
    use hppm::gpu_scene::{GpuScene, SceneResources};

    let registry = hppm::passes::Registry::builtin();
    let gpu_scene = GpuScene::with_bsdfs(scene, 4, 4, registry.bsdfs()).expect("layout");
    let resources = SceneResources::for_adapter(gpu, &gpu_scene).expect("resources");
    let shaders = registry
        .shader_library(gpu.has_float_atomics(), scene, &resources.placement)
        .expect("library");

    let mut rng = Rng(seed);
    let mut queries: Vec<[f32; 4]> = Vec::new();
    let mut pairs = Vec::new();
    for &material in materials {
        for _ in 0..per_material {
            // Near the mirror direction half the time, where the lobe has most of f.
            let mut wi = rng.direction();
            wi.z = wi.z.abs().max(0.05);
            let wi = wi.normalize();
            let mut wo = if rng.unit() < 0.5 {
                (Vec3::new(-wi.x, -wi.y, wi.z) + 0.1 * rng.direction()).normalize()
            } else {
                rng.direction()
            };
            wo.z = wo.z.abs().max(0.01);
            let wo = wo.normalize();
            queries.push([wi.x, wi.y, wi.z, material as f32]);
            queries.push([wo.x, wo.y, wo.z, threshold]);
            pairs.push((material, wi, wo));
        }
    }
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let query_buffer = gpu
        .create_buffer_init("queries", bytemuck::cast_slice(&queries), storage)
        .expect("queries");
    let answer_buffer = gpu
        .create_buffer("answers", (queries.len() * 16) as u64, storage)
        .expect("answers");
    let (layout, group) = bind_buffers(
        gpu,
        "glossy split check",
        &[
            (Access::Read, &query_buffer),
            (Access::ReadWrite, &answer_buffer),
        ],
    );
    let file = ShaderFile {
        path: "tests/mitsuba06_bsdfs_glossy_kernel.wgsl",
        source: GLOSSY_KERNEL,
    };
    // With HPPM_SHADER_DIR set (tests/mutation/run, tests/differential_faults.rs), every module
    // is read from there, this kernel too: it is written there so that the modules it imports
    // are the ones under test.
    if let Some(dir) = std::env::var_os("HPPM_SHADER_DIR") {
        let path = std::path::Path::new(&dir).join(file.path);
        std::fs::create_dir_all(path.parent().expect("a folder")).expect("the shader folder");
        std::fs::write(&path, GLOSSY_KERNEL).expect("the glossy kernel");
    }
    let pipeline = shaders
        .compute_pipeline_with(
            gpu,
            &file,
            "main",
            &[&resources.layout, &layout],
            &["GLOSSY"],
        )
        .expect("glossy kernel");
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &resources.bind_group, &[]);
        pass.set_bind_group(1, &group, &[]);
        pass.dispatch_workgroups((pairs.len() as u32).div_ceil(64), 1, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.check_errors().expect("kernel");
    let answers: Vec<[f32; 4]> = gpu
        .read_pod(&answer_buffer, queries.len())
        .expect("readback");

    (pairs, answers)
}

/// The glossy split on the GPU (`GLOSSY`, a `glossy_threshold` of 0.2, hybrid.ron's): a Phong
/// lobe of exponent 200 (Beckmann-equivalent alpha 0.0995) and a Ward lobe of alphas 0.05 and
/// 0.08 are specular there, so the split gives their lobe's f |cos wo| (the CPU model's lobe
/// alone) and its share of f, per channel; exponent 30 (alpha 0.25) and a Ward lobe of alphas
/// 0.1 and 0.3 (the larger counts) are not, and give nothing. 500 random pairs each. Catches a
/// split that returns the whole BSDF or the wrong lobe, a roughness packed where the threshold
/// test does not read it (the exponent itself in alpha_u), or a Ward lobe judged by its smaller
/// alpha.
#[test]
fn the_gpu_glossy_split_takes_the_lobe_below_the_threshold() {
    let gpu = common::gpu();
    let threshold = 0.2f32;
    let bsdfs = [
        (
            r#"<bsdf type="phong"><float name="exponent" value="200"/><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/><rgb name="specular_reflectance" value="0.3, 0.2, 0.1"/></bsdf>"#,
            true,
        ),
        (r#"<bsdf type="phong"/>"#, false),
        (
            r#"<bsdf type="ward"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.08"/><rgb name="diffuse_reflectance" value="0.6, 0.3, 0.1"/></bsdf>"#,
            true,
        ),
        (
            r#"<bsdf type="ward"><string name="variant" value="ward"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#,
            false,
        ),
    ];
    let xmls: Vec<&str> = bsdfs.iter().map(|(x, _)| *x).collect();
    let scene = scene_with("0.6.0", &xmls).unwrap_or_else(|e| panic!("{e}"));
    let materials: Vec<usize> = (0..bsdfs.len()).collect();
    let (pairs, answers) = glossy_split_on_gpu(&gpu, &scene, &materials, 500, 77, threshold);

    let mut failures = Vec::new();
    let mut lobe_seen = [0usize; 4];
    for (i, (material, wi, wo)) in pairs.iter().enumerate() {
        let bsdf = &scene.materials[*material].bsdf;
        let specular = bsdfs[*material].1;
        let lobe = if let Some(p) = bsdf.get::<Phong>() {
            p.specular_eval(*wi, *wo)
        } else {
            bsdf.get::<Ward>().expect("ward").specular_eval(*wi, *wo)
        };
        let full = bsdf.eval(*wi, *wo, Mode::Radiance);
        let (want_spec, want_share) = if specular {
            let share = Vec3::select(full.cmpgt(Vec3::ZERO), lobe / full, Vec3::ZERO);
            (lobe, share)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        let got_spec = Vec3::from_slice(&answers[2 * i][..3]);
        let got_share = Vec3::from_slice(&answers[2 * i + 1][..3]);
        lobe_seen[*material] += (lobe.max_element() > 1e-3 * full.max_element()) as usize;
        let near = |a: Vec3, b: Vec3| {
            (a - b).abs().max_element() <= 2e-3 * a.abs().max(b.abs()).max_element() + 1e-5
        };
        if !near(got_spec, want_spec) || !near(got_share, want_share) {
            failures.push(format!(
                "material {material} wi {wi} wo {wo}: GPU lobe {got_spec} share {got_share}, \
                 expected {want_spec} {want_share}"
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} differ:\n{}",
        failures.len(),
        pairs.len(),
        failures[..failures.len().min(20)].join("\n")
    );
    // The pairs reach each lobe, so the split is tested where it is not zero.
    assert!(lobe_seen.iter().all(|&n| n > 100), "{lobe_seen:?}");
}

// ================================================================ difftrans, mixturebsdf, hk
//
// Mitsuba 0.6's `difftrans`, `mixturebsdf` and `hk` (src/bsdfs/difftrans/, mixturebsdf/, hk/),
// against a double-precision transcription of 0.6's difftrans.cpp, mixturebsdf.cpp and hk.cpp
// (and src/phase/hg.cpp, isotropic.cpp) written below, independently of the units' code: 0.6's
// Henyey-Greenstein is taken in its own convention (1 + g^2 + 2 g wi.wo, wi pointing back),
// where the unit uses hppm's Phase with the travel direction.

use hppm::bsdfs::blendbsdf::Blend;
use hppm::bsdfs::difftrans::DiffTrans;
use hppm::bsdfs::diffuse::Diffuse;
use hppm::bsdfs::hk::Hk;
use hppm::scene::bsdf::{Lobes, Sample};
use hppm::scene::medium::Phase;

type D3 = [f64; 3];

fn d3(v: Vec3) -> D3 {
    [v.x as f64, v.y as f64, v.z as f64]
}

fn dot3(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// 0.6's DiffuseTransmitter::eval: T / pi |cos wo| where cos wi cos wo < 0.
fn difftrans06(t: f64, wi: D3, wo: D3) -> f64 {
    if wi[2] * wo[2] >= 0.0 {
        0.0
    } else {
        t * wo[2].abs() / std::f64::consts::PI
    }
}

/// 0.6's SmoothDiffuse::eval: rho / pi cos wo where both are above the surface.
fn diffuse06(rho: f64, wi: D3, wo: D3) -> f64 {
    if wi[2] <= 0.0 || wo[2] <= 0.0 {
        0.0
    } else {
        rho * wo[2] / std::f64::consts::PI
    }
}

/// 0.6's phase functions as its hg.cpp and isotropic.cpp evaluate them (wi pointing back).
fn phase06(g: Option<f64>, wi: D3, wo: D3) -> f64 {
    let inv_four_pi = 0.25 / std::f64::consts::PI;
    match g {
        None => inv_four_pi,
        Some(g) => {
            let temp = 1.0 + g * g + 2.0 * g * dot3(wi, wo);
            inv_four_pi * (1.0 - g * g) / (temp * temp.sqrt())
        }
    }
}

/// One channel of 0.6's HanrahanKrueger::eval(ESolidAngle) (f |cos wo|, wi the viewer's).
fn hk06(sigma_s: f64, sigma_a: f64, d: f64, g: Option<f64>, wi: D3, wo: D3) -> f64 {
    let sigma_t = sigma_s + sigma_a;
    let tau = sigma_t * d;
    let albedo = if sigma_t > 0.0 {
        sigma_s / sigma_t
    } else {
        0.0
    };
    let (ci, co) = (wi[2], wo[2]);
    let p = phase06(g, wi, wo);
    let dp = ci * co;
    let mut result = 0.0;
    if dp > 0.0 {
        result = albedo
            * (p * ci / (ci + co))
            * (1.0 - ((-1.0 / ci.abs() - 1.0 / co.abs()) * tau).exp());
    }
    if dp < 0.0 {
        if (ci + co).abs() < 1e-4 {
            result += albedo * p * tau / co.abs() * (-tau / co.abs()).exp();
        } else {
            result += albedo * p * ci.abs() / (ci.abs() - co.abs())
                * ((-tau / ci.abs()).exp() - (-tau / co.abs()).exp());
        }
    }
    result * co.abs()
}

/// 0.6's probability of hk's straight-through lobe from `wi`: exp(-tau / |cos wi|) averaged
/// over the channels.
fn hk06_straight(sigma_t: D3, d: f64, wi: D3) -> f64 {
    sigma_t
        .iter()
        .map(|s| (-s * d / wi[2].abs()).exp())
        .sum::<f64>()
        / 3.0
}

/// Directions on a midpoint grid of n x 2n cells over (cos theta, phi), with each cell's solid
/// angle: what the numerical albedos below integrate on.
fn sphere_grid(n: usize) -> impl Iterator<Item = (D3, f64)> {
    let cell = (2.0 / n as f64) * (std::f64::consts::PI / n as f64);
    (0..n).flat_map(move |i| {
        let z = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
        let r = (1.0 - z * z).sqrt();
        (0..2 * n).map(move |j| {
            let phi = (j as f64 + 0.5) * std::f64::consts::PI / n as f64;
            ([r * phi.cos(), r * phi.sin(), z], cell)
        })
    })
}

/// A sample's mean weight (red channel) over `samples` draws in `mode`, with its standard error.
fn mean_weight(b: &Bsdf, wi: Vec3, mode: Mode, samples: usize, rng: &mut Rng) -> (f64, f64) {
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..samples {
        let u = Vec2::new(rng.unit(), rng.unit());
        if let Some(x) = b.sample(wi, rng.unit(), u, mode) {
            let w = x.weight.x as f64;
            s += w;
            s2 += w * w;
        }
    }
    let n = samples as f64;
    (s / n, ((s2 / n - (s / n).powi(2)).max(0.0) / n).sqrt())
}

// ---------------------------------------------------------------- difftrans

/// 0.6's diffuse transmitter: T / pi |cos wo| towards the other side only, from above and from
/// below, nothing on the same side; pdf |cos wo| / pi there; a transmittance above 1 scaled by
/// 0.99 / its largest channel (0.6's ensureEnergyConservation with maximum 1); a sample lands
/// on the other side with weight T (scaled) and pdf |cos wo| / pi, in both transport modes.
/// Catches transmission towards the wrong side, a lost 1/pi or cosine, a pdf that is not the
/// sampler's, the scale missing.
#[test]
fn difftrans_eval_pdf_and_sample_are_mitsuba06s() {
    let b = loaded(
        "0.6.0",
        &[
            r#"<bsdf type="difftrans"><rgb name="transmittance" value="0.2, 0.5, 0.8"/></bsdf>"#,
            r#"<bsdf type="difftrans"><rgb name="transmittance" value="1.5, 0.5, 0.3"/></bsdf>"#,
            r#"<bsdf type="difftrans"/>"#,
        ],
    );
    let t = [
        Vec3::new(0.2, 0.5, 0.8),
        Vec3::new(1.5, 0.5, 0.3) * (0.99 / 1.5),
        Vec3::splat(0.5),
    ];
    let mut rng = Rng(41);
    for (bsdf, t) in b.iter().zip(t) {
        assert!(bsdf.get::<DiffTrans>().is_some());
        for _ in 0..300 {
            let (wi, wo) = (rng.direction(), rng.direction());
            let f = bsdf.eval(wi, wo, Mode::Radiance);
            for c in 0..3 {
                let expected = difftrans06(t[c] as f64, d3(wi), d3(wo));
                assert_close("difftrans eval", f[c], expected as f32, 1e-5);
            }
            assert_eq!(f, bsdf.eval(wi, wo, Mode::Importance));
            let pdf = if wi.z * wo.z < 0.0 {
                wo.z.abs() / PI
            } else {
                0.0
            };
            assert_close("difftrans pdf", bsdf.pdf(wi, wo), pdf, 1e-5);
            let u = Vec2::new(rng.unit(), rng.unit());
            for mode in [Mode::Radiance, Mode::Importance] {
                let s = bsdf.sample(wi, rng.unit(), u, mode).expect("a sample");
                assert!(s.wo.z * wi.z < 0.0 && !s.delta, "{s:?} from {wi}");
                assert!((s.weight - t).abs().max_element() < 1e-5, "{s:?}");
                assert_close("sample pdf", s.pdf, s.wo.z.abs() / PI, 1e-5);
            }
        }
    }
}

/// White furnace of a transmittance-1 difftrans (200,000 samples from each incident direction,
/// above and below): every sample weighs exactly 1 (0.6's sample returns T), and the integral of
/// eval over the sphere is 1 (0.6's albedo, within 4 standard errors). Catches weights that are
/// not eval / pdf and a lobe that loses or gains energy.
#[test]
fn difftrans_white_furnace_is_one() {
    let b = Bsdf::new(DiffTrans::new(Vec3::ONE));
    let mut rng = Rng(3);
    for wi in incident_directions(true) {
        let f = furnace(&b, wi, 200_000, &mut rng);
        assert!(
            (f.albedo.mean - 1.0).abs() < 1e-6 && f.albedo.error < 1e-6,
            "{f:?}"
        );
        assert!(
            (f.eval_integral.mean - 1.0).abs() <= 4.0 * f.eval_integral.error,
            "{f:?}"
        );
    }
}

// ---------------------------------------------------------------- mixturebsdf

/// The leaves a shape's material chooses among through its blend tree: (probability, material).
fn leaves_of(scene: &Scene, material: u32) -> Vec<(f64, u32)> {
    let m = &scene.materials[material as usize];
    match m.bsdf.get::<Blend>() {
        Some(blend) => {
            let w = blend.weight as f64;
            let mut out: Vec<(f64, u32)> = leaves_of(scene, blend.children[0])
                .into_iter()
                .map(|(p, i)| (p * (1.0 - w), i))
                .collect();
            out.extend(
                leaves_of(scene, blend.children[1])
                    .into_iter()
                    .map(|(p, i)| (p * w, i)),
            );
            out
        }
        None => vec![(1.0, material)],
    }
}

/// The blend tree as one BSDF, sampled as the GPU's choice does (a leaf by its probability,
/// then the leaf's own sample, a black leaf's draw lost): what the chi-square and the furnace
/// below hold to 0.6's mixture.
#[derive(Debug, PartialEq)]
struct Tree(Vec<(f32, Bsdf)>);

fn is_black(b: &Bsdf) -> bool {
    b.get::<Diffuse>()
        .is_some_and(|d| d.reflectance == Vec3::ZERO)
}

impl BsdfModel for Tree {
    fn kind(&self) -> &'static str {
        "tree"
    }
    fn lobes(&self) -> Lobes {
        Lobes::default()
    }
    fn is_valid(&self) -> bool {
        true
    }
    fn eval(&self, wi: Vec3, wo: Vec3, mode: Mode) -> Vec3 {
        self.0.iter().map(|(p, b)| *p * b.eval(wi, wo, mode)).sum()
    }
    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        self.0
            .iter()
            .filter(|(_, b)| !is_black(b))
            .map(|(p, b)| *p * b.pdf(wi, wo))
            .sum()
    }
    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2, mode: Mode) -> Option<Sample> {
        let mut start = 0.0;
        for (p, b) in &self.0 {
            if u1 < start + p || std::ptr::eq(b, &self.0.last()?.1) {
                if is_black(b) {
                    return None;
                }
                let u = ((u1 - start) / p).clamp(0.0, 0.999_999);
                return b.sample(wi, u, u2, mode);
            }
            start += p;
        }
        None
    }
    fn pack(&self, _: &mut GpuMaterial, _: &hppm::scene::SideTextures, _: &mut Vec<f32>) {}
}

fn tree_of(scene: &Scene, material: u32) -> Tree {
    Tree(
        leaves_of(scene, material)
            .into_iter()
            .map(|(p, i)| (p as f32, scene.materials[i as usize].bsdf.clone()))
            .collect(),
    )
}

const MIXTURES: [&str; 6] = [
    // 0.6's test_bsdf.xml: weights summing to 0.8, a black share of 0.2.
    r#"<bsdf type="mixturebsdf"><string name="weights" value=".5 .3"/><bsdf type="diffuse"><rgb name="reflectance" value=".5 0 0"/></bsdf><bsdf type="difftrans"><rgb name="transmittance" value="0 .5 0"/></bsdf></bsdf>"#,
    // Summing to 4: each divided by 4.
    r#"<bsdf type="mixturebsdf"><string name="weights" value="2, 2"/><bsdf type="diffuse"><float name="reflectance" value="0.8"/></bsdf><bsdf type="difftrans"><float name="transmittance" value="0.4"/></bsdf></bsdf>"#,
    r#"<bsdf type="mixturebsdf"><string name="weights" value="0.2; 0.8"/><bsdf type="conductor"/><bsdf type="dielectric"/></bsdf>"#,
    // All the weight on one child: that child.
    r#"<bsdf type="mixturebsdf"><string name="weights" value="0, 1"/><bsdf type="diffuse"/><bsdf type="difftrans"/></bsdf>"#,
    r#"<bsdf type="mixturebsdf"><string name="weights" value="0.1 0.2 0.3 0.4"/><bsdf type="diffuse"><float name="reflectance" value="0.9"/></bsdf><bsdf type="difftrans"><float name="transmittance" value="0.7"/></bsdf><bsdf type="diffuse"><float name="reflectance" value="0.3"/></bsdf><bsdf type="difftrans"><float name="transmittance" value="1"/></bsdf></bsdf>"#,
    // A mixture in a mixture.
    r#"<bsdf type="mixturebsdf"><string name="weights" value="0.5 0.5"/><bsdf type="mixturebsdf"><string name="weights" value="0.6 0.4"/><bsdf type="diffuse"><float name="reflectance" value="1"/></bsdf><bsdf type="difftrans"><float name="transmittance" value="1"/></bsdf></bsdf><bsdf type="hk"/></bsdf>"#,
];

/// Each mixture's blend tree chooses its children with 0.6's shares of the weight (weights
/// summing above 1 divided by the sum; below 1, the rest to a black child; weight 0 never
/// chosen, one child with all of it is that child; a nested mixture's shares multiplied), and
/// the tree's value in expectation, sum p_leaf f_leaf, is 0.6's mixture sum w_i f_i (its
/// transcription, 400 random pairs each from both sides). Catches weights not renormalised as
/// 0.6 does, a mixture brighter than 0.6's where they sum below 1, children swapped against
/// their weights, a blend tree whose probabilities do not multiply out to the weights.
#[test]
fn mixturebsdf_is_mitsuba06s_weighted_sum() {
    let scene = scene_with("0.6.0", &MIXTURES).unwrap_or_else(|e| panic!("{e}"));
    let shape = |i: usize| scene.spheres[i].material;
    let kinds = |i: usize| -> Vec<(f64, String)> {
        leaves_of(&scene, shape(i))
            .into_iter()
            .map(|(p, m)| {
                let b = &scene.materials[m as usize].bsdf;
                let name = if is_black(b) { "black" } else { b.kind() };
                (p, name.to_string())
            })
            .collect()
    };
    let expect = |i: usize, expected: &[(f64, &str)]| {
        let mut got = kinds(i);
        got.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.total_cmp(&b.0)));
        let mut want: Vec<(f64, String)> =
            expected.iter().map(|(p, k)| (*p, k.to_string())).collect();
        want.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.total_cmp(&b.0)));
        assert_eq!(got.len(), want.len(), "mixture {i}: {got:?}");
        for (g, w) in got.iter().zip(&want) {
            assert!(
                g.1 == w.1 && (g.0 - w.0).abs() < 1e-6,
                "mixture {i}: {got:?} vs {want:?}"
            );
        }
    };
    expect(0, &[(0.5, "diffuse"), (0.3, "difftrans"), (0.2, "black")]);
    expect(1, &[(0.5, "diffuse"), (0.5, "difftrans")]);
    expect(2, &[(0.2, "conductor"), (0.8, "dielectric")]);
    expect(3, &[(1.0, "difftrans")]);
    expect(
        4,
        &[
            (0.1, "diffuse"),
            (0.2, "difftrans"),
            (0.3, "diffuse"),
            (0.4, "difftrans"),
        ],
    );
    expect(5, &[(0.3, "diffuse"), (0.2, "difftrans"), (0.5, "hk")]);
    // 0.6's weighted sums, red channel: (weight, diffuse rho, difftrans T) per child.
    type Child = (f64, f64, f64);
    let sums: [(usize, &[Child]); 3] = [
        (0, &[(0.5, 0.5, 0.0), (0.3, 0.0, 0.0)]),
        (1, &[(0.5, 0.8, 0.0), (0.5, 0.0, 0.4)]),
        (
            4,
            &[
                (0.1, 0.9, 0.0),
                (0.2, 0.0, 0.7),
                (0.3, 0.3, 0.0),
                (0.4, 0.0, 1.0),
            ],
        ),
    ];
    let mut rng = Rng(8);
    for (i, children) in sums {
        let tree = tree_of(&scene, shape(i));
        for _ in 0..400 {
            let (wi, wo) = (rng.direction(), rng.direction());
            let expected: f64 = children
                .iter()
                .map(|&(w, rho, t)| {
                    w * (diffuse06(rho, d3(wi), d3(wo)) + difftrans06(t, d3(wi), d3(wo)))
                })
                .sum();
            assert_close(
                "mixture value",
                tree.eval(wi, wo, Mode::Radiance).x,
                expected as f32,
                1e-5,
            );
        }
    }
    // The green channel of mixture 0: only the difftrans child's 0.5 at weight 0.3.
    let tree = tree_of(&scene, shape(0));
    let (wi, wo) = (wi(), -wo_across());
    assert_close(
        "green",
        tree.eval(wi, wo, Mode::Radiance).y,
        (0.3 * difftrans06(0.5, d3(wi), d3(wo))) as f32,
        1e-5,
    );
}

/// White furnace of 0.6's mixtures of white children (200,000 samples from each incident
/// direction, the choice as the GPU makes it): weights 0.5, 0.3 of diffuse 1 and difftrans 1
/// give albedo 0.8 from above (0.3 from below: the diffuse child is one-sided), weights 2, 2
/// give 1; the mean weight within 4 standard errors of it. Catches a mixture that conserves
/// energy where 0.6's loses it (the black share) or the reverse.
#[test]
fn mixturebsdf_white_furnace_is_the_weights_sum() {
    let scene = scene_with(
        "0.6.0",
        &[
            r#"<bsdf type="mixturebsdf"><string name="weights" value="0.5, 0.3"/><bsdf type="diffuse"><float name="reflectance" value="1"/></bsdf><bsdf type="difftrans"><float name="transmittance" value="1"/></bsdf></bsdf>"#,
            r#"<bsdf type="mixturebsdf"><string name="weights" value="2 2"/><bsdf type="diffuse"><float name="reflectance" value="1"/></bsdf><bsdf type="difftrans"><float name="transmittance" value="1"/></bsdf></bsdf>"#,
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut rng = Rng(12);
    for (shape, above, below) in [(0, 0.8, 0.3), (1, 1.0, 0.5)] {
        let tree = Bsdf::new(tree_of(&scene, scene.spheres[shape].material));
        for wi in incident_directions(true) {
            let expected = if wi.z > 0.0 { above } else { below };
            let (mean, se) = mean_weight(&tree, wi, Mode::Importance, 200_000, &mut rng);
            assert!(
                (mean - expected).abs() <= 4.0 * se + 1e-6,
                "{shape}: {mean} +- {se} vs {expected}"
            );
        }
    }
}

// ---------------------------------------------------------------- hk

/// 0.6's hk from its transcription above: isotropic and Henyey-Greenstein (g 0.8 and -0.3)
/// layers, thin and thick, coloured; reflection and transmission pairs at random (both sides),
/// and pairs with |cos wi| and |cos wo| within 1e-4 (0.6's limit form of the transmission
/// term); the pdf p (1 - P) with P the channel mean of exp(-tau / |cos wi|); photons' value the
/// adjoint, f(wo, wi) |cos wo|. Catches a phase function in the wrong convention (forward
/// scattering backwards), a lost cos wi or |cos wo|, the near-equal-cosine limit, a pdf that
/// leaves out the straight lobe's probability, a photon value that is not the adjoint.
#[test]
fn hk_eval_and_pdf_are_mitsuba06s() {
    let layers = [
        (
            Vec3::new(0.5, 1.0, 2.0),
            Vec3::new(0.3, 0.2, 0.1),
            1.0,
            Phase::Isotropic,
            None,
        ),
        (
            Vec3::new(2.0, 2.0, 2.0),
            Vec3::new(0.1, 0.5, 1.0),
            0.3,
            Phase::HenyeyGreenstein { g: 0.8 },
            Some(0.8),
        ),
        (
            Vec3::new(0.2, 0.4, 0.1),
            Vec3::new(0.0, 0.0, 0.0),
            4.0,
            Phase::HenyeyGreenstein { g: -0.3 },
            Some(-0.3),
        ),
    ];
    let mut rng = Rng(21);
    for (sigma_s, sigma_a, d, phase, g) in layers {
        let b = Bsdf::new(Hk {
            sigma_s,
            sigma_a,
            thickness: d,
            phase,
        });
        let mut pairs: Vec<(Vec3, Vec3)> = (0..500)
            .map(|_| (rng.direction(), rng.direction()))
            .collect();
        // |cos wo| within 1e-4 of |cos wi|, on the other side.
        for k in 0..20 {
            let wi = rng.direction();
            let z = -wi.z.signum() * (wi.z.abs() + (k as f32 - 10.0) * 4e-6).clamp(0.0, 1.0);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = rng.unit() * 2.0 * PI;
            pairs.push((wi, Vec3::new(r * phi.cos(), r * phi.sin(), z)));
        }
        for (wi, wo) in pairs {
            if wi.z.abs() < 0.02 || wo.z.abs() < 0.02 {
                continue;
            }
            let f = b.eval(wi, wo, Mode::Radiance);
            let adjoint = b.eval(wi, wo, Mode::Importance);
            let straight = hk06_straight(d3(sigma_s + sigma_a), d as f64, d3(wi));
            // f32 cancels in exp(-tau/|cos wi|) - exp(-tau/|cos wo|) where the cosines are close
            // (but apart by more than 0.6's Epsilon): a looser bound there.
            let gap = (wi.z.abs() - wo.z.abs()).abs();
            let rel = if wi.z * wo.z < 0.0 && gap < 0.01 {
                5e-3
            } else {
                2e-4
            };
            for c in 0..3 {
                let expected = hk06(
                    sigma_s[c] as f64,
                    sigma_a[c] as f64,
                    d as f64,
                    g,
                    d3(wi),
                    d3(wo),
                );
                assert!(
                    close(f[c], expected as f32, rel) || (f[c] - expected as f32).abs() < 1e-6,
                    "hk {phase:?} channel {c} at {wi} {wo}: {} vs {expected}",
                    f[c]
                );
                let reverse = hk06(
                    sigma_s[c] as f64,
                    sigma_a[c] as f64,
                    d as f64,
                    g,
                    d3(wo),
                    d3(wi),
                );
                let expected = reverse / wi.z.abs() as f64 * wo.z.abs() as f64;
                assert!(
                    close(adjoint[c], expected as f32, rel)
                        || (adjoint[c] - expected as f32).abs() < 1e-6,
                    "adjoint {phase:?} channel {c}: {} vs {expected}",
                    adjoint[c]
                );
            }
            let pdf = phase06(g, d3(wi), d3(wo)) * (1.0 - straight);
            assert_close("hk pdf", b.pdf(wi, wo), pdf as f32, 2e-4);
        }
    }
}

/// hk's samples: the straight lobe (wo = -wi, delta) with probability P and weight
/// exp(-tau / |cos wi|) / P, else a phase-function direction with weight eval / pdf, in both
/// modes; the share of straight samples is P (binomial, 4 standard errors). Catches a delta
/// lobe's weight not divided by its probability, the lobe chosen with the wrong probability,
/// a scattered sample's weight that is not eval / pdf.
#[test]
fn hk_samples_are_weighted_as_mitsuba06s() {
    let hk = Hk {
        sigma_s: Vec3::new(0.5, 1.0, 1.5),
        sigma_a: Vec3::new(0.2, 0.1, 0.0),
        thickness: 0.8,
        phase: Phase::HenyeyGreenstein { g: 0.5 },
    };
    let b = Bsdf::new(hk);
    let mut rng = Rng(77);
    for wi in incident_directions(true) {
        let p = hk06_straight(d3(hk.sigma_s + hk.sigma_a), 0.8, d3(wi));
        let n = 4000;
        let mut straight = 0;
        for i in 0..n {
            let mode = if i % 2 == 0 {
                Mode::Radiance
            } else {
                Mode::Importance
            };
            let u = Vec2::new(rng.unit(), rng.unit());
            let Some(s) = b.sample(wi, rng.unit(), u, mode) else {
                continue;
            };
            if s.delta {
                straight += 1;
                assert_eq!(s.wo, -wi);
                let t = (-(hk.sigma_s + hk.sigma_a) * 0.8 / wi.z.abs()).exp();
                assert!(
                    (s.weight - t / p as f32).abs().max_element() < 1e-5,
                    "{s:?}"
                );
                assert_close("straight pdf", s.pdf, p as f32, 1e-5);
            } else {
                let expected = b.eval(wi, s.wo, mode) / b.pdf(wi, s.wo);
                assert!(
                    (s.weight - expected).abs().max_element()
                        <= 1e-5 * expected.max_element().max(1e-3),
                    "{s:?}"
                );
            }
        }
        let se = (p * (1.0 - p) / n as f64).sqrt();
        let share = straight as f64 / n as f64;
        assert!(
            (share - p).abs() <= 4.0 * se + 1e-3,
            "straight share {share} vs {p}"
        );
    }
}

/// White furnace of hk (sigma_s 1, sigma_a 0.2 and 0, thickness 1, isotropic and g 0.8): the
/// mean sample weight (200,000 per incident direction, camera paths' mode) equals 0.6's albedo,
/// its value integrated on a 400 x 800 grid plus the straight-through exp(-tau / |cos wi|), and
/// the photons' mode the adjoint's (4 standard errors + 0.2%). Single scattering only, and
/// with 0.6's extra |cos wi|, the layer returns little at grazing view: 0.6's albedo is 0.48,
/// 0.29, 0.069 at cos theta_i 0.95, 0.6, 0.2 (isotropic, sigma_a 0.2) and 0.66, 0.36, 0.047
/// (g 0.8, sigma_a 0), never more than 1. Catches a sample weight or lobe probability that
/// gains or loses energy against 0.6's formulas.
#[test]
fn hk_white_furnace_is_mitsuba06s_albedo() {
    let mut rng = Rng(5);
    for (sigma_a, phase, g) in [
        (0.2f32, Phase::Isotropic, None),
        (0.0, Phase::HenyeyGreenstein { g: 0.8 }, Some(0.8)),
    ] {
        let hk = Hk {
            sigma_s: Vec3::ONE,
            sigma_a: Vec3::splat(sigma_a),
            thickness: 1.0,
            phase,
        };
        let b = Bsdf::new(hk);
        for wi in incident_directions(true) {
            let w = d3(wi);
            let tau = 1.0 + sigma_a as f64;
            let straight = (-tau / w[2].abs()).exp();
            let (mut radiance, mut importance) = (straight, straight);
            for (wo, cell) in sphere_grid(400) {
                radiance += hk06(1.0, sigma_a as f64, 1.0, g, w, wo) * cell;
                importance +=
                    hk06(1.0, sigma_a as f64, 1.0, g, wo, w) / w[2].abs() * wo[2].abs() * cell;
            }
            eprintln!(
                "hk {phase:?} sigma_a {sigma_a} from {wi}: 0.6's albedo {radiance:.4}, adjoint \
                 {importance:.4}"
            );
            assert!(
                radiance <= 1.0 && importance <= 1.0,
                "{radiance} {importance}"
            );
            for (mode, expected) in [(Mode::Radiance, radiance), (Mode::Importance, importance)] {
                let (mean, se) = mean_weight(&b, wi, mode, 200_000, &mut rng);
                assert!(
                    (mean - expected).abs() <= 4.0 * se + 0.002 * expected,
                    "{phase:?} {mode:?} from {wi}: {mean} +- {se}, 0.6: {expected}"
                );
            }
        }
    }
}

/// Each sampler draws what its pdf says (chi-square as the three above: 200,000 samples per
/// incident direction, above and below, z under 5): difftrans; hk isotropic, Henyey-Greenstein
/// g 0.8 and -0.3, Rayleigh, its straight lobe in the extra cell; a mixture tree (weights 0.5,
/// 0.3 of diffuse and difftrans, its black share lost) against 0.6's density sum_i w_i pdf_i.
/// Catches a difftrans sample on the wrong side, a phase sample about the wrong axis, a mixture
/// that picks its children with other shares than its pdf says.
#[test]
fn difftrans_hk_and_mixture_samplers_match_their_pdf_chi_square() {
    let scene = scene_with("0.6.0", &[MIXTURES[0]]).unwrap_or_else(|e| panic!("{e}"));
    let hk = |phase| Hk {
        sigma_s: Vec3::new(0.8, 1.0, 1.2),
        sigma_a: Vec3::splat(0.1),
        thickness: 0.5,
        phase,
    };
    let models = [
        Bsdf::new(DiffTrans::new(Vec3::splat(0.7))),
        Bsdf::new(hk(Phase::Isotropic)),
        Bsdf::new(hk(Phase::HenyeyGreenstein { g: 0.8 })),
        Bsdf::new(hk(Phase::HenyeyGreenstein { g: -0.3 })),
        Bsdf::new(hk(Phase::Rayleigh)),
        Bsdf::new(tree_of(&scene, scene.spheres[0].material)),
    ];
    let mut rng = Rng(31);
    for b in &models {
        for wi in incident_directions(true) {
            let c = chi_square(b, wi, 200_000, &mut rng);
            assert!(c.z < 5.0, "{} from {wi}: {c:?}", b.kind());
        }
    }
}

/// The WGSL of difftrans and hk (through the generated dispatch) gives the CPU models' eval,
/// pdf and sample on 600 random pairs per material (both sides, both modes): difftrans
/// coloured and scaled by 0.6's energy check; hk isotropic, Henyey-Greenstein and Rayleigh,
/// thin and thick, from sigma_t and albedo; the children of a mixture. Read from a 0.6.0 file.
/// Catches a slot of the GPU record read wrong (sigma_s, sigma_a, thickness, the phase kind or
/// g), the adjoint missing on the GPU, a phase sample in another frame than the CPU's.
#[test]
fn gpu_matches_the_cpu_models_difftrans_hk() {
    let gpu = common::gpu();
    let bsdfs = [
        r#"<bsdf type="difftrans"><rgb name="transmittance" value="0.2, 0.5, 0.8"/></bsdf>"#,
        r#"<bsdf type="difftrans"><rgb name="transmittance" value="1.4, 0.5, 0.3"/></bsdf>"#,
        r#"<bsdf type="hk"><rgb name="sigma_s" value="0.5, 1, 2"/><rgb name="sigma_a" value="0.3, 0.2, 0.1"/></bsdf>"#,
        r#"<bsdf type="hk"><rgb name="sigma_s" value="2"/><rgb name="sigma_a" value="0.1, 0.5, 1"/><float name="thickness" value="0.3"/><phase type="hg"><float name="g" value="0.8"/></phase></bsdf>"#,
        r#"<bsdf type="hk"><rgb name="sigma_t" value="3"/><rgb name="albedo" value="0.9, 0.5, 0.2"/><float name="thickness" value="0.1"/><phase type="rayleigh"/></bsdf>"#,
        r#"<bsdf type="hk"><float name="thickness" value="0.01"/><phase type="hg"><float name="g" value="-0.4"/></phase></bsdf>"#,
        MIXTURES[0],
    ];
    let scene = scene_with("0.6.0", &bsdfs).unwrap_or_else(|e| panic!("{e}"));
    let registry = hppm::passes::Registry::builtin();
    let report =
        gpu_against_cpu(&gpu, &registry, &scene, 600, 2e-3, &mut Rng(17)).expect("bsdf kernel");
    assert!(report.evals >= 600 * 7, "{} evals", report.evals);
    assert!(
        report.eval_failures.is_empty(),
        "{} evals differ:\n{}",
        report.eval_failures.len(),
        report.eval_failures.join("\n")
    );
    eprintln!(
        "{} samples compared, {} differ",
        report.samples_compared, report.sample_mismatches
    );
    assert!(report.samples_compared > report.queries / 2);
    assert!(
        report.sample_mismatches * 200 <= report.queries,
        "{} of {} GPU samples differ from the CPU's",
        report.sample_mismatches,
        report.queries
    );
}

/// How the light-transport partition sees them: difftrans is continuous and transmits (path
/// traced, never photon mapped, like roughdiffuse); hk is continuous (its scattering, path
/// traced) and delta (its straight-through lobe, an S vertex, so a scene with one has a
/// specular surface for caustic photons) and transmits; neither has a microfacet lobe; a
/// mixture adds no kind, its diffuse child is a plain `diffuse` material (the D vertex), and a
/// black child is `diffuse` too. Catches a lobe class that would photon-map light through a
/// diffuse transmitter (which the Lambertian hit points cannot gather) or hide hk's delta lobe
/// from the caustic photons.
#[test]
fn the_partition_sees_continuous_difftrans_and_hk_with_a_delta_lobe() {
    let b = loaded(
        "0.6.0",
        &[r#"<bsdf type="difftrans"/>"#, r#"<bsdf type="hk"/>"#],
    );
    let l = b[0].lobes();
    assert!(l.continuous && l.transmits && !l.delta && !l.microfacet && !l.pass_through);
    let l = b[1].lobes();
    assert!(l.continuous && l.transmits && l.delta && !l.microfacet && !l.pass_through);
    assert_eq!(b[1].microfacet_roughness(), None);
    let registry = hppm::bsdfs::BsdfRegistry::builtin();
    for kind in ["difftrans", "hk"] {
        let (_, k) = registry.kind(kind).expect(kind);
        assert!(k.eval.is_some() && k.sample.is_some(), "{kind} dispatched");
        assert_eq!(k.glossy, hppm::bsdfs::Glossy::None);
    }
    assert!(registry.kind("mixturebsdf").is_none());
    let scene = scene_with("0.6.0", &[r#"<bsdf type="hk"/>"#]).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        scene.features().delta,
        "hk's straight lobe is a specular surface"
    );
    let scene = scene_with("0.6.0", &[MIXTURES[0]]).unwrap_or_else(|e| panic!("{e}"));
    let kinds: Vec<&str> = scene.materials.iter().map(|m| m.bsdf.kind()).collect();
    assert_eq!(
        kinds.iter().filter(|k| **k == "diffuse").count(),
        2,
        "{kinds:?}"
    );
    assert_eq!(
        kinds.iter().filter(|k| **k == "blend").count(),
        2,
        "{kinds:?}"
    );
}

/// A Mitsuba 0.5.0 file with 0.5's camelCase names: difftrans's diffuseTransmittance (0.6's
/// other name) and ensureEnergyConservation false (a transmittance above 1 kept), a textured
/// transmittance (kept in the diffuse texture slot, scaled by 0.99 / its largest texel); hk's sigmaS,
/// sigmaA, thickness and nested hg phase; hk from sigmaT and albedo; hk's defaults (0.6's skin1
/// preset: sigma_s (74, 88, 101), sigma_a (3.2, 17, 48) per unit, isotropic); a `material`
/// preset with its g (Regular Milk: sigma_s times 100 times 1 - g, g 0.75, 0.714, 0.681) and
/// `scale`; a `g` property replacing the preset's; a mixture with ensureEnergyConservation.
/// Catches a property read under the wrong name, a default or preset that is not 0.6's, the
/// preset's g or scale left out or applied to given coefficients.
#[test]
fn a_mitsuba_05_file_loads_difftrans_hk_and_mixtures() {
    let scene = scene_with(
        "0.5.0",
        &[
            r#"<bsdf type="difftrans"><rgb name="diffuseTransmittance" value="1.2, 0.5, 0.1"/><boolean name="ensureEnergyConservation" value="false"/></bsdf>"#,
            r#"<bsdf type="difftrans"><texture name="transmittance" type="checkerboard"><rgb name="color0" value="1.5"/><rgb name="color1" value="0.5"/></texture></bsdf>"#,
            r#"<bsdf type="hk"><rgb name="sigmaS" value="0.5, 1, 2"/><rgb name="sigmaA" value="0.1"/><float name="thickness" value="2"/><phase type="hg"><float name="g" value="0.6"/></phase></bsdf>"#,
            r#"<bsdf type="hk"><rgb name="sigmaT" value="2"/><rgb name="albedo" value="0.25, 0.5, 1"/></bsdf>"#,
            r#"<bsdf type="hk"/>"#,
            r#"<bsdf type="hk"><string name="material" value="regular milk"/><float name="scale" value="0.01"/></bsdf>"#,
            r#"<bsdf type="hk"><string name="material" value="Regular Milk"/><float name="g" value="0.5"/></bsdf>"#,
            r#"<bsdf type="hk"><rgb name="sigmaA" value="1"/><float name="scale" value="2"/></bsdf>"#,
            r#"<bsdf type="mixturebsdf"><string name="weights" value="3 1"/><boolean name="ensureEnergyConservation" value="true"/><bsdf type="diffuse"/><bsdf type="difftrans"/></bsdf>"#,
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let at = |i: usize| {
        scene.materials[scene.spheres[i].material as usize]
            .bsdf
            .clone()
    };
    let t = *at(0).get::<DiffTrans>().expect("difftrans");
    assert_eq!((t.transmittance, t.scale), (Vec3::new(1.2, 0.5, 0.1), 1.0));
    // A texture: the model keeps its mean, 0.6's scale comes from its largest texel (1.5).
    let t = *at(1).get::<DiffTrans>().expect("textured difftrans");
    assert!((t.scale - 0.99 / 1.5).abs() < 1e-6, "{t:?}");
    let m = &scene.materials[scene.spheres[1].material as usize];
    assert!(
        m.textures.front.diffuse.is_some(),
        "the texture in the diffuse slot"
    );
    let hk = |i: usize| *at(i).get::<Hk>().expect("hk");
    let near =
        |a: Vec3, b: Vec3| (a - b).abs().max_element() <= 1e-4 * b.abs().max_element().max(1.0);
    let h = hk(2);
    assert!(near(h.sigma_s, Vec3::new(0.5, 1.0, 2.0)) && near(h.sigma_a, Vec3::splat(0.1)));
    assert_eq!(
        (h.thickness, h.phase),
        (2.0, Phase::HenyeyGreenstein { g: 0.6 })
    );
    let h = hk(3);
    assert!(
        near(h.sigma_s, Vec3::new(0.5, 1.0, 2.0)) && near(h.sigma_a, Vec3::new(1.5, 1.0, 0.0)),
        "{h:?}"
    );
    let h = hk(4);
    assert!(near(h.sigma_s, Vec3::new(74.0, 88.0, 101.0)), "{h:?}");
    assert!(near(h.sigma_a, Vec3::new(3.2, 17.0, 48.0)), "{h:?}");
    assert_eq!((h.thickness, h.phase), (1.0, Phase::Isotropic));
    let milk_s = Vec3::new(18.2052, 20.3826, 22.3698) * 100.0;
    let milk_a = Vec3::new(0.00153, 0.00460, 0.01993) * 100.0;
    let milk_g = Vec3::new(0.75, 0.714, 0.681);
    let h = hk(5);
    assert!(
        near(h.sigma_s, milk_s * 0.01 * (Vec3::ONE - milk_g)),
        "{h:?}"
    );
    assert!(near(h.sigma_a, milk_a * 0.01), "{h:?}");
    let h = hk(6);
    assert!(near(h.sigma_s, milk_s * 0.5), "{h:?}");
    // Given coefficients are taken as given; the missing one is skin1's, scaled.
    let h = hk(7);
    assert!(
        near(h.sigma_a, Vec3::ONE) && near(h.sigma_s, Vec3::new(148.0, 176.0, 202.0)),
        "{h:?}"
    );
    let leaves = leaves_of(&scene, scene.spheres[8].material);
    let mut p: Vec<f64> = leaves.iter().map(|l| l.0).collect();
    p.sort_by(f64::total_cmp);
    assert!(
        (p[0] - 0.25).abs() < 1e-6 && (p[1] - 0.75).abs() < 1e-6,
        "{p:?}"
    );
}

/// The three are Mitsuba 0.6 plugins: a version 3 file (and one without a version) refuses
/// each at the element's line, naming the version; 0.6.0 loads it. Catches a file Mitsuba 3
/// would refuse loading silently.
#[test]
fn version_3_files_refuse_difftrans_mixturebsdf_and_hk() {
    for (kind, bsdf) in [
        ("difftrans", r#"<bsdf type="difftrans"/>"#),
        ("hk", r#"<bsdf type="hk"/>"#),
        ("mixturebsdf", MIXTURES[1]),
    ] {
        let err = scene_with("3.0.0", &[bsdf]).expect_err(kind).to_string();
        assert!(err.starts_with("m06.xml:2:"), "{err}");
        assert!(
            err.contains(&format!(
                "{kind} is a Mitsuba 0.6 plugin; this file is version 3.0.0"
            )),
            "{err}"
        );
        scene_with("0.6.0", &[bsdf]).unwrap_or_else(|e| panic!("{e}"));
        let xml = format!(
            "<scene><sensor type=\"perspective\"/>\n<shape type=\"sphere\">{bsdf}</shape></scene>"
        );
        let err = hppm::loaders::mitsuba::parse(Path::new("m06.xml"), &xml)
            .expect_err("no version")
            .to_string();
        assert!(err.contains("this file is version not given"), "{err}");
    }
}

/// Malformed parameters are errors at their line (line 2) saying what is wrong, as 0.6 refuses
/// them or would misrender them: mixture weights negative, unparsable, missing, summing to 0,
/// fewer or more than the nested BSDFs, above 1 with the energy check off; hk with a preset and
/// coefficients, sigma_s with sigma_t, sigma_t without albedo, an unknown preset, a negative
/// coefficient or thickness, g outside (-1, 1), an albedo above 1, two phase functions, a phase
/// function hppm does not read; difftrans's two names at once or a negative transmittance.
/// Catches a value accepted that would render light from nothing or a wrong weight, or an
/// error without its place.
#[test]
fn bad_difftrans_mixturebsdf_and_hk_parameters_are_errors_at_their_line() {
    let two = r#"<bsdf type="diffuse"/><bsdf type="difftrans"/>"#;
    let mix = |weights: &str, extra: &str| {
        format!(
            r#"<bsdf type="mixturebsdf"><string name="weights" value="{weights}"/>{extra}{two}</bsdf>"#
        )
    };
    let cases = [
        (mix("0.5, -0.2", ""), "weight -0.2 is negative"),
        (mix("0.5, x", ""), "\"x\" is not a finite number"),
        (mix(" , ", ""), "no weights were given"),
        (mix("0 0", ""), "must sum to more than 0"),
        (mix("0.5", ""), "1 weight(s) for 2 nested BSDF(s)"),
        (mix("0.2 0.3 0.5", ""), "3 weight(s) for 2 nested BSDF(s)"),
        (
            mix("0.8 0.8", r#"<boolean name="ensureEnergyConservation" value="false"/>"#),
            "the weights sum to 1.6",
        ),
        (format!(r#"<bsdf type="mixturebsdf">{two}</bsdf>"#), "mixturebsdf needs weights"),
        (
            r#"<bsdf type="hk"><string name="material" value="skin2"/><rgb name="sigmaS" value="1"/></bsdf>"#.into(),
            "a material preset or scattering coefficients, not both",
        ),
        (
            r#"<bsdf type="hk"><rgb name="sigmaS" value="1"/><rgb name="sigmaT" value="1"/></bsdf>"#.into(),
            "not a mix",
        ),
        (
            r#"<bsdf type="hk"><rgb name="sigmaT" value="1"/></bsdf>"#.into(),
            "give both sigma_t and albedo",
        ),
        (
            r#"<bsdf type="hk"><string name="material" value="milk"/></bsdf>"#.into(),
            "no material preset \"milk\"",
        ),
        (
            r#"<bsdf type="hk"><rgb name="sigmaA" value="0.1, -0.1, 0.1"/></bsdf>"#.into(),
            "must not be negative",
        ),
        (
            r#"<bsdf type="hk"><float name="thickness" value="-1"/></bsdf>"#.into(),
            "must not be negative",
        ),
        (
            r#"<bsdf type="hk"><float name="g" value="1"/></bsdf>"#.into(),
            "between -1 and 1",
        ),
        (
            r#"<bsdf type="hk"><rgb name="sigmaT" value="1"/><rgb name="albedo" value="1.2"/></bsdf>"#.into(),
            "must lie in [0, 1]",
        ),
        (
            r#"<bsdf type="hk"><phase type="isotropic"/><phase type="hg"/></bsdf>"#.into(),
            "a second <phase>",
        ),
        (
            r#"<bsdf type="hk"><phase type="kkay"/></bsdf>"#.into(),
            "phase function type \"kkay\" is not supported",
        ),
        (
            r#"<bsdf type="difftrans"><rgb name="transmittance" value="0.5"/><rgb name="diffuseTransmittance" value="0.5"/></bsdf>"#.into(),
            "not both",
        ),
        (
            r#"<bsdf type="difftrans"><rgb name="transmittance" value="-0.5"/></bsdf>"#.into(),
            "negative",
        ),
    ];
    for (bsdf, expected) in &cases {
        let err = scene_with("0.5.0", &[bsdf]).expect_err(bsdf).to_string();
        assert!(err.starts_with("m06.xml:2:"), "{bsdf}: {err}");
        assert!(err.contains(expected), "{bsdf}: {err}");
    }
}

/// A small 0.6.0 box lit from above through an hk pane (its straight-through lobe makes a
/// caustic on the floor that the hybrid's photons render), with a difftrans sphere (light
/// through it is path traced by both) and a mixture sphere (weights 0.4, 0.4 of diffuse and
/// copper: a diffuse child for hit points, a delta child's caustic, a black share).
const BOX_06: &str = r#"<scene version="0.6.0">
    <integrator type="path"><integer name="maxDepth" value="6"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="toWorld"><lookAt origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
    </sensor>
    <bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="0.75"/></bsdf></bsdf>
    <shape type="rectangle"><transform name="toWorld"><matrix value="0 1 0 0 0 0 1 -1 1 0 0 0 0 0 0 1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="1 0 0 0 0 0 -1 1 0 1 0 0 0 0 0 1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="1 0 0 0 0 1 0 0 0 0 1 -1 0 0 0 1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="0 0 1 -1 1 0 0 0 0 1 0 0 0 0 0 1"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.1, 0.1"/></bsdf></bsdf></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="0 0 -1 1 0 1 0 0 1 0 0 0 0 0 0 1"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.5, 0.1"/></bsdf></bsdf></shape>
    <shape type="rectangle">
        <transform name="toWorld"><matrix value="0.3 0 0 0 0 0 -1 0.99 0 0.3 0 0 0 0 0 1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="12, 11, 9"/></emitter>
    </shape>
    <shape type="rectangle">
        <transform name="toWorld"><matrix value="0.45 0 0 0 0 0 1 0.75 0 -0.45 0 0 0 0 0 1"/></transform>
        <bsdf type="hk"><rgb name="sigmaS" value="0.5, 0.6, 0.7"/><rgb name="sigmaA" value="0.2"/><float name="thickness" value="0.3"/>
            <phase type="hg"><float name="g" value="0.5"/></phase></bsdf></shape>
    <shape type="sphere"><point name="center" x="-0.5" y="-0.7" z="-0.2"/><float name="radius" value="0.3"/>
        <bsdf type="difftrans"><rgb name="transmittance" value="0.8, 0.7, 0.4"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="0.5" y="-0.7" z="-0.3"/><float name="radius" value="0.3"/>
        <bsdf type="mixturebsdf"><string name="weights" value="0.4, 0.4"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.3, 0.7"/></bsdf>
            <bsdf type="conductor"><string name="material" value="Cu"/></bsdf></bsdf></shape>
</scene>"#;

/// The hybrid renders `pt`'s image of the box above (8 seeds at 16 spp, paired by seed, the
/// whole image and every 8x8 block; tests/common/convergence.rs): light through hk's
/// straight-through lobe is counted once (photons, as a caustic) and its scattering and the
/// diffuse transmitter's light once (path tracing), and the mixture's blend tree makes the
/// same choices in both passes. Catches a lobe class the camera and the photons disagree on
/// (light through hk or difftrans counted twice or never), a mixture's diffuse child not
/// recorded as a hit point or its deposits not divided by its share.
#[test]
fn hybrid_equals_pt_with_difftrans_mixturebsdf_and_hk() {
    let scene = hppm::loaders::mitsuba::parse(Path::new("box06.xml"), BOX_06)
        .unwrap_or_else(|e| panic!("{e}"));
    common::convergence::hybrid_equals_pt("box06", "graphs/hybrid.ron", &scene);
}

// ================================================================ coating and roughcoating
//
// Mitsuba 0.6's `coating` and `roughcoating` (src/bsdfs/coating/): the CPU models against a
// separate double-precision transcription of 0.6's coating.cpp, roughcoating.cpp and
// microfacet.h (below; the rough interface's transmittance integrated on a grid of microfacet
// normals, as 0.6's rdielprec defines its tables), white furnaces, chi-square of the samplers,
// GPU = CPU through the dispatch, the partition's view, and reading from 0.x files.

use hppm::bsdfs::coating::{Coating, RoughCoating};

/// 0.6's `fresnelDielectricExt` from outside (cos_i > 0): the reflectance and |cos theta_t|.
fn fresnel06(cos_i: f64, eta: f64) -> (f64, f64) {
    let ct2 = 1.0 - (1.0 - cos_i * cos_i) / (eta * eta);
    if ct2 <= 0.0 {
        return (1.0, 0.0);
    }
    let ct = ct2.sqrt();
    let rs = (cos_i - eta * ct) / (cos_i + eta * ct);
    let rp = (eta * cos_i - ct) / (eta * cos_i + ct);
    (0.5 * (rs * rs + rp * rp), ct)
}

/// 0.6's Beckmann D and its rational Smith G1 (microfacet.h), isotropic alpha.
fn beckmann_d06(m: [f64; 3], alpha: f64) -> f64 {
    if m[2] <= 0.0 {
        return 0.0;
    }
    let c2 = m[2] * m[2];
    let e = (m[0] * m[0] + m[1] * m[1]) / (alpha * alpha * c2);
    (-e).exp() / (std::f64::consts::PI * alpha * alpha * c2 * c2)
}

fn smith_g1_06(v: [f64; 3], m: [f64; 3], alpha: f64) -> f64 {
    if dot3(v, m) * v[2] <= 0.0 {
        return 0.0;
    }
    let tan = ((1.0 - v[2] * v[2]).max(0.0)).sqrt() / v[2].abs();
    if tan == 0.0 {
        return 1.0;
    }
    let a = 1.0 / (alpha * tan);
    if a >= 1.6 {
        return 1.0;
    }
    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
}

/// 0.6's `m_specularSamplingWeight` and its reallocation of the reflection's probability.
fn specular_prob06(r: f64, sigma_t: [f64; 3]) -> f64 {
    let avg = sigma_t.iter().map(|s| (-2.0 * s).exp()).sum::<f64>() / 3.0;
    let w = 1.0 / (avg + 1.0);
    r * w / (r * w + (1.0 - r) * (1.0 - w))
}

/// coating.cpp's eval and pdf over a diffuse base of reflectance `rho` (both directions above):
/// f |cos wo| per channel and the density.
fn coating_diffuse06(
    wi: Vec3,
    wo: Vec3,
    eta: f64,
    rho: [f64; 3],
    sigma_t: [f64; 3],
) -> ([f64; 3], f64) {
    let (ci, co) = (wi.z as f64, wo.z as f64);
    let (r12, ci_in) = fresnel06(ci, eta);
    let (r21, co_in) = fresnel06(co, eta);
    let inv_pi = std::f64::consts::FRAC_1_PI;
    let jacobian = co / (eta * eta * co_in);
    let value = [0, 1, 2].map(|c| {
        rho[c]
            * inv_pi
            * co_in
            * (1.0 - r12)
            * (1.0 - r21)
            * (-sigma_t[c] * (1.0 / ci_in + 1.0 / co_in)).exp()
            * jacobian
    });
    let pdf = co_in * inv_pi * jacobian * (1.0 - specular_prob06(r12, sigma_t));
    (value, pdf)
}

/// The rough interface's transmittance from outside at cos `mu` (Beckmann, `alpha`): what 0.6's
/// rdielprec tabulates, the transmission of its roughdielectric, integrated here over the
/// microfacet normals on a 700 x 700 midpoint grid in (theta_m, phi_m):
/// int D(m) G1(wi, m) (wi.m) / cos_i (1 - F(wi.m)) G1(wt, m) dm.
fn rough_transmittance06(mu: f64, eta: f64, alpha: f64) -> f64 {
    let wi = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let n = 700;
    let (dt, dp) = (
        std::f64::consts::FRAC_PI_2 / n as f64,
        2.0 * std::f64::consts::PI / n as f64,
    );
    let mut sum = 0.0;
    for i in 0..n {
        let t = (i as f64 + 0.5) * dt;
        for j in 0..n {
            let p = (j as f64 + 0.5) * dp;
            let m = [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
            let c = dot3(wi, m);
            if c <= 0.0 {
                continue;
            }
            let (f, ct) = fresnel06(c, eta);
            if f >= 1.0 {
                continue;
            }
            let k = c / eta - ct;
            let wt = [0, 1, 2].map(|a| -wi[a] / eta + k * m[a]);
            let g = smith_g1_06(wi, m, alpha) * smith_g1_06(wt, m, alpha);
            sum += beckmann_d06(m, alpha) * c / mu * (1.0 - f) * g * t.sin() * dt * dp;
        }
    }
    sum
}

fn coating_xml(attrs: &str, nested: &str) -> String {
    format!(r#"<bsdf type="coating">{attrs}{nested}</bsdf>"#)
}

const WHITE_DIFFUSE: &str =
    r#"<bsdf type="diffuse"><rgb name="reflectance" value="1, 1, 1"/></bsdf>"#;

/// The coating a 0.6 file reads (the last material: the nested one comes before it).
fn coating_of(bsdf: &str) -> Bsdf {
    let scene = scene_with("0.6.0", &[bsdf]).unwrap_or_else(|e| panic!("{bsdf}: {e}"));
    scene.materials.last().expect("a material").bsdf.clone()
}

/// The smooth coating over a diffuse base (reflectance 0.8, 0.5, 0.2; eta 1.5; sigmaA 0.1, 0.2,
/// 0.3 times thickness 2, test_bsdf.xml's first coating) against coating.cpp transcribed in
/// double precision: eval and pdf at three pairs, the delta reflection's weight R12 / its
/// probability, and nothing from the base seen from below (the nested diffuse is one-sided)
/// while the reflection still answers there, as 0.6's coating is EFrontSide | EBackSide.
/// Catches a missing 1 / eta^2 or cos wo / cos wo' Jacobian, a Fresnel term at the outer
/// instead of the refracted angle, absorption along the normal instead of the refracted paths,
/// a lobe probability not reallocated as 0.6 does, and directions refracted without their
/// sign.
#[test]
fn coating_eval_and_pdf_are_mitsuba06s() {
    let b = coating_of(&coating_xml(
        r#"<float name="intIOR" value="1.5"/><float name="extIOR" value="1"/><rgb name="sigmaA" value="0.1 0.2 0.3"/><float name="thickness" value="2"/>"#,
        r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf>"#,
    ));
    assert!(b.get::<Coating>().is_some());
    let rho = [0.8, 0.5, 0.2];
    let sigma_t = [0.2, 0.4, 0.6];
    for (wi, wo) in [
        (wi(), wo_across()),
        (wi(), wo_beside()),
        (unit(0.0, 0.6, 0.8), unit(0.96, 0.0, 0.28)),
    ] {
        let (value, pdf) = coating_diffuse06(wi, wo, 1.5, rho, sigma_t);
        let got = b.eval(wi, wo, Mode::Radiance);
        for c in 0..3 {
            assert_close("coating eval", got[c], value[c] as f32, 1e-4);
        }
        assert_close("coating pdf", b.pdf(wi, wo), pdf as f32, 1e-4);
    }
    let (r12, _) = fresnel06(wi().z as f64, 1.5);
    let prob = specular_prob06(r12, sigma_t);
    let s = b
        .sample(wi(), 0.0, Vec2::splat(0.5), Mode::Radiance)
        .expect("reflection");
    assert!(s.delta);
    assert_close("reflection probability", s.pdf, prob as f32, 1e-5);
    assert_close("reflection weight", s.weight.x, (r12 / prob) as f32, 1e-5);
    assert!((s.wo - Vec3::new(-wi().x, -wi().y, wi().z)).length() < 1e-6);
    let below = -wi();
    assert_eq!(b.eval(below, -wo_across(), Mode::Radiance), Vec3::ZERO);
    let s = b
        .sample(below, 0.0, Vec2::splat(0.5), Mode::Radiance)
        .expect("back reflection");
    assert!(s.delta && s.wo.z < 0.0);
}

/// The rough coating (Beckmann alpha 0.3, eta 1.5) over a diffuse base against roughcoating.cpp
/// transcribed in double precision, its transmittance from the grid integral of the rough
/// interface (0.6's table's definition): the reflection lobe alone (F D G / (4 cos_i)) at a
/// near-mirror pair, eval and pdf in full at three pairs. The tolerance, 1%, is the table's
/// interpolation (0.6 interpolates its own table cubically). Catches the nested lobe without
/// the rough transmittance (or with the smooth one), the lobe choice by anything but 1 - T(wi),
/// and a reflection lobe that is not rough plastic's.
#[test]
fn roughcoating_eval_and_pdf_are_mitsuba06s() {
    let b = coating_of(
        r#"<bsdf type="roughcoating"><float name="intIOR" value="1.5"/><float name="extIOR" value="1"/><float name="alpha" value="0.3"/><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf></bsdf>"#,
    );
    let rc = b.get::<RoughCoating>().expect("roughcoating");
    let (eta, alpha, rho) = (1.5f64, 0.3f64, 0.6f64);
    for (wi, wo) in [
        (wi(), wo_near_mirror()),
        (wi(), wo_beside()),
        (unit(0.0, 0.6, 0.8), unit(0.96, 0.0, 0.28)),
    ] {
        let (i, o) = (d3(wi), d3(wo));
        let h = {
            let s = [i[0] + o[0], i[1] + o[1], i[2] + o[2]];
            let l = dot3(s, s).sqrt();
            s.map(|x| x / l)
        };
        let d = beckmann_d06(h, alpha);
        let (g1i, g1o) = (smith_g1_06(i, h, alpha), smith_g1_06(o, h, alpha));
        let f = fresnel06(dot3(i, h), eta).0;
        let reflection = f * d * g1i * g1o / (4.0 * i[2]);
        let (ti, to) = (
            rough_transmittance06(i[2], eta, alpha),
            rough_transmittance06(o[2], eta, alpha),
        );
        let ci_in = (1.0 - (1.0 - i[2] * i[2]) / (eta * eta)).sqrt();
        let co_in = (1.0 - (1.0 - o[2] * o[2]) / (eta * eta)).sqrt();
        let jacobian = o[2] / (eta * eta * co_in);
        let _ = ci_in;
        let nested = rho * std::f64::consts::FRAC_1_PI * co_in * ti * to * jacobian;
        let prob = specular_prob06(1.0 - ti, [0.0; 3]);
        let pdf = g1i * dot3(i, h) * d / i[2] / (4.0 * dot3(o, h)) * prob
            + co_in * std::f64::consts::FRAC_1_PI * jacobian * (1.0 - prob);
        assert_close(
            "reflection lobe",
            rc.reflection(wi, wo).x,
            reflection as f32,
            1e-3,
        );
        assert_close(
            "roughcoating eval",
            b.eval(wi, wo, Mode::Radiance).x,
            (reflection + nested) as f32,
            1e-2,
        );
        assert_close("roughcoating pdf", b.pdf(wi, wo), pdf as f32, 1e-2);
        assert_close("transmittance", rc.transmittance_at(wi.z), ti as f32, 1e-2);
    }
}

/// White furnaces: a coating without absorption over a white diffuse base reflects, from cos
/// theta_i, R12 + (1 - R12) 2 / eta^2 int_0^1 (1 - F(mu)) mu dmu (0.6's model keeps no internal
/// reflections, so it loses light), integrated here on 20,000 midpoints; the sampler's mean
/// weight, and eval integrated over the sphere plus R12, meet it within 4 standard errors.
/// With sigmaA the base's light drops by exp(-2 sigma t / cos) and the furnace follows. Catches
/// weights that are not eval / pdf, a reflection weight not R12 / its probability, and energy
/// the transcription does not have (a missing (1 - R21) makes it 1.0).
#[test]
fn coating_white_furnace_is_mitsuba06s_albedo() {
    let b = coating_of(&coating_xml(
        r#"<float name="intIOR" value="1.5"/><float name="extIOR" value="1"/>"#,
        WHITE_DIFFUSE,
    ));
    let eta = 1.5f64;
    let n = 20_000;
    let integral: f64 = (0..n)
        .map(|k| {
            let mu = (k as f64 + 0.5) / n as f64;
            (1.0 - fresnel06(mu, eta).0) * mu / n as f64
        })
        .sum();
    let mut rng = Rng(808);
    for wi in incident_directions(false) {
        let r12 = fresnel06(wi.z as f64, eta).0;
        let expected = r12 + (1.0 - r12) * 2.0 / (eta * eta) * integral;
        let f = furnace(&b, wi, 200_000, &mut rng);
        assert!(
            (f.albedo.mean - expected).abs() < 4.0 * f.albedo.error + 1e-4,
            "wi.z {}: albedo {:?}, 0.6's {expected}",
            wi.z,
            f.albedo
        );
        let through = f.eval_integral.mean + r12;
        assert!(
            (through - expected).abs() < 4.0 * f.eval_integral.error + 1e-4,
            "wi.z {}: eval integral + R12 {through}, 0.6's {expected}",
            wi.z
        );
        assert!(expected < 1.0);
    }
}

/// The coatings' samplers against their pdfs (chi-square, 100,000 samples from each test
/// direction; reflections and samples lost to total internal reflection in the extra cell): the
/// smooth coating over diffuse with absorption, over a rough conductor and over phong; the
/// rough coating over diffuse and over a rough conductor (test_bsdf.xml's). Catches a pdf
/// without the lobe's probability, the refraction's Jacobian, or a nested pdf at the wrong
/// directions.
#[test]
fn coating_samplers_match_their_pdf_chi_square() {
    let models = [
        coating_xml(
            r#"<rgb name="sigmaA" value="0.1 0.2 0.3"/><float name="thickness" value="2"/>"#,
            r#"<bsdf type="diffuse"/>"#,
        ),
        coating_xml(
            r#"<float name="intIOR" value="1.5"/><float name="extIOR" value="1"/>"#,
            r#"<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>"#,
        ),
        coating_xml("", r#"<bsdf type="phong"><float name="exponent" value="20"/></bsdf>"#),
        r#"<bsdf type="roughcoating"><float name="alpha" value="0.2"/><bsdf type="diffuse"/></bsdf>"#.into(),
        r#"<bsdf type="roughcoating"><bsdf type="roughconductor"><string name="distribution" value="beckmann"/><float name="alpha" value=".3"/></bsdf></bsdf>"#.into(),
    ];
    let mut rng = Rng(0xc0a7);
    for xml in &models {
        let b = coating_of(xml);
        for wi in incident_directions(false) {
            let chi = chi_square(&b, wi, 100_000, &mut rng);
            assert!(chi.z < 5.0, "{xml}, wi {wi}: {chi:?}");
        }
    }
}

/// A coating's sample weight is its eval over its pdf at the sampled direction (non-delta
/// samples), and the rough one's reflection samples too; 400 fixed random numbers each, from
/// above and from below. Catches the smooth coating's own weight (0.6 builds it from the
/// nested weight and the two refractions, not from eval / pdf) disagreeing with its eval and
/// pdf.
#[test]
fn coating_sample_weights_are_eval_over_pdf() {
    let models = [
        coating_xml(
            r#"<rgb name="sigmaA" value="0.3 0.1 0.0"/>"#,
            r#"<bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf>"#,
        ),
        r#"<bsdf type="roughcoating"><float name="alpha" value="0.25"/><rgb name="specularReflectance" value="0.5 0.7 0.9"/><bsdf type="ward"/></bsdf>"#.into(),
    ];
    let mut rng = Rng(41);
    for xml in &models {
        let b = coating_of(xml);
        let mut drawn = 0;
        for wi in [wi(), -wi()] {
            for _ in 0..400 {
                let u = Vec2::new(rng.unit(), rng.unit());
                let Some(s) = b.sample(wi, rng.unit(), u, Mode::Radiance) else {
                    continue;
                };
                if s.delta {
                    continue;
                }
                drawn += 1;
                let expected = b.eval(wi, s.wo, Mode::Radiance) / b.pdf(wi, s.wo);
                assert!(
                    (s.weight - expected).abs().max_element() <= 1e-4 * expected.max_element(),
                    "{xml}: weight {} but eval / pdf {expected}",
                    s.weight
                );
            }
        }
        assert!(drawn > 200, "{xml}: only {drawn} samples");
    }
}

/// The coatings' WGSL (through the generated dispatch, the nested record reached through the
/// coating's own) gives the CPU models' eval, pdf and sample on 600 random pairs each, over
/// every nested kind they accept, with absorption, a tinted reflection, eta below 1 and GGX.
/// Catches a nested record not found (children.x), a nested kind missing from the coating's
/// dispatch, a slot read wrong (sigma_a t in k, eta in int_ior), the transmittance table
/// indexed other than the CPU's.
#[test]
fn coatings_gpu_matches_the_cpu_models() {
    let gpu = common::gpu();
    let bsdfs = [
        coating_xml(
            r#"<rgb name="sigmaA" value="0.1 0.2 0.3"/><float name="thickness" value="2"/><rgb name="specularReflectance" value="0.9 0.8 0.7"/>"#,
            r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf>"#,
        ),
        coating_xml("", r#"<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>"#),
        coating_xml(
            r#"<float name="intIOR" value="1.0"/><float name="extIOR" value="1.33"/>"#,
            r#"<bsdf type="roughplastic"/>"#,
        ),
        coating_xml("", r#"<bsdf type="roughdiffuse"/>"#),
        coating_xml("", r#"<bsdf type="phong"/>"#),
        coating_xml("", r#"<bsdf type="ward"/>"#),
        r#"<bsdf type="roughcoating"><float name="alpha" value="0.2"/><rgb name="sigmaA" value="0.5 0 0"/><bsdf type="diffuse"/></bsdf>"#.into(),
        r#"<bsdf type="roughcoating"><string name="distribution" value="ggx"/><float name="alpha" value="0.4"/><bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></bsdf>"#.into(),
    ];
    let refs: Vec<&str> = bsdfs.iter().map(String::as_str).collect();
    let scene = scene_with("0.6.0", &refs).unwrap_or_else(|e| panic!("{e}"));
    let registry = hppm::passes::Registry::builtin();
    let report =
        gpu_against_cpu(&gpu, &registry, &scene, 600, 2e-3, &mut Rng(7)).expect("bsdf kernel");
    // The nested materials are dispatched too (all but the diffuse ones).
    assert!(report.evals >= 600 * bsdfs.len(), "{}", report.evals);
    assert!(
        report.eval_failures.is_empty(),
        "{} evals differ:\n{}",
        report.eval_failures.len(),
        report.eval_failures[..report.eval_failures.len().min(20)].join("\n")
    );
    eprintln!(
        "{} samples compared, {} differ",
        report.samples_compared, report.sample_mismatches
    );
    assert!(report.samples_compared > report.queries / 3);
    assert!(
        report.sample_mismatches * 200 <= report.queries,
        "{} of {} GPU samples differ from the CPU's",
        report.sample_mismatches,
        report.queries
    );
}

/// How the partition sees them: the smooth coating has a delta lobe (its reflection, an S
/// vertex when sampled) and a continuous one (the nested BSDF through the interface: path
/// traced, never photon-mapped, as plastic's base), no microfacet lobe whatever it coats; the
/// rough coating's reflection is a microfacet lobe of its alpha, split at the threshold as rough
/// plastic's coating (Glossy::Split), alpha packed where the split reads it. Catches a coating
/// that would photon-map its nested diffuse (seen through a refraction, it is not a Lambertian
/// vertex) or hide its reflection from the glossy threshold.
#[test]
fn the_partition_sees_the_coatings_reflection_and_a_continuous_nested_lobe() {
    let smooth = coating_of(&coating_xml("", WHITE_DIFFUSE));
    let l = smooth.lobes();
    assert!(l.delta && l.continuous && !l.microfacet && !l.transmits && !l.pass_through);
    assert_eq!(smooth.microfacet_roughness(), None);
    let rough = coating_of(
        r#"<bsdf type="roughcoating"><float name="alpha" value="0.15"/><bsdf type="roughconductor"/></bsdf>"#,
    );
    let l = rough.lobes();
    assert!(!l.delta && l.continuous && l.microfacet && !l.transmits);
    assert_eq!(rough.microfacet_roughness(), Some(0.15));
    let mut record = GpuMaterial::zeroed();
    rough.pack(&mut record, &Default::default(), &mut Vec::new());
    assert_eq!(record.alpha_u.max(record.alpha_v), 0.15);
    let registry = hppm::bsdfs::BsdfRegistry::builtin();
    for (kind, split) in [("coating", false), ("roughcoating", true)] {
        let (_, k) = registry.kind(kind).expect(kind);
        assert_eq!(matches!(k.glossy, hppm::bsdfs::Glossy::Split { .. }), split);
    }
}

/// A 0.5.0 file with 0.5's camelCase names (intIOR, extIOR, sigmaA, specularReflectance,
/// ensureEnergyConservation) and a nested BSDF by `<ref>`: each value where it belongs, 0.6's
/// defaults (bk7 inside, air outside, thickness 1, sigmaA 0, specularReflectance 1, Beckmann
/// alpha 0.1) where nothing is given, a specularReflectance above 1 scaled to 0.99 as 0.6's
/// energy check does, and the nested material before the coating. Catches a property read under
/// the wrong name or a default that is not 0.6's.
#[test]
fn a_mitsuba_05_file_with_coatings_loads() {
    let xml = "<scene version=\"0.5.0\"><sensor type=\"perspective\"/>\n\
        <bsdf type=\"diffuse\" id=\"base\"><rgb name=\"reflectance\" value=\"0.2 0.3 0.4\"/></bsdf>\n\
        <shape type=\"sphere\"><bsdf type=\"coating\"><string name=\"intIOR\" value=\"water\"/><float name=\"extIOR\" value=\"1.1\"/><rgb name=\"sigmaA\" value=\"0.5 0.25 0\"/><float name=\"thickness\" value=\"0.5\"/><rgb name=\"specularReflectance\" value=\"2 1 0.5\"/><ref id=\"base\"/></bsdf></shape>\n\
        <shape type=\"sphere\"><bsdf type=\"roughcoating\"><bsdf type=\"diffuse\"/></bsdf></shape>\n\
        <shape type=\"sphere\"><bsdf type=\"coating\"><rgb name=\"specularReflectance\" value=\"2 1 0.5\"/><boolean name=\"ensureEnergyConservation\" value=\"false\"/><bsdf type=\"diffuse\"/></bsdf></shape></scene>";
    let scene =
        hppm::loaders::mitsuba::parse(Path::new("m05.xml"), xml).unwrap_or_else(|e| panic!("{e}"));
    let coatings: Vec<(usize, &Bsdf)> = scene
        .materials
        .iter()
        .enumerate()
        .filter(|(_, m)| m.bsdf.kind().contains("coating"))
        .map(|(i, m)| (i, &m.bsdf))
        .collect();
    assert_eq!(coatings.len(), 3);
    let c = coatings[0].1.get::<Coating>().expect("coating");
    assert_close("eta", c.layer.eta, 1.333 / 1.1, 1e-6);
    assert_eq!(c.layer.optical_depth, Vec3::new(0.25, 0.125, 0.0));
    assert!(
        (c.layer.specular - Vec3::new(0.99, 0.495, 0.2475))
            .abs()
            .max_element()
            < 1e-6
    );
    let nested = &scene.materials[c.layer.nested_index as usize];
    assert!((c.layer.nested_index as usize) < coatings[0].0);
    assert_eq!(nested.bsdf.kind(), "diffuse");
    let mut record = GpuMaterial::zeroed();
    nested
        .bsdf
        .pack(&mut record, &Default::default(), &mut Vec::new());
    assert_eq!(record.albedo, [0.2, 0.3, 0.4]);
    let r = coatings[1].1.get::<RoughCoating>().expect("roughcoating");
    assert_close("default eta", r.layer.eta, 1.5046 / 1.000277, 1e-6);
    assert_eq!(r.layer.optical_depth, Vec3::ZERO);
    assert_eq!(r.layer.specular, Vec3::ONE);
    assert_eq!(r.microfacet.alpha_u, 0.1);
    let c = coatings[2].1.get::<Coating>().expect("coating");
    assert_eq!(c.layer.specular, Vec3::new(2.0, 1.0, 0.5));
}

/// Both are Mitsuba 0.6 plugins: a version 3 file is refused at the element's line with the
/// version named. Catches a file Mitsuba 3 would refuse loading as if it were a 0.6 one.
#[test]
fn version_3_files_refuse_the_coatings() {
    for kind in ["coating", "roughcoating"] {
        let bsdf = format!(r#"<bsdf type="{kind}"><bsdf type="diffuse"/></bsdf>"#);
        let err = scene_with("3.0.0", &[&bsdf]).expect_err(kind).to_string();
        assert!(err.starts_with("m06.xml:2:"), "{err}");
        assert!(
            err.contains(&format!(
                "{kind} is a Mitsuba 0.6 plugin; this file is version 3.0.0"
            )),
            "{err}"
        );
        scene_with("0.6.0", &[&bsdf]).unwrap_or_else(|e| panic!("{e}"));
    }
}

/// Malformed coatings are errors at their line (line 2) saying what is wrong: a negative
/// thickness or sigmaA, no nested BSDF, two, a nested kind the coating cannot reach on the GPU
/// (a smooth dielectric, a mask, a twosided, a textured diffuse), equal indices, a roughcoating
/// alpha outside 0.6's tables or anisotropic. Catches a coating that would render nothing or
/// something else silently.
#[test]
fn bad_coatings_are_errors_at_their_line() {
    let cases = [
        (
            coating_xml(r#"<float name="thickness" value="-1"/>"#, WHITE_DIFFUSE),
            "thickness",
        ),
        (
            coating_xml(r#"<rgb name="sigmaA" value="0.1 -0.2 0"/>"#, WHITE_DIFFUSE),
            "sigmaA",
        ),
        (coating_xml("", ""), "needs a nested <bsdf>"),
        (
            coating_xml("", &format!("{WHITE_DIFFUSE}{WHITE_DIFFUSE}")),
            "only a single nested BSDF",
        ),
        (
            coating_xml("", r#"<bsdf type="dielectric"/>"#),
            "a nested dielectric is not supported; hppm coats diffuse, roughconductor",
        ),
        (
            coating_xml("", r#"<bsdf type="mask"><bsdf type="diffuse"/></bsdf>"#),
            "a nested blend is not supported",
        ),
        (
            coating_xml("", r#"<bsdf type="twosided"><bsdf type="diffuse"/></bsdf>"#),
            "twosided",
        ),
        (
            coating_xml(
                "",
                r#"<bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf>"#,
            ),
            "textured nested BSDF",
        ),
        (
            coating_xml(r#"<float name="intIOR" value="1.3"/><float name="extIOR" value="1.3"/>"#, WHITE_DIFFUSE),
            "must differ",
        ),
        (
            r#"<bsdf type="roughcoating"><float name="alpha" value="5"/><bsdf type="diffuse"/></bsdf>"#.into(),
            "outside the range [0, 4]",
        ),
        (
            r#"<bsdf type="roughcoating"><float name="intIOR" value="5"/><bsdf type="diffuse"/></bsdf>"#.into(),
            "outside the range",
        ),
        (
            r#"<bsdf type="roughcoating"><float name="alphaU" value="0.1"/><float name="alphaV" value="0.3"/><bsdf type="diffuse"/></bsdf>"#.into(),
            "anisotropic",
        ),
    ];
    for (bsdf, expected) in &cases {
        let err = scene_with("0.6.0", &[bsdf]).expect_err(bsdf).to_string();
        assert!(err.starts_with("m06.xml:2:"), "{bsdf}: {err}");
        assert!(err.contains(expected), "{bsdf}: {err}");
    }
}

/// A small 0.6 box for hybrid == pt: a coated diffuse back wall (intIOR 8, so that its delta
/// reflection sends over half of the light it gets onto the floor and ceiling: a caustic L S D
/// the hybrid photon-maps), a small coated panel on the floor tilted to reflect the light onto
/// the left wall (a bright caustic patch there; its layer absorbs) and a rough-coated rough
/// conductor sphere smoother than the hybrid's glossy_threshold (its reflection a glossy
/// caustic below the threshold, its nested lobe path traced), under an area light.
const COATED_BOX: &str = r#"<scene version="0.6.0">
    <integrator type="path"><integer name="maxDepth" value="6"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="toWorld"><lookat origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/></film>
    </sensor>
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf>
    <shape type="rectangle"><transform name="toWorld"><matrix value="0 1 0 0 0 0 1 -1 1 0 0 0 0 0 0 1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="1 0 0 0 0 0 -1 1 0 1 0 0 0 0 0 1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="1 0 0 0 0 1 0 0 0 0 1 -1 0 0 0 1"/></transform>
        <bsdf type="coating"><float name="intIOR" value="8"/><float name="extIOR" value="1"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.3"/></bsdf></bsdf></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="0 0 1 -1 1 0 0 0 0 1 0 0 0 0 0 1"/></transform>
        <bsdf type="coating"><float name="intIOR" value="8"/><float name="extIOR" value="1"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.1, 0.1"/></bsdf></bsdf></shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="0 0 -1 1 0 1 0 0 1 0 0 0 0 0 0 1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.5, 0.1"/></bsdf></shape>
    <shape type="rectangle">
        <transform name="toWorld"><matrix value="0.5 0 0 0 0 0 -1 0.99 0 0.5 0 0 0 0 0 1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="5, 4.5, 3.7"/></emitter>
    </shape>
    <shape type="rectangle"><transform name="toWorld"><matrix value="0 0.1414 -0.7071 -0.2 0 0.1414 0.7071 -0.8 0.2 0 0 0.2 0 0 0 1"/></transform>
        <bsdf type="coating"><float name="intIOR" value="8"/><float name="extIOR" value="1"/><rgb name="sigmaA" value="0.2, 0.1, 0"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.3, 0.6"/></bsdf></bsdf></shape>
    <shape type="sphere"><point name="center" x="0.3" y="-0.6" z="-0.2"/><float name="radius" value="0.4"/>
        <bsdf type="roughcoating"><float name="alpha" value="0.05"/><float name="intIOR" value="1.8"/>
            <bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></bsdf></shape>
</scene>"#;

/// The hybrid renders `pt`'s image of a 0.6 box whose caustics come off the coatings
/// (tests/common/convergence.rs: same camera paths, the image mean and every 8x8 block within
/// their tolerances, the caustic large enough that dropping or doubling it fails, a caustic moved
/// by a block refused). Measured: hybrid - pt -0.00005 +- 0.00086 in red against a tolerance of
/// 0.0043, the caustic 5.2% of the image. Catches a coating lobe the camera and photon passes
/// classify differently: the reflection specular on one side only, the light through the
/// interface into the base deposited as at a Lambertian vertex (it is path traced, as plastic's
/// base), the rough coating's glossy split applied by one pass only. About 4 s with lavapipe's
/// shader cache warm, 30 s cold.
#[test]
fn hybrid_equals_pt_through_coatings() {
    let scene = hppm::loaders::mitsuba::parse(Path::new("coated_box.xml"), COATED_BOX)
        .unwrap_or_else(|e| panic!("{e}"));
    common::convergence::hybrid_equals_pt("coated_box", "graphs/hybrid.ron", &scene);
}

/// The rough coating's glossy split on the GPU (`GLOSSY`, threshold 0.2): at alpha 0.1 its
/// reflection lobe is specular, so the split gives the CPU model's reflection alone and its
/// share of f per channel (coloured nested base, tinted reflection); at alpha 0.3 it gives
/// nothing, and the smooth coating's continuous part is never split. 400 pairs each, half near
/// the mirror direction. Catches a split that returns the whole BSDF or the nested lobe, and
/// alpha packed where the threshold test does not read it.
#[test]
fn the_gpu_glossy_split_takes_the_rough_coatings_reflection() {
    let gpu = common::gpu();
    let threshold = 0.2f32;
    let bsdfs = [
        r#"<bsdf type="roughcoating"><float name="alpha" value="0.1"/><rgb name="specularReflectance" value="0.9 0.6 0.3"/><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.8"/></bsdf></bsdf>"#,
        r#"<bsdf type="roughcoating"><float name="alpha" value="0.3"/><bsdf type="roughconductor"/></bsdf>"#,
        r#"<bsdf type="coating"><bsdf type="roughconductor"><float name="alpha" value="0.05"/></bsdf></bsdf>"#,
    ];
    let scene = scene_with("0.6.0", &bsdfs).unwrap_or_else(|e| panic!("{e}"));
    // The coatings' materials (their nested ones come before each).
    let coatings: Vec<usize> = (0..scene.materials.len())
        .filter(|&i| scene.materials[i].bsdf.kind().contains("coating"))
        .collect();
    assert_eq!(coatings.len(), 3);
    let (pairs, answers) = glossy_split_on_gpu(&gpu, &scene, &coatings, 400, 78, threshold);

    let mut failures = Vec::new();
    let mut lobe_seen = 0;
    for (i, (material, wi, wo)) in pairs.iter().enumerate() {
        let bsdf = &scene.materials[*material].bsdf;
        let full = bsdf.eval(*wi, *wo, Mode::Radiance);
        let (want_spec, want_share) = match bsdf.get::<RoughCoating>() {
            Some(rc) if rc.microfacet.alpha_u < threshold => {
                let lobe = rc.reflection(*wi, *wo);
                lobe_seen += (lobe.max_element() > 1e-3 * full.max_element()) as usize;
                let share = Vec3::select(full.cmpgt(Vec3::ZERO), lobe / full, Vec3::ZERO);
                (lobe, share)
            }
            _ => (Vec3::ZERO, Vec3::ZERO),
        };
        let got_spec = Vec3::from_slice(&answers[2 * i][..3]);
        let got_share = Vec3::from_slice(&answers[2 * i + 1][..3]);
        let near = |a: Vec3, b: Vec3| {
            (a - b).abs().max_element() <= 2e-3 * a.abs().max(b.abs()).max_element() + 1e-5
        };
        if !near(got_spec, want_spec) || !near(got_share, want_share) {
            failures.push(format!(
                "material {material} wi {wi} wo {wo}: GPU lobe {got_spec} share {got_share}, \
                 expected {want_spec} {want_share}"
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} differ:\n{}",
        failures.len(),
        pairs.len(),
        failures[..failures.len().min(20)].join("\n")
    );
    assert!(lobe_seen > 100, "{lobe_seen}");
}
