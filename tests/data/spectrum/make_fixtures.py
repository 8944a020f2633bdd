"""Writes src/loaders/spectrum/fixtures.rs: what Mitsuba 3.9.1 makes of spectra in its RGB
variants, the table src/loaders/spectrum.rs's unit tests check against.

    pip install mitsuba==3.9.1 && python3 tests/data/spectrum/make_fixtures.py [--llvm] [--render]

Run from the repository root.

Every value goes through Mitsuba's own XML parser (mi.load_string), in the three ways its
plugins read a colour (Properties::get_texture_impl, src/core/properties.cpp):
- reflectance: a `diffuse` BSDF's `reflectance` (get_texture),
- unbounded: a `conductor`'s `eta` (get_unbounded_texture),
- illuminant: an `area` emitter's `radiance` (get_emissive_texture),
and the RGB is read back with mi.traverse. The same for a `.spd` file (example.spd), and the
texts Mitsuba's parser rejects (the `value` attribute and `.spd` files).

Blackbody: Mitsuba 3's RGB variants load `<spectrum type="blackbody">` but fail when it is
evaluated ("Not implemented for non-spectral modes", src/spectra/blackbody.cpp), so the value
recorded is what its spectral variants render: the plugin's spectrum (evaluated by Mitsuba,
scalar_spectral) integrated against mi.cie1931_xyz over 360-830 nm (16-point Gauss-Legendre in
every 5 nm interval, where the CIE table is linear), times MI_CIE_Y_NORMALIZATION, converted
with Mitsuba's XYZ -> linear sRGB matrix (the film's spectrum_to_srgb,
include/mitsuba/core/spectrum.h). `--render` also renders an emitter filling the view in
scalar_spectral and checks the reference against it (within 4 standard errors). `--llvm` checks
that llvm_ad_rgb gives the same values as scalar_rgb (needs DRJIT_LIBLLVM_PATH).
"""
import os
import subprocess
import sys
import tempfile

import numpy as np

import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))
SPD = os.path.join(HERE, "example.spd")

# Wavelength:value lists (and constants), each converted as the three kinds.
VALUES = [
    # A measured-looking reflectance every 20 nm over 400-700 nm.
    "400:0.343, 420:0.445, 440:0.551, 460:0.624, 480:0.645, 500:0.610, 520:0.541, "
    "540:0.473, 560:0.402, 580:0.331, 600:0.298, 620:0.287, 640:0.291, 660:0.310, "
    "680:0.334, 700:0.352",
    # Irregular spacing.
    "380:0.1, 395.5:0.4, 450:0.8, 452:0.2, 600:0.9, 780:0.3",
    # Narrower than the visible range.
    "500:0.7, 550:0.2",
    # Wider than the CIE range (360-830 nm) at both ends.
    "200:0.5, 300:0.6, 900:0.4, 1000:0.3",
    # Entirely outside the CIE range: black.
    "100:1, 200:1",
    # Flat over exactly the CIE range.
    "360:1, 830:1",
    # A saturated red: out of the sRGB gamut (reflectance clips to [0, 1]; the others clamp
    # negatives to 0).
    "600:1, 650:1",
    # A saturated cyan-blue, negative red.
    "440:0, 470:1, 500:0",
    # Above 1 (reflectance clips).
    "400:2, 700:3",
    # Negative values.
    "400:-0.5, 700:0.5",
    # Conductor-like index of refraction.
    "400:1.6, 500:0.9, 600:0.3, 700:0.2",
    # Number forms Mitsuba's parser accepts: exponent, leading '.', leading '+', tabs and
    # newlines between pairs (turned into spaces by the XML parser), no spaces after commas.
    "4e2:.5,+700:5e-1",
    "400:0.2\t500:0.4\n600:0.6",
    # Empty pieces between colons are skipped by Mitsuba's tokenizer.
    "400::0.5, 700:0.25",
    # Constants.
    "0.5",
    "1",
    "2",
    "0",
    "-0.25",
]

# Texts Mitsuba rejects as a <spectrum>'s value.
REJECTED_VALUES = [
    "",
    "   ",
    "abc",
    "0.5 0.6",
    "0.5, 0.6, 0.7",
    "400:0.5",
    "500:1, 400:2",
    "400:1, 400:2",
    "400:1:2, 500:1",
    "400:x, 500:1",
    "400:1, 500",
    "400:1, :500",
    "400 :1, 500:1",
    "0.5x",
    "400:1, 500:1, 450:1",
]

# .spd file contents Mitsuba rejects.
REJECTED_SPD = [
    "",
    "# only a comment\n",
    "400 0.5\n",
    "400 0.5\n500\n",
    "400 0.5\n   \n500 0.6\n",
    "400 0.5\n  # indented comment\n500 0.6\n",
    "400,0.5\n500,0.6\n",
    "500 0.5\n400 0.6\n",
    "400 0.5\nx 0.6\n",
]

BLACKBODY = [
    # temperature, wavelength_min, wavelength_max (None: the plugin's default, 360-830 nm)
    (1000.0, None, None),
    (2700.0, None, None),
    (6504.0, None, None),
    (10000.0, None, None),
    (5000.0, 400.0, 700.0),
]

