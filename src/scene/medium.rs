//! Participating media as Mitsuba 3 defines them (src/media/homogeneous.cpp, src/phase/): a
//! homogeneous medium of extinction `sigma_t` (per unit of scene length, `scale` applied) and
//! single-scattering albedo, with a phase function. Media fill the inside or outside of shapes
//! (`interior` / `exterior`) and the space around the camera; a path's medium changes only where
//! it crosses a shape that names one. The CPU forms here are what the tests check the WGSL
//! (shaders/common/medium.wgsl) against.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3};

use crate::scene::grid::{FilterType, Grid, WrapMode};

/// How a medium scatters light: the density over directions of leaving along `wo` having
/// travelled along `d_in` (both unit, world space). Each integrates to 1 over the sphere and is
/// sampled exactly, so a sample's weight is 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Phase {
    Isotropic,
    /// Henyey-Greenstein with mean cosine `g` in (-1, 1): forward scattering for g > 0.
    HenyeyGreenstein {
        g: f32,
    },
    /// Rayleigh's 3 / (16 pi) (1 + cos^2).
    Rayleigh,
}

impl Phase {
    /// Density of scattering from travel direction `d_in` into `wo`.
    pub fn eval(&self, d_in: Vec3, wo: Vec3) -> f32 {
        let cos = d_in.dot(wo).clamp(-1.0, 1.0);
        match *self {
            Phase::Isotropic => 1.0 / (4.0 * PI),
            Phase::HenyeyGreenstein { g } => henyey_greenstein(g, cos),
            Phase::Rayleigh => 3.0 / (16.0 * PI) * (1.0 + cos * cos),
        }
    }

    /// A direction drawn from [`Phase::eval`] around `d_in`, from two uniform numbers.
    pub fn sample(&self, d_in: Vec3, u: Vec2) -> Vec3 {
        let cos = match *self {
            Phase::Isotropic => 1.0 - 2.0 * u.x,
            Phase::HenyeyGreenstein { g } => henyey_greenstein_cos(g, u.x),
            Phase::Rayleigh => rayleigh_cos(u.x),
        };
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let (b1, b2) = d_in.any_orthonormal_pair();
        (b1 * (sin * phi.cos()) + b2 * (sin * phi.sin()) + d_in * cos).normalize()
    }

    /// The WGSL's phase kind (common::medium's PHASE_*) and its parameter.
    pub fn gpu(&self) -> (u32, f32) {
        match *self {
            Phase::Isotropic => (0, 0.0),
            Phase::HenyeyGreenstein { g } => (1, g),
            Phase::Rayleigh => (2, 0.0),
        }
    }
}

