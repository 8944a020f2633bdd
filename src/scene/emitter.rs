//! Lights that are not shapes, beside point lights: Mitsuba 3's `spot`, `projector`,
//! `directional`, `constant`, `envmap` and `sunsky` (its model in src/scene/sunsky), with what their GPU form needs (an environment map's
//! texels and its sampling tables) and their power (what photon emission must reproduce).

use std::f32::consts::PI;
use std::path::PathBuf;

use glam::{Mat3, Vec2, Vec3};

use super::sunsky::SunSkyMap;
use super::texture::{Texture, luminance};

/// Mitsuba's `spot`: intensity `intensity` along its axis, full out to `beam_width` from it,
/// falling linearly in angle to zero at `cutoff` (src/emitters/spot.cpp, `falloff_curve`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpotLight {
    pub position: Vec3,
    /// Unit direction the spot shines along (its local +z).
    pub axis: Vec3,
    /// W/sr per RGB channel on the axis.
    pub intensity: Vec3,
    /// Radians; `beam_width` <= `cutoff`.
    pub cutoff: f32,
    pub beam_width: f32,
    /// The spot's unit local x and y in the world, across which `texture` is laid.
    pub frame: [Vec3; 2],
    /// Mitsuba's projected `texture` (an index of `Scene::textures`), which multiplies the
    /// intensity at [`SpotLight::uv`] of each direction.
    pub texture: Option<u32>,
}

impl SpotLight {
    /// The falloff towards a direction at cosine `cos_theta` from the axis.
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        if cos_theta <= self.cutoff.cos() {
            return 0.0;
        }
        if cos_theta >= self.beam_width.cos() {
            return 1.0;
        }
        ((self.cutoff - cos_theta.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam_width))
            .clamp(0.0, 1.0)
    }

    /// The texture coordinates of a world direction (unit or not) leaving the spot, as
    /// Mitsuba's `direction_to_uv` has them: the local direction (x, y, z) projected on the
    /// plane z = 1, where the square |x|, |y| <= tan(cutoff) is [0, 1]^2, u along +x, v along
    /// +y.
    pub fn uv(&self, dir: Vec3) -> Vec2 {
        let local = Vec3::new(
            dir.dot(self.frame[0]),
            dir.dot(self.frame[1]),
            dir.dot(self.axis),
        );
        let scale = 0.5 / (local.z * self.cutoff.tan());
        Vec2::new(0.5 + local.x * scale, 0.5 + local.y * scale)
    }

    /// Emitted power, untextured or with `textures` (the scene's): for a textured spot the
    /// integral of intensity x falloff x texture over the cone by the midpoint rule in (theta,
    /// phi), fine enough (256 x 512 cells) that a texture's structure averages out to well
    /// under a percent; it only shares photons between lights, so an error there costs noise,
    /// never bias.
    pub fn power_with(&self, textures: &[Texture]) -> Vec3 {
        let Some(texture) = self.texture.and_then(|t| textures.get(t as usize)) else {
            return self.power();
        };
        let (n_theta, n_phi) = (256usize, 512usize);
        let cutoff = self.cutoff.min(PI) as f64;
        let (d_theta, d_phi) = (
            cutoff / n_theta as f64,
            2.0 * std::f64::consts::PI / n_phi as f64,
        );
        let mut sum = glam::DVec3::ZERO;
        for i in 0..n_theta {
            let theta = (i as f64 + 0.5) * d_theta;
            let (sin, cos) = theta.sin_cos();
            let falloff = self.falloff(cos as f32) as f64;
            if falloff <= 0.0 {
                continue;
            }
            for j in 0..n_phi {
                let phi = (j as f64 + 0.5) * d_phi;
                let dir = (self.frame[0] * (sin * phi.cos()) as f32)
                    + (self.frame[1] * (sin * phi.sin()) as f32)
                    + self.axis * cos as f32;
                sum += texture.eval(self.uv(dir)).as_dvec3() * (falloff * sin);
            }
        }
        self.intensity * (sum * d_theta * d_phi).as_vec3()
    }

    /// Emitted power: the integral of intensity x falloff over the sphere, in closed form,
    /// 2 pi I [1 - (sin c - sin b) / (c - b)] for cutoff c > beam width b (2 pi I (1 - cos c)
    /// when they are equal).
    pub fn power(&self) -> Vec3 {
        let (c, b) = (self.cutoff as f64, self.beam_width as f64);
        let solid = if c - b > 1e-9 {
            1.0 - (c.sin() - b.sin()) / (c - b)
        } else {
            1.0 - c.cos()
        };
        self.intensity * (2.0 * std::f64::consts::PI * solid) as f32
    }
}

