//! Mitsuba 3's `sunsky` emitter as its RGB variants evaluate it: the Hosek-Wilkie sky (2012) and
//! sun (2013) driven by Mitsuba's own datasets, and its bake into an equirectangular
//! [`EnvMap`], which is what hppm renders (path tracing, photons and the error estimate all
//! read it as any environment map).
//!
//! The specification is Mitsuba 3.9.1's source: `include/mitsuba/render/sunsky.h`
//! (`BaseSunskyEmitter`: `eval`, `eval_sky`, `eval_sun`, `sun_cos_psi`, `get_area_ratio`,
//! `bilinear_interp`, `sun_coordinates`, the constants) and `src/emitters/sunsky.cpp`
//! (`SunskyEmitter`: the sun direction, `bezier_interp`, `update_irradiance_data`), with
//! drjit's `take_interp` (include/drjit/tensor.h), `unit_angle`, `unit_angle_z`, `sphdir`
//! (include/drjit/sphere.h) and Mitsuba's `spectrum_to_srgb` / `linear_rgb_rec`
//! (include/mitsuba/core/spectrum.h). Facts and formulas are copied, computed in f32 in
//! Mitsuba's order so that the values agree to a few ulps (tests/sunsky.rs holds them to
//! Mitsuba's own, tests/refs/sunsky/values.py).
//!
//! The datasets (data/sunsky_rgb.bin: the RGB fields of Mitsuba's `sunsky_datasets.bin` and
//! the sun irradiance of its `sampling_data.bin`, written by data/extract_rgb.py in Mitsuba's
//! TensorFile format) are Hosek and Wilkie's, BSD-3 licensed (data/LICENSE).
//!
//! The local frame is Mitsuba's: z up; the sun at azimuth a (from north through east, as
//! Blanco-Muriel et al.'s algorithm gives it) lies at angle a - pi from +x towards +y, so +x
//! points south and +y west (Mitsuba's documentation says "X towards north"; its code is
//! followed). `to_world` turns that frame into the scene; `sun_direction` is given in world
//! space.

mod tensor_file;

pub use tensor_file::{Field, parse as parse_tensor_file};

use std::f32::consts::PI;
use std::sync::OnceLock;

use glam::{DMat3, DVec3, Mat3, Vec3};

use super::emitter::EnvMap;

/// The datasets, Mitsuba's RGB fields as f32 (data/extract_rgb.py).
const DATA: &[u8] = include_bytes!("data/sunsky_rgb.bin");

/// The wavelengths (nm) of the sun irradiance dataset (`WAVELENGTHS`).
pub const WAVELENGTHS: [f32; 11] = [
    320.0, 360.0, 400.0, 440.0, 480.0, 520.0, 560.0, 600.0, 640.0, 680.0, 720.0,
];
const TURBIDITY_LEVELS: usize = 10;
const ALBEDO_LEVELS: usize = 2;
const SKY_CONTROL_POINTS: usize = 6;
const SKY_PARAMS: usize = 9;
const SUN_SEGMENTS: usize = 45;
const SUN_CONTROL_POINTS: usize = 4;
const SUN_LD_PARAMS: usize = 6;
/// Elevations of the irradiance tables, 2 to 89 degrees in steps of 3 (`MPDF_ELEVATION_COUNT`).
const ELEVATIONS: usize = 30;
/// The sun's half aperture the datasets were made for, in radians (`SUN_HALF_APERTURE`:
/// pi (0.5 0.5358) / 180; a smaller or larger `sun_aperture` keeps the irradiance).
const SUN_HALF_APERTURE: f64 = std::f64::consts::PI * (0.5 * 0.5358) / 180.0;
/// `SPEC_TO_RGB_SUN_CONV`: spectral solar radiance to RGB.
const SPEC_TO_RGB_SUN_CONV: f32 = 467.069_28;
/// Mitsuba's `MI_CIE_Y_NORMALIZATION` (1 / the CIE y-bar table's integral).
const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
/// `EARTH_MEAN_RADIUS` and `ASTRONOMICAL_UNIT` in km (the parallax correction).
const EARTH_MEAN_RADIUS: f64 = 6371.01;
const ASTRONOMICAL_UNIT: f64 = 149_597_890.0;
/// drjit's `OneMinusEpsilon<float>`.
const ONE_MINUS_EPSILON: f32 = 0.999_999_94;

/// Mitsuba's defaults for the sun's aperture (degrees, the full angle).
pub const DEFAULT_SUN_APERTURE: f32 = 0.5358;

