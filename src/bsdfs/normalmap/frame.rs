//! Mitsuba 3's `normalmap` and `bumpmap` BSDFs: the shading frame a texture perturbs, in which
//! the nested BSDF is then evaluated and sampled. Written from Mitsuba 3.9.1's
//! `src/bsdfs/normalmap.cpp`, `bumpmap.cpp` and `normalmap_helpers.h`, with the unperturbed
//! frame and dp_du / dp_dv as its shapes build them (`src/render/mesh.cpp`
//! `compute_surface_interaction`, `src/shapes/sphere.cpp`, `interaction.h`
//! `initialize_sh_frame`). This is the CPU reference of `normalmap.wgsl` beside it;
//! tests/normal_map.rs checks both against frames read from Mitsuba itself.
//!
//! How the nestings with `twosided` differ: `twosided` turns the local directions over (z to
//! -z) before its nested BSDF sees them and leaves the surface's frame alone. So for
//! `twosided` > `normalmap` the back is perturbed in the frame (s, t, -n), the texture's normal
//! read in it as on the front; for `normalmap` > `twosided` the frame is perturbed as on the
//! front and its normal then turned over, (s', t', -n'). The local numbers each yields are
//! exactly the directions Mitsuba's nested BSDF is handed.

use glam::{Vec2, Vec3};

use crate::scene::texture::Texture;
use crate::scene::{FramePerturbation, PerturbationKind};

/// What the perturbation reads of the surface point, for its front side as the shape defines
/// it (after `flip_normals`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceGeometry {
    pub uv: Vec2,
    /// The geometric normal (Mitsuba's `si.n`).
    pub normal: Vec3,
    /// The unperturbed shading normal (`si.sh_frame.n`).
    pub shading_normal: Vec3,
    /// The derivatives of the position in the texture coordinates.
    pub dp_du: Vec3,
    pub dp_dv: Vec3,
}

/// A perturbed shading frame in world space: the nested BSDF's local x, y and z axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerturbedFrame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
    /// The unperturbed shading normal of the side seen, which decides the masking and the
    /// shadow terminator's angle.
    pub base: Vec3,
    /// Estevez et al.'s alpha squared for the perturbed normal; `None` without the shadow
    /// terminator.
    pub alpha2: Option<f32>,
}

impl PerturbedFrame {
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// What Mitsuba multiplies the nested BSDF's value (and sampled weight) by for the light's
    /// direction `light` (its `wo`, unit, world space): 0 where the unperturbed and perturbed
    /// frames put it on different sides, else the shadow terminator
    /// 2 / (1 + sqrt(1 + alpha^2 tan^2 theta)), theta from the unperturbed normal.
    pub fn factor(&self, light: Vec3) -> f32 {
        let cos_base = light.dot(self.base);
        let agree = cos_base * light.dot(self.n);
        if agree.is_nan() || agree <= 0.0 {
            return 0.0;
        }
        match self.alpha2 {
            Some(alpha2) => 2.0 / (1.0 + (1.0 + alpha2 * tan_theta_2(cos_base)).sqrt()),
            None => 1.0,
        }
    }
}

/// Mitsuba's `Frame3f::tan_theta_2` of a unit vector whose z (cosine) is `cos`.
fn tan_theta_2(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0) / (cos * cos)
}

/// Mitsuba's `coordinate_system` (Duff et al. 2017): two tangents completing unit `n`.
pub fn coordinate_system(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(sign * n.x * n.x * a + 1.0, sign * b, -sign * n.x),
        Vec3::new(b, n.y * n.y * a + sign, -n.y),
    )
}

/// Mitsuba's `initialize_sh_frame`: the tangent is dp_du made perpendicular to the shading
/// normal, or `coordinate_system`'s first where dp_du is zero; the bitangent n x s.
pub fn shading_tangents(n: Vec3, dp_du: Vec3) -> (Vec3, Vec3) {
    let s = if dp_du == Vec3::ZERO {
        coordinate_system(n).0
    } else {
        (dp_du - n * n.dot(dp_du)).normalize()
    };
    (s, n.cross(s))
}

