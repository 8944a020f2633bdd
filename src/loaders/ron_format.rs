//! hppm's own scene format, for `scenes/*.ron`. Every struct denies unknown fields, and every
//! error (syntax or meaning) is reported as `file:line:col`.
//!
//! ```ron
//! (
//!     // Required. `up` defaults to (0, 1, 0); fov_x is the full horizontal field of view in
//!     // degrees (0 to 180); width and height are the film size in pixels.
//!     camera: (origin: (0, 0, 3.9), target: (0, 0, 0), up: (0, 1, 0), fov_x: 39.3, width: 128, height: 128),
//!     // Optional, default (max_depth: 12, rr_depth: None). Depths count path segments as in
//!     // Mitsuba (1 = emitters seen directly); None = unbounded / no Russian roulette.
//!     integrator: (max_depth: 12, rr_depth: None),
//!     spp: 64,                                       // optional suggested sample count
//!     // (optional values may be written `x` or `Some(x)`)
//!     materials: {                                   // required, names are unique
//!         "white": Diffuse(reflectance: (0.8, 0.8, 0.8)),
//!         "glass": Dielectric(int_ior: 1.5, ext_ior: 1.0),   // ext_ior defaults to 1
//!         "mirror": Mirror,
//!     },
//!     shapes: [                                      // required (may be empty)
//!         // Rectangle: [-1,1]^2 at z=0 facing +z. Cube: [-1,1]^3 facing out. Sphere: centre
//!         // and radius. Obj: a mesh file relative to this file, counter-clockwise = front.
//!         // `to_world` is a list of steps applied in order: Translate((x, y, z)),
//!         // Scale((x, y, z)), Rotate(axis: (x, y, z), degrees: d), Matrix((16 numbers,
//!         // row-major, last row 0 0 0 1)). A sphere only takes uniform scales.
//!         // `emission` is the radiance emitted on the front side; `flip_normals` swaps sides.
//!         (shape: Rectangle, material: "white", to_world: [Scale((2, 2, 1)), Translate((0, -1, 0))]),
//!         (shape: Sphere(center: (0, 0, 0), radius: 0.5), material: "glass"),
//!         (shape: Cube, material: "white", emission: Some((1, 1, 1)), flip_normals: true),
//!         (shape: Obj(path: "mesh.obj"), material: "white",
//!          to_world: [Matrix((1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1))]),
//!     ],
//!     point_lights: [(position: (0, 2, 0), intensity: (10, 10, 10))],   // optional, W/sr
//! )
//! ```
//!
//! Each shape gets its own [`Material`] entry (its named BSDF plus its own emission). Numbers
//! must be finite: `NaN` and `inf`, which RON itself accepts, are rejected.

use std::collections::BTreeMap;
use std::path::Path;

use glam::{Mat4, Vec3, Vec4};
use serde::Deserialize;