M = np.array(
    [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556], [0.055648, -0.204043, 1.057311]],
    dtype=np.float32,
).astype(np.float64)


def xml_escape(text):
    # Tabs and newlines stay literal: the XML parser turns them into spaces (attribute-value
    # normalisation), whereas escaped as &#9; they would reach Mitsuba's tokenizer, which
    # splits at spaces and commas only.
    return text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")


def scene(inner):
    return f'<scene version="3.0.0"><shape type="sphere">{inner}</shape></scene>'


def rgb_of(value, key):
    arr = np.array(value, dtype=np.float32).reshape(-1)
    if arr.size == 1:
        arr = np.repeat(arr, 3)
    assert arr.size == 3, (key, value)
    return [float(v) for v in arr]


def convert(spectrum_tag):
    """The RGB Mitsuba makes of a <spectrum name=NAME .../> tag ({name} placeholder) read as a
    reflectance, an unbounded quantity and an illuminant."""
    out = {}
    s = mi.load_string(scene('<bsdf type="diffuse">' + spectrum_tag.format(name="reflectance") + "</bsdf>"))
    out["reflectance"] = rgb_of(mi.traverse(s.shapes()[0].bsdf())["reflectance.value"], "reflectance")
    s = mi.load_string(scene('<bsdf type="conductor">' + spectrum_tag.format(name="eta") + "</bsdf>"))
    out["unbounded"] = rgb_of(mi.traverse(s.shapes()[0].bsdf())["eta.value"], "eta")
    s = mi.load_string(scene('<emitter type="area">' + spectrum_tag.format(name="radiance") + "</emitter>"))
    out["illuminant"] = rgb_of(mi.traverse(s.shapes()[0].emitter())["radiance.value"], "radiance")
    return out


def value_tag(value):
    return '<spectrum name="{name}" value="' + xml_escape(value) + '"/>'


def rejected(tag):
    """Mitsuba's message (its first line, without the parser's location prefix) if it rejects
    the tag, else None."""
    try:
        mi.load_string(scene('<bsdf type="diffuse">' + tag.format(name="reflectance") + "</bsdf>"))
    except Exception as e:
        return str(e).splitlines()[0].split("col 67): ", 1)[-1]
    return None


def blackbody_reference(temperature, wmin, wmax):
    mi.set_variant("scalar_spectral")
    props = {"type": "blackbody", "temperature": temperature}
    if wmin is not None:
        props["wavelength_min"] = wmin
        props["wavelength_max"] = wmax
    bb = mi.load_dict(props)
    nodes, weights = np.polynomial.legendre.leggauss(16)
    si = mi.SurfaceInteraction3f()
    xyz = np.zeros(3)
    for k in range(94):
        a = 360.0 + 5.0 * k
        lam = a + 2.5 * (nodes + 1.0)
        for j in range(0, 16, 4):
            quad = [float(v) for v in lam[j:j + 4]]
            si.wavelengths = mi.Spectrum(*quad)
            b = np.array(bb.eval(si), dtype=np.float64)
            for q in range(4):
                cmf = np.array(mi.cie1931_xyz(quad[q]), dtype=np.float64)
                xyz += weights[j + q] * 2.5 * b[q] * cmf
    mi.set_variant("scalar_rgb")
    return M @ (xyz * mi.MI_CIE_Y_NORMALIZATION)


def blackbody_render(temperature):
    """Mean pixel and its standard error of an emitter filling the view, scalar_spectral."""
    mi.set_variant("scalar_spectral")
    xml = f'''<scene version="3.0.0"><integrator type="direct"/>
<sensor type="perspective"><float name="fov" value="10"/>
<transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
<film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
<sampler type="independent"><integer name="sample_count" value="256"/></sampler></sensor>
<shape type="rectangle"><emitter type="area"><spectrum type="blackbody" name="radiance">
<float name="temperature" value="{temperature}"/></spectrum></emitter></shape></scene>'''
    img = np.array(mi.render(mi.load_string(xml)), dtype=np.float64).reshape(-1, 3)
    mi.set_variant("scalar_rgb")
    return img.mean(0), img.std(0) / np.sqrt(img.shape[0])


def f32(v):
    s = np.format_float_positional(np.float32(v), unique=True)
    return s + "0" if s.endswith(".") else s


def f64(v):
    s = repr(float(v))
    return s if ("." in s or "e" in s or "inf" in s) else s + ".0"


def arr32(v):
    return "[" + ", ".join(f32(x) for x in v) + "]"


def rust_str(s):
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"').replace("\t", "\\t").replace("\n", "\\n").replace("\r", "\\r") + '"'


def collect(variant):
    mi.set_variant(variant)
    cases = [(v, convert(value_tag(v))) for v in VALUES]
    spd = convert('<spectrum name="{name}" filename="' + SPD + '"/>')
    return cases, spd