/// The map the sun and sky are baked into when the sun is drawn: width x height texels, its
/// pole on the sun. Rows are pi / 4096 = 0.044 degrees apart, so the sun's disc (0.27 degrees
/// in radius at Mitsuba's default aperture) spans six rows from its centre and its edge is
/// blurred by at most one; around the pole the columns are finer still (1024 of them around
/// the disc). The sky away from the sun is resolved to 0.35 degrees at worst (columns at 90
/// degrees from the sun), which its smooth gradients need; the horizon's cut is projected
/// (below). 4.2 million texels: 50 MB of f32 RGB, 84 MB with the sampling tables on the GPU,
/// under the 128 MiB a storage binding may hold on lavapipe.
pub const BAKE_WIDTH: u32 = 1024;
pub const BAKE_HEIGHT: u32 = 4097;
/// Sectors of the sun's disc quadrature: one per column of a [`BAKE_WIDTH`] map, through the
/// columns' centres when the sun is its pole.
const DISC_SECTORS: usize = BAKE_WIDTH as usize;

/// The map of a sky without a drawn sun: its pole at the zenith, the horizon on its middle
/// row, 0.35 degrees a texel.
pub const SKY_BAKE_WIDTH: u32 = 1024;
pub const SKY_BAKE_HEIGHT: u32 = 513;

/// Mitsuba's datasets for the RGB variants, each row-major as in the file.
struct Datasets {
    /// (turbidity 10, albedo 2, control point 6, channel 3, parameter 9).
    sky_params: Vec<f32>,
    /// (turbidity 10, albedo 2, control point 6, channel 3).
    sky_radiance: Vec<f32>,
    /// (turbidity 10, segment 45, channel 3, control point 4, limb-darkening power 6).
    sun_radiance: Vec<f32>,
    /// (turbidity 10, elevation 30, wavelength 11).
    sun_irradiance: Vec<f32>,
}

fn datasets() -> &'static Datasets {
    static DATASETS: OnceLock<Datasets> = OnceLock::new();
    DATASETS.get_or_init(|| {
        let fields = parse_tensor_file(DATA).expect("the built-in sunsky datasets");
        let field = |name: &str, shape: &[usize]| -> Vec<f32> {
            let f = fields
                .iter()
                .find(|f| f.name == name)
                .unwrap_or_else(|| panic!("sunsky dataset {name} missing"));
            assert_eq!(f.shape, shape, "sunsky dataset {name}'s shape");
            f.values.iter().map(|&v| v as f32).collect()
        };
        let (t, a) = (TURBIDITY_LEVELS, ALBEDO_LEVELS);
        Datasets {
            sky_params: field("sky_params_rgb", &[t, a, SKY_CONTROL_POINTS, 3, SKY_PARAMS]),
            sky_radiance: field("sky_rad_rgb", &[t, a, SKY_CONTROL_POINTS, 3]),
            sun_radiance: field(
                "sun_rad_rgb",
                &[t, SUN_SEGMENTS, 3, SUN_CONTROL_POINTS, SUN_LD_PARAMS],
            ),
            sun_irradiance: field("sun_irradiance", &[t, ELEVATIONS, WAVELENGTHS.len()]),
        }
    })
}

/// drjit's `take_interp` along the first axis of `data` (`n` entries): entries floor(pos) and
/// the next (floor clamped to [0, n - 2], so a position past the end extrapolates), weighted
/// 1 - w and w, w = pos - floor. `pos(j)` gives the position for element j of an entry (one
/// for all, or per element as Mitsuba's albedo is per channel).
fn take_interp(data: &[f32], n: usize, pos: impl Fn(usize) -> f32) -> Vec<f32> {
    let stride = data.len() / n;
    (0..stride)
        .map(|j| {
            let p = pos(j);
            let index = (p.max(0.0) as usize).min(n - 2);
            let w1 = p - index as f32;
            let w0 = 1.0 - w1;
            let (v0, v1) = (data[index * stride + j], data[(index + 1) * stride + j]);
            v0.mul_add(w0, v1 * w1)
        })
        .collect()
}

/// `SunskyEmitter::bezier_interp`: the quintic Bezier over the six control points (the first
/// axis of `data`) at x = cbrt(2 eta / pi), eta the sun's elevation.
fn bezier_interp(data: &[f32], eta: f32) -> Vec<f32> {
    const COEFS: [f32; SKY_CONTROL_POINTS] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    let stride = data.len() / SKY_CONTROL_POINTS;
    let x = (2.0 * std::f32::consts::FRAC_1_PI * eta)
        .cbrt()
        .min(ONE_MINUS_EPSILON);
    let mut out = vec![0.0f32; stride];
    let mut x_pow = 1.0f32;
    let mut x_pow_inv = (1.0 - x).powi(SKY_CONTROL_POINTS as i32 - 1);
    let x_pow_inv_scale = 1.0 / (1.0 - x);
    for (k, coef) in COEFS.iter().enumerate() {
        let weight = coef * x_pow * x_pow_inv;
        for (o, d) in out.iter_mut().zip(&data[k * stride..(k + 1) * stride]) {
            *o += weight * d;
        }
        x_pow *= x;
        x_pow_inv *= x_pow_inv_scale;
    }
    out
}