/// Mitsuba's `projector` (src/emitters/projector.cpp): a pinhole at `position` that projects
/// `irradiance` through the frustum of a perspective camera with the same `fov`. A point p at
/// local (x, y, z), z > 0, is lit at texture coordinates u = 1/2 - x / (2 z t),
/// v = 1/2 - aspect y / (2 z t) (t = tan(fov_x / 2); the image upright as that camera would
/// see it), with intensity pi scale E(u, v) / cos^3(theta) towards it, so that a plane at z = 1
/// facing it receives irradiance pi scale E. Its power is pi scale A times E's mean over
/// [0, 1]^2, A = 4 t^2 / aspect being the image's area on the plane z = 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projector {
    pub position: Vec3,
    /// Unit local x, y and z (the direction it faces) in the world.
    pub frame: [Vec3; 3],
    /// `scale` x the constant irradiance, or `scale` alone when `texture` gives it.
    pub irradiance: Vec3,
    /// The irradiance texture (an index of `Scene::textures`).
    pub texture: Option<u32>,
    /// tan of half the horizontal field of view.
    pub tan_half_fov: f32,
    /// The irradiance's width over height in texels (1 for anything but a bitmap, as Mitsuba's
    /// `Texture::resolution`), which sets the frustum's height.
    pub aspect: f32,
}

impl Projector {
    /// The image's area on the plane one unit ahead (Mitsuba's `m_sensor_area`).
    pub fn sensor_area(&self) -> f32 {
        4.0 * self.tan_half_fov * self.tan_half_fov / self.aspect
    }

    /// Texture coordinates where world direction `dir` leaving the projector crosses its image,
    /// `None` outside the frustum.
    pub fn uv(&self, dir: Vec3) -> Option<Vec2> {
        let local = Vec3::new(
            dir.dot(self.frame[0]),
            dir.dot(self.frame[1]),
            dir.dot(self.frame[2]),
        );
        if local.z <= 0.0 {
            return None;
        }
        let k = 0.5 / (local.z * self.tan_half_fov);
        let uv = Vec2::new(0.5 - local.x * k, 0.5 - self.aspect * local.y * k);
        ((0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)).then_some(uv)
    }

    /// Emitted power: pi x sensor area x the mean of irradiance over the image (by the midpoint
    /// rule on a grid twice the texture's resolution, at most 512 a side).
    pub fn power_with(&self, textures: &[Texture]) -> Vec3 {
        let mean = match self.texture.and_then(|t| textures.get(t as usize)) {
            None => Vec3::ONE,
            Some(texture) => {
                let (w, h) = match texture {
                    Texture::Bitmap(b) => (b.width, b.height),
                    Texture::Checkerboard { .. } => (64, 64),
                };
                let (nu, nv) = (
                    (2 * w).clamp(2, 512) as usize,
                    (2 * h).clamp(2, 512) as usize,
                );
                let mut sum = glam::DVec3::ZERO;
                for j in 0..nv {
                    for i in 0..nu {
                        let uv =
                            Vec2::new((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nv as f32);
                        sum += texture.eval(uv).as_dvec3();
                    }
                }
                (sum / (nu * nv) as f64).as_vec3()
            }
        };
        self.irradiance * mean * (PI * self.sensor_area())
    }
}

/// Mitsuba's `directional`: irradiance `irradiance` on a plane facing it, arriving along
/// `direction` from infinitely far.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction the light travels in.
    pub direction: Vec3,
    pub irradiance: Vec3,
}

