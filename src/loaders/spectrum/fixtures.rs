//! Mitsuba 3.9.1's RGB for spectra, written by tests/data/spectrum/make_fixtures.py
//! (see there how each was obtained); do not edit.

/// A `<spectrum value=...>` text and Mitsuba's RGB for it as each kind.
pub(super) struct ValueCase {
    pub value: &'static str,
    pub reflectance: [f32; 3],
    pub unbounded: [f32; 3],
    pub illuminant: [f32; 3],
}

pub(super) const VALUE_CASES: &[ValueCase] = &[
    ValueCase {
        value: "400:0.343, 420:0.445, 440:0.551, 460:0.624, 480:0.645, 500:0.610, 520:0.541, 540:0.473, 560:0.402, 580:0.331, 600:0.298, 620:0.287, 640:0.291, 660:0.310, 680:0.334, 700:0.352",
        reflectance: [0.20225397, 0.47608945, 0.5952952],
        unbounded: [0.20225397, 0.47608945, 0.5952952],
        illuminant: [0.27376738, 0.4495349, 0.53730476],
    },
    ValueCase {
        value: "380:0.1, 395.5:0.4, 450:0.8, 452:0.2, 600:0.9, 780:0.3",
        reflectance: [0.9637228, 0.60712266, 0.44494286],
        unbounded: [0.9637228, 0.60712266, 0.44494286],
        illuminant: [1.1165891, 0.5812759, 0.41347307],
    },
    ValueCase {
        value: "500:0.7, 550:0.2",
        reflectance: [0.0, 0.2631056, 0.0],
        unbounded: [0.0, 0.2631056, 0.0],
        illuminant: [0.0, 0.24485174, 0.0],
    },
    ValueCase {
        value: "200:0.5, 300:0.6, 900:0.4, 1000:0.3",
        reflectance: [0.48536524, 0.51841563, 0.5523943],
        unbounded: [0.48536524, 0.51841563, 0.5523943],
        illuminant: [0.5882976, 0.49190307, 0.5038999],
    },
    ValueCase {
        value: "100:1, 200:1",
        reflectance: [0.0, 0.0, 0.0],
        unbounded: [0.0, 0.0, 0.0],
        illuminant: [0.0, 0.0, 0.0],
    },
    ValueCase {
        value: "360:1, 830:1",
        reflectance: [0.9989853, 0.9988737, 0.9988016],
        unbounded: [0.9989853, 0.9988737, 0.9988016],
        illuminant: [1.2048837, 0.9482282, 0.9092668],
    },
    ValueCase {
        value: "600:1, 650:1",
        reflectance: [0.7486834, 0.0, 0.0],
        unbounded: [0.7486834, 0.0, 0.0],
        illuminant: [0.8538676, 0.0, 0.0],
    },
    ValueCase {
        value: "440:0, 470:1, 500:0",
        reflectance: [0.0, 0.018547915, 0.421481],
        unbounded: [0.0, 0.018547915, 0.421481],
        illuminant: [0.0, 0.016719025, 0.36070207],
    },
    ValueCase {
        value: "400:2, 700:3",
        reflectance: [1.0, 1.0, 1.0],
        unbounded: [2.7948322, 2.4759684, 2.1258602],
        illuminant: [3.339694, 2.3537614, 1.920583],
    },
    ValueCase {
        value: "400:-0.5, 700:0.5",
        reflectance: [0.30647722, 0.0, 0.0],
        unbounded: [0.30647722, 0.0, 0.0],
        illuminant: [0.34045997, 0.0, 0.0],
    },
    ValueCase {
        value: "400:1.6, 500:0.9, 600:0.3, 700:0.2",
        reflectance: [0.15324701, 0.6302518, 1.0],
        unbounded: [0.15324701, 0.6302518, 1.2978834],
        illuminant: [0.23462476, 0.5923423, 1.1980021],
    },
    ValueCase {
        value: "4e2:.5,+700:5e-1",
        reflectance: [0.497671, 0.4998782, 0.49745455],
        unbounded: [0.497671, 0.4998782, 0.49745455],
        illuminant: [0.5998468, 0.47476017, 0.45172167],
    },
    ValueCase {
        value: "400:0.2\t500:0.4\n600:0.6",
        reflectance: [0.13493174, 0.511488, 0.2884563],
        unbounded: [0.13493174, 0.511488, 0.2884563],
        illuminant: [0.17306639, 0.49346548, 0.25783202],
    },
    ValueCase {
        value: "400::0.5, 700:0.25",
        reflectance: [0.29663396, 0.38076434, 0.46344405],
        unbounded: [0.29663396, 0.38076434, 0.46344405],
        illuminant: [0.3647701, 0.36108005, 0.42329758],
    },
    ValueCase {
        value: "0.5",
        reflectance: [0.5, 0.5, 0.5],
        unbounded: [0.5, 0.5, 0.5],
        illuminant: [0.60239697, 0.4741455, 0.45445803],
    },
    ValueCase {
        value: "1",
        reflectance: [1.0, 1.0, 1.0],
        unbounded: [1.0, 1.0, 1.0],
        illuminant: [1.2047939, 0.948291, 0.90891606],
    },
    ValueCase {
        value: "2",
        reflectance: [2.0, 2.0, 2.0],
        unbounded: [2.0, 2.0, 2.0],
        illuminant: [2.4095879, 1.896582, 1.8178321],
    },
    ValueCase {
        value: "0",
        reflectance: [0.0, 0.0, 0.0],
        unbounded: [0.0, 0.0, 0.0],
        illuminant: [0.0, 0.0, 0.0],
    },
    ValueCase {
        value: "-0.25",
        reflectance: [-0.25, -0.25, -0.25],
        unbounded: [-0.25, -0.25, -0.25],
        illuminant: [-0.30119848, -0.23707275, -0.22722901],
    },
];

