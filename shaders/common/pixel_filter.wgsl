#define_import_path common::pixel_filter

// Pixel reconstruction filters (Mitsuba 3's rfilter) sampled by inverting their CDF: a camera
// sample's offset from its pixel centre has the filter's density, cut to the window [lo, hi]
// (the film's extent around the pixel), so averaging the samples gives Mitsuba's filtered pixel
// without splatting. CPU mirror and tests: src/scene/filter.rs.

const FILTER_BOX: u32 = 0u;
const FILTER_TENT: u32 = 1u;
const FILTER_GAUSSIAN: u32 = 2u;

const GAUSSIAN_INVERSION_STEPS: u32 = 24u;

fn filter_radius(kind: u32, param: f32) -> f32 {
    if kind == FILTER_GAUSSIAN {
        return 4.0 * param;
    }
    return param;
}

// The 1D filter at `x` pixels from the centre, unnormalised, as Mitsuba defines it (the box
// [-1/2, 1/2), the tent 1 - |x| / r, the Gaussian less its value at 4 stddev, clamped at 0):
// the weight of a splatted sample.
fn filter_weight(kind: u32, param: f32, x: f32) -> f32 {
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
