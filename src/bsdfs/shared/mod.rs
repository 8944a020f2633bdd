//! What several BSDF units share: Fresnel terms and microfacet distributions (each with its
//! WGSL twin beside it), the dielectrics' tint, the readers of properties several plugins
//! read alike (indices of refraction, roughness), and what the Mitsuba 0.6 units share
//! (`mitsuba06`).

pub mod fresnel;
pub mod microfacet;
pub mod mitsuba06;
pub mod tint;

use super::BsdfReader;
use crate::scene::{SceneError, SideTextures};
use microfacet::{Distribution, Microfacet};
use tint::Tint;

/// Mitsuba's defaults: BK7 glass inside a dielectric, air outside.
pub const BK7: f32 = 1.5046;
pub const AIR: f32 = 1.000277;

/// Mitsuba's named indices of refraction (include/mitsuba/render/ior.h).
pub const NAMED_IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// An index of refraction: a positive number or one of Mitsuba's named media (`default` when
/// absent).
pub fn ior(r: &mut dyn BsdfReader, name: &str, default: f32) -> Result<f32, SceneError> {
    if r.is_string(name) {
        let medium = r.string(name)?.unwrap_or_default();
        return NAMED_IORS
            .iter()
            .find(|(m, _)| *m == medium.to_ascii_lowercase())
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                let names: Vec<&str> = NAMED_IORS.iter().map(|(m, _)| *m).collect();
                r.error_at(
                    name,
                    format!("{name} \"{medium}\" is not one of {}", names.join(", ")),
                )
            });
    }
    let Some(v) = r.float(name)? else {
        return Ok(default);
    };
    if v <= 0.0 {
        return Err(r.error_at(name, format!("{name} {v}: must be positive")));
    }
    Ok(v)
}

/// `int_ior` and `ext_ior`, which the rough interfaces need to differ (as Mitsuba's do).
pub fn distinct_iors(r: &dyn BsdfReader, int_ior: f32, ext_ior: f32) -> Result<(), SceneError> {
    if int_ior == ext_ior {
        return Err(r.error(format!(
            "{}: int_ior and ext_ior are both {int_ior}; they must differ",
            r.describe()
        )));
    }
    Ok(())
}

/// A dielectric's `specular_reflectance` and `specular_transmittance` (1 by default), their
/// textures in the specular and diffuse slots.
pub fn dielectric_tint(
    r: &mut dyn BsdfReader,
    textures: &mut SideTextures,
) -> Result<Tint, SceneError> {
    let (reflectance, reflectance_texture) = r.color_or_texture("specular_reflectance", 1.0)?;
    let (transmittance, transmittance_texture) =
        r.color_or_texture("specular_transmittance", 1.0)?;
    textures.specular = reflectance_texture;
    textures.diffuse = transmittance_texture;
    Ok(Tint {
        reflectance,
        transmittance,
    })
}

/// The roughness a microfacet BSDF reads: one number (`roughplastic`), numbers that may differ
/// along u and v (`pplastic`), or numbers or textures along u and v (rough conductors and
/// dielectrics), as each Mitsuba plugin reads it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Alphas {
    Isotropic,
    Anisotropic,
    Textured,
}

/// `distribution`, `alpha` or `alpha_u` + `alpha_v`, `sample_visible` as Mitsuba's
/// MicrofacetDistribution reads them (Beckmann, alpha 0.1 by default). Textured roughness is
/// recorded in `textures`.
pub fn microfacet(
    r: &mut dyn BsdfReader,
    alphas: Alphas,
    textures: &mut SideTextures,
) -> Result<Microfacet, SceneError> {
    let distribution = match r.string("distribution")? {
        None => Distribution::Beckmann,
        Some(name) => match name.to_ascii_lowercase().as_str() {
            "beckmann" => Distribution::Beckmann,
            "ggx" => Distribution::Ggx,
            other => {
                return Err(r.error_at(
                    "distribution",
                    format!("distribution \"{other}\": expected \"beckmann\" or \"ggx\""),
                ));
            }
        },
    };
    let given = |r: &dyn BsdfReader, name: &str| r.has(name);
    let (a, au, av) = (given(r, "alpha"), given(r, "alpha_u"), given(r, "alpha_v"));
    // One alpha as the plugin reads it: a number, or with textured roughness its texture's mean.
    let read = |r: &mut dyn BsdfReader, name: &str| -> Result<(f32, Option<u32>), SceneError> {
        let (v, texture) = if alphas == Alphas::Textured {
            r.scalar_or_texture(name, 0.0)?
        } else {
            (r.float(name)?.unwrap_or(0.0), None)
        };
        if texture.is_none() && (v.is_nan() || v < 0.0) {
            let what = r.describe_property(name);
            return Err(r.error_at(name, format!("{what}: must not be negative")));
        }
        Ok((v, texture))
    };
    let (alpha_u, alpha_v) = match (a, au, av) {
        (true, false, false) => {
            let (v, texture) = read(r, "alpha")?;
            (textures.alpha_u, textures.alpha_v) = (texture, texture);
            (v, v)
        }
        (false, false, false) => (0.1, 0.1),
        (false, true, true) => {
            let (u, tu) = read(r, "alpha_u")?;
            let (v, tv) = read(r, "alpha_v")?;
            if alphas == Alphas::Isotropic && u != v {
                return Err(r.error(format!(
                    "{}: anisotropic roughness is not supported by Mitsuba's roughplastic; give \
                     one alpha",
                    r.describe()
                )));
            }
            (textures.alpha_u, textures.alpha_v) = (tu, tv);
            (u, v)
        }
        (true, _, _) => {
            return Err(r.error_at(
                "alpha",
                "give either alpha or alpha_u and alpha_v, not both".into(),
            ));
        }
        (false, u, _) => {
            let given = if u { "alpha_u" } else { "alpha_v" };
            return Err(r.error_at(given, "alpha_u and alpha_v must both be given".into()));
        }
    };
    if r.boolean("sample_visible")? == Some(false) {
        return Err(r.error_at(
            "sample_visible",
            "sample_visible false is not supported (visible normals are always sampled)".into(),
        ));
    }
    Ok(Microfacet {
        distribution,
        alpha_u,
        alpha_v,
    })
}