/// The light arriving from infinitely far in every direction a ray escapes to.
#[derive(Debug, Clone, PartialEq)]
pub enum Environment {
    /// Mitsuba's `constant`: the same radiance from every direction.
    Constant { radiance: Vec3 },
    /// Mitsuba's `envmap`.
    Map(EnvMap),
    /// Mitsuba's `sunsky`: the Hosek-Wilkie model and the map baked from it, which is what
    /// renders (src/scene/sunsky).
    SunSky(Box<SunSkyMap>),
}

impl Environment {
    /// Radiance arriving from world direction `dir` (unit, pointing away from the scene), as
    /// the renderer sees it (a sunsky's baked map).
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        match self.map() {
            None => match self {
                Environment::Constant { radiance } => *radiance,
                _ => unreachable!("every other environment is a map"),
            },
            Some(map) => map.eval(dir),
        }
    }

    /// The integral of radiance over all directions (W / m^2 / sr x sr per channel): the power
    /// that crosses a disc of area A facing every direction in turn is A times this.
    pub fn radiance_integral(&self) -> Vec3 {
        match (self, self.map()) {
            (Environment::Constant { radiance }, _) => *radiance * (4.0 * PI),
            (_, Some(map)) => map.radiance_integral(),
            (_, None) => unreachable!("every other environment is a map"),
        }
    }

    /// The map the renderer reads (an `envmap`'s, or a `sunsky`'s bake); `None` for a constant.
    pub fn map(&self) -> Option<&EnvMap> {
        match self {
            Environment::Constant { .. } => None,
            Environment::Map(map) => Some(map),
            Environment::SunSky(sunsky) => Some(&sunsky.map),
        }
    }
}

/// A latitude-longitude environment map in Mitsuba 3's conventions (src/emitters/envmap.cpp):
/// a local direction d has u = atan2(d.x, -d.z) / 2 pi (texel centres, wrapping in u) and
/// v = acos(d.y) / pi (rows at v = i / (H - 1), the first and last on the poles), radiance
/// bilinear between the four nearest texels, times `scale` (already applied to `texels`).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    pub width: u32,
    pub height: u32,
    /// Linear RGB, row by row from the top (v = 0, local +y), scale applied.
    pub texels: Vec<Vec3>,
    /// Rotation from the map's local frame to the world.
    pub to_world: Mat3,
    pub source: PathBuf,
}