fn henyey_greenstein(g: f32, cos: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// The cosine between travel and scattered direction with HG's density, by inversion of its CDF
/// (the form Mitsuba's hg.cpp uses, with the sign of our `cos`).
fn henyey_greenstein_cos(g: f32, u: f32) -> f32 {
    if g.abs() < 1e-3 {
        return 1.0 - 2.0 * u;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// Rayleigh's cosine by inverting its CDF (3 cos + cos^3 + 4) / 8 = u: the real root of the
/// cubic, by Cardano's formula.
fn rayleigh_cos(u: f32) -> f32 {
    let q = 4.0 * u - 2.0;
    let d = (q * q + 1.0).sqrt();
    let a = (q + d).cbrt();
    let b = (q - d).cbrt();
    (a + b).clamp(-1.0, 1.0)
}

/// A medium: Mitsuba's `homogeneous`, or its `heterogeneous` with a grid of extinction.
#[derive(Debug, Clone, PartialEq)]
pub struct Medium {
    /// Extinction per unit length, `scale` applied; with `density`, what the grid's value
    /// multiplies.
    pub sigma_t: Vec3,
    /// Single-scattering albedo: sigma_s = albedo sigma_t.
    pub albedo: Vec3,
    pub phase: Phase,
    /// Mitsuba's `sample_emitters`: next-event estimation at its scattering points.
    pub sample_emitters: bool,
    /// A heterogeneous medium's grid (Mitsuba's `gridvolume` as its `sigma_t`).
    pub density: Option<Density>,
}

/// A grid of extinction placed in the world (Mitsuba's `gridvolume`: the grid fills the unit
/// cube of its local space, src/scene/grid.rs).
#[derive(Debug, Clone, PartialEq)]
pub struct Density {
    pub grid: Arc<Grid>,
    /// World to the grid's unit cube (`to_world`'s inverse, and the file's box with
    /// `use_grid_bbox`).
    pub to_local: Mat4,
    pub filter: FilterType,
    pub wrap: WrapMode,
}

impl Medium {
    /// The fraction of light that crosses `distance` without interacting (a homogeneous
    /// medium's).
    pub fn transmittance(&self, distance: f32) -> Vec3 {
        (-self.sigma_t * distance).exp()
    }

    /// Extinction at world point `p`.
    pub fn extinction_at(&self, p: Vec3) -> Vec3 {
        match &self.density {
            None => self.sigma_t,
            Some(d) => {
                self.sigma_t
                    * d.grid
                        .eval_with(d.to_local.transform_point3(p), d.filter, d.wrap)
            }
        }
    }

    /// The largest extinction anywhere (a grid medium's majorant, as Mitsuba's: `scale` times
    /// the grid's largest value, here times the largest channel of `sigma_t`).
    pub fn majorant(&self) -> f32 {
        let grid = self.density.as_ref().map_or(1.0, |d| d.grid.max().max(0.0));
        self.sigma_t.max_element() * grid
    }

    pub fn sigma_s(&self) -> Vec3 {
        self.sigma_t * self.albedo
    }

    /// The record the WGSL reads (common::medium), `MEDIUM_RECORD_FLOATS` floats; `grid` is
    /// where its grid's values start in the same tables (ignored without a grid).
    pub fn gpu_record(&self, grid: u32) -> [f32; MEDIUM_RECORD_FLOATS] {
        let (kind, g) = self.phase.gpu();
        let s = self.sigma_t;
        let a = self.albedo;
        let mut r = [0.0f32; MEDIUM_RECORD_FLOATS];
        r[..8].copy_from_slice(&[s.x, s.y, s.z, kind as f32, a.x, a.y, a.z, g]);
        let nearest = matches!(&self.density, Some(d) if d.filter == FilterType::Nearest);
        r[8] = (self.sample_emitters as u32 | (nearest as u32) << 1) as f32;
        // An offset as its bits: exact beyond 2^24 floats of tables.
        r[9] = f32::from_bits(if self.density.is_some() {
            grid
        } else {
            NO_GRID
        });
        r[10] = self.majorant();
        if let Some(d) = &self.density {
            r[11] = d.grid.channels as f32;
            r[12..15].copy_from_slice(&d.grid.size.map(|n| n as f32));
            r[15] = match d.wrap {
                WrapMode::Clamp => 0.0,
                WrapMode::Repeat => 1.0,
                WrapMode::Mirror => 2.0,
            };
            let m = d.to_local.to_cols_array_2d();
            for row in 0..3 {
                for col in 0..4 {
                    r[16 + 4 * row + col] = m[col][row];
                }
            }
        }
        r
    }
}

/// Floats per medium in the scene's float tables.
pub const MEDIUM_RECORD_FLOATS: usize = 28;
/// A record's grid offset for a medium without one (common::medium's NO_GRID).
pub const NO_GRID: u32 = u32::MAX;

/// The media on the two sides of a shape (Mitsuba's `interior` and `exterior`, indices of
/// [`Media::list`]). A shape that names neither leaves a path's medium as it was.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MediumInterface {
    pub interior: Option<u32>,
    pub exterior: Option<u32>,
}

impl MediumInterface {
    /// Whether crossing the shape changes the medium (Mitsuba's `is_medium_transition`).
    pub fn is_transition(&self) -> bool {
        self.interior.is_some() || self.exterior.is_some()
    }

    /// The medium on the side `dir` leaves towards, given the shape's geometric normal (front:
    /// the exterior), as Mitsuba's `target_medium`.
    pub fn target(&self, dir: Vec3, normal: Vec3) -> Option<u32> {
        if dir.dot(normal) > 0.0 {
            self.exterior
        } else {
            self.interior
        }
    }
}

/// A scene's media: the list shapes and the camera refer to, and the camera's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Media {
    pub list: Vec<Medium>,
    /// The medium around the sensor (Mitsuba's sensor `medium`): where camera paths start.
    pub camera: Option<u32>,
}

impl Media {
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }
}