/// A triangle's dp_du and dp_dv from its corners `p` and texture coordinates `uv` (Mitsuba's
/// mesh: without texture coordinates they are the barycentrics, dp_du = p1 - p0); where the
/// texture coordinates are degenerate (zero determinant), `coordinate_system` of the face
/// normal `face_normal` as Mitsuba falls back.
pub fn triangle_derivatives(p: [Vec3; 3], uv: [Vec2; 3], face_normal: Vec3) -> (Vec3, Vec3) {
    let (dp0, dp1) = (p[1] - p[0], p[2] - p[0]);
    let (duv0, duv1) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    if det == 0.0 {
        return coordinate_system(face_normal);
    }
    let inv = 1.0 / det;
    (
        (duv1.y * dp0 - duv0.y * dp1) * inv,
        (duv0.x * dp1 - duv1.x * dp0) * inv,
    )
}

/// A sphere's dp_du and dp_dv at unit direction `d` from its centre (Mitsuba's sphere, whose
/// u turns about +z and v runs from +z down; the sphere unrotated, as hppm keeps them).
pub fn sphere_derivatives(d: Vec3, radius: f32) -> (Vec3, Vec3) {
    let dp_du = Vec3::new(-d.y, d.x, 0.0) * (2.0 * std::f32::consts::PI * radius);
    let rd = (d.x * d.x + d.y * d.y).sqrt();
    let local = if rd == 0.0 {
        Vec3::X
    } else {
        Vec3::new(d.z * d.x / rd, d.z * d.y / rd, -rd)
    };
    (dp_du, local * (std::f32::consts::PI * radius))
}

/// The frame `perturbation` gives the side seen (`back`: the back of a `twosided`) at a point
/// of `geometry`, `texture` being its texture. `toward_viewer` (unit, world space) is where
/// the camera path came from: Mitsuba's `flip_invalid_normals` mirrors the normal's
/// tangential part when that direction sees it from below. `None` leaves it unflipped, what
/// photons use (they do not know the viewer yet).
pub fn perturbed_frame(
    perturbation: &FramePerturbation,
    texture: &Texture,
    geometry: &SurfaceGeometry,
    back: bool,
    toward_viewer: Option<Vec3>,
) -> PerturbedFrame {
    let g = geometry;
    let n_sh = g.shading_normal;
    let (s, t) = shading_tangents(n_sh, g.dp_du);
    let mut local = match perturbation.kind {
        PerturbationKind::Normal => texture.eval(g.uv) * 2.0 - Vec3::ONE,
        PerturbationKind::Bump { scale } => {
            let grad = scale * texture.eval_1_grad(g.uv);
            let du = g.dp_du + n_sh * (grad.x - n_sh.dot(g.dp_du));
            let dv = g.dp_dv + n_sh * (grad.y - n_sh.dot(g.dp_dv));
            let mut n = du.cross(dv).normalize();
            if g.normal.dot(n) < 0.0 {
                n = -n;
            }
            Vec3::new(n.dot(s), n.dot(t), n.dot(n_sh))
        }
    };
    let inside_back = back && !perturbation.outside_twosided;
    let frame_n = if inside_back { -n_sh } else { n_sh };
    let to_world = |v: Vec3| s * v.x + t * v.y + frame_n * v.z;
    if perturbation.flip_invalid_normals
        && let Some(w) = toward_viewer
    {
        let wi = Vec3::new(w.dot(s), w.dot(t), w.dot(frame_n));
        if wi.z * wi.dot(local) <= 0.0 {
            local = Vec3::new(-local.x, -local.y, local.z);
        }
    }
    // A texel of (0.5, 0.5, 0.5) has no normal (Mitsuba's would be NaN): leave it unperturbed.
    let n = local.try_normalize().unwrap_or(Vec3::Z);
    let tangent = match perturbation.kind {
        PerturbationKind::Normal => (Vec3::X - n * n.x).try_normalize(),
        // bumpmap.cpp takes world-space dp_du's numbers as if local here; copied for the
        // anisotropic BSDFs whose tangent it sets.
        PerturbationKind::Bump { .. } => (g.dp_du - n * n.dot(g.dp_du)).try_normalize(),
    }
    .unwrap_or_else(|| coordinate_system(n).0);
    let bitangent = n.cross(tangent);
    let turned = if back && perturbation.outside_twosided {
        -1.0
    } else {
        1.0
    };
    PerturbedFrame {
        s: to_world(tangent),
        t: to_world(bitangent),
        n: turned * to_world(n),
        base: if back { -n_sh } else { n_sh },
        alpha2: perturbation
            .shadowing
            .then(|| (0.125 * tan_theta_2(n.z)).min(1.0)),
    }
}