/// Mitsuba's RGB for tests/data/spectrum/example.spd (reflectance, unbounded, illuminant).
pub(super) const SPD_EXAMPLE: [[f32; 3]; 3] = [
    [0.20849228, 0.47330505, 0.49772322],
    [0.20849228, 0.47330505, 0.49772322],
    [0.2846064, 0.44600427, 0.4478362],
];

/// `value` texts Mitsuba rejects, with the first line of its message.
pub(super) const REJECTED_VALUES: &[(&str, &str)] = &[
    ("", "<spectrum> element requires either \"value\" or \"filename\" attribute (but not both)"),
    ("   ", "[properties.cpp:795] Spectrum must have at least two entries"),
    ("abc", "[properties.cpp:828] Could not parse uniform spectrum value \"abc\""),
    ("0.5 0.6", "[properties.cpp:839] Invalid spectrum value \"0.5\" (expected wavelength:value pairs)"),
    ("0.5, 0.6, 0.7", "[properties.cpp:839] Invalid spectrum value \"0.5\" (expected wavelength:value pairs)"),
    ("400:0.5", "[properties.cpp:795] Spectrum must have at least two entries"),
    ("500:1, 400:2", "[properties.cpp:802] Wavelengths must be specified in increasing order."),
    ("400:1, 400:2", "[properties.cpp:802] Wavelengths must be specified in increasing order."),
    ("400:1:2, 500:1", "[properties.cpp:839] Invalid spectrum value \"400:1:2\" (expected wavelength:value pairs)"),
    ("400:x, 500:1", "[properties.cpp:845] Could not parse wavelength:value pair \"400:x\""),
    ("400:1, 500", "[properties.cpp:839] Invalid spectrum value \"500\" (expected wavelength:value pairs)"),
    ("400:1, :500", "[properties.cpp:839] Invalid spectrum value \":500\" (expected wavelength:value pairs)"),
    ("400 :1, 500:1", "[properties.cpp:839] Invalid spectrum value \"400\" (expected wavelength:value pairs)"),
    ("0.5x", "[properties.cpp:828] Could not parse uniform spectrum value \"0.5x\""),
    ("400:1, 500:1, 450:1", "[properties.cpp:802] Wavelengths must be specified in increasing order."),
];

/// `.spd` file contents Mitsuba rejects, with the first line of its message.
pub(super) const REJECTED_SPD: &[(&str, &str)] = &[
    ("", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:795] Spectrum must have at least two entries"),
    ("# only a comment\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:795] Spectrum must have at least two entries"),
    ("400 0.5\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:795] Spectrum must have at least two entries"),
    ("400 0.5\n500\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:955] Could not extract value in line 2 of spectrum file \"rejected.spd\": \"500"),
    ("400 0.5\n   \n500 0.6\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:947] Could not extract wavelength in line 2 of spectrum file \"rejected.spd\": \"   "),
    ("400 0.5\n  # indented comment\n500 0.6\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:947] Could not extract wavelength in line 2 of spectrum file \"rejected.spd\": \"  # indented comment"),
    ("400,0.5\n500,0.6\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:955] Could not extract value in line 1 of spectrum file \"rejected.spd\": \"400,0.5"),
    ("500 0.5\n400 0.6\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:802] Wavelengths must be specified in increasing order."),
    ("400 0.5\nx 0.6\n", "failed to load spectrum from file \"rejected.spd\": [properties.cpp:947] Could not extract wavelength in line 2 of spectrum file \"rejected.spd\": \"x 0.6"),
];

/// A blackbody: temperature (K), Mitsuba's wavelength_min/max, and what Mitsuba's
/// spectral variants render for it as linear sRGB (negative channels not clamped).
pub(super) struct BlackbodyCase {
    pub temperature: f32,
    pub range: Option<(f32, f32)>,
    pub spectral_render: [f64; 3],
}

pub(super) const BLACKBODY_CASES: &[BlackbodyCase] = &[
    BlackbodyCase {
        temperature: 1000.0,
        range: None,
        spectral_render: [0.00016974808976774237, 1.476090188524697e-06, -3.3236665077698363e-06],
    },
    BlackbodyCase {
        temperature: 2700.0,
        range: None,
        spectral_render: [314.50574873590006, 130.62905233240062, 31.199437137910692],
    },
    BlackbodyCase {
        temperature: 6504.0,
        range: None,
        spectral_render: [44058.84586396206, 41554.01718099621, 43761.97659119417],
    },
    BlackbodyCase {
        temperature: 10000.0,
        range: None,
        spectral_render: [158567.15756026053, 180899.01944744354, 260286.0572311844],
    },
    BlackbodyCase {
        temperature: 5000.0,
        range: Some((400.0, 700.0)),
        spectral_render: [15221.689043979086, 12106.72375911891, 9554.901376754196],
    },
];
