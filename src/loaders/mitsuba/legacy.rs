//! Mitsuba 0.5/0.6 files (`<scene version>` below 2.0), read with 0.6's rules where 0.6 and
//! Mitsuba 3 differ, so that research scenes render as shipped. Mitsuba 3 itself upgrades such
//! files only by renaming (camelCase properties to snake_case, `<lookAt>` to `<lookat>`, the
//! diffuse `diffuse_reflectance` to `reflectance`); the rest of what 0.6 accepted it refuses.
//! Here, as in 0.6:
//! - an unknown property is a warning (0.6 printed "unqueried property" and rendered);
//! - 0.6's own defaults and properties hold where its plugins read them (a conductor's `Cu`
//!   and `ext_eta`, a homogeneous medium's presets and `skin1` default, a bitmap's
//!   `uscale`/`uoffset`/`gamma`, a heterogeneous medium's `density`), and
//! - what only 0.6's algorithms or outputs used is read and dropped with a note (`ldrfilm`'s
//!   tonemapping, EWA and trilinear texture filtering, sampling strategies).
//!
//! Every such change is recorded where it applies ([`Report::upgrades`], `hppm check
//! --verbose`); whatever changes the image from what 0.6 rendered is a warning as well.

use super::*;

/// The rules one file of a scene was read with.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleSet {
    pub file: PathBuf,
    /// The file's `<scene version=...>`, if it gives one.
    pub version: Option<String>,
    /// Read with 0.6's rules (a version below 2.0), not Mitsuba 3's.
    pub legacy: bool,
}

impl std::fmt::Display for RuleSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let version = self.version.as_deref().unwrap_or("none given");
        let rules = if self.legacy {
            "Mitsuba 0.5/0.6 rules"
        } else {
            "Mitsuba 3 rules"
        };
        write!(f, "{}: {rules} (version {version})", self.file.display())
    }
}

/// Properties that Mitsuba 0.5/0.6 plugins read and Mitsuba 3's do not (after the version
/// upgrade renames them): a scene written for those versions renders without them, so they are
/// warnings, not errors, in files of any version.
pub(super) const LEGACY_PROPERTIES: &[&str] = &[
    "high_quality_edges",
    "strict_normals",
    "banner",
    "attach_log",
    "max_smooth_angle",
    "generate_normals",
    "sample_count_per_pass",
];

/// A property name as Mitsuba 3 upgrades it from a file older than version 2.0: camelCase
/// words joined by underscores (`maxDepth` -> `max_depth`, `fovAxis` -> `fov_axis`).
pub(super) fn snake_case(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    let mut previous_lower = false;
    for c in name.chars() {
        if c.is_ascii_uppercase() && previous_lower {
            out.push('_');
        }
        out.push(c.to_ascii_lowercase());
        previous_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
    }
    out
}

