#define_import_path common::pixel_filter

#import common::sampling::PI

// Pixel reconstruction filters (Mitsuba 3's rfilter) sampled by inverting their CDF: a camera
// sample's offset from its pixel centre has the filter's density, cut to the window [lo, hi]
// (the film's extent around the pixel), so averaging the samples gives Mitsuba's filtered pixel
// without splatting. CPU mirror and tests: src/scene/filter.rs. Lanczos and the Mitchell
// cubics have negative lobes: they are splatted with their signed weights, and their
// filter-distributed samples come from a table in the scene uniform (common::signed_filter).

const FILTER_BOX: u32 = 0u;
const FILTER_TENT: u32 = 1u;
const FILTER_GAUSSIAN: u32 = 2u;
const FILTER_LANCZOS: u32 = 3u;
const FILTER_MITCHELL: u32 = 4u;

// Below this |x| Lanczos is 1 (Mitsuba's test against its float epsilon).
const LANCZOS_CENTRE: f32 = 5.9604645e-8;

const GAUSSIAN_INVERSION_STEPS: u32 = 24u;

fn filter_radius(kind: u32, param: f32) -> f32 {
    if kind == FILTER_GAUSSIAN {
        return 4.0 * param;
    }
    if kind == FILTER_MITCHELL {
        return 2.0;
    }
    return param;
}

fn is_signed_filter(kind: u32) -> bool {
    return kind == FILTER_LANCZOS || kind == FILTER_MITCHELL;
}

// sinc(x) sinc(x / lobes) within the lobes (Mitsuba's lanczos).
fn lanczos(lobes: f32, x: f32) -> f32 {
    let a = abs(x);
    if a < LANCZOS_CENTRE {
        return 1.0;
    }
    if a > lobes {
        return 0.0;
    }
    let x1 = PI * a;
    let x2 = x1 / lobes;
    return sin(x1) * sin(x2) / (x1 * x2);
}

// The Mitchell-Netravali cubic with parameters b and c on |x| < 2 (Mitsuba's mitchell and, with
// b = 0 and c = 1/2, its catmullrom).
fn mitchell(b: f32, c: f32, x: f32) -> f32 {
    let a = abs(x);
    let a2 = a * a;
    let a3 = a2 * a;
    var value = (12.0 - 9.0 * b - 6.0 * c) * a3 + (-18.0 + 12.0 * b + 6.0 * c) * a2 + (6.0 - 2.0 * b);
    if a >= 1.0 {
        value = (-b - 6.0 * c) * a3 + (6.0 * b + 30.0 * c) * a2 + (-12.0 * b - 48.0 * c) * a + (8.0 * b + 24.0 * c);
    }
    return select(0.0, value / 6.0, a < 2.0);
}

// The 1D filter at `x` pixels from the centre, unnormalised, as Mitsuba defines it (the box
// [-1/2, 1/2), the tent 1 - |x| / r, the Gaussian less its value at 4 stddev, clamped at 0,
// Lanczos and the cubics signed): the weight of a splatted sample. `param` holds the filter's
// parameters (x: tent radius, Gaussian stddev, Lanczos lobes, Mitchell's B; y: Mitchell's C).
fn filter_weight(kind: u32, param: vec2<f32>, x: f32) -> f32 {
    if kind == FILTER_LANCZOS {
        return lanczos(param.x, x);
    }
    if kind == FILTER_MITCHELL {
        return mitchell(param.x, param.y, x);
    }
    return nonnegative_filter_weight(kind, param.x, x);
}

fn nonnegative_filter_weight(kind: u32, param: f32, x: f32) -> f32 {
    if kind == FILTER_GAUSSIAN {
        let r = 4.0 * param;
        let k = -0.5 / (param * param);
        return max(exp(k * x * x) - exp(k * r * r), 0.0);
    }
    if kind == FILTER_TENT {
        return max(1.0 - abs(x) / param, 0.0);
    }
    return select(0.0, 1.0, x >= -0.5 && x < 0.5);
}

// erf by Abramowitz & Stegun 7.1.26 (absolute error below 1.5e-7).
fn erf_approx(z: f32) -> f32 {
    let a = abs(z);
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let poly = t * (0.2548296 + t * (-0.28449674 + t * (1.4214137 + t * (-1.4531521 + t * 1.0614054))));
    let value = 1.0 - poly * exp(-a * a);
    return select(value, -value, z < 0.0);
}

// The windowed Gaussian exp(-x^2 / 2s^2) - bias integrated from 0 to x.
fn gaussian_integral(s: f32, bias: f32, x: f32) -> f32 {
    return s * 1.2533141 * erf_approx(x * (0.70710678 / s)) - bias * x;
}

fn gaussian_offset(s: f32, u: f32, lo: f32, hi: f32) -> f32 {
    let r = 4.0 * s;
    let bias = exp(-r * r / (2.0 * s * s));
    let target_value = gaussian_integral(s, bias, lo) + u * (gaussian_integral(s, bias, hi) - gaussian_integral(s, bias, lo));
    var a = lo;
    var b = hi;
    var x = clamp(0.0, lo, hi);
    for (var i = 0u; i < GAUSSIAN_INVERSION_STEPS; i++) {
        let err = gaussian_integral(s, bias, x) - target_value;
        if err > 0.0 {
            b = x;
        } else {
            a = x;
        }
        let density = exp(-x * x / (2.0 * s * s)) - bias;
        let next = x - err / density;
        // A step out of the bracket (or through a vanishing density in the tail) bisects.
        if next > a && next < b {
            x = next;
        } else {
            x = 0.5 * (a + b);
        }
    }
    return x;
}

fn tent_cdf(r: f32, x: f32) -> f32 {
    return x - x * abs(x) / (2.0 * r);
}

// An offset from the pixel centre, in pixels, with the filter's density on [lo, hi] cut to its
// support; `u` in [0, 1).
fn filter_offset(kind: u32, param: f32, u: f32, window_lo: f32, window_hi: f32) -> f32 {
    let r = filter_radius(kind, param);
    let lo = max(window_lo, -r);
    let hi = min(window_hi, r);
    if kind == FILTER_TENT {
        let t = tent_cdf(param, lo) + u * (tent_cdf(param, hi) - tent_cdf(param, lo));
        let a = param * (1.0 - sqrt(max(1.0 - 2.0 * abs(t) / param, 0.0)));
        return clamp(select(a, -a, t < 0.0), lo, hi);
    }
    if kind == FILTER_GAUSSIAN {
        return gaussian_offset(param, u, lo, hi);
    }
    return lo + u * (hi - lo);
}