use crate::bsdfs::conductor::Mirror;
use crate::bsdfs::dielectric::Dielectric;
use crate::bsdfs::diffuse::Diffuse;
use crate::error::Location;
use crate::ron_span::{self, Item, Key, Kind, Outline, Token};
use crate::scene::filter::PixelFilter;
use crate::scene::{
    Bsdf, Camera, Integrator, Material, PointLight, Scene, SceneError, Sphere, mesh,
};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: CameraFile,
    #[serde(default)]
    integrator: IntegratorFile,
    #[serde(default)]
    spp: Option<u32>,
    materials: BTreeMap<String, MaterialFile>,
    shapes: Vec<ShapeFile>,
    #[serde(default)]
    point_lights: Vec<PointLightFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    origin: [f32; 3],
    target: [f32; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    fov_x: f32,
    width: u32,
    height: u32,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
struct IntegratorFile {
    max_depth: Option<u32>,
    rr_depth: Option<u32>,
}

impl Default for IntegratorFile {
    fn default() -> Self {
        let Integrator {
            max_depth,
            rr_depth,
            ..
        } = Integrator::default();
        Self {
            max_depth,
            rr_depth,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum MaterialFile {
    Diffuse {
        reflectance: [f32; 3],
    },
    Dielectric {
        int_ior: f32,
        #[serde(default = "one")]
        ext_ior: f32,
    },
    Mirror,
}

fn one() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum ShapeKind {
    Rectangle,
    Cube,
    Sphere { center: [f32; 3], radius: f32 },
    Obj { path: String },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
enum TransformStep {
    Translate([f32; 3]),
    Scale([f32; 3]),
    Rotate { axis: [f32; 3], degrees: f32 },
    Matrix([f32; 16]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShapeFile {
    shape: ShapeKind,
    material: String,
    #[serde(default)]
    to_world: Vec<TransformStep>,
    #[serde(default)]
    emission: Option<[f32; 3]>,
    #[serde(default)]
    flip_normals: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLightFile {
    position: [f32; 3],
    intensity: [f32; 3],
}

/// The CLI's default scene, built into the binary so that an installed `hppm` (a wheel, a binary
/// copied off its clone) renders it without the repository: its repository path and its text.
pub const DEFAULT_SCENE: (&str, &str) = (
    "scenes/cornell_box.ron",
    include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/cornell_box.ron"
    )),
);

/// Loads a scene file; where none is at `path` and `path` ends with [`DEFAULT_SCENE`]'s repository
/// path, the built-in copy (as bundled graphs are found by their paths).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    match crate::loaders::read_text(path) {
        Ok(text) => parse(path, &text),
        Err(SceneError::Io { source, .. })
            if source.kind() == std::io::ErrorKind::NotFound && path.ends_with(DEFAULT_SCENE.0) =>
        {
            parse(Path::new(DEFAULT_SCENE.0), DEFAULT_SCENE.1)
        }
        Err(e) => Err(e),
    }
}

/// Parses scene `text`; `path` names the file in errors and anchors relative OBJ paths.
pub fn parse(path: &Path, text: &str) -> Result<Scene, SceneError> {
    // RON itself accepts NaN and inf, so serde would neither refuse them nor say where they are.
    let outline = Outline::new(text);
    let non_finite = outline.tokens().iter().find(|t| {
        matches!(t.kind, Kind::Ident | Kind::Number) && is_non_finite_number(outline.text_of(t))
    });
    if let Some(token) = non_finite {
        return Err(SceneError::at(
            Location::from_offset(path, text, token.span.start),
            format!(
                "\"{}\": numbers must be finite (NaN and infinity are not allowed)",
                outline.text_of(token)
            ),
        ));
    }
    let options =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let file: SceneFile = options.from_str(text).map_err(|e| {
        SceneError::at(
            Location::new(path, e.span.start.line, e.span.start.col),
            e.code.to_string(),
        )
    })?;
    Builder {
        path,
        text,
        outline: &outline,
    }
    .build(file)
}

/// Turns the deserialised file into a [`Scene`], checking what serde cannot and placing each
/// error at the entry it concerns.
struct Builder<'a> {
    path: &'a Path,
    text: &'a str,
    outline: &'a Outline<'a>,
}

impl<'a> Builder<'a> {
    fn at(&self, offset: usize, message: impl Into<String>) -> SceneError {
        SceneError::at(Location::from_offset(self.path, self.text, offset), message)
    }

    /// The item `name: ...` of the file's top-level struct.
    fn top_item(&self, name: &str) -> Option<Item<'a>> {
        self.outline.value()?.field(name)
    }

    /// Where top-level field `name` starts (the file start if it is not written).
    fn field(&self, name: &str) -> usize {
        self.top_item(name).map_or(0, |f| f.span().start)
    }

    /// Element `index` of the top-level list `list`.
    fn list_element(&self, list: &str, index: usize) -> Option<Item<'a>> {
        self.top_item(list)?.group()?.items().nth(index)
    }

    /// Where element `index` of the top-level list `list` starts.
    fn element(&self, list: &str, index: usize) -> usize {
        self.list_element(list, index)
            .map_or_else(|| self.field(list), |e| e.span().start)
    }

    /// Where the first token of element `index` of list `list` that satisfies `wanted` starts
    /// (or where the element starts).
    fn token_in_element(&self, list: &str, index: usize, wanted: impl Fn(&Token) -> bool) -> usize {
        self.list_element(list, index)
            .and_then(|e| e.tokens().iter().find(|t| wanted(t)))
            .map_or_else(|| self.element(list, index), |t| t.span.start)
    }

    /// Where `word` first appears within element `index` of list `list`.
    fn word_in_element(&self, list: &str, index: usize, word: &str) -> usize {
        self.token_in_element(list, index, |t| self.outline.text_of(t) == word)
    }

    /// Where a string holding `contents` first appears within element `index` of list `list`.
    fn string_in_element(&self, list: &str, index: usize, contents: &str) -> usize {
        self.token_in_element(list, index, |t| {
            t.kind == Kind::Str
                && ron_span::string_contents(self.outline.text_of(t)) == Some(contents)
        })
    }

    /// The quoted keys of the `materials` map, in file order.
    fn material_keys(&self) -> Vec<Key<'a>> {
        let Some(map) = self.top_item("materials").and_then(|f| f.group()) else {
            return Vec::new();
        };
        map.items()
            .filter_map(|item| item.key())
            .filter(|k| k.quoted)
            .collect()
    }

    /// The second occurrence of a material name written twice.
    fn duplicate_material_key(&self) -> Option<Key<'a>> {
        let keys = self.material_keys();
        keys.iter().enumerate().find_map(|(i, k)| {
            keys[..i]
                .iter()
                .any(|earlier| earlier.name == k.name)
                .then(|| k.clone())
        })
    }

    fn build(&self, file: SceneFile) -> Result<Scene, SceneError> {
        self.check_materials(&file.materials)?;
        let mut scene = Scene {
            media: Default::default(),
            source: self.path.to_path_buf(),
            camera: self.camera(&file.camera)?,
            integrator: self.integrator(&file.integrator)?,
            spp_hint: match file.spp {
                Some(0) => return Err(self.at(self.field("spp"), "spp must be at least 1")),
                spp => spp,
            },
            materials: Vec::new(),
            triangles: Vec::new(),
            spheres: Vec::new(),
            point_lights: Vec::new(),
            emitters: Default::default(),
            textures: Vec::new(),
        };
        if let Some(message) = crate::scene::beyond_extent(
            "the camera",
            scene.camera.origin.abs().max_element() as f64,
        ) {
            return Err(self.at(self.field("camera"), message));
        }
        for (i, shape) in file.shapes.iter().enumerate() {
            let (triangles, spheres) = (scene.triangles.len(), scene.spheres.len());
            self.add_shape(&mut scene, &file.materials, i, shape)?;
            let reach = scene.reach_since(triangles, spheres);
            if let Some(message) = crate::scene::beyond_extent("this shape", reach) {
                return Err(self.at(self.element("shapes", i), message));
            }
        }
        for (i, light) in file.point_lights.iter().enumerate() {
            let intensity = Vec3::from(light.intensity);
            if intensity.min_element() < 0.0 {
                return Err(self.at(
                    self.word_in_element("point_lights", i, "intensity"),
                    "point light intensity must not be negative",
                ));
            }
            let position = Vec3::from(light.position);
            let reach = position.abs().max_element() as f64;
            if let Some(message) = crate::scene::beyond_extent("this point light", reach) {
                return Err(self.at(self.element("point_lights", i), message));
            }
            scene.point_lights.push(PointLight {
                position,
                intensity,
            });
        }
        scene.validate()?;
        Ok(scene)
    }

    fn camera(&self, c: &CameraFile) -> Result<Camera, SceneError> {
        let camera = Camera {
            origin: c.origin.into(),
            target: c.target.into(),
            up: c.up.into(),
            fov_x_deg: c.fov_x,
            width: c.width,
            height: c.height,
            filter: PixelFilter::Box,
            sample_border: false,
            crop: None,
            lens: None,
        };
        let here = self.field("camera");
        let view = camera.target - camera.origin;
        if view.length_squared() == 0.0 {
            return Err(self.at(here, "camera: origin equals target"));
        }
        if view.cross(camera.up).length_squared() == 0.0 {
            return Err(self.at(here, "camera: up is zero or parallel to the view direction"));
        }
        if !(camera.fov_x_deg > 0.0 && camera.fov_x_deg < 180.0) {
            return Err(self.at(
                here,
                format!(
                    "camera: fov_x {}: expected degrees between 0 and 180",
                    c.fov_x
                ),
            ));
        }
        for (name, side) in [("width", c.width), ("height", c.height)] {
            if !(1..=crate::scene::MAX_FILM_SIDE).contains(&side) {
                return Err(self.at(
                    here,
                    format!(
                        "camera: {name} {side}: expected 1 to {} pixels",
                        crate::scene::MAX_FILM_SIDE
                    ),
                ));
            }
        }
        Ok(camera)
    }

    fn integrator(&self, i: &IntegratorFile) -> Result<Integrator, SceneError> {
        if i.max_depth == Some(0) || i.rr_depth == Some(0) {
            return Err(self.at(
                self.field("integrator"),
                "integrator: depths count path segments and start at 1 (None = unbounded)",
            ));
        }
        Ok(Integrator {
            max_depth: i.max_depth,
            rr_depth: i.rr_depth,
            hide_emitters: false,
        })
    }

    /// Ranges of parameters, and names written twice (a map would silently keep the last).
    fn check_materials(
        &self,
        materials: &BTreeMap<String, MaterialFile>,
    ) -> Result<(), SceneError> {
        if let Some(key) = self.duplicate_material_key() {
            return Err(self.at(
                key.span.start,
                format!(
                    "material {} is defined twice",
                    self.text.get(key.span).unwrap_or_default()
                ),
            ));
        }
        for (name, material) in materials {
            let problem = match material {
                MaterialFile::Diffuse { reflectance } if reflectance.iter().any(|&r| r < 0.0) => {
                    "reflectance must not be negative"
                }
                MaterialFile::Dielectric { int_ior, ext_ior }
                    if *int_ior <= 0.0 || *ext_ior <= 0.0 =>
                {
                    "indices of refraction must be positive"
                }
                _ => continue,
            };
            let here = self
                .material_keys()
                .into_iter()
                .find(|k| k.name == name)
                .map_or_else(|| self.field("materials"), |k| k.span.start);
            return Err(self.at(here, format!("material \"{name}\": {problem}")));
        }
        Ok(())
    }

    fn add_shape(
        &self,
        scene: &mut Scene,
        materials: &BTreeMap<String, MaterialFile>,
        index: usize,
        shape: &ShapeFile,
    ) -> Result<(), SceneError> {
        let bsdf = match materials.get(&shape.material) {
            Some(m) => bsdf_of(m),
            None => {
                let names: Vec<&String> = materials.keys().collect();
                return Err(self.at(
                    self.string_in_element("shapes", index, &shape.material),
                    format!(
                        "unknown material \"{}\" (defined: {names:?})",
                        shape.material
                    ),
                ));
            }
        };
        let emission = Vec3::from(shape.emission.unwrap_or([0.0; 3]));
        if emission.min_element() < 0.0 {
            return Err(self.at(
                self.word_in_element("shapes", index, "emission"),
                "emission must not be negative",
            ));
        }
        let to_world = to_world(&shape.to_world)
            .map_err(|e| self.at(self.word_in_element("shapes", index, "to_world"), e))?;
        let material = scene.materials.len() as u32;
        scene.materials.push(Material::new(bsdf, emission));
        let object_triangles = match &shape.shape {
            ShapeKind::Rectangle => mesh::rectangle(),
            ShapeKind::Cube => mesh::cube(),
            ShapeKind::Obj { path: obj } => self.obj_triangles(index, obj)?,
            ShapeKind::Sphere { center, radius } => {
                let sphere = self.sphere(index, *center, *radius, to_world)?;
                scene.spheres.push(Sphere {
                    material,
                    flip_normals: shape.flip_normals,
                    ..sphere
                });
                return Ok(());
            }
        };
        scene.push_mesh(object_triangles, to_world, material, shape.flip_normals);
        Ok(())
    }

    /// The sphere of shape `index`, placed by `to_world`; material and side are set by the caller.
    fn sphere(
        &self,
        index: usize,
        center: [f32; 3],
        radius: f32,
        to_world: Mat4,
    ) -> Result<Sphere, SceneError> {
        if radius.is_nan() || radius <= 0.0 {
            return Err(self.at(
                self.word_in_element("shapes", index, "radius"),
                format!("sphere radius {radius}: must be positive"),
            ));
        }
        let Some(scale) = crate::scene::similarity_scale(to_world) else {
            return Err(self.at(
                self.word_in_element("shapes", index, "to_world"),
                "a sphere's to_world may only scale uniformly, rotate and translate",
            ));
        };
        Ok(Sphere {
            center: to_world.transform_point3(Vec3::from(center)),
            radius: radius * scale,
            material: 0,
            flip_normals: false,
        })
    }

    fn obj_triangles(&self, index: usize, obj: &str) -> Result<Vec<[Vec3; 3]>, SceneError> {
        let here = self.word_in_element("shapes", index, "path");
        let obj_path = self.path.parent().unwrap_or(Path::new(".")).join(obj);
        let used_at = Location::from_offset(self.path, self.text, here);
        crate::loaders::obj::load_triangles(&obj_path)
            .map_err(|e| e.referenced_from("OBJ", &used_at))
    }
}