/// Where 0.6's rules differ from Mitsuba 3's, as docs/scenes.md lists them (`hppm plugins`):
/// (where, the rule, with Mitsuba 3's in brackets).
pub const RULES: &[(&str, &str)] = &[
    (
        "any property",
        "one no plugin reads is a warning with a did-you-mean, as 0.6 printed \"unqueried \
         property\" (an error); so is a property under `<scene>`",
    ),
    (
        "`<lookAt>`",
        "the camelCase tag places the camera (Mitsuba 3.9.1 refuses it)",
    ),
    (
        "film",
        "`ldrfilm` and `tiledhdrfilm` give the image's size (refused); `gamma`, `exposure`, \
         `key`, `burn`, `tonemapMethod` only shaped 0.6's PNG: a warning where they would \
         have changed it, a note otherwise (`gamma` on an hdrfilm, which 0.6 never read, a \
         note); `mfilm` is refused",
    ),
    (
        "bitmap",
        "`filterType` ewa (0.6's default) and trilinear are read bilinear with a note: 0.6 \
         MIP-mapped over the pixel's footprint, bilinear converges to the same picture \
         wherever a pixel covers at most a texel and is sharper where the texture is \
         minified, since a pixel's samples then average its texels themselves (Mitsuba 3 has \
         only bilinear and nearest); `uscale`, `vscale`, `uvscale`, `uoffset`, `voffset` map \
         uv as 0.6's Texture2D does, uv * scale + offset (`to_uv`); `gamma` 1 reads the file \
         as linear, -1 as sRGB, other values as that power, 0 as the file says (`raw`); \
         `wrapModeU`/`wrapModeV` must agree (hppm wraps both axes alike); `maxAnisotropy` and \
         `cache` are notes; `channel` is refused",
    ),
    (
        "conductor",
        "`material` defaults to `Cu` (`none`, a mirror); `eta` or `k` replaces the material's \
         own where given, with a material given too (refused); both are divided by `extEta`, \
         a number or a named dielectric, default air",
    ),
    (
        "homogeneous medium",
        "`material` is one of 0.6's 47 measured presets (Jensen et al. 2001, Narasimhan et \
         al. 2006; its table in mm^-1, times 100 as 0.6 applies it, then times `scale`); with \
         no coefficient the medium is `skin1`, 0.6's default (sigma_t 1, albedo 0.75); \
         `sigmaS`/`sigmaA` or `sigmaT`/`albedo`, each missing one from the preset; a preset \
         with coefficients, or the two pairs mixed, is refused as 0.6 refuses it; `strategy`, \
         `samplingDensity`, `mediumSamplingWeight` and `channel` only chose 0.6's distance \
         sampling (notes); `monochromatic` is refused",
    ),
    (
        "heterogeneous medium",
        "the extinction grid is `<volume name=\"density\">` (`sigma_t`), placed in the box \
         the `.vol` file states or `min`/`max` (the unit cube), with the first and last \
         voxels' values on the box's faces (half a voxel inside); `method` and `stepSize` are \
         notes",
    ),
    (
        "shape",
        "a shape with a medium and no BSDF is a null boundary (diffuse 0.5); an area light \
         without a BSDF is black in both",
    ),
    (
        "spectrum",
        "three plain values are RGB, as 0.6's RGB build read as many values as it had \
         spectral samples (refused)",
    ),
    (
        "files",
        "a texture, mesh, environment map or grid file missing under its exact name is found in another case, \
         with a warning (0.6 scenes were often written on file systems that ignore case)",
    ),
    (
        "plugins",
        "`roughdiffuse`, `phong`, `ward`, `difftrans`, `mixturebsdf`, `hk`, `coating` and \
         `roughcoating` (in the table above; files of version 0.x only)",
    ),
];

/// One of 0.6's homogeneous medium presets (src/medium/materials.h of Mitsuba 0.6): scattering
/// and absorption coefficients in mm^-1 (0.6 multiplies them by 100 before `scale`), and the
/// anisotropy its dipole models read (a homogeneous medium's phase function is its own
/// `<phase>`, isotropic by default, so `g` does not enter here).
struct MediumPreset {
    name: &'static str,
    sigma_s: [f32; 3],
    sigma_a: [f32; 3],
}

const fn preset(name: &'static str, sigma_s: [f32; 3], sigma_a: [f32; 3]) -> MediumPreset {
    MediumPreset {
        name,
        sigma_s,
        sigma_a,
    }
}

