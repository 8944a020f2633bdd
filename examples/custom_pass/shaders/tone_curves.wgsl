#define_import_path custom::tone_curves

// Tone curves from linear radiance to display values in [0, 1] (before sRGB encoding), as the
// CPU reference in src/lib.rs computes them. A module of this crate, registered with
// `Registry::with_module`, importing one of hppm's own.

#import common::sampling::luminance

const CURVE_LINEAR: u32 = 0u;
const CURVE_REINHARD: u32 = 1u;
const CURVE_ACES: u32 = 2u;

// Reinhard et al. 2002 on luminance: the colour scaled by 1 / (1 + L), so hue is kept.
fn reinhard(c: vec3<f32>) -> vec3<f32> {
    return c / (1.0 + luminance(c));
}

// Narkowicz's 2016 fit of the ACES filmic curve, per channel.
fn aces(c: vec3<f32>) -> vec3<f32> {
    let x = max(c, vec3<f32>(0.0));
    return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn tone_curve(curve: u32, c: vec3<f32>) -> vec3<f32> {
    if curve == CURVE_REINHARD {
        return reinhard(c);
    }
    if curve == CURVE_ACES {
        return aces(c);
    }
    return c;
}
