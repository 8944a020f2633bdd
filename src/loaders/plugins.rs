//! The Mitsuba 3 plugins the XML loader reads itself (the BSDFs' rows are their units', in
//! src/bsdfs/), with every property each one reads, its default and what hppm does with it: the
//! one list the loader's messages, `hppm plugins` and the table of docs/scenes.md come from. Tests hold it to the loader: every property listed is one the
//! loader reads, and every property the loader reads is listed (tests/mitsuba_compat.rs).

use crate::bsdfs::BsdfRegistry;
use crate::scene::plugin::{Plugin, Property, p};

const MESH_FILE: &[Property] = &[
    p("filename", ""),
    p("face_normals", "false"),
    p("flip_tex_coords", "true for OBJ, false for PLY"),
    p("to_world", "identity"),
    p("flip_normals", "false"),
    p("silhouette_sampling_weight", "1"),
];

/// The plugins before the BSDFs, in the order docs/scenes.md lists them.
pub const BEFORE_BSDFS: &[Plugin] = &[
    Plugin {
        object: "integrator",
        kinds: &["path", "volpath", "volpathmis", "any other"],
        properties: &[
            p("max_depth", "-1"),
            p("rr_depth", "5"),
            p("hide_emitters", "false"),
        ],
        notes: "The render graph chooses the algorithm; `path`, `volpath` and `volpathmis` are \
                what hppm renders (media as `volpath` renders them). Another integrator (`bdpt`, \
                `direct`: max_depth 2, a plugin of a research project) is rendered with its path \
                depths and a warning naming it and what it leaves out; one that wraps another \
                (`aov`) gives the wrapped one's. `hide_emitters`: camera rays pass through \
                emitting shapes and see no environment.",
    },
    Plugin {
        object: "sensor",
        kinds: &["perspective"],
        properties: &[
            p("fov", ""),
            p("fov_axis", "x"),
            p("focal_length", "50mm"),
            p("near_clip", "0.01"),
            p("far_clip", "10000"),
            p("focus_distance", "far_clip"),
            p("principal_point_offset_x", "0"),
            p("principal_point_offset_y", "0"),
            p("shutter_open", "0"),
            p("shutter_close", "0"),
            p("srf", ""),
            p("to_world", "identity"),
        ],
        notes: "`fov_axis` x, y, diagonal, smaller or larger; without `fov`, the `focal_length` \
                of a 36 x 24 mm frame gives the diagonal fov (of the whole film, whatever its \
                crop window), as in Mitsuba. A pinhole: the focus distance changes nothing; clip \
                planes are checked as Mitsuba checks them but cut no camera ray (only geometry \
                within `near_clip` of the camera or beyond `far_clip` would show it); shutter \
                times change nothing; an off-centre principal point is refused; `srf` (spectral \
                rendering only) is a warning. No mirroring `to_world`.",
    },
    Plugin {
        object: "sensor",
        kinds: &["thinlens"],
        properties: &[
            p("aperture_radius", ""),
            p("focus_distance", "far_clip"),
            p("fov", ""),
            p("fov_axis", "x"),
            p("focal_length", "50mm"),
            p("near_clip", "0.01"),
            p("far_clip", "10000"),
            p("shutter_open", "0"),
            p("shutter_close", "0"),
            p("srf", ""),
            p("to_world", "identity"),
        ],
        notes: "As `perspective`, through a thin lens: rays leave a uniform point of the \
                aperture disc (Mitsuba's concentric map) and meet on the plane `focus_distance` \
                ahead along the view axis. `aperture_radius` is required, as in Mitsuba; 0 is a \
                pinhole with a warning. No principal point shift (Mitsuba's thinlens reads \
                none).",
    },
    Plugin {
        object: "sampler",
        kinds: &["independent", "any other"],
        properties: &[p("sample_count", "4"), p("seed", "0")],
        notes: "`sample_count` is the default budget. hppm draws independent samples: another \
                sampler (`stratified`, `multijitter`, `ldsampler`) is a warning.",
    },
    Plugin {
        object: "film",
        kinds: &["hdrfilm"],
        properties: &[
            p("width", "768"),
            p("height", "576"),
            p("crop_offset_x", "0"),
            p("crop_offset_y", "0"),
            p("crop_width", "width"),
            p("crop_height", "height"),
            p("sample_border", "false"),
            p("pixel_format", "rgb"),
            p("component_format", "float16"),
            p("file_format", "openexr"),
            p("compensate", "false"),
        ],
        notes: "A crop window renders that part of the film's view into an image of the \
                window's size; its samples keep to the window unless `sample_border`, as in \
                Mitsuba; a window off the film is refused. `--size` scales film and window \
                together. Output is RGB: the pixel, component and file formats are read and ignored; \
                `compensate` is a warning (Mitsuba 3 removed it).",
    },
    Plugin {
        object: "rfilter",
        kinds: &["box"],
        properties: &[],
        notes: "",
    },
    Plugin {
        object: "rfilter",
        kinds: &["tent"],
        properties: &[p("radius", "1")],
        notes: "Splats as Mitsuba's film does.",
    },
    Plugin {
        object: "rfilter",
        kinds: &["gaussian"],
        properties: &[p("stddev", "0.5")],
        notes: "The filter when none is given, as in Mitsuba; its radius is 4 stddev; splats as \
                Mitsuba's film does.",
    },
    Plugin {
        object: "rfilter",
        kinds: &["lanczos"],
        properties: &[p("lobes", "3")],
        notes: "Radius `lobes` (at most 16). Splats with its signed weights as Mitsuba's film \
                does; the samples that record hit points (in the hybrid, all) are drawn from \
                |f| and splatted too, over the density of all pixels' draws. Their hit points, \
                and with `sample_border` every sample, carry the sign as a weight of about \
                ±1.85: unbiased, noisier than splatting in flat regions (2.4 L^2 a sample)",
    },
    Plugin {
        object: "rfilter",
        kinds: &["mitchell"],
        properties: &[p("B", "1/3"), p("C", "1/3")],
        notes: "Radius 2; as `lanczos`, with weights of about ±1.14 at the defaults (0.31 L^2 \
                a sample)",
    },
    Plugin {
        object: "rfilter",
        kinds: &["catmullrom"],
        properties: &[],
        notes: "The Mitchell cubic with B = 0, C = 1/2, as in Mitsuba (weights of about ±1.36, \
                0.85 L^2 a sample)",
    },
    Plugin {
        object: "shape",
        kinds: &["rectangle", "disk"],
        properties: &[
            p("to_world", "identity"),
            p("flip_normals", "false"),
            p("silhouette_sampling_weight", "1"),
        ],
        notes: "A disk is a fan of 256 triangles whose area (and an emitting disk's power) is \
                exactly Mitsuba's, its outline within 0.01% of the radius. Every shape may \
                carry a `bsdf` and an `area` emitter. `silhouette_sampling_weight` (every \
                shape) serves Mitsuba's differentiable rendering: read, no effect.",
    },
    Plugin {
        object: "shape",
        kinds: &["cube"],
        properties: &[
            p("to_world", "identity"),
            p("flip_normals", "false"),
            p("face_normals", "false"),
            p("silhouette_sampling_weight", "1"),
        ],
        notes: "Its faces are flat, so `face_normals` changes nothing.",
    },
    Plugin {
        object: "shape",
        kinds: &["sphere"],
        properties: &[
            p("center", "0, 0, 0"),
            p("radius", "1"),
            p("to_world", "identity"),
            p("flip_normals", "false"),
            p("silhouette_sampling_weight", "1"),
        ],
        notes: "Analytic. Its `to_world` may only scale uniformly, rotate and translate.",
    },
    Plugin {
        object: "shape",
        kinds: &["cylinder"],
        properties: &[
            p("p0", "0, 0, 0"),
            p("p1", "0, 0, 1"),
            p("radius", "1"),
            p("to_world", "identity"),
            p("flip_normals", "false"),
            p("silhouette_sampling_weight", "1"),
        ],
        notes: "An open tube of 256 quads with radial vertex normals, its area exactly \
                Mitsuba's, in the frame Mitsuba builds about its axis (so its uvs match).",
    },
    Plugin {
        object: "shape",
        kinds: &["obj", "ply"],
        properties: MESH_FILE,
        notes: "PLY ASCII and binary. Vertex normals from the file, or computed angle-weighted \
                as Mitsuba does when it has none, shade smoothly unless `face_normals`.",
    },
    Plugin {
        object: "shape",
        kinds: &["serialized"],
        properties: &[
            p("filename", ""),
            p("shape_index", "0"),
            p("face_normals", "false"),
            p("to_world", "identity"),
            p("flip_normals", "false"),
            p("silhouette_sampling_weight", "1"),
        ],
        notes: "Mitsuba's zlib-compressed mesh format, versions 3 and 4; the file's own \
                face-normal flag is ignored, as Mitsuba 3 does.",
    },
    Plugin {
        object: "shape",
        kinds: &["shapegroup"],
        properties: &[],
        notes: "Holds shapes (not emitters) that instances place.",
    },
    Plugin {
        object: "shape",
        kinds: &["instance"],
        properties: &[p("to_world", "identity")],
        notes: "A `<ref>` to a shapegroup, placed after each shape's own `to_world`; each \
                instance adds its own copy of the triangles.",
    },
];