fn bsdf_of(m: &MaterialFile) -> Bsdf {
    match *m {
        MaterialFile::Diffuse { reflectance } => Diffuse::bsdf(reflectance.into()),
        MaterialFile::Dielectric { int_ior, ext_ior } => Dielectric::bsdf(int_ior, ext_ior),
        MaterialFile::Mirror => Mirror::bsdf(),
    }
}

fn to_world(steps: &[TransformStep]) -> Result<Mat4, String> {
    let mut m = Mat4::IDENTITY;
    for step in steps {
        let next = match step {
            TransformStep::Translate(t) => Mat4::from_translation(Vec3::from(*t)),
            TransformStep::Scale(s) => Mat4::from_scale(Vec3::from(*s)),
            TransformStep::Rotate { axis, degrees } => {
                let axis = Vec3::from(*axis)
                    .try_normalize()
                    .ok_or("Rotate: the axis is zero")?;
                Mat4::from_axis_angle(axis, degrees.to_radians())
            }
            TransformStep::Matrix(v) => {
                let m = Mat4::from_cols_array(v).transpose();
                if m.row(3) != Vec4::W {
                    return Err(
                        "Matrix: the last row must be 0, 0, 0, 1 (projective transforms \
                                are not supported)"
                            .into(),
                    );
                }
                m
            }
        };
        m = next * m;
    }
    Ok(m)
}

