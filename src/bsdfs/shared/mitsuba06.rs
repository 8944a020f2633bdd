//! What the units of Mitsuba 0.6's plugins that Mitsuba 3 dropped (`roughdiffuse`, `phong`,
//! `ward`) share: the refusal of them in files of version 2 and later, Mitsuba 0.6's energy
//! conservation of its reflectances (`BSDF::ensureEnergyConservation`,
//! src/librender/bsdf.cpp), the weight `phong` and `ward` pick their specular lobe by, and the
//! frame 0.6 builds about a direction (`coordinateSystem`, src/libcore/util.cpp).

use glam::{Vec2, Vec3};

use crate::bsdfs::BsdfReader;
use crate::bsdfs::shared::microfacet::square_to_cosine_hemisphere;
use crate::scene::bsdf::GpuMaterial;
use crate::scene::texture::luminance;
use crate::scene::{SceneError, SideTextures};

/// Refuses the element in a file read with Mitsuba 3's rules (one that declares version 2 or
/// later, or none): Mitsuba 2 and 3 dropped `roughdiffuse`, `phong` and `ward`.
pub fn only_in_mitsuba06(r: &dyn BsdfReader) -> Result<(), SceneError> {
    if r.legacy() {
        return Ok(());
    }
    let version = r.file_version().unwrap_or_else(|| "not given".into());
    Err(r.error(format!(
        "{} is a Mitsuba 0.6 plugin; this file is version {version} (Mitsuba 2 and 3 have no \
         {}; hppm reads it from files of version 0.x only)",
        r.plugin(),
        r.plugin()
    )))
}

/// Mitsuba 0.6's `ensureEnergyConservation` property (true by default): whether the unit scales
/// its reflectances down when they could reflect more than comes in.
pub fn ensures_energy_conservation(r: &mut dyn BsdfReader) -> Result<bool, SceneError> {
    Ok(r.boolean("ensure_energy_conservation")?.unwrap_or(true))
}

/// A reflectance as Mitsuba 0.6 reads it: a colour or a texture, with what its checks need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reflectance {
    /// The colour, or the texture's scalar mean (the CPU model's stand-in for it).
    pub value: Vec3,
    pub texture: Option<u32>,
    /// Its mean colour (`getAverage`): the colour, or the texture's.
    pub average: Vec3,
    /// Its largest value per channel (`getMaximum`).
    pub maximum: Vec3,
}

/// Property `name` (`default` when absent), a colour or a texture, not negative.
pub fn reflectance(
    r: &mut dyn BsdfReader,
    name: &str,
    default: f32,
) -> Result<Reflectance, SceneError> {
    let (value, texture) = r.color_or_texture(name, default)?;
    let (average, maximum) = texture
        .and_then(|t| r.texture_average_and_maximum(t))
        .unwrap_or((value, value));
    Ok(Reflectance {
        value,
        texture,
        average,
        maximum,
    })
}

/// The factor 0.6's `ensureEnergyConservation` scales reflectances by whose maxima, summed per
/// channel, come to `sum_of_maxima`: 0.99 / the largest channel where that is above 1, else 1
/// (and 1 when the file turns the check off).
pub fn energy_scale(ensure: bool, sum_of_maxima: Vec3) -> f32 {
    let largest = sum_of_maxima.max_element();
    if ensure && largest > 1.0 {
        0.99 / largest
    } else {
        1.0
    }
}

/// The diffuse and specular reflectances of `phong` and `ward` (0.5 and 0.2 by default,
/// colours or textures), as 0.6's `configure` leaves them: scaled together when their maxima
/// sum to more than 1, and the probability of sampling the specular lobe, the luminance of the
/// specular reflectance's mean over both means' (`m_specularSamplingWeight`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseAndSpecular {
    /// As given (a texture's scalar mean where textured); `scale` applies to both.
    pub diffuse: Vec3,
    pub specular: Vec3,
    /// 0.6's energy-conservation factor (1 unless the sum exceeded 1).
    pub scale: f32,
    /// The probability of choosing the specular lobe.
    pub specular_weight: f32,
}