/// The plugins after the BSDFs (whose rows come from their units), in the order docs/scenes.md
/// lists them.
pub const AFTER_BSDFS: &[Plugin] = &[
    Plugin {
        object: "medium",
        kinds: &["homogeneous", "heterogeneous"],
        properties: &[
            p("albedo", "0.75"),
            p("sigma_t", "1"),
            p("scale", "1"),
            p("sample_emitters", "true"),
            p("has_spectral_extinction", "true"),
        ],
        notes: "A shape's `interior` / `exterior` (nested or `<ref>`), or the sensor's medium. \
                Coefficients as numbers, colours or a `constvolume`; one phase function \
                (isotropic when none). Rendered as Mitsuba's `volpath` renders it (null \
                surfaces do not count towards max_depth); path tracing renders every path \
                that scatters in a medium, photons carry what crosses one unscattered. \
                `has_spectral_extinction` only changes Mitsuba's sampling. `heterogeneous`: \
                `sigma_t` a `gridvolume` (times `scale`), tracked against the grid's largest \
                value (delta and ratio tracking); a grid of albedo is refused with its place.",
    },
    Plugin {
        object: "phase",
        kinds: &["isotropic", "rayleigh"],
        properties: &[],
        notes: "",
    },
    Plugin {
        object: "phase",
        kinds: &["hg"],
        properties: &[p("g", "0.8")],
        notes: "Henyey-Greenstein, `g` in (-1, 1).",
    },
    Plugin {
        object: "volume",
        kinds: &["constvolume"],
        properties: &[p("value", "1"), p("to_world", "identity")],
        notes: "As a medium's `albedo` or `sigma_t`.",
    },
    Plugin {
        object: "volume",
        kinds: &["gridvolume"],
        properties: &[
            p("filename", ""),
            p("to_world", "identity"),
            p("filter_type", "trilinear"),
            p("wrap_mode", "clamp"),
            p("use_grid_bbox", "false"),
            p("raw", "false"),
            p("accel", "true"),
        ],
        notes: "Mitsuba's binary `.vol` (float32, 1 or 3 channels), filling the unit cube that \
                `to_world` places (the file's box with `use_grid_bbox`), cell-centred samples; \
                as a heterogeneous medium's `sigma_t`. `raw` and `accel` change nothing in RGB.",
    },
    Plugin {
        object: "texture",
        kinds: &["checkerboard"],
        properties: &[
            p("color0", "0.4"),
            p("color1", "0.2"),
            p("to_uv", "identity"),
        ],
        notes: "On colour parameters and rough BSDFs' `alpha`s.",
    },
    Plugin {
        object: "texture",
        kinds: &["bitmap"],
        properties: &[
            p("filename", ""),
            p("raw", "false"),
            p("wrap_mode", "repeat"),
            p("filter_type", "bilinear"),
            p("to_uv", "identity"),
            p("accel", "true"),
            p("format", "auto"),
        ],
        notes: "PNG, JPEG (progressive too), BMP decoded from sRGB unless `raw`, OpenEXR \
                linear; the format from the file's bytes, not its name; alpha dropped; at most \
                16384 texels a side; `accel` is read and changes nothing; `format` (auto, variant, \
                float16, uint8) is Mitsuba's storage precision: hppm keeps the file's.",
    },
    Plugin {
        object: "emitter",
        kinds: &["area"],
        properties: &[p("radiance", "1"), p("sampling_weight", "1")],
        notes: "Inside a shape; one-sided, by the geometric normal. `sampling_weight` (every \
                emitter) is how often Mitsuba's light sampling picks it, which changes only \
                noise: read, and hppm picks lights by power.",
    },
    Plugin {
        object: "emitter",
        kinds: &["point"],
        properties: &[
            p("position", ""),
            p("to_world", "identity"),
            p("intensity", "1"),
            p("sampling_weight", "1"),
        ],
        notes: "",
    },
    Plugin {
        object: "emitter",
        kinds: &["spot"],
        properties: &[
            p("to_world", "identity"),
            p("intensity", "1"),
            p("cutoff_angle", "20"),
            p("beam_width", "3/4 of cutoff_angle"),
            p("texture", ""),
            p("sampling_weight", "1"),
        ],
        notes: "Shines along its +z; Mitsuba's falloff; `to_world` must keep the cone round; \
                `texture` (a bitmap or checkerboard) multiplies the intensity at Mitsuba's uv, \
                the direction projected on z = 1 with tan(cutoff_angle) at the square's edge.",
    },
    Plugin {
        object: "emitter",
        kinds: &["projector"],
        properties: &[
            p("irradiance", "1"),
            p("scale", "1"),
            p("to_world", "identity"),
            p("fov", ""),
            p("fov_axis", "x"),
            p("focal_length", "50mm"),
            p("sampling_weight", "1"),
        ],
        notes: "Mitsuba's intensity pi scale E / cos^3, so a plane at z = 1 gets pi scale E; \
                the frustum is the perspective camera's for an image of the texture's \
                resolution (1 x 1 for a colour); `to_world` a rotation and translation.",
    },
    Plugin {
        object: "emitter",
        kinds: &["directional"],
        properties: &[
            p("direction", ""),
            p("to_world", "identity"),
            p("irradiance", "1"),
            p("sampling_weight", "1"),
        ],
        notes: "",
    },
    Plugin {
        object: "emitter",
        kinds: &["constant"],
        properties: &[
            p("radiance", "1"),
            p("to_world", "identity"),
            p("sampling_weight", "1"),
        ],
        notes: "At most one environment emitter, as in Mitsuba; `to_world` is read and \
                changes nothing.",
    },
    Plugin {
        object: "emitter",
        kinds: &["envmap"],
        properties: &[
            p("filename", ""),
            p("scale", "1"),
            p("to_world", "identity"),
            p("filter_type", "bilinear"),
            p("mis_compensation", "false"),
            p("sampling_weight", "1"),
        ],
        notes: "OpenEXR, Radiance HDR, PNG/JPEG/BMP; Mitsuba's orientation; `to_world` a \
                rotation; `filter_type` bilinear and `mis_compensation` false only.",
    },
    Plugin {
        object: "emitter",
        kinds: &["sunsky"],
        properties: &[
            p("turbidity", "3"),
            p("albedo", "0.3"),
            p("latitude", "35.6894"),
            p("longitude", "139.6917"),
            p("timezone", "9"),
            p("year", "2010"),
            p("month", "7"),
            p("day", "10"),
            p("hour", "15"),
            p("minute", "0"),
            p("second", "0"),
            p("sun_direction", ""),
            p("sun_scale", "1"),
            p("sky_scale", "1"),
            p("sun_aperture", "0.5358"),
            p("complex_sun", "false"),
            p("to_world", "identity"),
            p("sampling_weight", "1"),
        ],
        notes: "The Hosek-Wilkie sky and sun as Mitsuba 3.9.1's RGB variants evaluate them, \
                from its own datasets (src/scene/sunsky; Mitsuba's values in \
                tests/refs/sunsky), baked at load into a 1024 x 4097 environment map whose \
                pole is the sun (0.044 degrees a row; the disc integrated into its texels so \
                that its power is exact), rendered as an `envmap` is. The sun from \
                `sun_direction` (world space) or a place and time (not both), in Mitsuba's \
                frame: z up, +x south, +y west (its docs say x north; its code is followed), \
                turned by `to_world`, a rotation. `albedo` a colour in [0, 1], not a texture; \
                `turbidity` in [1, 10]; `complex_sun` Mitsuba's limb-darkened disc. Beyond \
                Mitsuba: latitude, longitude, timezone, date and time must be real ones (year \
                1 to 9999). A sun below the horizon renders black, sky included, as in \
                Mitsuba (a warning).",
    },
    Plugin {
        object: "spectrum",
        kinds: &["blackbody"],
        properties: &[
            p("temperature", ""),
            p("wavelength_min", "360"),
            p("wavelength_max", "830"),
        ],
        notes: "What Mitsuba's spectral variants render (its RGB variants cannot).",
    },
    Plugin {
        object: "spectrum",
        kinds: &["regular"],
        properties: &[
            p("values", ""),
            p("wavelength_min", "360"),
            p("wavelength_max", "830"),
        ],
        notes: "Converted as Mitsuba converts sampled spectra (below).",
    },
    Plugin {
        object: "spectrum",
        kinds: &["irregular"],
        properties: &[p("wavelengths", ""), p("values", "")],
        notes: "Converted as Mitsuba converts sampled spectra (below).",
    },
    Plugin {
        object: "spectrum",
        kinds: &["d65"],
        properties: &[p("color", "1"), p("scale", "1")],
        notes: "In RGB, `color` times `scale`.",
    },
    Plugin {
        object: "spectrum",
        kinds: &["srgb"],
        properties: &[p("color", ""), p("unbounded", "false")],
        notes: "`color` within [0, 1] unless `unbounded`.",
    },
];