/// Whether a number-like token is NaN or infinite as an `f32` (`NaN`, `-inf`, `1e39`).
fn is_non_finite_number(word: &str) -> bool {
    let unsigned = word.trim_start_matches(['+', '-']).to_ascii_lowercase();
    if matches!(unsigned.as_str(), "nan" | "inf" | "infinity") {
        return true;
    }
    let starts_like_number = unsigned.starts_with(|c: char| c.is_ascii_digit() || c == '.');
    let digits = unsigned.replace('_', "");
    starts_like_number && digits.parse::<f64>().is_ok_and(|v| !(v as f32).is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An installed `hppm` (a wheel built in a temporary folder that is gone) asks for the
    /// default scene at a path that no longer exists: it must get the repository's file, and any
    /// other missing file must still be an error naming it.
    #[test]
    fn the_default_scene_is_built_in() {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_SCENE.0);
        let from_file = load(&file).expect("the repository's default scene loads");
        let built_in = load(Path::new("/gone/build/scenes/cornell_box.ron"))
            .expect("a missing default scene falls back to the built-in copy");
        assert_eq!(built_in.source, Path::new(DEFAULT_SCENE.0));
        assert_eq!(
            Scene {
                media: Default::default(),
                source: from_file.source.clone(),
                ..built_in
            },
            from_file
        );
        let other = load(Path::new("/gone/build/scenes/other.ron"));
        assert!(matches!(other, Err(SceneError::Io { .. })), "{other:?}");
    }

    fn error(text: &str) -> String {
        match parse(Path::new("t.ron"), text) {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => e.to_string(),
        }
    }

    /// The scene's own tokenizer read `r#"a" // )"#` as a word, a string and a comment that
    /// swallowed the rest of the line, so the `"glass"` key was not found and the error fell
    /// back to line 3.
    #[test]
    fn errors_after_a_raw_string_and_a_nested_comment_point_at_their_entry() {
        let material = "(\n camera: (origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8),\n materials: {\n  r#\"a\" // )\"#: Mirror,\n  /* a /* b */ c */ \"glass\": Dielectric(int_ior: -1.5),\n },\n shapes: [],\n)";
        let err = error(material);
        assert!(
            err.contains("t.ron:5:21:") && err.contains("glass"),
            "{err}"
        );
        let shape = "(\n camera: (origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8),\n materials: { \"m\": Mirror },\n shapes: [\n  (shape: Cube, material: \"m\"),\n  /* a /* b */ c */ (shape: Cube,\n   material: r#\"x\" // )\"#),\n ],\n)";
        let err = error(shape);
        assert!(
            err.contains("t.ron:7:14:") && err.contains("unknown material"),
            "{err}"
        );
    }

    #[test]
    fn a_non_finite_number_is_found_past_a_raw_string() {
        let text = "(\n camera: (origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8),\n materials: { r#\"NaN \" // \"#: Mirror },\n shapes: [(shape: Cube, material: \"NaN \", emission: (1, -inf, 1))],\n)";
        let err = error(text);
        assert!(err.contains("t.ron:4:") && err.contains("-inf"), "{err}");
    }
}
