//! The tint dielectrics take (`specular_reflectance`, `specular_transmittance`).

use glam::Vec3;

/// A dielectric's `specular_reflectance` and `specular_transmittance` (Mitsuba's, 1 by
/// default): factors on the light it reflects and transmits. Not physical (energy is not
/// conserved when they differ from 1), but scenes use them to tint glass. Textures on them sit
/// in the material's specular (reflectance) and diffuse (transmittance) texture slots.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tint {
    pub reflectance: Vec3,
    pub transmittance: Vec3,
}

impl Tint {
    /// Mitsuba's default: no tint.
    pub const NONE: Tint = Tint {
        reflectance: Vec3::ONE,
        transmittance: Vec3::ONE,
    };

    /// The factor on reflected (`true`) or transmitted light.
    pub fn factor(&self, reflected: bool) -> Vec3 {
        if reflected {
            self.reflectance
        } else {
            self.transmittance
        }
    }
}

impl Tint {
    pub fn is_valid(&self) -> bool {
        self.reflectance.is_finite() && self.transmittance.is_finite()
    }
}
