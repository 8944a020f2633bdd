//! The thin lens's geometry on the GPU, measured on the image of two small lights in the dark
//! (Mitsuba's thinlens: a uniform point of the aperture disc, aimed where the pinhole ray meets
//! the focus plane). Block means against Mitsuba (tests/differential.rs, `thinlens`) catch an
//! ignored aperture; this catches what they cannot see: where the focus lies and how large and
//! how even the blur disc is.

mod common;

use std::path::Path;

use common::*;
use hppm::loaders::mitsuba;

/// A 32x32 thinlens image (fov 40, aperture 1, focus 6 ahead) of a light of radius 0.05 on the
/// focus plane and one of radius 0.1 at 3 units from the lens.
const SCENE: &str = r#"<scene version="3.0.0">
    <sensor type="thinlens">
        <float name="fov" value="40"/>
        <float name="aperture_radius" value="1"/>
        <float name="focus_distance" value="6"/>
        <transform name="to_world"><lookat origin="0, 0, 6" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
    <shape type="sphere"><point name="center" value="1.2, 0.6, 0"/><float name="radius" value="0.05"/>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
    <shape type="sphere"><point name="center" value="-0.6, -0.3, 3"/><float name="radius" value="0.1"/>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
</scene>"#;

/// Where a point at camera-plane coordinates (x, y) (one unit ahead) lands, in pixels.
fn pixel_of(x: f64, y: f64) -> (f64, f64) {
    let tan = (20f64).to_radians().tan();
    let step = 2.0 * tan / 32.0;
    ((x + tan) / step, (tan - y) / step)
}

/// The light on the focus plane stays sharp: 90% of the light in the image's right half falls
/// in the 3x3 pixels around where the pinhole sees it (a focus 30% too far spreads it over a
/// disc of 1.7 pixels' radius and fails; so would a focus measured to a sphere at this angle,
/// 1.3 pixels). The light at half the focus distance is a disc of radius
/// aperture x (1/3 - 1/6) on the camera plane, 7.3 pixels, centred where the pinhole sees it:
/// its light's centroid within a pixel of there and its RMS radius that of a uniform disc
/// (R/sqrt 2, widened by the light's own 1.5-pixel image) within 10%. An ignored aperture (no
/// disc), a radius off by a factor, a focus 30% off (R 9 pixels) or a disc sampled with
/// uniform radius instead of uniform area (RMS R/sqrt 3) fails.
#[test]
fn the_thin_lens_focuses_on_its_plane_and_blurs_the_rest() {
    let report = mitsuba::check_text(Path::new("lens.xml"), SCENE, &[]);
    let scene = report
        .scene
        .unwrap_or_else(|| panic!("{:?}", report.errors));
    let gpu = gpu();
    let mut r = renderer(&gpu, &scene, load_graph("graphs/pt.ron"), 1);
    let image = render_to(&mut r, 1024);
    let at = |x: usize, y: usize| {
        let p = image.pixels[y * 32 + x];
        (p[0] + p[1] + p[2]) as f64 / 3.0
    };
    // The sharp light, at (1.2, 0.6) / 6 on the camera plane.
    let (sx, sy) = pixel_of(0.2, 0.1);
    let (sx, sy) = (sx.floor() as usize, sy.floor() as usize);
    let mut right = 0.0;
    let mut near = 0.0;
    for y in 0..32 {
        for x in 16..32 {
            right += at(x, y);
            if x.abs_diff(sx) <= 1 && y.abs_diff(sy) <= 1 {
                near += at(x, y);
            }
        }
    }
    assert!(right > 0.0, "the focused light is not in the image");
    let sharp = near / right;
    eprintln!(
        "focused light: {:.3} of its light in the 3x3 at ({sx}, {sy})",
        sharp
    );
    assert!(
        sharp > 0.9,
        "the focus plane is blurred: {sharp:.3} in the 3x3"
    );
    // The blurred light, at (-0.6, -0.3) / 3.
    let (cx, cy) = pixel_of(-0.2, -0.1);
    let step = 2.0 * (20f64).to_radians().tan() / 32.0;
    let disc = 1.0 * (1.0 / 3.0 - 1.0 / 6.0) / step;
    let own = 0.1 / 3.0 / step;
    let (mut total, mut mx, mut my) = (0.0, 0.0, 0.0);
    let mut samples = Vec::new();
    for y in 0..32 {
        for x in 0..16 {
            let v = at(x, y);
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            total += v;
            mx += v * px;
            my += v * py;
            samples.push((px, py, v));
        }
    }
    assert!(total > 0.0, "the blurred light is not in the image");
    let (mx, my) = (mx / total, my / total);
    let rms = (samples
        .iter()
        .map(|&(x, y, v)| v * ((x - mx).powi(2) + (y - my).powi(2)))
        .sum::<f64>()
        / total)
        .sqrt();
    // A uniform disc of radius R has RMS radius R/sqrt 2; the light's own disc and a pixel's
    // width (1/6 each way) add in quadrature.
    let expected = ((disc * disc + own * own) / 2.0 + 1.0 / 6.0).sqrt();
    eprintln!(
        "blurred light: centroid ({mx:.2}, {my:.2}) against ({cx:.2}, {cy:.2}), RMS radius \
         {rms:.2} against {expected:.2}"
    );
    assert!(
        (mx - cx).abs() < 1.0 && (my - cy).abs() < 1.0,
        "the blur disc is off centre"
    );
    assert!(
        (rms / expected - 1.0).abs() < 0.1,
        "the blur disc's RMS radius {rms:.2} is not {expected:.2}"
    );
}