impl DiffuseAndSpecular {
    /// 0.6's sampling of the two lobes: the specular one (`specular`'s direction, `None` where
    /// it falls below the surface) with probability `specular_weight`, else the diffuse one,
    /// cosine-weighted; the direction `wo` drawn.
    pub fn sample_direction(
        &self,
        wi: Vec3,
        u1: f32,
        u2: Vec2,
        specular: impl FnOnce(Vec2) -> Vec3,
    ) -> Option<Vec3> {
        if wi.z <= 0.0 {
            return None;
        }
        if u1 < self.specular_weight {
            Some(specular(u2)).filter(|wo| wo.z > 0.0)
        } else {
            Some(square_to_cosine_hemisphere(u2))
        }
    }

    /// The lobes into the GPU record: reflectances, 0.6's scale (in `int_ior`) and the
    /// specular lobe's probability.
    pub fn pack(&self, record: &mut GpuMaterial) {
        record.albedo = self.diffuse.to_array();
        record.specular = self.specular.to_array();
        record.int_ior = self.scale;
        record.specular_weight = self.specular_weight;
    }

    /// Reads `diffuse_reflectance` and `specular_reflectance` (textures into the diffuse and
    /// specular slots) and `ensure_energy_conservation`.
    pub fn read(r: &mut dyn BsdfReader, textures: &mut SideTextures) -> Result<Self, SceneError> {
        let diffuse = reflectance(r, "diffuse_reflectance", 0.5)?;
        let specular = reflectance(r, "specular_reflectance", 0.2)?;
        let ensure = ensures_energy_conservation(r)?;
        textures.diffuse = diffuse.texture;
        textures.specular = specular.texture;
        Ok(Self::new(diffuse, specular, ensure))
    }

    pub fn new(diffuse: Reflectance, specular: Reflectance, ensure: bool) -> Self {
        let scale = energy_scale(ensure, diffuse.maximum + specular.maximum);
        DiffuseAndSpecular {
            diffuse: diffuse.value,
            specular: specular.value,
            scale,
            specular_weight: specular_sampling_weight(diffuse.average, specular.average),
        }
    }

    /// Untextured reflectances, checked as 0.6 checks them (what tests build models from).
    pub fn constant(diffuse: Vec3, specular: Vec3) -> Self {
        let constant = |v: Vec3| Reflectance {
            value: v,
            texture: None,
            average: v,
            maximum: v,
        };
        Self::new(constant(diffuse), constant(specular), true)
    }

    pub fn is_valid(&self) -> bool {
        self.diffuse.is_finite()
            && self.specular.is_finite()
            && self.diffuse.min_element() >= 0.0
            && self.specular.min_element() >= 0.0
            && self.scale.is_finite()
            && (0.0..=1.0).contains(&self.specular_weight)
    }
}

/// 0.6's `m_specularSamplingWeight`: sAvg / (dAvg + sAvg) of the means' luminances. Where both
/// are 0 (a black BSDF, which 0.6 leaves at 0 / 0) the diffuse lobe is sampled.
pub fn specular_sampling_weight(diffuse_average: Vec3, specular_average: Vec3) -> f32 {
    let d = luminance(diffuse_average);
    let s = luminance(specular_average);
    if d + s > 0.0 { s / (d + s) } else { 0.0 }
}

/// The two directions 0.6's `Frame(n)` puts beside a unit `n` (`coordinateSystem`): `s` and
/// `t` with (s, t, n) right-handed. Phong's lobe is sampled in this frame about the mirror
/// direction; `phong.wgsl` builds the same one.
pub fn coordinate_system(n: Vec3) -> (Vec3, Vec3) {
    let t = if n.x.abs() > n.y.abs() {
        let inv = 1.0 / (n.x * n.x + n.z * n.z).sqrt();
        Vec3::new(n.z * inv, 0.0, -n.x * inv)
    } else {
        let inv = 1.0 / (n.y * n.y + n.z * n.z).sqrt();
        Vec3::new(0.0, n.z * inv, -n.y * inv)
    };
    (t.cross(n), t)
}