/// drjit's `sphdir`: the unit vector at polar angle `theta` from +z and azimuth `phi` from +x.
pub fn sph_to_dir(theta: f32, phi: f32) -> Vec3 {
    let (sin_theta, cos_theta) = theta.sin_cos();
    let (sin_phi, cos_phi) = phi.sin_cos();
    Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta)
}

/// Mitsuba's `dir_to_sph`: (polar angle by drjit's `unit_angle_z`, azimuth).
pub fn dir_to_sph(v: Vec3) -> (f32, f32) {
    let up = v.z >= 0.0;
    let temp = 2.0 * (0.5 * Vec3::new(v.x, v.y, v.z - if up { 1.0 } else { -1.0 }).length()).asin();
    (if up { temp } else { PI - temp }, v.y.atan2(v.x))
}

/// drjit's `unit_angle`: the angle between unit vectors, accurate near 0 and pi.
pub fn unit_angle(a: Vec3, b: Vec3) -> f32 {
    let positive = a.dot(b) >= 0.0;
    let d = if positive { b - a } else { b + a };
    let temp = 2.0 * (0.5 * d.length()).asin();
    if positive { temp } else { PI - temp }
}

/// A place and a time, Mitsuba's `LocationRecord` and `DateTimeRecord` (defaults: Tokyo,
/// 2010-07-10 15:00, timezone +9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaceTime {
    /// Degrees, north positive.
    pub latitude: f32,
    /// Degrees, east positive.
    pub longitude: f32,
    /// Hours ahead of UTC.
    pub timezone: f32,
    pub year: i32,
    pub month: i32,
    pub day: i32,
    pub hour: f32,
    pub minute: f32,
    pub second: f32,
}

impl Default for PlaceTime {
    fn default() -> Self {
        PlaceTime {
            latitude: 35.6894,
            longitude: 139.6917,
            timezone: 9.0,
            year: 2010,
            month: 7,
            day: 10,
            hour: 15.0,
            minute: 0.0,
            second: 0.0,
        }
    }
}

/// `BaseSunskyEmitter::sun_coordinates`: the sun's polar angle from the zenith and its azimuth
/// in the emitter's frame (from +x towards +y), after Blanco-Muriel, Alarcon-Padilla,
/// Lopez-Moratalla and Lara-Coira, "Computing the Solar Vector", Solar Energy 70(5), 2001, in
/// f32 as Mitsuba computes it (its Julian day, near 2.45 million, is kept to a quarter of a
/// day there; the hour enters the sidereal time directly, so the sun still moves smoothly).
/// Its constants are written as Mitsuba writes them and rounded to f32 as its compiler does.
#[allow(clippy::excessive_precision)]
pub fn sun_coordinates(t: &PlaceTime) -> (f32, f32) {
    let dec_hours = t.hour - t.timezone + (t.minute + t.second / 60.0) / 60.0;
    // The Julian day, in integer arithmetic truncating towards zero as C++ does.
    let aux_1 = (t.month - 14) / 12;
    let aux_2 = (1461 * (t.year + 4800 + aux_1)) / 4 + (367 * (t.month - 2 - 12 * aux_1)) / 12
        - (3 * ((t.year + 4900 + aux_1) / 100)) / 4
        + t.day
        - 32075;
    let julian_date = aux_2 as f32 - 0.5 + dec_hours / 24.0;
    let elapsed = julian_date - 2_451_545.0;

    // Ecliptic coordinates.
    let omega = 2.1429 - 0.001_039_459_4 * elapsed;
    let mean_longitude = 4.895_063 + 0.017_202_791_698 * elapsed;
    let anomaly = 6.240_06 + 0.017_201_969_9 * elapsed;
    let ecliptic_longitude =
        mean_longitude + 0.033_416_07 * anomaly.sin() + 0.000_348_94 * (2.0 * anomaly).sin()
            - 0.000_113_4
            - 0.000_020_3 * omega.sin();
    let ecliptic_obliquity = 0.409_092_8 - 6.2140e-9 * elapsed + 0.000_039_6 * omega.cos();

    // Celestial coordinates.
    let sin_ecliptic_longitude = ecliptic_longitude.sin();
    let dy = ecliptic_obliquity.cos() * sin_ecliptic_longitude;
    let dx = ecliptic_longitude.cos();
    let mut right_ascension = dy.atan2(dx);
    if right_ascension < 0.0 {
        right_ascension += 2.0 * PI;
    }
    let declination = (ecliptic_obliquity.sin() * sin_ecliptic_longitude).asin();

    // Local coordinates.
    let greenwich_mean_sidereal_time = 6.697_424_324_2 + 0.065_709_828_3 * elapsed + dec_hours;
    let local_mean_sidereal_time = (greenwich_mean_sidereal_time * 15.0 + t.longitude).to_radians();
    let latitude = t.latitude.to_radians();
    let (sin_latitude, cos_latitude) = latitude.sin_cos();
    let hour_angle = local_mean_sidereal_time - right_ascension;
    let cos_hour_angle = hour_angle.cos();
    let mut zenith = (cos_latitude * cos_hour_angle * declination.cos()
        + declination.sin() * sin_latitude)
        .acos();
    let dy = -hour_angle.sin();
    let dx = declination.tan() * cos_latitude - sin_latitude * cos_hour_angle;
    let mut azimuth = dy.atan2(dx);
    if azimuth < 0.0 {
        azimuth += 2.0 * PI;
    }
    // Parallax.
    zenith += (EARTH_MEAN_RADIUS / ASTRONOMICAL_UNIT) as f32 * zenith.sin();
    (zenith, azimuth - PI)
}