/// Every plugin the loader reads with the BSDF units of `bsdfs`, in the order docs/scenes.md
/// lists them.
pub fn all(bsdfs: &BsdfRegistry) -> Vec<Plugin> {
    BEFORE_BSDFS
        .iter()
        .copied()
        .chain(bsdfs.plugin_rows())
        .chain(AFTER_BSDFS.iter().copied())
        .collect()
}

/// The loader's own plugins (all but the BSDFs).
fn own() -> impl Iterator<Item = &'static Plugin> {
    BEFORE_BSDFS.iter().chain(AFTER_BSDFS)
}

/// The plugins of `object` by type, for messages: "rectangle, cube, disk, ...".
pub fn kinds_of(object: &str) -> String {
    own()
        .filter(|p| p.object == object)
        .flat_map(|p| p.kinds.iter().copied())
        .filter(|k| *k != "any other")
        .collect::<Vec<_>>()
        .join(", ")
}

/// The plugin of `object` with `type` `kind`, if the loader reads it itself.
pub fn find(object: &str, kind: &str) -> Option<&'static Plugin> {
    own().find(|p| p.object == object && p.kinds.contains(&kind))
}

/// The properties `kind` of `object` reads, for messages: "int_ior, ext_ior".
pub fn properties_of(object: &str, kind: &str) -> String {
    match find(object, kind) {
        Some(plugin) if !plugin.properties.is_empty() => plugin
            .properties
            .iter()
            .map(|p| p.name)
            .collect::<Vec<_>>()
            .join(", "),
        _ => "no properties".into(),
    }
}