impl EnvMap {
    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = x.rem_euclid(w);
        let y = y.clamp(0, h - 1);
        self.texels[(y * w + x) as usize]
    }

    /// The map's (u, v) of a local direction.
    pub fn uv(local: Vec3) -> Vec2 {
        let u = local.x.atan2(-local.z) / (2.0 * PI);
        let v = local.y.clamp(-1.0, 1.0).acos() / PI;
        Vec2::new(u - u.floor(), v)
    }

    /// Bilinear radiance at (u, v): texel-centred in u, align-corners in v.
    pub fn eval_uv(&self, uv: Vec2) -> Vec3 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y.clamp(0.0, 1.0) * (self.height - 1) as f32;
        let (x0, y0) = (x.floor(), y.floor().min((self.height - 2) as f32));
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }

    /// Radiance from world direction `dir`.
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        self.eval_uv(Self::uv(self.to_world.transpose() * dir))
    }

    /// Sampling cells: the W x (H - 1) patches between texel centres, over which radiance is
    /// bilinear. Each weighs the mean luminance of its corners times sin(theta) at its middle
    /// row, so a cell with any light has a positive weight.
    fn cell_weights(&self) -> Vec<f64> {
        let (w, h) = (self.width as i64, self.height as i64);
        let mut weights = Vec::with_capacity((w * (h - 1)) as usize);
        for y in 0..h - 1 {
            let sin_theta = ((y as f64 + 0.5) / (h - 1) as f64 * std::f64::consts::PI).sin();
            for x in 0..w {
                let corners = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)];
                let lum: f64 = corners
                    .iter()
                    .map(|&(cx, cy)| luminance(self.texel(cx, cy)).max(0.0) as f64)
                    .sum::<f64>()
                    / 4.0;
                weights.push(lum * sin_theta);
            }
        }
        weights
    }

    /// The solid angle of the bilinear hat of a texel of row `y` of a `width` x `height` map:
    /// the integral over the sphere of the weight [`EnvMap::eval_uv`] gives that texel. Its u
    /// part integrates to 1 / width of the turn; in theta (rows h = pi / (height - 1) apart)
    /// the hat against sin theta gives sin(theta_y) 2 (1 - cos h) / h inside and 1 - sin(h) / h
    /// on a pole row. The hats sum to one everywhere, so these sum to 4 pi.
    pub fn hat_solid_angle(width: u32, height: u32, y: u32) -> f64 {
        use std::f64::consts::PI;
        let h = PI / (height - 1) as f64;
        let along_theta = if y == 0 || y == height - 1 {
            // 1 - sin(h) / h, by its series where h is small (cancellation).
            if h < 1e-2 {
                h * h / 6.0 * (1.0 - h * h / 20.0)
            } else {
                1.0 - h.sin() / h
            }
        } else {
            (y as f64 * h).sin() * 4.0 * (0.5 * h).sin().powi(2) / h
        };
        2.0 * PI / width as f64 * along_theta
    }

    /// The integral of radiance over the sphere: exactly, each texel times the solid angle of
    /// its bilinear hat ([`EnvMap::hat_solid_angle`]).
    pub fn radiance_integral(&self) -> Vec3 {
        let w = self.width as usize;
        let mut sum = glam::DVec3::ZERO;
        for (y, row) in self.texels.chunks(w).enumerate() {
            let row_sum: glam::DVec3 = row.iter().map(|t| t.as_dvec3()).sum();
            sum += row_sum * Self::hat_solid_angle(self.width, self.height, y as u32);
        }
        sum.as_vec3()
    }

    /// The map as the GPU reads it, appended to a table of f32 (see `gpu_table`'s layout in
    /// shaders/common/environment.wgsl): returns its first index.
    pub fn append_gpu_table(&self, table: &mut Vec<f32>) -> u32 {
        let start = table.len() as u32;
        let to_local = self.to_world.transpose();
        // Rows of the world-to-local rotation.
        for r in 0..3 {
            table.extend(to_local.row(r).to_array());
        }
        table.extend([self.width as f32, self.height as f32, 0.0]);
        for t in &self.texels {
            table.extend(t.to_array());
        }
        let weights = self.cell_weights();
        let w = self.width as usize;
        let rows: Vec<f64> = weights.chunks(w).map(|r| r.iter().sum()).collect();
        let total: f64 = rows.iter().sum();
        // Marginal CDF over rows, then each row's conditional CDF, then each cell's probability.
        let mut running = 0.0;
        for r in &rows {
            running += r;
            table.push(if total > 0.0 {
                (running / total) as f32
            } else {
                0.0
            });
        }
        for (row, sum) in weights.chunks(w).zip(&rows) {
            let mut running = 0.0;
            for c in row {
                running += c;
                table.push(if *sum > 0.0 {
                    (running / sum) as f32
                } else {
                    0.0
                });
            }
        }
        for c in &weights {
            table.push(if total > 0.0 { (c / total) as f32 } else { 0.0 });
        }
        start
    }
}

/// Lights beside shapes and point lights.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Emitters {
    pub spots: Vec<SpotLight>,
    pub projectors: Vec<Projector>,
    pub directionals: Vec<DirectionalLight>,
    /// At most one (Mitsuba allows one environment emitter).
    pub environment: Option<Environment>,
}

impl Emitters {
    pub fn is_empty(&self) -> bool {
        self.spots.is_empty()
            && self.projectors.is_empty()
            && self.directionals.is_empty()
            && self.environment.is_none()
    }
}