/// Where the sun is: `sun_direction` (world space) or a place and time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SunPosition {
    Direction(Vec3),
    PlaceTime(PlaceTime),
}

/// Everything Mitsuba's `sunsky` reads, checked by the loader.
#[derive(Debug, Clone, PartialEq)]
pub struct SunSkyParams {
    /// In [1, 10].
    pub turbidity: f32,
    /// Ground albedo per channel, in [0, 1].
    pub albedo: Vec3,
    pub sun: SunPosition,
    pub sun_scale: f32,
    pub sky_scale: f32,
    /// The sun's full aperture in degrees, in (0, 180).
    pub sun_aperture: f32,
    /// Mitsuba's limb-darkened sun (the RGB dataset's polynomial in elevation and the cosine
    /// across the disc) instead of a uniform disc of the same irradiance.
    pub complex_sun: bool,
    /// A rotation.
    pub to_world: Mat3,
    /// Mitsuba's `linear_rgb_rec` at [`WAVELENGTHS`] (zero outside the CIE tables' 360-830
    /// nm): how `spectrum_to_srgb` turns the sun's spectral irradiance into RGB. The loader
    /// fills it from its CIE tables.
    pub rgb_matching: [Vec3; 11],
}

/// The model, set up as Mitsuba's constructor sets it up: the sky's nine parameters and mean
/// radiance per channel interpolated in turbidity, albedo and the sun's elevation, the sun's
/// irradiance in RGB, its limb-darkening polynomial.
#[derive(Debug, Clone, PartialEq)]
pub struct SunSky {
    pub params: SunSkyParams,
    to_local: Mat3,
    /// Mitsuba's `m_sun_dir`: towards the sun's centre, world space.
    sun_world: Vec3,
    /// `sph_to_dir(m_sun_angles)`: towards the sun's centre, local.
    sun_local: Vec3,
    sky_params: [[f32; SKY_PARAMS]; 3],
    sky_radiance: [f32; 3],
    /// `m_sun_irrad`: the sun's RGB irradiance at its elevation (before Mitsuba's constant
    /// factors).
    sun_irradiance: [f32; 3],
    /// `m_sun_radiance`: sun_rad_rgb at the turbidity, (segment, channel, control point, power).
    sun_polynomial: Vec<f32>,
    /// The sun's half aperture (`m_sun_half_aperture`) and its cosine.
    half_aperture: f32,
    cos_half_aperture: f32,
}