/// The table in Markdown (`hppm plugins`, docs/scenes.md).
pub fn markdown(bsdfs: &BsdfRegistry) -> String {
    let mut out = String::from("| object | type | properties (Mitsuba's defaults) | notes |\n");
    out.push_str("|---|---|---|---|\n");
    for plugin in all(bsdfs) {
        let kinds: Vec<String> = plugin
            .kinds
            .iter()
            .map(|k| match *k {
                "any other" => "any other".to_string(),
                k => format!("`{k}`"),
            })
            .collect();
        let properties: Vec<String> = plugin
            .properties
            .iter()
            .map(|p| match p.default {
                "" => format!("`{}`", p.name),
                d => format!("`{}` ({d})", p.name),
            })
            .collect();
        out.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            plugin.object,
            kinds.join(", "),
            properties.join(", "),
            plugin.notes
        ));
    }
    out.push_str(
        "\n**Mitsuba 0.5/0.6 files** (a `<scene version>` below 2.0; names upgraded from \
         camelCase first) are read with 0.6's rules where 0.6 and Mitsuba 3 differ:\n\n\
         | where | 0.6's rule (Mitsuba 3's in brackets) |\n|---|---|\n",
    );
    for (place, rule) in crate::loaders::mitsuba::LEGACY_RULES {
        out.push_str(&format!("| {place} | {rule} |\n"));
    }
    out
}