def main():
    mi.set_variant("scalar_rgb")
    cases, spd = collect("scalar_rgb")

    if "--llvm" in sys.argv:
        # In a child process, which fails loudly (check=True) where LLVM is not found.
        code = ("import sys; sys.argv=['x']; sys.path.insert(0, %r); import make_fixtures as m; "
                "import json; c, s = m.collect('llvm_ad_rgb'); print('JSON' + json.dumps([c, s]))") % HERE
        res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        import json
        # Mitsuba's log shares stdout (and colour codes end up before the marker).
        line = [x for x in res.stdout.splitlines() if "JSON" in x][-1]
        lc, ls = json.loads(line.split("JSON", 1)[1])
        assert lc == [[v, r] for v, r in cases], "llvm_ad_rgb differs from scalar_rgb"
        assert ls == spd, "llvm differs on the .spd file"
        print("llvm_ad_rgb: same values as scalar_rgb", file=sys.stderr)

    rejected_values = []
    for v in REJECTED_VALUES:
        err = rejected(value_tag(v))
        assert err is not None, f"Mitsuba accepted {v!r}"
        rejected_values.append((v, err))
    rejected_spd = []
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "rejected.spd")
        for text in REJECTED_SPD:
            with open(path, "w", newline="") as f:
                f.write(text)
            err = rejected('<spectrum name="{name}" filename="' + path + '"/>')
            assert err is not None, f"Mitsuba accepted the .spd {text!r}"
            rejected_spd.append((text, err.replace(tmp + os.sep, "")))

    blackbody = []
    for t, lo, hi in BLACKBODY:
        ref = blackbody_reference(t, lo, hi)
        if "--render" in sys.argv and lo is None:
            mean, err = blackbody_render(t)
            assert np.all(np.abs(mean - ref) <= 4 * err + 1e-9 * np.abs(ref).max()), (t, mean, err, ref)
            print(f"blackbody {t} K: render {mean} +- {err}, reference {ref}", file=sys.stderr)
        blackbody.append((t, lo, hi, ref))

    o = []
    o.append("//! Mitsuba 3.9.1's RGB for spectra, written by tests/data/spectrum/make_fixtures.py")
    o.append("//! (see there how each was obtained); do not edit.")
    o.append("")
    o.append("/// A `<spectrum value=...>` text and Mitsuba's RGB for it as each kind.")
    o.append("pub(super) struct ValueCase {")
    o.append("    pub value: &'static str,")
    o.append("    pub reflectance: [f32; 3],")
    o.append("    pub unbounded: [f32; 3],")
    o.append("    pub illuminant: [f32; 3],")
    o.append("}")
    o.append("")
    o.append("pub(super) const VALUE_CASES: &[ValueCase] = &[")
    for v, r in cases:
        o.append("    ValueCase {")
        o.append(f"        value: {rust_str(v)},")
        for k in ("reflectance", "unbounded", "illuminant"):
            o.append(f"        {k}: {arr32(r[k])},")
        o.append("    },")
    o.append("];")
    o.append("")
    o.append("/// Mitsuba's RGB for tests/data/spectrum/example.spd (reflectance, unbounded, illuminant).")
    o.append("pub(super) const SPD_EXAMPLE: [[f32; 3]; 3] = [")
    for k in ("reflectance", "unbounded", "illuminant"):
        o.append(f"    {arr32(spd[k])},")
    o.append("];")
    o.append("")
    o.append("/// `value` texts Mitsuba rejects, with the first line of its message.")
    o.append("pub(super) const REJECTED_VALUES: &[(&str, &str)] = &[")
    for v, e in rejected_values:
        o.append(f"    ({rust_str(v)}, {rust_str(e)}),")
    o.append("];")
    o.append("")
    o.append("/// `.spd` file contents Mitsuba rejects, with the first line of its message.")
    o.append("pub(super) const REJECTED_SPD: &[(&str, &str)] = &[")
    for v, e in rejected_spd:
        o.append(f"    ({rust_str(v)}, {rust_str(e)}),")
    o.append("];")
    o.append("")
    o.append("/// A blackbody: temperature (K), Mitsuba's wavelength_min/max, and what Mitsuba's")
    o.append("/// spectral variants render for it as linear sRGB (negative channels not clamped).")
    o.append("pub(super) struct BlackbodyCase {")
    o.append("    pub temperature: f32,")
    o.append("    pub range: Option<(f32, f32)>,")
    o.append("    pub spectral_render: [f64; 3],")
    o.append("}")
    o.append("")
    o.append("pub(super) const BLACKBODY_CASES: &[BlackbodyCase] = &[")
    for t, lo, hi, ref in blackbody:
        rng = "None" if lo is None else f"Some(({f32(lo)}, {f32(hi)}))"
        o.append("    BlackbodyCase {")
        o.append(f"        temperature: {f32(t)},")
        o.append(f"        range: {rng},")
        o.append(f"        spectral_render: [{', '.join(f64(x) for x in ref)}],")
        o.append("    },")
    o.append("];")
    o.append("")
    path = "src/loaders/spectrum/fixtures.rs"
    with open(path, "w") as f:
        f.write("\n".join(o))
    print("wrote", path, file=sys.stderr)


if __name__ == "__main__":
    main()