impl SunSky {
    pub fn new(params: SunSkyParams) -> SunSky {
        let data = datasets();
        let to_local = params.to_world.inverse();
        let sun_world = match params.sun {
            SunPosition::Direction(d) => d.normalize(),
            SunPosition::PlaceTime(t) => {
                let (theta, phi) = sun_coordinates(&t);
                params.to_world * sph_to_dir(theta, phi)
            }
        };
        let (theta, phi) = dir_to_sph(to_local * sun_world);
        let sun_local = sph_to_dir(theta, phi);
        let eta = 0.5 * PI - theta;
        let turbidity = params.turbidity - 1.0;

        // `bilinear_interp` (turbidity, then albedo per channel), then `bezier_interp`.
        let per_channel = |data: &[f32], per: usize| {
            let by_turbidity = take_interp(data, TURBIDITY_LEVELS, |_| turbidity);
            let by_albedo = take_interp(&by_turbidity, ALBEDO_LEVELS, |j| {
                params.albedo[(j / per) % 3]
            });
            bezier_interp(&by_albedo, eta)
        };
        let p = per_channel(&data.sky_params, SKY_PARAMS);
        let sky_params = [0, 1, 2].map(|c| {
            let mut row = [0.0; SKY_PARAMS];
            row.copy_from_slice(&p[c * SKY_PARAMS..(c + 1) * SKY_PARAMS]);
            row
        });
        let r = per_channel(&data.sky_radiance, 1);
        let sky_radiance = [r[0], r[1], r[2]];

        // `update_irradiance_data`: the sun's spectral irradiance at the turbidity and
        // elevation (tables from 2 degrees in steps of 3, clamped), to RGB.
        let angle =
            ((eta.to_degrees() - 2.0) / 3.0).clamp(0.0, ELEVATIONS as f32 - ONE_MINUS_EPSILON);
        let by_turbidity = take_interp(&data.sun_irradiance, TURBIDITY_LEVELS, |_| turbidity);
        let spectral = take_interp(&by_turbidity, ELEVATIONS, |_| angle);
        let y = CIE_Y_NORMALIZATION as f32;
        let sun_irradiance = [0, 1, 2].map(|c| {
            let sum: f32 = params
                .rgb_matching
                .iter()
                .zip(&spectral)
                .map(|(m, s)| m[c] * s)
                .sum();
            sum / WAVELENGTHS.len() as f32 * y / y
        });
        let sun_polynomial = take_interp(&data.sun_radiance, TURBIDITY_LEVELS, |_| turbidity);
        let half_aperture = (0.5 * params.sun_aperture).to_radians();
        SunSky {
            to_local,
            sun_world,
            sun_local,
            sky_params,
            sky_radiance,
            sun_irradiance,
            sun_polynomial,
            half_aperture,
            cos_half_aperture: half_aperture.cos(),
            params,
        }
    }

    /// Towards the sun's centre in world space (Mitsuba's `sun_direction` parameter; unit).
    pub fn sun_direction(&self) -> Vec3 {
        self.sun_world
    }

    /// The zenith in world space.
    pub fn zenith(&self) -> Vec3 {
        (self.params.to_world * Vec3::Z).normalize()
    }

    /// Whether the sun is at or above the horizon: Mitsuba renders the whole emitter black
    /// otherwise (`eval`'s `Frame3f::cos_theta(sun_dir) >= 0`).
    pub fn sun_is_up(&self) -> bool {
        self.sun_local.z >= 0.0
    }

    /// Whether anything is drawn at all.
    pub fn is_lit(&self) -> bool {
        self.sun_is_up() && (self.params.sky_scale > 0.0 || self.params.sun_scale > 0.0)
    }

    /// Whether the sun's disc is drawn.
    pub fn sun_drawn(&self) -> bool {
        self.sun_is_up() && self.params.sun_scale > 0.0
    }

    /// The sun's half aperture in radians.
    pub fn half_aperture(&self) -> f32 {
        self.half_aperture
    }

    fn local(&self, world: Vec3) -> Vec3 {
        (self.to_local * world).normalize()
    }