/// 0.6's table: the first twelve fitted by Jensen et al. 2001 ("A practical model for subsurface
/// light transport"), the rest measured by Narasimhan et al. 2006 ("Acquiring scattering
/// properties of participating media by dilution"), as 0.6 lists them.
const MEDIUM_PRESETS: &[MediumPreset] = &[
    preset("Apple", [2.29, 2.39, 1.97], [0.0030, 0.0034, 0.046]),
    preset("Chicken1", [0.15, 0.21, 0.38], [0.0015, 0.077, 0.19]),
    preset("Chicken2", [0.19, 0.25, 0.32], [0.0018, 0.088, 0.20]),
    preset("Cream", [7.38, 5.47, 3.15], [0.0002, 0.0028, 0.0163]),
    preset("Ketchup", [0.18, 0.07, 0.03], [0.061, 0.97, 1.45]),
    preset("Marble", [2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
    preset("Potato", [0.68, 0.70, 0.55], [0.0024, 0.0090, 0.12]),
    preset("Skimmilk", [0.70, 1.22, 1.90], [0.0014, 0.0025, 0.0142]),
    preset("Skin1", [0.74, 0.88, 1.01], [0.032, 0.17, 0.48]),
    preset("Skin2", [1.09, 1.59, 1.79], [0.013, 0.070, 0.145]),
    preset("Spectralon", [11.6, 20.4, 14.9], [0.00, 0.00, 0.00]),
    preset("Wholemilk", [2.55, 3.21, 3.77], [0.0011, 0.0024, 0.014]),
    preset(
        "Lowfat Milk",
        [13.1157, 15.4445, 17.9572],
        [0.00287, 0.00575, 0.01150],
    ),
    preset(
        "Reduced Milk",
        [13.7335, 15.6003, 17.8007],
        [0.00256, 0.00511, 0.01278],
    ),
    preset(
        "Regular Milk",
        [18.2052, 20.3826, 22.3698],
        [0.00153, 0.00460, 0.01993],
    ),
    preset(
        "Espresso",
        [7.78262, 8.13050, 8.53875],
        [4.79838, 6.57512, 8.84925],
    ),
    preset(
        "Mint Mocha Coffee",
        [3.51133, 4.14383, 5.59667],
        [3.77200, 5.82283, 7.82000],
    ),
    preset(
        "Lowfat Soy Milk",
        [2.03838, 2.32875, 3.90281],
        [0.00144, 0.00719, 0.03594],
    ),
    preset(
        "Regular Soy Milk",
        [4.66325, 5.20183, 8.74575],
        [0.00192, 0.00958, 0.06517],
    ),
    preset(
        "Lowfat Chocolate Milk",
        [9.83710, 11.4954, 13.1629],
        [0.01150, 0.03680, 0.15640],
    ),
    preset(
        "Regular Chocolate Milk",
        [10.5685, 13.1416, 15.2202],
        [0.01006, 0.04313, 0.14375],
    ),
    preset(
        "Coke",
        [0.00254, 0.00299, 0.00000],
        [0.10014, 0.16503, 0.24680],
    ),
    preset(
        "Pepsi",
        [0.00083, 0.00203, 0.00000],
        [0.09164, 0.14158, 0.20729],
    ),
    preset(
        "Sprite",
        [0.00011, 0.00014, 0.00014],
        [0.00189, 0.00183, 0.00200],
    ),
    preset(
        "Gatorade",
        [0.03668, 0.04488, 0.05742],
        [0.02479, 0.01929, 0.00888],
    ),
    preset(
        "Chardonnay",
        [0.00021, 0.00033, 0.00048],
        [0.01078, 0.01186, 0.02400],
    ),
    preset(
        "White Zinfandel",
        [0.00022, 0.00033, 0.00046],
        [0.01207, 0.01618, 0.01984],
    ),
    preset(
        "Merlot",
        [0.00081, 0.00000, 0.00000],
        [0.11632, 0.25191, 0.29434],
    ),
    preset(
        "Budweiser Beder",
        [0.00029, 0.00055, 0.00059],
        [0.01149, 0.02491, 0.05779],
    ),
    preset(
        "Coors Light Beer",
        [0.00062, 0.00127, 0.00000],
        [0.00616, 0.01398, 0.03498],
    ),
    preset(
        "Clorox",
        [0.02731, 0.03302, 0.03695],
        [0.00335, 0.01489, 0.02630],
    ),
    preset(
        "Apple Juice",
        [0.00257, 0.00311, 0.00413],
        [0.01296, 0.02374, 0.05218],
    ),
    preset(
        "Cranberry Juice",
        [0.00196, 0.00238, 0.00301],
        [0.03944, 0.09422, 0.12426],
    ),
    preset(
        "Grape Juice",
        [0.00138, 0.00000, 0.00000],
        [0.10404, 0.23958, 0.29325],
    ),
    preset(
        "Ruby Grapefruit Juice",
        [0.15496, 0.15391, 0.15995],
        [0.08587, 0.18314, 0.25262],
    ),
    preset(
        "White Grapefruit Juice",
        [0.50499, 0.52742, 0.75282],
        [0.01380, 0.01883, 0.05678],
    ),
    preset(
        "Shampoo",
        [0.00797, 0.00874, 0.01127],
        [0.01411, 0.04569, 0.06172],
    ),
    preset(
        "Strawberry Shampoo",
        [0.00215, 0.00245, 0.00253],
        [0.01449, 0.05796, 0.07582],
    ),
    preset(
        "Head & Shoulders Shampoo",
        [0.26747, 0.27696, 0.29574],
        [0.08462, 0.15688, 0.20365],
    ),
    preset(
        "Lemon Tea Powder",
        [0.74489, 0.83823, 1.00158],
        [2.42881, 4.57573, 7.21270],
    ),
    preset(
        "Orange Juice Powder",
        [0.00193, 0.00213, 0.00226],
        [0.00145, 0.00344, 0.00786],
    ),
    preset(
        "Pink Lemonade Powder",
        [0.00123, 0.00133, 0.00131],
        [0.00116, 0.00237, 0.00320],
    ),
    preset(
        "Cappuccino Powder",
        [12.2094, 16.4659, 29.2727],
        [35.8441, 49.5470, 61.0844],
    ),
    preset(
        "Salt Powder",
        [0.13805, 0.15677, 0.17865],
        [0.28415, 0.32570, 0.34148],
    ),
    preset(
        "Sugar Powder",
        [0.00282, 0.00315, 0.00393],
        [0.01264, 0.03105, 0.05012],
    ),
    preset(
        "Suisse Mocha Powder",
        [30.0848, 33.4452, 38.7191],
        [17.5020, 27.0044, 35.4334],
    ),
    preset(
        "Pacific Ocean Surface Water",
        [0.00180, 0.00183, 0.00228],
        [0.03184, 0.03132, 0.03015],
    ),
];

/// The factor 0.6 applies to its presets' coefficients before the medium's `scale`.
const PRESET_UNITS: f32 = 100.0;

/// 0.6's default preset when a homogeneous medium gives no coefficients.
pub(super) const DEFAULT_PRESET: &str = "skin1";

/// A preset's (sigma_s, sigma_a), as 0.6 applies them (its name matched ignoring case).
pub(super) fn medium_preset(name: &str) -> Option<(Vec3, Vec3)> {
    let entry = MEDIUM_PRESETS
        .iter()
        .find(|p| p.name.eq_ignore_ascii_case(name))?;
    Some((
        Vec3::from(entry.sigma_s) * PRESET_UNITS,
        Vec3::from(entry.sigma_a) * PRESET_UNITS,
    ))
}

/// The presets' anisotropy g per channel where 0.6 lists one (Narasimhan et al.'s measurements;
/// Jensen et al.'s are 0): its `hk` BSDF multiplies a preset's scattering by 1 - g.
const PRESET_ANISOTROPY: &[(&str, [f32; 3])] = &[
    ("Lowfat Milk", [0.93200, 0.90200, 0.85900]),
    ("Reduced Milk", [0.81900, 0.79700, 0.74600]),
    ("Regular Milk", [0.75000, 0.71400, 0.68100]),
    ("Espresso", [0.90700, 0.89600, 0.88000]),
    ("Mint Mocha Coffee", [0.91000, 0.90700, 0.91400]),
    ("Lowfat Soy Milk", [0.85000, 0.85300, 0.84200]),
    ("Regular Soy Milk", [0.87300, 0.85800, 0.83200]),
    ("Lowfat Chocolate Milk", [0.93400, 0.92700, 0.91600]),
    ("Regular Chocolate Milk", [0.86200, 0.83800, 0.80600]),
    ("Coke", [0.96500, 0.97200, 0.00000]),
    ("Pepsi", [0.92600, 0.97900, 0.00000]),
    ("Sprite", [0.94300, 0.95300, 0.95200]),
    ("Gatorade", [0.93300, 0.93300, 0.93500]),
    ("Chardonnay", [0.91400, 0.95800, 0.97500]),
    ("White Zinfandel", [0.91900, 0.94300, 0.97200]),
    ("Merlot", [0.97400, 0.00000, 0.00000]),
    ("Budweiser Beder", [0.91700, 0.95600, 0.98200]),
    ("Coors Light Beer", [0.91800, 0.96600, 0.00000]),
    ("Clorox", [0.91200, 0.90500, 0.89200]),
    ("Apple Juice", [0.94700, 0.94900, 0.94500]),
    ("Cranberry Juice", [0.94700, 0.95100, 0.97400]),
    ("Grape Juice", [0.96100, 0.00000, 0.00000]),
    ("Ruby Grapefruit Juice", [0.92900, 0.92900, 0.93100]),
    ("White Grapefruit Juice", [0.54800, 0.54500, 0.56500]),
    ("Shampoo", [0.91000, 0.90500, 0.92000]),
    ("Strawberry Shampoo", [0.92700, 0.93500, 0.99400]),
    ("Head & Shoulders Shampoo", [0.91100, 0.89600, 0.88400]),
    ("Lemon Tea Powder", [0.94600, 0.94600, 0.94900]),
    ("Orange Juice Powder", [0.91900, 0.91800, 0.92200]),
    ("Pink Lemonade Powder", [0.90200, 0.90200, 0.90400]),
    ("Cappuccino Powder", [0.84900, 0.84300, 0.92600]),
    ("Salt Powder", [0.80200, 0.79300, 0.82100]),
    ("Sugar Powder", [0.92100, 0.91900, 0.93100]),
    ("Suisse Mocha Powder", [0.90700, 0.89400, 0.88800]),
    ("Pacific Ocean Surface Water", [0.90200, 0.82500, 0.91400]),
];

/// A preset's (sigma_s, sigma_a, g) as 0.6's `lookupMaterial` gives them to `hk`: the
/// coefficients of [`medium_preset`] and the anisotropy (0 where 0.6 has none).
pub(super) fn medium_preset_with_anisotropy(name: &str) -> Option<(Vec3, Vec3, Vec3)> {
    let (sigma_s, sigma_a) = medium_preset(name)?;
    let g = PRESET_ANISOTROPY
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .map_or(Vec3::ZERO, |(_, g)| Vec3::from(*g));
    Some((sigma_s, sigma_a, g))
}

/// The preset names, for messages.
pub(super) fn medium_preset_names() -> String {
    MEDIUM_PRESETS
        .iter()
        .map(|p| p.name)
        .collect::<Vec<_>>()
        .join(", ")
}

impl<'a, 'input> Reader<'a, 'input> {
    /// `node` is in a file read with 0.6's rules.
    pub(super) fn legacy(&self, node: Node) -> bool {
        self.file_of(node).before_v2
    }

    /// Records what reading a 0.6 file changed at `node`.
    pub(super) fn upgrade(&self, node: Node, message: impl Into<String>) {
        self.upgrades.borrow_mut().push(self.error(node, message));
    }

    /// The rules each file of the scene was read with.
    pub(super) fn rule_sets(&self) -> Vec<RuleSet> {
        self.files
            .iter()
            .map(|f| RuleSet {
                file: f.path.clone(),
                version: f.version.clone(),
                legacy: f.before_v2,
            })
            .collect()
    }

    /// A 0.6 `<spectrum value="r, g, b">`: 0.6's RGB build (the one its scenes were made with)
    /// reads as many plain values as it has spectral samples, three, as the colour itself.
    /// `None` for one value (a constant, read as Mitsuba 3 reads it).
    pub(super) fn legacy_rgb_spectrum(
        &self,
        node: Node,
        value: &str,
    ) -> Result<Option<Vec3>, SceneError> {
        let tokens: Vec<&str> = value
            .split([',', ' ', '\t', '\n'])
            .filter(|t| !t.is_empty())
            .collect();
        if tokens.len() == 1 {
            return Ok(None);
        }
        let numbers = self.numbers(node, "value", value)?;
        let [r, g, b] = numbers.as_slice() else {
            return Err(self.attr_error(
                node,
                "value",
                format!(
                    "{}: {} plain values; Mitsuba 0.6's RGB build reads three (or one \
                     constant, or wavelength:value pairs)",
                    describe(node),
                    tokens.len()
                ),
            ));
        };
        self.upgrade(
            node,
            "spectrum of three plain values read as RGB, as 0.6's RGB build reads it",
        );
        Ok(Some(Vec3::new(*r, *g, *b)))
    }

    /// `node`'s tag as Mitsuba 3 reads it: 0.6's `<lookAt>` is Mitsuba 3's `<lookat>`.
    pub(super) fn tag_of<'n>(&self, node: Node<'n, '_>) -> &'n str {
        let tag = node.tag_name().name();
        if tag == "lookAt" && self.legacy(node) {
            return "lookat";
        }
        tag
    }

    /// Property `name` of `owner` in a 0.6 file, renamed as Mitsuba 3's loader renames it; a
    /// renaming is recorded at `at`.
    pub(super) fn upgraded_name(&self, owner: Node, at: Node, name: &str) -> String {
        let mut upgraded = snake_case(name);
        let diffuse = owner.has_tag_name("bsdf") && owner.attribute("type") == Some("diffuse");
        if diffuse && upgraded == "diffuse_reflectance" {
            upgraded = "reflectance".into();
        }
        if upgraded != name {
            self.upgrade(at, format!("property \"{name}\" read as \"{upgraded}\""));
        }
        upgraded
    }

    /// A property no plugin read in a 0.6 file: 0.6 printed "unqueried property" and rendered
    /// without it, so it is a warning here too (with a did-you-mean).
    pub(super) fn unqueried(&self, props: &Props, owner: Node, name: &str, node: Node) {
        let mut message = format!(
            "{}: {} does not read \"{name}\"; ignored, as Mitsuba 0.6 ignored an unqueried \
             property (this file's version is below 2.0)",
            describe(node),
            describe_object(owner)
        );
        if let Some(near) = props.suggestion(name) {
            message.push_str(&format!("; did you mean \"{near}\"?"));
        }
        self.warn(node, message);
    }

    /// A file named in a 0.6 scene, found ignoring case when the exact name is missing (0.6
    /// scenes were often written on file systems that ignore case); a warning says which file
    /// was taken.
    pub(super) fn existing_file(&self, node: Node, path: PathBuf) -> PathBuf {
        if path.exists() || !self.legacy(node) {
            return path;
        }
        let (Some(dir), Some(name)) = (path.parent(), path.file_name()) else {
            return path;
        };
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        let Ok(entries) = std::fs::read_dir(dir) else {
            return path;
        };
        let wanted = name.to_string_lossy().to_lowercase();
        let mut found: Vec<PathBuf> = entries
            .filter_map(Result::ok)
            .map(|e| dir.join(e.file_name()))
            .filter(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().to_lowercase() == wanted)
            })
            .collect();
        found.sort();
        match found.as_slice() {
            [one] => {
                self.warn(
                    node,
                    format!(
                        "{}: no file {}; read {} (the same name in another case, as 0.6 on a \
                         file system that ignores case would)",
                        describe(node),
                        path.display(),
                        one.display()
                    ),
                );
                one.clone()
            }
            _ => path,
        }
    }
}