    /// Radiance arriving from world direction `dir` (unit, away from the scene): Mitsuba's
    /// `eval(si)` with `si.wi = -dir`.
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let local = self.local(dir);
        let hit_sun = self.sun_local.dot(local) >= self.cos_half_aperture;
        self.eval(local, hit_sun)
    }

    /// `BaseSunskyEmitter::eval` for the RGB variants: the sky times `sky_scale`, plus, where
    /// `hit_sun`, the sun times `sun_scale`, the area ratio and the RGB conversion constant;
    /// all times the CIE normalisation; black below the horizon and whenever the sun is.
    fn eval(&self, local: Vec3, hit_sun: bool) -> Vec3 {
        let cos_theta = local.z;
        if !(cos_theta >= 0.0 && self.sun_local.z >= 0.0) {
            return Vec3::ZERO;
        }
        let gamma = unit_angle(self.sun_local, local);
        let mut res = Vec3::ZERO;
        if self.params.sky_scale > 0.0 {
            res = self.params.sky_scale * self.eval_sky(cos_theta, gamma);
        }
        if self.params.sun_scale > 0.0 && hit_sun {
            res += self.params.sun_scale
                * self.eval_sun(cos_theta, gamma)
                * self.area_ratio()
                * SPEC_TO_RGB_SUN_CONV;
        }
        res * CIE_Y_NORMALIZATION as f32
    }

    /// The sky alone at a local direction (what the map holds besides the sun).
    fn sky_local(&self, local: Vec3) -> Vec3 {
        if !(local.z >= 0.0 && self.sun_local.z >= 0.0) || self.params.sky_scale <= 0.0 {
            return Vec3::ZERO;
        }
        let gamma = unit_angle(self.sun_local, local);
        self.params.sky_scale * self.eval_sky(local.z, gamma) * CIE_Y_NORMALIZATION as f32
    }

    /// The sun alone at a local direction inside its disc.
    fn sun_inside(&self, local: Vec3) -> Vec3 {
        if !(local.z >= 0.0 && self.sun_local.z >= 0.0) || self.params.sun_scale <= 0.0 {
            return Vec3::ZERO;
        }
        let gamma = unit_angle(self.sun_local, local);
        self.params.sun_scale
            * self.eval_sun(local.z, gamma)
            * self.area_ratio()
            * SPEC_TO_RGB_SUN_CONV
            * CIE_Y_NORMALIZATION as f32
    }

    /// `eval_sky`: the Hosek-Wilkie sky, (1 + A exp(B / (cos theta + 0.01))) times (C + D
    /// exp(E gamma) + F cos^2 gamma + G chi + H sqrt(cos theta)) times the mean radiance, where
    /// chi = (1 + cos^2 gamma) / (1 + I^2 - 2 I cos gamma)^1.5 and the parameters come in the
    /// dataset's order A B C D E F G H I.
    fn eval_sky(&self, cos_theta: f32, gamma: f32) -> Vec3 {
        let cos_gamma = gamma.cos();
        let cos_gamma_sqr = cos_gamma * cos_gamma;
        Vec3::from_array([0, 1, 2].map(|c| {
            let p = &self.sky_params[c];
            let c1 = 1.0 + p[0] * (p[1] / (cos_theta + 0.01)).exp();
            let chi =
                (1.0 + cos_gamma_sqr) / (1.0 + p[8] * p[8] - 2.0 * p[8] * cos_gamma).powf(1.5);
            let c2 = p[2]
                + p[3] * (p[4] * gamma).exp()
                + p[5] * cos_gamma_sqr
                + p[6] * chi
                + p[7] * cos_theta.max(0.0).sqrt();
            c1 * c2 * self.sky_radiance[c]
        }))
    }

    /// `eval_sun` inside the disc: the irradiance over the dataset's disc's solid angle, or with
    /// `complex_sun` the RGB dataset's polynomial in the view's elevation (45 segments at
    /// (k / 45)^3 pi / 2) and the cosine psi across the disc (limb darkening baked in).
    fn eval_sun(&self, cos_theta: f32, gamma: f32) -> Vec3 {
        if !self.params.complex_sun {
            let solid = 2.0 * PI * (1.0 - (SUN_HALF_APERTURE as f32).cos());
            return Vec3::from_array(self.sun_irradiance) / solid;
        }
        let elevation = 0.5 * PI - cos_theta.clamp(-1.0, 1.0).acos();
        let segment = (((2.0 * elevation * std::f32::consts::FRAC_1_PI).cbrt()
            * SUN_SEGMENTS as f32)
            .floor()
            .max(0.0) as usize)
            .min(SUN_SEGMENTS - 1);
        let break_x = 0.5 * PI * (segment as f32 / SUN_SEGMENTS as f32).powf(3.0);
        let x = elevation - break_x;
        let cos_psi = self.sun_cos_psi(gamma);
        let per = 3 * SUN_CONTROL_POINTS * SUN_LD_PARAMS;
        let data = &self.sun_polynomial[segment * per..(segment + 1) * per];
        let mut res = [0.0f32; 3];
        for (idx, d) in data.iter().enumerate() {
            let j = idx % SUN_LD_PARAMS;
            let k = (idx / SUN_LD_PARAMS) % SUN_CONTROL_POINTS;
            let c = idx / (SUN_LD_PARAMS * SUN_CONTROL_POINTS);
            res[c] += x.powi(k as i32) * cos_psi.powi(j as i32) * d;
        }
        Vec3::from_array(res)
    }

    /// `sun_cos_psi`: the cosine between the sun's radius and the view, from gamma.
    fn sun_cos_psi(&self, gamma: f32) -> f32 {
        let sol_rad_sin = self.half_aperture.sin();
        let ar2 = 1.0 / (sol_rad_sin * sol_rad_sin);
        let sin_gamma = gamma.sin();
        (1.0 - ar2 * sin_gamma * sin_gamma).max(0.0).sqrt()
    }

    /// `get_area_ratio`: keeps the sun's irradiance whatever its aperture.
    fn area_ratio(&self) -> f32 {
        (1.0 - (SUN_HALF_APERTURE as f32).cos()) / (1.0 - self.half_aperture.cos())
    }

    /// The sun's power on a unit area facing it (its radiance integrated over its disc, the
    /// part above the horizon), by the bake's quadrature on a finer grid (1024 rings): exact
    /// for the uniform disc up to rounding, for `complex_sun` and a disc cut by the horizon to
    /// the grid's fineness.
    pub fn sun_irradiance_normal(&self) -> Vec3 {
        let mut total = DVec3::ZERO;
        self.disc_quadrature(
            &self.frame_about(self.params.to_world * self.sun_local),
            1024,
            |_, value| total += value,
        );
        total.as_vec3()
    }

    /// An orthonormal frame (columns x, y, z, a rotation) whose y is `pole`, in f64: near
    /// the pole a direction's polar angle comes from acos of its y, where an f32 frame's
    /// rounding (1e-7) would move points by half a row of the map.
    fn frame_about(&self, pole: Vec3) -> DMat3 {
        let pole = pole.as_dvec3().normalize();
        let helper = if pole.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Z
        };
        let x = helper.cross(pole).normalize();
        DMat3::from_cols(x, pole, x.cross(pole))
    }

    /// Quadrature of the sun's radiance over its disc (centred on `frame`'s y): `rings`
    /// rings (narrower towards the limb), each of [`DISC_SECTORS`] sectors (one per column of the
    /// map at its pole), each point at its cell's centroid in cos psi and weighted by the
    /// cell's exact solid angle (the weights sum to the disc's, 2 pi (1 - cos a), in f64).
    /// Calls `add(world direction, radiance x weight)` for every point.
    fn disc_quadrature(&self, frame: &DMat3, rings: usize, mut add: impl FnMut(DVec3, DVec3)) {
        if !self.sun_drawn() {
            return;
        }
        let sectors = DISC_SECTORS;
        let half = self.half_aperture as f64;
        // 1 - cos psi as 2 sin^2(psi / 2), free of cancellation.
        let versine = |psi: f64| 2.0 * (0.5 * psi).sin().powi(2);
        // Ring edges at psi = a (1 - (1 - i / rings)^2): denser towards the limb, where the
        // limb-darkened radiance falls as the square root of the distance to the edge (which
        // is smooth in this variable), so that the quadrature converges as fast there as
        // inside.
        let edge = |i: usize| half * (1.0 - (1.0 - i as f64 / rings as f64).powi(2));
        for i in 0..rings {
            let (inner, outer) = (versine(edge(i)), versine(edge(i + 1)));
            let weight = 2.0 * std::f64::consts::PI * (outer - inner) / sectors as f64;
            // The ring's centroid in cos psi.
            let psi = (1.0 - 0.5 * (inner + outer)).acos();
            let (sin_psi, cos_psi) = psi.sin_cos();
            for s in 0..sectors {
                let phi = (s as f64 + 0.5) / sectors as f64 * 2.0 * std::f64::consts::PI;
                let d = *frame * DVec3::new(phi.sin() * sin_psi, cos_psi, -phi.cos() * sin_psi);
                let value = self.sun_inside(self.local(d.as_vec3())).as_dvec3();
                add(d, value * weight);
            }
        }
    }

    /// The map rendered for this emitter (see [`BAKE_WIDTH`]).
    pub fn bake(&self) -> EnvMap {
        if !self.is_lit() {
            // Mitsuba renders nothing when the sun is below the horizon.
            return self.bake_at(4, 3);
        }
        if self.sun_drawn() {
            self.bake_at(BAKE_WIDTH, BAKE_HEIGHT)
        } else {
            self.bake_at(SKY_BAKE_WIDTH, SKY_BAKE_HEIGHT)
        }
    }

    /// Bakes sky and sun into a `width` x `height` map (Mitsuba's envmap conventions,
    /// [`EnvMap`]) whose pole is the sun when its disc is drawn, else the zenith.
    ///
    /// The sky is sampled at the texel centres, except in texels whose bilinear footprint
    /// (the four cells around the centre) the horizon crosses: there the texel holds the
    /// footprint's average of the sky weighted by the texel's bilinear hat, over an 8 x 8 grid,
    /// so that the horizon's cut keeps the sky's power instead of smearing or clipping it.
    ///
    /// The sun's disc is far smaller than anything a point sample per texel would hold: a
    /// texel centre inside it would carry its radiance over the whole texel, one outside
    /// none, and its power would follow where the texel centres fall. Instead the disc is
    /// integrated on its own fine polar grid (256 rings or more, 64 per row it spans at
    /// the centre and more towards the limb, and 1024 sectors), and each
    /// point's radiance times its solid angle is shared among the four texels around it by the
    /// bilinear weights the renderer interpolates with; each texel then divides what it got by
    /// the solid angle of its own bilinear hat ([`EnvMap::hat_solid_angle`]). Since the hats
    /// sum to one everywhere, the map's integral over the sphere is the disc's integral exactly
    /// (to rounding): the sun's power is conserved, only blurred by the texels' bilinear
    /// footprint (a texel's width; 0.044 degrees at [`BAKE_HEIGHT`]).
    pub fn bake_at(&self, width: u32, height: u32) -> EnvMap {
        let pole = if self.sun_drawn() {
            self.params.to_world * self.sun_local
        } else {
            self.zenith()
        };
        let frame64 = self.frame_about(pole);
        let frame = frame64.as_mat3();
        let (w, h) = (width as usize, height as usize);
        let mut texels = vec![Vec3::ZERO; w * h];
        let map = |texels| EnvMap {
            width,
            height,
            texels,
            to_world: frame,
            source: "sunsky".into(),
        };
        if !self.is_lit() {
            return map(texels);
        }
        let direction = |u: f32, v: f32| {
            let (theta, phi) = (v * PI, u * 2.0 * PI);
            frame
                * Vec3::new(
                    phi.sin() * theta.sin(),
                    theta.cos(),
                    -phi.cos() * theta.sin(),
                )
        };
        let zenith = self.zenith();
        let (d_theta, d_phi) = (PI / (h - 1) as f32, 2.0 * PI / w as f32);
        let sky_row = |y: usize, row: &mut [Vec3]| {
            let v = y as f32 / (h - 1) as f32;
            let sin_theta = (v * PI).sin();
            // The angular reach of this row's bilinear footprints, with a margin.
            let reach = 1.1 * d_theta.hypot(d_phi * (sin_theta + d_theta).min(1.0));
            for (x, texel) in row.iter_mut().enumerate() {
                let u = (x as f32 + 0.5) / w as f32;
                let d = direction(u, v);
                if d.dot(zenith).abs() >= reach.sin() {
                    *texel = self.sky_local(self.local(d));
                    continue;
                }
                // The hat-weighted mean over the footprint.
                let n = 8;
                let (mut sum, mut weights) = (Vec3::ZERO, 0.0f32);
                for j in 0..n {
                    let t = (j as f32 + 0.5) / n as f32 * 2.0 - 1.0;
                    let vv = v + t / (h - 1) as f32;
                    if !(0.0..=1.0).contains(&vv) {
                        continue;
                    }
                    let hat_v = (1.0 - t.abs()) * (vv * PI).sin();
                    for i in 0..n {
                        let s = (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
                        let weight = hat_v * (1.0 - s.abs());
                        sum += weight * self.sky_local(self.local(direction(u + s / w as f32, vv)));
                        weights += weight;
                    }
                }
                *texel = if weights > 0.0 {
                    sum / weights
                } else {
                    Vec3::ZERO
                };
            }
        };
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(16);
        let rows_per = h.div_ceil(threads);
        std::thread::scope(|scope| {
            for (chunk, rows) in texels.chunks_mut(rows_per * w).enumerate() {
                let sky_row = &sky_row;
                scope.spawn(move || {
                    for (i, row) in rows.chunks_mut(w).enumerate() {
                        sky_row(chunk * rows_per + i, row);
                    }
                });
            }
        });

        // The sun: each quadrature point shared by the bilinear weights, then divided by the
        // receiving texel's hat's solid angle.
        let mut shares: std::collections::HashMap<usize, DVec3> = Default::default();
        let to_map = frame64.transpose();
        // Rings 1/64 of a row wide at the centre (the narrowest ones, at the limb, four
        // times finer), 256 or more.
        let rings = ((64.0 * self.half_aperture / d_theta).ceil() as usize).max(256);
        self.disc_quadrature(&frame64, rings, |d, value| {
            let local = to_map * d;
            let u = local.x.atan2(-local.z) / (2.0 * std::f64::consts::PI);
            let u = u - u.floor();
            let v = local.y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI;
            let x = u * w as f64 - 0.5;
            let y = v * (h - 1) as f64;
            let (x0, y0) = (x.floor(), y.floor().min((h - 2) as f64));
            let (fx, fy) = (x - x0, y - y0);
            let (x0, y0) = (x0 as i64, y0 as usize);
            for (dx, dy, weight) in [
                (0, 0, (1.0 - fx) * (1.0 - fy)),
                (1, 0, fx * (1.0 - fy)),
                (0, 1, (1.0 - fx) * fy),
                (1, 1, fx * fy),
            ] {
                let column = (x0 + dx).rem_euclid(w as i64) as usize;
                *shares.entry((y0 + dy) * w + column).or_default() += value * weight;
            }
        });
        for (index, share) in shares {
            let solid = EnvMap::hat_solid_angle(width, height, (index / w) as u32);
            texels[index] += (share / solid).as_vec3();
        }
        map(texels)
    }
}

/// Mitsuba's `sunsky` as hppm renders it: the model and the map baked from it
/// ([`SunSky::bake`]), which is what the renderer reads.
#[derive(Debug, Clone, PartialEq)]
pub struct SunSkyMap {
    pub model: SunSky,
    pub map: EnvMap,
}

impl SunSkyMap {
    pub fn new(model: SunSky) -> SunSkyMap {
        let map = model.bake();
        SunSkyMap { model, map }
    }
}
