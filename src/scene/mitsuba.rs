//! Mitsuba 3 XML scenes, read as Mitsuba 3 reads them. The plugins and properties read are
//! listed in `plugins.rs` (the README's table); `<default>` and `$name`, `<include>`, `<path>`,
//! `<alias>`, `<ref>` and top-level declarations with an `id` work as in Mitsuba, and a file older
//! than version 2.0 has its property names upgraded as Mitsuba 3 upgrades them.
//!
//! Like Mitsuba, an unknown tag, attribute or property is an error with its line and column (and
//! a did-you-mean), so a typo never silently renders a different scene; so is anything this
//! renderer would have to ignore to load the file (a mirroring camera, a scaled
//! projector). What only changes the algorithm (another integrator or sampler) or only old
//! versions read is a warning. A check reports every problem in the file at once: an element
//! that fails is reported and reading goes on with the next (see [`check_with`]).

use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Vec3, Vec4};
use roxmltree::{Document, Node};

use super::emitter::{DirectionalLight, EnvMap, Environment, Projector, SpotLight};
use super::filter::{
    DEFAULT_GAUSSIAN_STDDEV, DEFAULT_LANCZOS_LOBES, DEFAULT_MITCHELL_B_C, DEFAULT_TENT_RADIUS,
    PixelFilter,
};
use super::texture::{self, Bitmap, Filter, Texture, UvTransform, WrapMode};
use super::{
    Bsdf, Camera, Crop, Distribution, FramePerturbation, Integrator, Lens, Material,
    MaterialTextures, Microfacet, PRINCIPLED_TEXTURED, PRINCIPLED_THIN_TEXTURED, PerturbationKind,
    PointLight, Report, Scene, SceneError, SideTextures, Sphere, Tint, bsdf, mesh, plugins,
    spectrum,
};
use crate::error::{Location, edit_distance};

/// Mitsuba's default BSDF for a shape that names none.
const DEFAULT_BSDF: Bsdf = Bsdf::Diffuse {
    reflectance: Vec3::splat(0.5),
};

/// The widest pixel filter accepted (radius or stddev, in pixels).
const MAX_FILTER_WIDTH: f32 = 16.0;

/// Mitsuba's default `rr_depth`.
const DEFAULT_RR_DEPTH: u32 = 5;

pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, &[])
}

/// Loads with `-D name=value` parameters (`defines`), which take the place of the scene's
/// `<default name=...>` of the same name and may give `$name`s the scene declares no default
/// for. As in Mitsuba 3, a parameter no attribute uses is an error.
pub fn load_with(path: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
    check_with(path, defines).into_result()
}

/// Parses Mitsuba XML `text`; `path` names the file in errors and anchors relative OBJ paths.
pub fn parse(path: &Path, text: &str) -> Result<Scene, SceneError> {
    parse_with(path, text, &[])
}

/// [`parse`] with `-D` parameters (see [`load_with`]).
pub fn parse_with(
    path: &Path,
    text: &str,
    defines: &[(String, String)],
) -> Result<Scene, SceneError> {
    check_text(path, text, defines).into_result()
}

/// Reads the whole file and reports every problem in it, not only the first: a shape, emitter
/// or declaration that cannot be read is reported and skipped, and reading goes on with the
/// next.
pub fn check_with(path: &Path, defines: &[(String, String)]) -> Report {
    match super::read_text(path) {
        Ok(text) => check_text(path, &text, defines),
        Err(e) => Report::failed(e),
    }
}

/// [`check_with`] on `text` (`path` names it in messages and anchors relative paths).
pub fn check_text(path: &Path, text: &str, defines: &[(String, String)]) -> Report {
    let texts = with_includes(path, text);
    let mut docs = Vec::with_capacity(texts.len());
    for (file, text) in &texts {
        match Document::parse(text) {
            Ok(doc) => docs.push((file.clone(), doc)),
            Err(e) => {
                let pos = e.pos();
                return Report::failed(SceneError::at(
                    Location::new(file, pos.row as usize, pos.col as usize),
                    format!("XML syntax error: {e}"),
                ));
            }
        }
    }
    let files = docs
        .iter()
        .map(|(file, doc)| SourceFile {
            path: file.clone(),
            doc,
            before_v2: false,
        })
        .collect();
    let doc = &docs[0].1;
    let mut reader = Reader {
        path,
        files,
        search_dirs: Vec::new(),
        defaults: defines.iter().cloned().collect(),
        defined: defines.iter().map(|(k, _)| k.clone()).collect(),
        used: RefCell::new(HashSet::new()),
        declared: Vec::new(),
        named_bsdfs: HashMap::new(),
        failed_ids: HashMap::new(),
        shape_groups: HashMap::new(),
        meshes: RefCell::new(HashMap::new()),
        in_group: false,
        named_textures: HashMap::new(),
        textures: RefCell::new(Vec::new()),
        materials: RefCell::new(Vec::new()),
        scene: empty_scene(path),
        has_integrator: false,
        has_sensor: false,
        errors: RefCell::new(Vec::new()),
        warnings: RefCell::new(Vec::new()),
        properties_read: RefCell::new(BTreeMap::new()),
    };
    reader.check_attributes();
    let read = reader.read_scene(doc.root_element());
    reader.keep(read);
    let unused = reader.check_defines_used(defines);
    reader.keep(unused);
    reader.scene.textures = reader.textures.take();
    reader.scene.materials = reader.materials.take();
    if !reader.has_sensor {
        reader.report(reader.error(doc.root_element(), "the scene has no <sensor>"));
    }
    // In file order, whichever recovery point recorded them.
    let by_place = |e: &SceneError| match e {
        SceneError::At { location, .. } => (location.line, location.col),
        _ => (usize::MAX, 0),
    };
    let mut errors = reader.errors.take();
    errors.sort_by_key(by_place);
    let mut warnings = reader.warnings.take();
    warnings.sort_by_key(by_place);
    // Validation judges the scene as a whole: with parts of it missing it would only repeat
    // what is reported already.
    if errors.is_empty()
        && let Err(e) = reader.scene.validate()
    {
        errors.push(e);
    }
    Report {
        scene: errors.is_empty().then_some(reader.scene),
        errors,
        warnings,
        properties_read: reader.properties_read.take(),
    }
}

/// Deepest nesting of `<include>`s followed (Mitsuba's limit is similar); deeper ones, and
/// cycles, are reported where they are included.
const MAX_INCLUDE_DEPTH: usize = 16;

/// The scene's text and every file it `<include>`s, directly or not, that can be read, each once.
/// An include that cannot be read is left out here and reported where the scene includes it.
fn with_includes(path: &Path, text: &str) -> Vec<(PathBuf, String)> {
    let mut files = vec![(path.to_path_buf(), text.to_string())];
    let mut next = 0;
    while next < files.len() && files.len() <= MAX_INCLUDE_DEPTH * 4 {
        let found: Vec<PathBuf> = match Document::parse(&files[next].1) {
            Ok(doc) => doc
                .descendants()
                .filter(|n| n.has_tag_name("include"))
                .filter_map(|n| n.attribute("filename"))
                .map(|f| relative_to(&files[next].0, f))
                .collect(),
            Err(_) => Vec::new(),
        };
        for file in found {
            if files.iter().any(|(known, _)| *known == file) {
                continue;
            }
            if let Ok(text) = std::fs::read_to_string(&file) {
                files.push((file, text));
            }
        }
        next += 1;
    }
    files
}

/// `file` as named in `from`: relative to `from`'s folder unless absolute.
fn relative_to(from: &Path, file: &str) -> PathBuf {
    from.parent().unwrap_or(Path::new(".")).join(file)
}

/// What a scene is before its elements are read: Mitsuba's defaults where it has them.
fn empty_scene(path: &Path) -> Scene {
    Scene {
        source: path.to_path_buf(),
        camera: Camera {
            origin: Vec3::ZERO,
            target: Vec3::Z,
            up: Vec3::Y,
            // Replaced once the sensor is read (Mitsuba's default is a 50 mm lens).
            fov_x_deg: 39.3077,
            width: 768,
            height: 576,
            filter: PixelFilter::MITSUBA_DEFAULT,
            sample_border: false,
            crop: None,
            lens: None,
        },
        integrator: Integrator {
            max_depth: None,
            rr_depth: Some(DEFAULT_RR_DEPTH),
            hide_emitters: false,
        },
        spp_hint: None,
        materials: Vec::new(),
        triangles: Vec::new(),
        spheres: Vec::new(),
        point_lights: Vec::new(),
        emitters: Default::default(),
        textures: Vec::new(),
    }
}

/// The attributes each known tag may carry; `None` for tags this loader does not know (those
/// are reported where they appear, as unknown tags).
fn allowed_attributes(tag: &str) -> Option<&'static [&'static str]> {
    Some(match tag {
        "scene" => &["version"],
        "default" => &["name", "value"],
        "integrator" | "sensor" | "sampler" | "film" | "rfilter" | "shape" | "bsdf" | "emitter"
        | "texture" => &["type", "id", "name"],
        "integer" | "float" | "boolean" | "string" | "rgb" => &["name", "value"],
        "spectrum" => &["name", "value", "filename", "type"],
        "point" | "vector" => &["name", "value", "x", "y", "z"],
        "transform" => &["name"],
        "matrix" => &["value"],
        "translate" | "scale" => &["value", "x", "y", "z"],
        "rotate" => &["value", "x", "y", "z", "angle"],
        "lookat" => &["origin", "target", "up"],
        "include" => &["filename", "name"],
        "path" => &["value"],
        "alias" => &["id", "as"],
        "ref" => &["id", "name"],
        _ => return None,
    })
}

const PROPERTY_TAGS: &[&str] = &[
    "integer",
    "float",
    "boolean",
    "string",
    "rgb",
    "spectrum",
    "point",
    "vector",
    "transform",
    // A texture given to a colour parameter, inline or by reference.
    "texture",
    "ref",
];

/// One XML file of the scene: the scene's own, or one it includes.
struct SourceFile<'a, 'input> {
    path: PathBuf,
    doc: &'a Document<'input>,
    /// The file declares a Mitsuba version before 2.0: property names are upgraded as Mitsuba
    /// 3 upgrades them (camelCase to snake_case, ...).
    before_v2: bool,
}

struct Reader<'a, 'input> {
    path: &'a Path,
    /// The scene's file first, then those it includes.
    files: Vec<SourceFile<'a, 'input>>,
    /// Folders added by `<path value=...>`, searched after a file's own folder.
    search_dirs: Vec<PathBuf>,
    defaults: HashMap<String, String>,
    /// The names given on the command line (`-D`), which `<default>` does not replace, and
    /// which of all names an attribute has used.
    defined: HashSet<String>,
    used: RefCell<HashSet<String>>,
    /// The names of the scene's `<default>`s, for messages.
    declared: Vec<String>,
    named_bsdfs: HashMap<String, Sides>,
    /// Textures declared at top level with an `id`, and their index in `textures` once used.
    named_textures: HashMap<String, (Texture, RefCell<Option<u32>>)>,
    /// The textures the scene's materials use, in the order first used.
    textures: RefCell<Vec<Texture>>,
    /// The scene's materials: each shape's, and the ones blends and masks choose among
    /// (pushed while their BSDF is read, so before the blend that uses them).
    materials: RefCell<Vec<Material>>,
    /// The ids of top-level BSDFs and textures that could not be read, and where they were:
    /// a reference to one is reported as such, not as an undeclared id.
    failed_ids: HashMap<String, usize>,
    /// Mesh files read for shapegroups (by path and serialized shape index), read once for
    /// all their instances. Others are not kept: a large mesh would be held twice.
    meshes: RefCell<HashMap<(PathBuf, u32), mesh::MeshData>>,
    /// A shapegroup or an instance is being read.
    in_group: bool,
    /// Shapegroups by id: their shapes, read again for each instance.
    shape_groups: HashMap<String, Vec<Node<'a, 'input>>>,
    scene: Scene,
    has_integrator: bool,
    has_sensor: bool,
    errors: RefCell<Vec<SceneError>>,
    warnings: RefCell<Vec<SceneError>>,
    /// See [`Report::properties_read`].
    properties_read: RefCell<BTreeMap<String, BTreeSet<String>>>,
}

/// The properties of one object (`<float name=...>` and friends), consumed by name; whatever is
/// left over at the end is an unknown property.
#[derive(Default)]
struct Props<'a, 'input> {
    entries: Vec<(String, Node<'a, 'input>)>,
    /// Every name asked for, present or not: what the plugin reads, for did-you-mean.
    asked: Vec<String>,
}

impl<'a, 'input> Props<'a, 'input> {
    fn take(&mut self, name: &str) -> Option<Node<'a, 'input>> {
        if !self.asked.iter().any(|a| a == name) {
            self.asked.push(name.to_string());
        }
        let i = self.entries.iter().position(|(n, _)| n == name)?;
        Some(self.entries.remove(i).1)
    }

    /// The asked-for name closest to `unknown`, if close enough to be a typo of it.
    fn suggestion(&self, unknown: &str) -> Option<&str> {
        self.asked
            .iter()
            .map(|a| (edit_distance(a, unknown), a))
            .filter(|(d, a)| *d <= (a.len().max(unknown.len()) / 3).max(1))
            .min_by_key(|(d, _)| *d)
            .map(|(_, a)| a.as_str())
    }
}

/// Properties that Mitsuba 0.5/0.6 plugins read and Mitsuba 3's do not (after the version
/// upgrade renames them): a scene written for those versions renders without them, so they are
/// warnings, not errors.
const LEGACY_PROPERTIES: &[&str] = &[
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
fn snake_case(name: &str) -> String {
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

/// A `<bsdf>` as a shape uses it: the front BSDF and, for `twosided`, the back's, with the
/// textures of their colour parameters.
#[derive(Debug, Clone, Copy)]
struct Sides {
    front: Bsdf,
    back: Option<Bsdf>,
    textures: MaterialTextures,
}

impl Sides {
    fn material(self, emission: Vec3) -> Material {
        Material {
            bsdf: self.front,
            back: self.back,
            emission,
            textures: self.textures,
        }
    }
}

/// A view angle as a file gives it: degrees along `axis` (x, y, diagonal, smaller, larger),
/// and the element a bad axis is reported at.
struct ViewAngle<'a, 'input> {
    fov: f64,
    axis_node: Node<'a, 'input>,
    axis: String,
}

/// The parameters that take a texture, for messages.
const TEXTURED_PARAMETERS: &str = "reflectance (diffuse), diffuse_reflectance (plastic, \
    roughplastic, pplastic), specular_reflectance (conductor, roughconductor, plastic, \
    roughplastic, pplastic, dielectric, thindielectric, roughdielectric), \
    specular_transmittance (dielectric, thindielectric, roughdielectric), alpha, alpha_u, \
    alpha_v (roughconductor, roughdielectric), weight (blendbsdf), opacity (mask), every \
    parameter of principled but eta, specular and its sampling rates, every parameter of \
    principledthin but its sampling rates";

/// The roughness a microfacet BSDF reads: one number (`roughplastic`), numbers that may differ
/// along u and v (`pplastic`), or numbers or textures along u and v (rough conductors and
/// dielectrics), as each Mitsuba plugin reads it.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Alphas {
    Isotropic,
    Anisotropic,
    Textured,
}

/// Mitsuba's named indices of refraction (include/mitsuba/render/ior.h).
const NAMED_IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The parts of a shape that do not depend on its type.
struct ShapeCommon {
    to_world: Mat4,
    material: u32,
    flip_normals: bool,
}

impl<'a, 'input> Reader<'a, 'input> {
    /// The file `node` is in.
    fn file_of(&self, node: Node) -> &SourceFile<'a, 'input> {
        self.files
            .iter()
            .find(|f| std::ptr::eq(f.doc, node.document()))
            .unwrap_or(&self.files[0])
    }

    /// Where byte `offset` of `node`'s file is.
    fn location_of(&self, node: Node, offset: usize) -> Location {
        let file = self.file_of(node);
        let pos = file.doc.text_pos_at(offset);
        Location::new(&file.path, pos.row as usize, pos.col as usize)
    }

    fn location(&self, node: Node) -> Location {
        self.location_of(node, node.range().start)
    }

    fn error(&self, node: Node, message: impl Into<String>) -> SceneError {
        SceneError::at(self.location(node), message)
    }

    /// An error placed at attribute `attr` of `node` (at the node if it has no such attribute).
    fn attr_error(&self, node: Node, attr: &str, message: impl Into<String>) -> SceneError {
        let offset = node
            .attribute_node(attr)
            .map_or(node.range().start, |a| a.range().start);
        SceneError::at(self.location_of(node, offset), message)
    }

    /// Records a problem that keeps the scene from rendering; reading goes on.
    fn report(&self, error: SceneError) {
        self.errors.borrow_mut().push(error);
    }

    /// Records `result`'s error, if any.
    fn keep(&self, result: Result<(), SceneError>) {
        if let Err(e) = result {
            self.report(e);
        }
    }

    /// Records something the scene renders without, at `node`.
    fn warn(&self, node: Node, message: impl Into<String>) {
        self.warnings.borrow_mut().push(self.error(node, message));
    }

    /// Every attribute of every known tag must be one it takes.
    fn check_attributes(&self) {
        let all = self.files.iter().flat_map(|f| f.doc.descendants());
        for node in all.filter(Node::is_element) {
            let tag = node.tag_name().name();
            let Some(allowed) = allowed_attributes(tag) else {
                continue;
            };
            for a in node.attributes() {
                if a.namespace().is_none() && !allowed.contains(&a.name()) {
                    self.report(self.attr_error(
                        node,
                        a.name(),
                        format!(
                            "{}: unknown attribute \"{}\" (expected one of: {})",
                            describe(node),
                            a.name(),
                            allowed.join(", ")
                        ),
                    ));
                }
            }
        }
    }

    /// An attribute with `$name` defaults substituted.
    fn attr(&self, node: Node, name: &str) -> Result<Option<String>, SceneError> {
        let Some(raw) = node.attribute(name) else {
            return Ok(None);
        };
        if !raw.contains('$') {
            return Ok(Some(raw.to_string()));
        }
        let mut out = String::new();
        let mut rest = raw;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let tail = &rest[i + 1..];
            let end = tail
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(tail.len());
            let key = &tail[..end];
            let value = self.defaults.get(key).ok_or_else(|| {
                self.attr_error(
                    node,
                    name,
                    format!(
                        "{}: {name}=\"{raw}\" uses ${key}, but there is no <default name=\"{key}\">",
                        describe(node)
                    ),
                )
            })?;
            out.push_str(value);
            self.used.borrow_mut().insert(key.to_string());
            rest = &tail[end..];
        }
        out.push_str(rest);
        Ok(Some(out))
    }

    /// Mitsuba 3 refuses a `-D` parameter that no attribute substitutes (a typo would
    /// otherwise render the scene unchanged).
    fn check_defines_used(&self, defines: &[(String, String)]) -> Result<(), SceneError> {
        let used = self.used.borrow();
        let Some((key, value)) = defines.iter().find(|(k, _)| !used.contains(k)) else {
            return Ok(());
        };
        let mut known: Vec<&str> = self
            .declared
            .iter()
            .chain(used.iter())
            .map(String::as_str)
            .collect();
        known.sort_unstable();
        known.dedup();
        let known = if known.is_empty() {
            "none".to_string()
        } else {
            known.join(", ")
        };
        Err(SceneError::File {
            file: self.path.to_path_buf(),
            message: format!(
                "-D {key}={value}: the scene uses no ${key}, so the parameter would change \
                 nothing (Mitsuba refuses unused parameters too); the scene's parameters: {known}"
            ),
        })
    }

    fn required_attr(&self, node: Node, name: &str) -> Result<String, SceneError> {
        self.attr(node, name)?.ok_or_else(|| {
            self.error(
                node,
                format!("{} needs a {name}=\"...\" attribute", describe(node)),
            )
        })
    }

    fn read_scene(&mut self, root: Node<'a, 'input>) -> Result<(), SceneError> {
        if root.tag_name().name() != "scene" {
            return Err(self.error(root, "the root element must be <scene>"));
        }
        self.read_version(root)?;
        self.read_children(root, 0);
        Ok(())
    }

    /// The top-level elements of `root` (the scene's, or an included file's). Each is read on
    /// its own: one that fails is reported and the next is read, so that a check lists every
    /// problem in the file.
    fn read_children(&mut self, root: Node<'a, 'input>, depth: usize) {
        for child in root.children().filter(Node::is_element) {
            let read = self.read_top_level(child, depth);
            self.keep(read);
        }
    }

    fn read_top_level(&mut self, child: Node<'a, 'input>, depth: usize) -> Result<(), SceneError> {
        match child.tag_name().name() {
            "include" => self.read_include(child, depth),
            "path" => {
                let dir = self.required_attr(child, "value")?;
                let dir = relative_to(&self.file_of(child).path, &dir);
                self.search_dirs.insert(0, dir);
                Ok(())
            }
            "alias" => self.read_alias(child),
            _ => self.read_element(child),
        }
    }

    /// `<include filename=...>`: an included `<scene>`'s elements are read as if they stood
    /// here; a file holding one object (a `<bsdf>`, a `<shape>`) adds that object.
    fn read_include(&mut self, node: Node<'a, 'input>, depth: usize) -> Result<(), SceneError> {
        let name = self.required_attr(node, "filename")?;
        let file = relative_to(&self.file_of(node).path, &name);
        let Some(index) = self.files.iter().position(|f| f.path == file) else {
            return Err(self.attr_error(
                node,
                "filename",
                format!("<include>: cannot read {}", file.display()),
            ));
        };
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(self.error(
                node,
                format!("<include>: includes nested deeper than {MAX_INCLUDE_DEPTH} (a cycle?)"),
            ));
        }
        let root = self.files[index].doc.root_element();
        if root.has_tag_name("scene") {
            self.read_version(root)?;
            self.read_children(root, depth + 1);
            Ok(())
        } else {
            self.read_top_level(root, depth + 1)
        }
    }

    /// `<alias id=... as=...>`: a second name for a BSDF or texture.
    fn read_alias(&mut self, node: Node) -> Result<(), SceneError> {
        let id = self.required_attr(node, "id")?;
        let alias = self.required_attr(node, "as")?;
        if self.named_bsdfs.contains_key(&alias) || self.named_textures.contains_key(&alias) {
            return Err(self.attr_error(
                node,
                "as",
                format!("<alias>: the id \"{alias}\" is taken already"),
            ));
        }
        if let Some(bsdf) = self.named_bsdfs.get(&id).copied() {
            self.named_bsdfs.insert(alias, bsdf);
        } else if let Some((texture, _)) = self.named_textures.get(&id) {
            let copy = (texture.clone(), RefCell::new(None));
            self.named_textures.insert(alias, copy);
        } else {
            return Err(self.attr_error(
                node,
                "id",
                format!("<alias>: no <bsdf> or <texture> with id \"{id}\" is declared before this"),
            ));
        }
        Ok(())
    }

    fn read_element(&mut self, child: Node<'a, 'input>) -> Result<(), SceneError> {
        {
            match child.tag_name().name() {
                "default" => self.read_default(child),
                "integrator" => self.read_integrator(child),
                "sensor" => self.read_sensor(child),
                "shape" => self.read_shape(child),
                "emitter" => self.read_emitter(child),
                "bsdf" => self.read_named_bsdf(child),
                "texture" => self.read_named_texture(child),
                "medium" | "phase" | "volume" => Err(self.error(
                    child,
                    format!(
                        "<{}>: participating media are not supported",
                        child.tag_name().name()
                    ),
                )),
                other => Err(self.error(child, format!("unknown tag <{other}> in <scene>"))),
            }
        }
    }

    fn read_default(&mut self, node: Node) -> Result<(), SceneError> {
        let name = self.required_attr(node, "name")?;
        let value = self.required_attr(node, "value")?;
        if !self.defined.contains(&name) {
            self.defaults.insert(name.clone(), value);
        }
        self.declared.push(name);
        Ok(())
    }

    /// `<scene version="...">`: files older than 2.0 have their property names upgraded.
    fn read_version(&mut self, root: Node) -> Result<(), SceneError> {
        let Some(version) = self.attr(root, "version")? else {
            return Ok(());
        };
        let major = version
            .split('.')
            .next()
            .and_then(|m| m.trim().parse::<u32>().ok());
        let Some(major) = major else {
            return Err(self.attr_error(
                root,
                "version",
                format!("<scene version=\"{version}\">: expected a version such as 3.0.0"),
            ));
        };
        let index = self
            .files
            .iter()
            .position(|f| std::ptr::eq(f.doc, root.document()))
            .unwrap_or(0);
        self.files[index].before_v2 = major < 2;
        Ok(())
    }

    /// The property children of `node`, by name; children whose tag is in `nested` are objects
    /// the caller reads itself. Anything else is an unknown tag.
    fn props(
        &self,
        node: Node<'a, 'input>,
        nested: &[&str],
    ) -> Result<Props<'a, 'input>, SceneError> {
        let mut entries: Vec<(String, Node)> = Vec::new();
        for child in node.children().filter(Node::is_element) {
            let tag = child.tag_name().name();
            if nested.contains(&tag) {
                continue;
            }
            if !PROPERTY_TAGS.contains(&tag) {
                return Err(self.error(
                    child,
                    format!("unknown tag <{tag}> in {}", describe_object(node)),
                ));
            }
            let mut name = self.required_attr(child, "name")?;
            if self.file_of(child).before_v2 {
                name = self.upgraded_name(node, &name);
            }
            if let Some((_, first)) = entries.iter().find(|(n, _)| *n == name) {
                return Err(self.attr_error(
                    child,
                    "name",
                    format!(
                        "{}: property \"{name}\" given twice in {} (first at line {})",
                        describe(child),
                        describe_object(node),
                        self.location(*first).line
                    ),
                ));
            }
            entries.push((name, child));
        }
        Ok(Props {
            entries,
            asked: Vec::new(),
        })
    }

    /// Property `name` of `owner` in a file older than Mitsuba 2.0, renamed as Mitsuba 3's
    /// loader renames it.
    fn upgraded_name(&self, owner: Node, name: &str) -> String {
        let name = snake_case(name);
        let diffuse = owner.has_tag_name("bsdf") && owner.attribute("type") == Some("diffuse");
        if diffuse && name == "diffuse_reflectance" {
            return "reflectance".into();
        }
        name
    }

    /// Records what `owner`'s plugin looked for (see [`Report::properties_read`]).
    fn note_read(&self, props: &Props, owner: Node) {
        let plugin = format!(
            "{} {}",
            owner.tag_name().name(),
            owner.attribute("type").unwrap_or_default()
        );
        self.properties_read
            .borrow_mut()
            .entry(plugin)
            .or_default()
            .extend(props.asked.iter().cloned());
    }

    /// Reports every property nobody took (the first is returned, the others recorded); a
    /// property only old Mitsuba versions read is a warning.
    fn finish(&self, props: Props, owner: Node) -> Result<(), SceneError> {
        self.finish_with(props, owner, None)
    }

    /// [`Self::finish`], saying what the plugin takes (`takes`) in each message.
    fn finish_with(
        &self,
        props: Props,
        owner: Node,
        takes: Option<&str>,
    ) -> Result<(), SceneError> {
        self.note_read(&props, owner);
        let mut unknown = Vec::new();
        for (name, node) in &props.entries {
            if LEGACY_PROPERTIES.contains(&name.as_str()) {
                self.warn(
                    *node,
                    format!(
                        "{}: \"{name}\" was read by Mitsuba 0.x only; ignored",
                        describe(*node)
                    ),
                );
                continue;
            }
            let mut message = format!(
                "{}: unknown property \"{name}\" for {}",
                describe(*node),
                describe_object(owner)
            );
            if let Some(takes) = takes {
                message.push_str(&format!(" (it takes {takes})"));
            }
            if let Some(near) = props.suggestion(name) {
                message.push_str(&format!("; did you mean \"{near}\"?"));
            }
            unknown.push(self.attr_error(*node, "name", message));
        }
        let mut unknown = unknown.into_iter();
        match unknown.next() {
            None => Ok(()),
            Some(first) => {
                unknown.for_each(|e| self.report(e));
                Err(first)
            }
        }
    }

    /// Properties whose value is read but does not affect our rendering (clip planes, pixel
    /// formats): checked for type, then dropped.
    fn ignore(
        &self,
        props: &mut Props,
        names: &[&str],
        read: impl Fn(&Self, Node) -> Result<(), SceneError>,
    ) -> Result<(), SceneError> {
        for name in names {
            if let Some(n) = props.take(name) {
                read(self, n)?;
            }
        }
        Ok(())
    }

    fn expect_tag(&self, node: Node, allowed: &[&str]) -> Result<(), SceneError> {
        if allowed.contains(&node.tag_name().name()) {
            return Ok(());
        }
        if matches!(node.tag_name().name(), "texture" | "ref") {
            return Err(self.error(
                node,
                format!(
                    "{}: this parameter takes no texture (textures are supported on \
                     {TEXTURED_PARAMETERS}); expected {}",
                    describe(node),
                    allowed
                        .iter()
                        .map(|t| format!("<{t}>"))
                        .collect::<Vec<_>>()
                        .join(" or ")
                ),
            ));
        }
        let expected: Vec<String> = allowed.iter().map(|t| format!("<{t}>")).collect();
        Err(self.error(
            node,
            format!("{}: expected {}", describe(node), expected.join(" or ")),
        ))
    }

    /// One number from attribute `attr` (whose value, after substitution, is `text`).
    fn number(&self, node: Node, attr: &str, text: &str) -> Result<f32, SceneError> {
        let value: f32 = text.trim().parse().map_err(|_| {
            self.attr_error(
                node,
                attr,
                format!("{}: expected a number, got \"{text}\"", describe(node)),
            )
        })?;
        if !value.is_finite() {
            return Err(self.attr_error(
                node,
                attr,
                format!("{}: \"{text}\" is not a finite number", describe(node)),
            ));
        }
        Ok(value)
    }

    /// Numbers separated by commas and/or white space.
    fn numbers(&self, node: Node, attr: &str, text: &str) -> Result<Vec<f32>, SceneError> {
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| self.number(node, attr, s))
            .collect()
    }

    fn float(&self, node: Node) -> Result<f32, SceneError> {
        self.expect_tag(node, &["float", "integer"])?;
        let value = self.required_attr(node, "value")?;
        self.number(node, "value", &value)
    }

    fn integer(&self, node: Node) -> Result<i64, SceneError> {
        self.expect_tag(node, &["integer"])?;
        let value = self.required_attr(node, "value")?;
        value.trim().parse().map_err(|_| {
            self.attr_error(
                node,
                "value",
                format!(
                    "{}: expected a whole number, got \"{value}\"",
                    describe(node)
                ),
            )
        })
    }

    fn string(&self, node: Node) -> Result<String, SceneError> {
        self.expect_tag(node, &["string"])?;
        self.required_attr(node, "value")
    }

    fn boolean(&self, node: Node) -> Result<bool, SceneError> {
        self.expect_tag(node, &["boolean"])?;
        match self.required_attr(node, "value")?.as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            other => Err(self.attr_error(
                node,
                "value",
                format!(
                    "{}: expected true or false, got \"{other}\"",
                    describe(node)
                ),
            )),
        }
    }

    /// An RGB colour: `<rgb value="r, g, b">`, or one number for grey (`<rgb>`, `<float>`,
    /// `<spectrum>`).
    fn color(&self, node: Node) -> Result<Vec3, SceneError> {
        self.expect_tag(node, &["rgb", "float", "spectrum"])?;
        if node.has_tag_name("spectrum") {
            return self.spectrum(node);
        }
        let value = self.required_attr(node, "value")?;
        match self.numbers(node, "value", &value)?.as_slice() {
            [x] => Ok(Vec3::splat(*x)),
            [r, g, b] => Ok(Vec3::new(*r, *g, *b)),
            _ => Err(self.attr_error(
                node,
                "value",
                format!(
                    "{}: expected 1 or 3 numbers, got \"{value}\"",
                    describe(node)
                ),
            )),
        }
    }

    /// A `<spectrum>` as Mitsuba's RGB variants turn it into a colour: wavelength:value pairs,
    /// a constant, a `.spd` file or a spectrum plugin (`blackbody`, `regular`, `irregular`,
    /// `d65`, `srgb`), converted as the property that holds it is read (an emitter's radiance
    /// as light, an index of refraction unclamped, anything else as a reflectance).
    fn spectrum(&self, node: Node) -> Result<Vec3, SceneError> {
        let owner = node.parent_element();
        let kind = spectrum::SpectrumKind::of(
            owner.map_or("", |o| o.tag_name().name()),
            owner.and_then(|o| o.attribute("type")).unwrap_or(""),
            node.attribute("name").unwrap_or(""),
        );
        let fail = |attr: &str, why: String| {
            self.attr_error(node, attr, format!("{}: {why}", describe(node)))
        };
        if let Some(plugin) = self.attr(node, "type")? {
            return self.spectrum_plugin(node, &plugin, kind);
        }
        let parsed = match (self.attr(node, "value")?, self.attr(node, "filename")?) {
            (Some(value), None) => {
                spectrum::parse_spectrum_value(&value).map_err(|why| fail("value", why))?
            }
            (None, Some(file)) => {
                spectrum::read_spd(&self.relative(&file)).map_err(|why| fail("filename", why))?
            }
            _ => {
                return Err(self.error(
                    node,
                    format!(
                        "{}: give value=\"...\" or filename=\"...\" (one of them)",
                        describe(node)
                    ),
                ));
            }
        };
        Ok(parsed.to_rgb(kind))
    }

    /// `<spectrum type=...>` with its own properties.
    fn spectrum_plugin(
        &self,
        node: Node<'a, 'input>,
        plugin: &str,
        kind: spectrum::SpectrumKind,
    ) -> Result<Vec3, SceneError> {
        let mut props = self.props(node, &[])?;
        let float =
            |props: &mut Props, name: &str| props.take(name).map(|n| self.float(n)).transpose();
        let fail = |why: String| self.error(node, format!("<spectrum type=\"{plugin}\">: {why}"));
        let rgb = match plugin {
            // Mitsuba 3's RGB variants load a blackbody but cannot render it; its spectral
            // variants render what this gives.
            "blackbody" => {
                let Some(t) = float(&mut props, "temperature")? else {
                    return Err(fail("needs <float name=\"temperature\">".into()));
                };
                let lo = float(&mut props, "wavelength_min")?.unwrap_or(360.0);
                let hi = float(&mut props, "wavelength_max")?.unwrap_or(830.0);
                spectrum::blackbody_rgb_in_range(t, lo, hi).map_err(fail)?
            }
            "regular" | "irregular" => {
                let mut text = |name: &str| match props.take(name) {
                    Some(n) => self.string(n),
                    None => Err(fail(format!("needs <string name=\"{name}\">"))),
                };
                let sampled = if plugin == "regular" {
                    let values = text("values")?;
                    let lo = float(&mut props, "wavelength_min")?.unwrap_or(360.0);
                    let hi = float(&mut props, "wavelength_max")?.unwrap_or(830.0);
                    spectrum::Sampled::regular(&values, lo as f64, hi as f64)
                } else {
                    let wavelengths = text("wavelengths")?;
                    let values = text("values")?;
                    spectrum::Sampled::irregular(&wavelengths, &values)
                }
                .map_err(fail)?;
                spectrum::Spectrum::Sampled(sampled).to_rgb(kind)
            }
            "d65" => {
                let color = props.take("color").map(|n| self.color(n)).transpose()?;
                let scale = float(&mut props, "scale")?.unwrap_or(1.0);
                color.unwrap_or(Vec3::ONE) * scale
            }
            "srgb" => {
                let Some(n) = props.take("color") else {
                    return Err(fail("needs <rgb name=\"color\">".into()));
                };
                let color = self.color(n)?;
                let unbounded = match props.take("unbounded") {
                    Some(n) => self.boolean(n)?,
                    None => false,
                };
                if !unbounded && (color.max_element() > 1.0 || color.min_element() < 0.0) {
                    return Err(fail(
                        "color must lie in [0, 1] unless unbounded is true (as in Mitsuba)".into(),
                    ));
                }
                color
            }
            other => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "spectrum type \"{other}\" is not supported (blackbody, regular, \
                         irregular, d65, srgb)"
                    ),
                ));
            }
        };
        self.finish(props, node)?;
        Ok(rgb)
    }

    /// A colour that must not be negative (reflectance, radiance, intensity).
    fn non_negative_color(&self, node: Node) -> Result<Vec3, SceneError> {
        let c = self.color(node)?;
        if c.min_element() < 0.0 {
            return Err(self.attr_error(
                node,
                "value",
                format!("{}: must not be negative", describe(node)),
            ));
        }
        Ok(c)
    }

    /// `<point x= y= z=>` or `<point value="x, y, z">`.
    fn point(&self, node: Node) -> Result<Vec3, SceneError> {
        self.expect_tag(node, &["point", "vector"])?;
        self.xyz_or_value(node, 0.0, false)
    }

    fn vec3_attr(&self, node: Node, name: &str) -> Result<Vec3, SceneError> {
        let value = self.required_attr(node, name)?;
        match self.numbers(node, name, &value)?.as_slice() {
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(self.attr_error(
                node,
                name,
                format!(
                    "{}: {name}: expected 3 numbers, got \"{value}\"",
                    describe(node)
                ),
            )),
        }
    }

    /// `x= y= z=` attributes (missing ones take `default`), or a single `value=` with 3
    /// numbers (or 1, repeated, when `splat`).
    fn xyz_or_value(&self, node: Node, default: f32, splat: bool) -> Result<Vec3, SceneError> {
        if let Some(value) = self.attr(node, "value")? {
            return match self.numbers(node, "value", &value)?.as_slice() {
                [s] if splat => Ok(Vec3::splat(*s)),
                [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                _ => Err(self.attr_error(
                    node,
                    "value",
                    format!(
                        "{}: expected {}3 numbers, got \"{value}\"",
                        describe(node),
                        if splat { "1 or " } else { "" }
                    ),
                )),
            };
        }
        let coord = |axis: &str| -> Result<f32, SceneError> {
            match self.attr(node, axis)? {
                Some(v) => self.number(node, axis, &v),
                None => Ok(default),
            }
        };
        Ok(Vec3::new(coord("x")?, coord("y")?, coord("z")?))
    }

    /// A `<transform>`: its children compose left to right, each applied after the previous.
    /// Only affine transforms are accepted (the bottom row of a `<matrix>` must be 0 0 0 1).
    fn transform(&self, node: Node) -> Result<Mat4, SceneError> {
        self.expect_tag(node, &["transform"])?;
        let mut m = Mat4::IDENTITY;
        for child in node.children().filter(Node::is_element) {
            let step = match child.tag_name().name() {
                "matrix" => self.matrix(child)?,
                "translate" => Mat4::from_translation(self.xyz_or_value(child, 0.0, false)?),
                "scale" => Mat4::from_scale(self.xyz_or_value(child, 1.0, true)?),
                "rotate" => self.rotation(child)?,
                "lookat" => {
                    let origin = self.vec3_attr(child, "origin")?;
                    let target = self.vec3_attr(child, "target")?;
                    // Mitsuba picks an up vector itself when none (or zero) is given.
                    let up = match self.attr(child, "up")? {
                        Some(_) => self.vec3_attr(child, "up")?,
                        None => Vec3::ZERO,
                    };
                    let up = if up == Vec3::ZERO {
                        orthogonal_to((target - origin).normalize_or_zero())
                    } else {
                        up
                    };
                    look_at(origin, target, up).ok_or_else(|| {
                        self.error(
                            child,
                            "<lookat>: origin equals target or up is parallel to the view",
                        )
                    })?
                }
                other => {
                    return Err(self.error(child, format!("unknown tag <{other}> in <transform>")));
                }
            };
            m = step * m;
        }
        Ok(m)
    }

    fn matrix(&self, node: Node) -> Result<Mat4, SceneError> {
        let value = self.required_attr(node, "value")?;
        let v = self.numbers(node, "value", &value)?;
        let Ok(rows) = <[f32; 16]>::try_from(v.as_slice()) else {
            return Err(self.attr_error(
                node,
                "value",
                format!("<matrix>: expected 16 numbers (row-major), got {}", v.len()),
            ));
        };
        let m = Mat4::from_cols_array(&rows).transpose();
        if m.row(3) != Vec4::W {
            return Err(self.attr_error(
                node,
                "value",
                "<matrix>: the last row must be 0 0 0 1 (projective transforms are not supported)",
            ));
        }
        Ok(m)
    }

    fn rotation(&self, node: Node) -> Result<Mat4, SceneError> {
        let axis = self.xyz_or_value(node, 0.0, false)?;
        let angle = match self.attr(node, "angle")? {
            Some(a) => self.number(node, "angle", &a)?,
            None => return Err(self.error(node, "<rotate> needs angle=\"degrees\"")),
        };
        let axis = axis
            .try_normalize()
            .ok_or_else(|| self.error(node, "<rotate>: the axis is zero"))?;
        Ok(Mat4::from_axis_angle(axis, angle.to_radians()))
    }

    fn read_integrator(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        if std::mem::replace(&mut self.has_integrator, true) {
            return Err(self.error(node, "a second <integrator>: only one is allowed"));
        }
        self.read_integrator_settings(node)
    }

    /// The integrator's settings. In hppm the render graph chooses the algorithm, so any
    /// integrator is advice: its path depths and `hide_emitters` are taken, the rest of another
    /// integrator's properties belong to its algorithm and are left with one warning. One that
    /// wraps another (`aov`, `moment`) gives the wrapped one's settings.
    fn read_integrator_settings(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let nested = self.single_child(node, "integrator")?;
        let mut props = self.props(node, &["integrator"])?;
        if let Some(n) = props.take("max_depth") {
            self.scene.integrator.max_depth = match self.integer(n)? {
                -1 => None,
                d => Some(self.depth(n, d, "max_depth")?),
            };
        } else if kind == "direct" {
            // Emitters seen directly and lit directly: paths of at most two segments.
            self.scene.integrator.max_depth = Some(2);
        }
        if let Some(n) = props.take("rr_depth") {
            let d = self.integer(n)?;
            self.scene.integrator.rr_depth = Some(self.depth(n, d, "rr_depth")?);
        }
        // Russian roulette that can never start is no roulette.
        if let (Some(max), Some(rr)) = (
            self.scene.integrator.max_depth,
            self.scene.integrator.rr_depth,
        ) && rr >= max
        {
            self.scene.integrator.rr_depth = None;
        }
        if let Some(n) = props.take("hide_emitters") {
            self.scene.integrator.hide_emitters = self.boolean(n)?;
        }
        if kind == "path" {
            return self.finish(props, node);
        }
        self.note_read(&props, node);
        let mut message = format!(
            "integrator \"{kind}\": the render graph chooses the algorithm; rendering with \
             its path depths"
        );
        if kind == "direct" {
            message.push_str(" (direct lighting only: max_depth 2)");
        }
        if !props.entries.is_empty() {
            let rest: Vec<&str> = props.entries.iter().map(|(n, _)| n.as_str()).collect();
            message.push_str(&format!(", without {}", rest.join(", ")));
        }
        self.warn(node, message);
        match nested {
            Some(inner) => self.read_integrator_settings(inner),
            None => Ok(()),
        }
    }

    /// A path depth: at least 1 (-1 for "unbounded" is handled by the caller).
    fn depth(&self, node: Node, depth: i64, name: &str) -> Result<u32, SceneError> {
        u32::try_from(depth)
            .ok()
            .filter(|d| (1..u32::MAX).contains(d))
            .ok_or_else(|| {
                self.attr_error(
                    node,
                    "value",
                    format!("{name} {depth}: expected -1 (unbounded) or at least 1"),
                )
            })
    }

    fn read_sensor(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        if std::mem::replace(&mut self.has_sensor, true) {
            return Err(self.error(node, "a second <sensor>: only one is supported"));
        }
        let kind = self.required_attr(node, "type")?;
        if kind != "perspective" && kind != "thinlens" {
            return Err(self.attr_error(
                node,
                "type",
                format!(
                    "sensor type \"{kind}\" is not supported (only \"perspective\" and \
                     \"thinlens\")"
                ),
            ));
        }
        // The film first: the fov conversion needs its aspect ratio.
        let sampler = self.single_child(node, "sampler")?;
        let film = self.single_child(node, "film")?;
        // A failed sampler or film is reported and the sensor read on, so that its other
        // problems are listed too.
        if let Some(s) = sampler {
            let read = self.read_sampler(s);
            self.keep(read);
        }
        if let Some(f) = film {
            let read = self.read_film(f);
            self.keep(read);
        }
        let mut props = self.props(node, &["sampler", "film"])?;
        let view = self.view_angle(&mut props, node)?;
        // Checked as Mitsuba checks them, not applied: camera rays are not cut at the clip
        // planes (only what lies within near_clip of the camera or beyond far_clip would show
        // the difference), and nothing moves while the shutter is open.
        let near = props.take("near_clip");
        let far = props.take("far_clip");
        let near_clip = near.map(|n| self.float(n)).transpose()?.unwrap_or(0.01);
        let far_clip = far.map(|n| self.float(n)).transpose()?.unwrap_or(1e4);
        if let Some(n) = near
            && (near_clip <= 0.0 || near_clip.is_nan())
        {
            return Err(self.attr_error(
                n,
                "value",
                format!("near_clip {near_clip}: expected more than 0 (Mitsuba refuses it too)"),
            ));
        }
        if let Some(n) = far.or(near)
            && (near_clip >= far_clip || far_clip.is_nan())
        {
            return Err(self.attr_error(
                n,
                "value",
                format!(
                    "near_clip {near_clip} is not below far_clip {far_clip} (Mitsuba refuses it \
                     too)"
                ),
            ));
        }
        let focus = props.take("focus_distance");
        let focus_distance = focus.map(|n| self.float(n)).transpose()?;
        self.ignore(&mut props, &["shutter_open", "shutter_close"], |r, n| {
            r.float(n).map(drop)
        })?;
        if kind == "thinlens" {
            // Mitsuba focuses on the far clip plane unless told.
            let focus_distance = focus_distance.unwrap_or(far_clip);
            self.scene.camera.lens = self.read_lens(node, &mut props, focus, focus_distance)?;
        } else {
            // A pinhole renders everything in focus, so the focal distance changes nothing.
            for name in ["principal_point_offset_x", "principal_point_offset_y"] {
                if let Some(n) = props.take(name)
                    && self.float(n)? != 0.0
                {
                    return Err(self.attr_error(
                        n,
                        "value",
                        format!("{name}: an off-centre principal point is not supported"),
                    ));
                }
            }
        }
        if let Some(n) = props.take("srf") {
            self.warn(
                n,
                "sensor srf: a spectral response applies to spectral rendering only; hppm \
                 renders RGB, as Mitsuba's RGB variants do, without it",
            );
        }
        if let Some(n) = props.take("to_world") {
            self.read_camera_transform(n)?;
        }
        self.finish(props, node)?;
        // The fov is the whole film's, whatever window of it a crop renders.
        let camera = &self.scene.camera;
        let (film_w, film_h) = camera.crop.map_or((camera.width, camera.height), |c| {
            (c.film_width, c.film_height)
        });
        let aspect = film_w as f64 / film_h as f64;
        self.scene.camera.fov_x_deg =
            self.horizontal_fov(view.axis_node, view.fov, &view.axis, aspect)?;
        Ok(())
    }

    /// A camera's or projector's view angle as given: `fov` along `fov_axis` (x by default),
    /// or a 35 mm `focal_length` (50 mm by default) as a diagonal fov; both together are
    /// refused, as Mitsuba refuses them.
    fn view_angle(
        &self,
        props: &mut Props<'a, 'input>,
        node: Node<'a, 'input>,
    ) -> Result<ViewAngle<'a, 'input>, SceneError> {
        let fov = props
            .take("fov")
            .map(|n| self.float(n).map(|v| (n, v)))
            .transpose()?;
        let fov_axis = props
            .take("fov_axis")
            .map(|n| self.string(n).map(|v| (n, v)))
            .transpose()?;
        match (fov, props.take("focal_length")) {
            (Some((n, _)), Some(_)) => Err(self.error(
                n,
                "give either fov or focal_length, not both (Mitsuba refuses both too)",
            )),
            (Some((n, fov)), None) => {
                let (axis_node, axis) = match fov_axis {
                    Some((axis_node, axis)) => (axis_node, axis.to_ascii_lowercase()),
                    None => (n, "x".to_string()),
                };
                Ok(ViewAngle {
                    fov: fov as f64,
                    axis_node,
                    axis,
                })
            }
            (None, focal) => Ok(ViewAngle {
                fov: match focal {
                    Some(n) => self.focal_length_fov(n)?,
                    None => focal_length_to_fov(50.0),
                },
                axis_node: node,
                axis: "diagonal".to_string(),
            }),
        }
    }

    /// A `thinlens` sensor's lens: `aperture_radius` (which Mitsuba requires) and the focus
    /// distance. A zero aperture is a pinhole (Mitsuba warns and uses a radius of 1e-7).
    fn read_lens(
        &self,
        sensor: Node,
        props: &mut Props<'a, 'input>,
        focus: Option<Node>,
        focus_distance: f32,
    ) -> Result<Option<Lens>, SceneError> {
        let Some(n) = props.take("aperture_radius") else {
            return Err(self.error(
                sensor,
                "a thinlens sensor needs aperture_radius (Mitsuba has no default for it)",
            ));
        };
        let aperture_radius = self.float(n)?;
        if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
            return Err(self.attr_error(
                n,
                "value",
                format!("aperture_radius {aperture_radius}: expected 0 or more scene units"),
            ));
        }
        // Without one the default (far_clip) is already checked to lie beyond near_clip > 0.
        if let Some(f) = focus
            && !(focus_distance > 0.0 && focus_distance.is_finite())
        {
            return Err(self.attr_error(
                f,
                "value",
                format!(
                    "focus_distance {focus_distance}: expected a positive distance along the view"
                ),
            ));
        }
        if aperture_radius == 0.0 {
            self.warn(
                n,
                "aperture_radius 0: rendered as a pinhole (Mitsuba warns and uses 1e-7)",
            );
            return Ok(None);
        }
        Ok(Some(Lens {
            aperture_radius,
            focus_distance,
        }))
    }

    /// `focal_length` ("50mm", or a bare number of millimetres) as the diagonal field of view
    /// of a 36 x 24 mm frame.
    fn focal_length_fov(&self, node: Node) -> Result<f64, SceneError> {
        let text = self.string(node)?;
        let millimetres = text.trim().strip_suffix("mm").unwrap_or(text.trim());
        match millimetres.trim().parse::<f64>() {
            Ok(f) if f > 0.0 => Ok(focal_length_to_fov(f)),
            _ => Err(self.attr_error(
                node,
                "value",
                format!("focal_length \"{text}\": expected millimetres, such as 50mm"),
            )),
        }
    }

    /// The child of `node` with tag `tag`, if any; two are an error.
    fn single_child(
        &self,
        node: Node<'a, 'input>,
        tag: &str,
    ) -> Result<Option<Node<'a, 'input>>, SceneError> {
        let mut found = node.children().filter(|c| c.has_tag_name(tag));
        let first = found.next();
        if let Some(second) = found.next() {
            return Err(self.error(
                second,
                format!("a second <{tag}> in {}", describe_object(node)),
            ));
        }
        Ok(first)
    }

    fn read_camera_transform(&mut self, node: Node) -> Result<(), SceneError> {
        let m = self.transform(node)?;
        // The camera is stored as origin/target/up, which cannot express a mirror image.
        if Mat3::from_mat4(m).determinant() < 0.0 {
            return Err(self.error(
                node,
                "a mirroring sensor to_world (negative determinant) is not supported",
            ));
        }
        let camera = &mut self.scene.camera;
        camera.origin = m.transform_point3(Vec3::ZERO);
        camera.target = m.transform_point3(Vec3::Z);
        camera.up = m.transform_vector3(Vec3::Y);
        // Far from the origin a unit step rounds away in f32 and the view direction vanishes.
        let view = camera.target - camera.origin;
        if !(view.is_finite() && view.cross(camera.up).length_squared() > 0.0) {
            return Err(self.error(
                node,
                "the sensor's to_world gives no view direction in f32 (an origin too far from 0, \
                 or a zero scale)",
            ));
        }
        let reach = camera.origin.abs().max_element() as f64;
        if let Some(message) = super::beyond_extent("the camera", reach) {
            return Err(self.error(node, message));
        }
        Ok(())
    }

    /// The horizontal fov for a `fov` given along `axis` (x, y, diagonal, smaller or larger)
    /// of a film of `aspect` (width / height), as Mitsuba's projective cameras convert it.
    fn horizontal_fov(
        &self,
        node: Node,
        fov: f64,
        axis: &str,
        aspect: f64,
    ) -> Result<f32, SceneError> {
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.attr_error(
                node,
                "value",
                format!("fov {fov}: expected degrees between 0 and 180"),
            ));
        }
        let half_tan = (fov.to_radians() * 0.5).tan();
        let axis = match axis {
            "smaller" if aspect > 1.0 => "y",
            "smaller" => "x",
            "larger" if aspect > 1.0 => "x",
            "larger" => "y",
            other => other,
        };
        let x_half_tan = match axis {
            "x" => half_tan,
            "y" => half_tan * aspect,
            "diagonal" => half_tan / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
            other => {
                return Err(self.attr_error(
                    node,
                    "value",
                    format!("fov_axis \"{other}\": expected x, y, diagonal, smaller or larger"),
                ));
            }
        };
        Ok((2.0 * x_half_tan.atan()).to_degrees() as f32)
    }

    /// Any sampler gives the sample count; hppm draws independent random numbers, so another
    /// sampler's pattern (stratified, low-discrepancy) is left with a warning.
    fn read_sampler(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        if let Some(n) = props.take("sample_count") {
            let spp = self.integer(n)?;
            let spp = u32::try_from(spp).ok().filter(|&s| s >= 1).ok_or_else(|| {
                self.attr_error(
                    n,
                    "value",
                    format!("sample_count {spp}: expected at least 1"),
                )
            })?;
            self.scene.spp_hint = Some(spp);
        }
        self.ignore(&mut props, &["seed"], |r, n| r.integer(n).map(drop))?;
        if kind == "independent" {
            return self.finish(props, node);
        }
        self.note_read(&props, node);
        self.warn(
            node,
            format!(
                "sampler \"{kind}\": hppm draws independent samples; its sample_count is taken, \
                 its pattern is not"
            ),
        );
        Ok(())
    }

    fn read_film(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "hdrfilm" {
            return Err(self.attr_error(
                node,
                "type",
                format!("film type \"{kind}\" is not supported (only \"hdrfilm\")"),
            ));
        }
        if let Some(filter) = self.single_child(node, "rfilter")? {
            match self.read_rfilter(filter) {
                Ok(filter) => self.scene.camera.filter = filter,
                // Reported, and the film read on for its other problems.
                Err(e) => self.report(e),
            }
        }
        let mut props = self.props(node, &["rfilter"])?;
        if let Some(n) = props.take("width") {
            self.scene.camera.width = self.film_side(n, "width")?;
        }
        if let Some(n) = props.take("height") {
            self.scene.camera.height = self.film_side(n, "height")?;
        }
        self.ignore(
            &mut props,
            &["pixel_format", "component_format", "file_format"],
            |r, n| r.string(n).map(drop),
        )?;
        if let Some(n) = props.take("compensate") {
            self.boolean(n)?;
            self.warn(
                n,
                "hdrfilm compensate: Mitsuba 3 removed error-compensated accumulation and \
                 ignores it; so does hppm",
            );
        }
        if let Some(n) = props.take("sample_border") {
            self.scene.camera.sample_border = self.boolean(n)?;
        }
        let (x, width) = self.crop_window(
            self.scene.camera.width,
            ("crop_offset_x", props.take("crop_offset_x")),
            ("crop_width", props.take("crop_width")),
        )?;
        let (y, height) = self.crop_window(
            self.scene.camera.height,
            ("crop_offset_y", props.take("crop_offset_y")),
            ("crop_height", props.take("crop_height")),
        )?;
        let camera = &mut self.scene.camera;
        if (x, y, width, height) != (0, 0, camera.width, camera.height) {
            camera.crop = Some(Crop {
                film_width: camera.width,
                film_height: camera.height,
                x,
                y,
            });
            camera.width = width;
            camera.height = height;
        }
        self.finish(props, node)
    }

    /// One axis of hdrfilm's crop window, (offset, size) on a film `film` pixels long: Mitsuba's
    /// defaults (offset 0, the whole film) and its rule that the window lies inside the film.
    fn crop_window(
        &self,
        film: u32,
        (offset_name, offset): (&str, Option<Node>),
        (size_name, size): (&str, Option<Node>),
    ) -> Result<(u32, u32), SceneError> {
        let read = |name: &str, node: Node, least: i64| -> Result<u32, SceneError> {
            let v = self.integer(node)?;
            if v < least || v > film as i64 {
                return Err(self.attr_error(
                    node,
                    "value",
                    format!("{name} {v}: expected {least} to {film} (the film's side)"),
                ));
            }
            Ok(v as u32)
        };
        let at = offset
            .map(|n| read(offset_name, n, 0))
            .transpose()?
            .unwrap_or(0);
        // Mitsuba's default size is the whole film even beside an offset (the window then runs
        // off the film, which it refuses).
        let length = size
            .map(|n| read(size_name, n, 1))
            .transpose()?
            .unwrap_or(film);
        // Past the film only with an offset given: blame the size if given, else the offset.
        if let Some(blame) = size.or(offset)
            && at as u64 + length as u64 > film as u64
        {
            return Err(self.attr_error(
                blame,
                "value",
                format!(
                    "crop window: {offset_name} {at} + {size_name} {length} runs past the \
                     film's {film} pixels (Mitsuba refuses it too)"
                ),
            ));
        }
        Ok((at, length))
    }

    fn film_side(&self, node: Node, name: &str) -> Result<u32, SceneError> {
        let v = self.integer(node)?;
        if !(1..=super::MAX_FILM_SIDE as i64).contains(&v) {
            return Err(self.attr_error(
                node,
                "value",
                format!(
                    "film {name} {v}: expected 1 to {} pixels",
                    super::MAX_FILM_SIDE
                ),
            ));
        }
        Ok(v as u32)
    }

    /// `box`, `tent` (`radius`), `gaussian` (`stddev`), `lanczos` (`lobes`), `mitchell` (`B`,
    /// `C`) or `catmullrom`, with Mitsuba 3's defaults.
    fn read_rfilter(&self, node: Node<'a, 'input>) -> Result<PixelFilter, SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        let filter = match kind.as_str() {
            "box" => PixelFilter::Box,
            "tent" => PixelFilter::Tent {
                radius: self.filter_width(&mut props, "radius", DEFAULT_TENT_RADIUS)?,
            },
            "gaussian" => PixelFilter::Gaussian {
                stddev: self.filter_width(&mut props, "stddev", DEFAULT_GAUSSIAN_STDDEV)?,
            },
            "lanczos" => PixelFilter::Lanczos {
                lobes: self.lanczos_lobes(&mut props)?,
            },
            "mitchell" => {
                let mut coefficient = |name: &str| match props.take(name) {
                    Some(n) => self.float(n),
                    None => Ok(DEFAULT_MITCHELL_B_C),
                };
                PixelFilter::Mitchell {
                    b: coefficient("B")?,
                    c: coefficient("C")?,
                }
            }
            "catmullrom" => PixelFilter::CATMULL_ROM,
            other => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "rfilter \"{other}\" is not supported ({})",
                        plugins::kinds_of("rfilter")
                    ),
                ));
            }
        };
        self.finish(props, node)?;
        Ok(filter)
    }

    /// Lanczos's lobes (its radius in pixels): Mitsuba's default 3, at most 16 as for the other
    /// filters' widths.
    fn lanczos_lobes(&self, props: &mut Props) -> Result<u32, SceneError> {
        let Some(n) = props.take("lobes") else {
            return Ok(DEFAULT_LANCZOS_LOBES);
        };
        let v = self.integer(n)?;
        if !(1..=MAX_FILTER_WIDTH as i64).contains(&v) {
            return Err(self.attr_error(
                n,
                "value",
                format!("rfilter lobes {v}: expected 1 to {MAX_FILTER_WIDTH} lobes"),
            ));
        }
        Ok(v as u32)
    }

    /// A filter's radius or standard deviation: positive, and at most 16 pixels (a sanity
    /// bound: wider filters blur the image away and only typos ask for them).
    fn filter_width(&self, props: &mut Props, name: &str, default: f32) -> Result<f32, SceneError> {
        let Some(n) = props.take(name) else {
            return Ok(default);
        };
        let v = self.float(n)?;
        if !(v > 0.0 && v <= MAX_FILTER_WIDTH) {
            return Err(self.attr_error(
                n,
                "value",
                format!(
                    "rfilter {name} {v}: expected more than 0 and at most {MAX_FILTER_WIDTH} pixels"
                ),
            ));
        }
        Ok(v)
    }

    fn read_named_bsdf(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        // Mitsuba allows a top-level BSDF without an id; nothing can use it, but it is checked.
        let Some(id) = self.attr(node, "id")? else {
            return self.read_bsdf(node).map(drop);
        };
        if self.named_bsdfs.contains_key(&id) {
            return Err(self.attr_error(
                node,
                "id",
                format!("a second <bsdf id=\"{id}\">: ids must be unique"),
            ));
        }
        let bsdf = self.read_bsdf(node).inspect_err(|_| {
            self.failed_ids.insert(id.clone(), self.location(node).line);
        })?;
        self.named_bsdfs.insert(id, bsdf);
        Ok(())
    }

    /// A `<bsdf>`: one BSDF, or a `twosided` pair.
    fn read_bsdf(&self, node: Node<'a, 'input>) -> Result<Sides, SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind == "twosided" {
            return self.read_twosided(node);
        }
        if kind == "normalmap" || kind == "bumpmap" {
            return self.read_perturbed(node, &kind);
        }
        if kind == "blendbsdf" || kind == "mask" {
            return self.read_blend(node, &kind);
        }
        if kind == "null" {
            let props = self.props(node, &[])?;
            self.finish(props, node)?;
            return Ok(Sides {
                front: Bsdf::Null,
                back: None,
                textures: MaterialTextures::default(),
            });
        }
        let (front, textures) = self.read_one_sided(node, &kind)?;
        Ok(Sides {
            front,
            back: None,
            textures: MaterialTextures {
                front: textures,
                back: SideTextures::default(),
            },
        })
    }

    /// Mitsuba's `twosided`: one nested BSDF seen from both sides, or two (front, back); they
    /// must not transmit.
    fn read_twosided(&self, node: Node<'a, 'input>) -> Result<Sides, SceneError> {
        let mut props = self.props(node, &["bsdf", "ref"])?;
        if let Some(n) = props.take("allow_transmission")
            && self.boolean(n)?
        {
            return Err(self.attr_error(
                n,
                "value",
                "twosided allow_transmission: a transmitting BSDF mirrored onto both sides is \
                 not supported",
            ));
        }
        self.finish(props, node)?;
        let mut nested = Vec::new();
        for child in node.children().filter(Node::is_element) {
            let sides = match child.tag_name().name() {
                "bsdf" => self.read_bsdf(child)?,
                _ => self.bsdf_ref(child)?,
            };
            if sides.back.is_some() {
                return Err(self.error(child, "twosided: a nested BSDF is already twosided"));
            }
            if self.transmits(&sides.front) {
                return Err(self.error(
                    child,
                    "twosided: only BSDFs without transmission can be nested (as in Mitsuba; \
                     a mask's pass-through counts); a dielectric is two-sided already",
                ));
            }
            if nested.len() == 2 {
                return Err(self.error(child, "twosided: at most two nested BSDFs"));
            }
            nested.push((sides.front, sides.textures.front));
        }
        match nested.as_slice() {
            [(one, textures)] => Ok(Sides {
                front: *one,
                back: Some(*one),
                textures: MaterialTextures {
                    front: *textures,
                    back: *textures,
                },
            }),
            [(front, front_textures), (back, back_textures)] => Ok(Sides {
                front: *front,
                back: Some(*back),
                textures: MaterialTextures {
                    front: *front_textures,
                    back: *back_textures,
                },
            }),
            _ => Err(self.error(node, "twosided: a nested <bsdf> is required")),
        }
    }

    /// Adds a material the scene's shapes or blends refer to; its index.
    fn add_material(&self, material: Material) -> u32 {
        let mut materials = self.materials.borrow_mut();
        materials.push(material);
        materials.len() as u32 - 1
    }

    /// Whether `bsdf`, or any BSDF a blend or mask of it may choose, transmits.
    fn transmits(&self, bsdf: &Bsdf) -> bool {
        match *bsdf {
            Bsdf::Blend { first, second, .. } => {
                let children: Vec<Material> = {
                    let materials = self.materials.borrow();
                    [first, second]
                        .iter()
                        .filter_map(|&i| materials.get(i as usize).copied())
                        .collect()
                };
                children
                    .iter()
                    .any(|m| m.bsdfs().any(|b| self.transmits(b)))
            }
            _ => bsdf.transmits(),
        }
    }

    /// Mitsuba's `blendbsdf` (two nested BSDFs; `weight`, the second's share, is required)
    /// and `mask` (one nested BSDF; `opacity`, its share, defaults to 0.5, and the rest passes
    /// through as `null`). Each nested BSDF becomes a material of its own, which the blend's
    /// choice at each interaction points at.
    fn read_blend(&self, node: Node<'a, 'input>, kind: &str) -> Result<Sides, SceneError> {
        let mask = kind == "mask";
        let name = if mask { "opacity" } else { "weight" };
        let mut props = self.props(node, &["bsdf", "ref"])?;
        let mut weight_node = props.take(name);
        let mut nested: Vec<Sides> = Vec::new();
        let wanted = if mask { 1 } else { 2 };
        for child in node.children().filter(Node::is_element) {
            let sides = match child.tag_name().name() {
                "bsdf" => self.read_bsdf(child)?,
                "ref" if self.attr(child, "name")?.as_deref() == Some(name) => {
                    if weight_node.replace(child).is_some() {
                        return Err(self.error(child, format!("{kind}: {name} given twice")));
                    }
                    continue;
                }
                "ref" => self.bsdf_ref(child)?,
                _ => continue,
            };
            if nested.len() == wanted {
                return Err(self.error(
                    child,
                    format!("{kind}: at most {wanted} nested BSDF(s), as in Mitsuba"),
                ));
            }
            nested.push(sides);
        }
        let takes = plugins::properties_of("bsdf", kind);
        self.finish_with(props, node, Some(&takes))?;
        if nested.len() < wanted {
            let needed = if mask {
                "one nested <bsdf>"
            } else {
                "two nested <bsdf>s"
            };
            return Err(self.error(node, format!("{kind} needs {needed} (as in Mitsuba)")));
        }
        let (weight, texture) = match weight_node {
            Some(n) => self.float_or_texture(n, name)?,
            None if mask => (0.5, None),
            None => {
                return Err(self.error(
                    node,
                    "blendbsdf needs a weight (a <float name=\"weight\"> or a texture), as in \
                     Mitsuba",
                ));
            }
        };
        if mask {
            nested.insert(
                0,
                Sides {
                    front: Bsdf::Null,
                    back: None,
                    textures: MaterialTextures::default(),
                },
            );
        }
        let first = self.add_material(nested[0].material(Vec3::ZERO));
        let second = self.add_material(nested[1].material(Vec3::ZERO));
        Ok(Sides {
            front: Bsdf::Blend {
                weight,
                first,
                second,
            },
            back: None,
            textures: MaterialTextures {
                front: SideTextures {
                    blend_weight: texture,
                    ..SideTextures::default()
                },
                back: SideTextures::default(),
            },
        })
    }

    /// Mitsuba's `normalmap` and `bumpmap`: one nested BSDF (inline or `<ref>`, possibly a
    /// `twosided`) whose shading frame a bitmap perturbs (src/scene/normal_map.rs). The
    /// normal map is the property `normalmap`; the bump map's height is any texture child, as
    /// Mitsuba takes the one texture object it finds.
    fn read_perturbed(&self, node: Node<'a, 'input>, kind: &str) -> Result<Sides, SceneError> {
        let bump = kind == "bumpmap";
        let objects: &[&str] = if bump {
            &["bsdf", "ref", "texture"]
        } else {
            &["bsdf", "ref"]
        };
        let mut props = self.props(node, objects)?;
        let mut nested: Option<Sides> = None;
        let mut texture: Option<u32> = None;
        let mut add_texture = |child: Node<'a, 'input>, name: &str| {
            let Some((_, index)) = self.texture_node(child, name)? else {
                return Err(self.error(child, format!("{kind}: expected a <texture>")));
            };
            if texture.replace(index).is_some() {
                return Err(self.error(
                    child,
                    format!("{kind}: only one texture can be given (as in Mitsuba)"),
                ));
            }
            Ok(())
        };
        if !bump && let Some(n) = props.take("normalmap") {
            add_texture(n, "normalmap")?;
        }
        for child in node.children().filter(Node::is_element) {
            let sides = match child.tag_name().name() {
                "bsdf" => self.read_bsdf(child)?,
                "texture" if bump => {
                    add_texture(child, "texture")?;
                    continue;
                }
                "ref" if !bump && self.attr(child, "name")?.as_deref() == Some("normalmap") => {
                    add_texture(child, "normalmap")?;
                    continue;
                }
                "ref" => {
                    let id = self.required_attr(child, "id")?;
                    match self.named_bsdfs.get(&id) {
                        Some(sides) => *sides,
                        None if bump && self.named_textures.contains_key(&id) => {
                            add_texture(child, "texture")?;
                            continue;
                        }
                        None => {
                            let what = format!("<ref id=\"{id}\">");
                            return Err(self.missing_ref(child, &id, "bsdf", &what));
                        }
                    }
                }
                _ => continue,
            };
            if nested.is_some() {
                return Err(self.error(
                    child,
                    format!("{kind}: only one nested BSDF can be given (as in Mitsuba)"),
                ));
            }
            if sides.textures.front.frame.is_some() || sides.textures.back.frame.is_some() {
                return Err(self.error(
                    child,
                    format!("{kind}: a nested normalmap or bumpmap is not supported"),
                ));
            }
            nested = Some(sides);
        }
        let scale = match bump.then(|| props.take("scale")).flatten() {
            Some(n) => self.float(n)?,
            None => 1.0,
        };
        let mut flag = |name: &str| match props.take(name) {
            Some(n) => self.boolean(n),
            None => Ok(true),
        };
        let flip_invalid_normals = flag("flip_invalid_normals")?;
        let shadowing = flag("use_shadowing_function")?;
        let takes = plugins::properties_of("bsdf", kind);
        self.finish_with(props, node, Some(&takes))?;
        let Some(texture) = texture else {
            let needed = if bump {
                "a <texture type=\"bitmap\"> (the height map)"
            } else {
                "<texture name=\"normalmap\" type=\"bitmap\">"
            };
            return Err(self.error(node, format!("{kind} needs {needed}")));
        };
        if !matches!(
            self.textures.borrow().get(texture as usize),
            Some(Texture::Bitmap(_))
        ) {
            return Err(self.error(
                node,
                format!(
                    "{kind}: the texture must be a bitmap (Mitsuba's other textures have no \
                     {})",
                    if bump { "gradient" } else { "RGB lookup" }
                ),
            ));
        }
        let Some(sides) = nested else {
            return Err(self.error(
                node,
                format!("{kind}: a nested <bsdf> is required (as in Mitsuba)"),
            ));
        };
        let frame = FramePerturbation {
            kind: if bump {
                PerturbationKind::Bump { scale }
            } else {
                PerturbationKind::Normal
            },
            texture,
            flip_invalid_normals,
            shadowing,
            outside_twosided: false,
        };
        self.perturbed(sides, frame, node)
    }

    /// `sides` in the frame `frame` perturbs. A blend's or mask's children each get the frame
    /// instead (the same surface: a blend is linear in its children), as copies, since a
    /// `<ref>`'d child may be used elsewhere without it.
    fn perturbed(
        &self,
        mut sides: Sides,
        frame: FramePerturbation,
        node: Node,
    ) -> Result<Sides, SceneError> {
        let Bsdf::Blend {
            weight,
            first,
            second,
        } = sides.front
        else {
            if sides.textures.front.frame.is_some() || sides.textures.back.frame.is_some() {
                return Err(self.error(
                    node,
                    "a normalmap or bumpmap inside another (here through a blendbsdf or mask) \
                     is not supported",
                ));
            }
            sides.textures.front.frame = Some(frame);
            if sides.back.is_some() {
                sides.textures.back.frame = Some(FramePerturbation {
                    outside_twosided: true,
                    ..frame
                });
            }
            return Ok(sides);
        };
        if sides.back.is_some() {
            return Err(self.error(
                node,
                "a normalmap or bumpmap around a twosided blendbsdf is not supported: put it \
                 around the BSDFs nested in the blend",
            ));
        }
        let mut children = [first, second];
        for child in &mut children {
            let Some(material) = self.materials.borrow().get(*child as usize).copied() else {
                return Err(self.error(node, "internal: a blend's child is missing"));
            };
            let nested = Sides {
                front: material.bsdf,
                back: material.back,
                textures: material.textures,
            };
            let turned = self.perturbed(nested, frame, node)?;
            *child = self.add_material(turned.material(material.emission));
        }
        sides.front = Bsdf::Blend {
            weight,
            first: children[0],
            second: children[1],
        };
        Ok(sides)
    }

    /// One side's BSDF and the textures of its colour parameters.
    fn read_one_sided(
        &self,
        node: Node<'a, 'input>,
        kind: &str,
    ) -> Result<(Bsdf, SideTextures), SceneError> {
        if plugins::find("bsdf", kind).is_none() {
            return Err(self.attr_error(
                node,
                "type",
                format!(
                    "bsdf type \"{kind}\" is not supported ({})",
                    plugins::kinds_of("bsdf")
                ),
            ));
        }
        let mut props = self.props(node, &[])?;
        let props = &mut props;
        let mut textures = SideTextures::default();
        let bsdf = match kind {
            "diffuse" => {
                let (reflectance, texture) = self.color_param(props, "reflectance", 0.5)?;
                textures.diffuse = texture;
                Bsdf::Diffuse { reflectance }
            }
            // Mitsuba's defaults: BK7 glass inside, air outside.
            "dielectric" => Bsdf::Dielectric {
                int_ior: self.ior(props, "int_ior", 1.5046)?,
                ext_ior: self.ior(props, "ext_ior", 1.000277)?,
                tint: self.dielectric_tint(props, &mut textures)?,
            },
            "thindielectric" => Bsdf::ThinDielectric {
                int_ior: self.ior(props, "int_ior", 1.5046)?,
                ext_ior: self.ior(props, "ext_ior", 1.000277)?,
                tint: self.dielectric_tint(props, &mut textures)?,
            },
            "roughdielectric" => {
                let int_ior = self.ior(props, "int_ior", 1.5046)?;
                let ext_ior = self.ior(props, "ext_ior", 1.000277)?;
                self.distinct_iors(node, int_ior, ext_ior)?;
                Bsdf::RoughDielectric {
                    int_ior,
                    ext_ior,
                    microfacet: self.microfacet(props, node, Alphas::Textured, &mut textures)?,
                    tint: self.dielectric_tint(props, &mut textures)?,
                }
            }
            "conductor" | "roughconductor" => {
                let (eta, k) = self.conductor_index(props)?;
                let (specular, texture) = self.color_param(props, "specular_reflectance", 1.0)?;
                textures.specular = texture;
                if kind == "roughconductor" {
                    Bsdf::RoughConductor {
                        eta,
                        k,
                        specular,
                        microfacet: self.microfacet(
                            props,
                            node,
                            Alphas::Textured,
                            &mut textures,
                        )?,
                    }
                } else if eta == Vec3::ZERO
                    && k == Vec3::ONE
                    && specular == Vec3::ONE
                    && texture.is_none()
                {
                    Bsdf::Mirror
                } else {
                    Bsdf::Conductor { eta, k, specular }
                }
            }
            "plastic" | "roughplastic" | "pplastic" => {
                // Mitsuba's defaults: polypropylene inside, air outside.
                let int_ior = self.ior(props, "int_ior", 1.49)?;
                let ext_ior = self.ior(props, "ext_ior", 1.000277)?;
                let (diffuse, diffuse_texture) =
                    self.color_param(props, "diffuse_reflectance", 0.5)?;
                let (specular, specular_texture) =
                    self.color_param(props, "specular_reflectance", 1.0)?;
                (textures.diffuse, textures.specular) = (diffuse_texture, specular_texture);
                // Mitsuba's `nonlinear` (plastic, roughplastic): pplastic has no internal
                // reflections, and leaves the property to be refused as unknown.
                let mut nonlinear = || match props.take("nonlinear") {
                    Some(n) => self.boolean(n),
                    None => Ok(false),
                };
                match kind {
                    "plastic" => Bsdf::Plastic {
                        int_ior,
                        ext_ior,
                        diffuse,
                        specular,
                        nonlinear: nonlinear()?,
                    },
                    "roughplastic" => {
                        self.distinct_iors(node, int_ior, ext_ior)?;
                        Bsdf::RoughPlastic {
                            int_ior,
                            ext_ior,
                            diffuse,
                            specular,
                            nonlinear: nonlinear()?,
                            microfacet: self.microfacet(
                                props,
                                node,
                                Alphas::Isotropic,
                                &mut textures,
                            )?,
                        }
                    }
                    _ => {
                        self.distinct_iors(node, int_ior, ext_ior)?;
                        Bsdf::PolarizedPlastic {
                            int_ior,
                            ext_ior,
                            diffuse,
                            specular,
                            microfacet: self.microfacet(
                                props,
                                node,
                                Alphas::Anisotropic,
                                &mut textures,
                            )?,
                        }
                    }
                }
            }
            "principled" => self.read_principled(props, &mut textures)?,
            "principledthin" => self.read_principled_thin(props, &mut textures)?,
            other => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "bsdf type \"{other}\" is not supported ({})",
                        plugins::kinds_of("bsdf")
                    ),
                ));
            }
        };
        let takes = plugins::properties_of("bsdf", kind);
        self.finish_with(std::mem::take(props), node, Some(&takes))?;
        Ok((bsdf, textures))
    }

    /// Mitsuba's `principled`, every property its plugin reads; each parameter its plugin reads
    /// as a texture may be one.
    fn read_principled(
        &self,
        props: &mut Props<'a, 'input>,
        textures: &mut SideTextures,
    ) -> Result<Bsdf, SceneError> {
        use super::principled::{self as pr, Principled};
        let (base_color, base_texture) = self.color_param(props, "base_color", 0.5)?;
        textures.diffuse = base_texture;
        let mut has = 0;
        // (value, texture), and whether Mitsuba counts it as given (m_has_*: a texture, or a
        // float other than 0).
        let mut scalar =
            |name: &str, default: f32, bit: u32| -> Result<(f32, Option<u32>), SceneError> {
                let Some(n) = props.take(name) else {
                    return Ok((default, None));
                };
                let (value, texture) = self.float_or_texture(n, name)?;
                if texture.is_some() || value != 0.0 {
                    has |= bit;
                }
                Ok((value, texture))
            };
        let (roughness, roughness_texture) = scalar("roughness", 0.5, 0)?;
        let (metallic, metallic_texture) = scalar("metallic", 0.0, pr::HAS_METALLIC)?;
        (textures.alpha_u, textures.alpha_v) = (roughness_texture, metallic_texture);
        // The rest in PRINCIPLED_TEXTURED's order, each a float or a texture.
        let bits = [
            pr::HAS_ANISOTROPIC,
            pr::HAS_SPEC_TRANS,
            pr::HAS_SPEC_TINT,
            pr::HAS_SHEEN,
            pr::HAS_SHEEN_TINT,
            pr::HAS_FLATNESS,
            pr::HAS_CLEARCOAT,
            0,
        ];
        let mut values = [0.0; PRINCIPLED_TEXTURED.len()];
        for (i, (name, bit)) in PRINCIPLED_TEXTURED.iter().zip(bits).enumerate() {
            (values[i], textures.principled[i]) = scalar(name, 0.0, bit)?;
        }
        let [
            anisotropic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
        ] = values;
        let mut rate = |name: &str| match props.take(name) {
            Some(n) => self.float(n),
            None => Ok(1.0),
        };
        let spec_srate = rate("main_specular_sampling_rate")?;
        let clearcoat_srate = rate("clearcoat_sampling_rate")?;
        let diffuse_srate = rate("diffuse_reflectance_sampling_rate")?;
        let transmits = has & pr::HAS_SPEC_TRANS != 0;
        let eta = match (props.take("eta"), props.take("specular")) {
            (Some(_), Some(n)) => {
                return Err(self.error(
                    n,
                    "principled: give eta or specular, not both (as in Mitsuba)",
                ));
            }
            (Some(n), None) => {
                let eta = self.float(n)?;
                if eta.is_nan() || eta <= 0.0 {
                    return Err(self.attr_error(
                        n,
                        "value",
                        format!("eta {eta}: must be positive"),
                    ));
                }
                // Mitsuba's nudge: eta 1 cannot refract.
                if transmits && eta == 1.0 { 1.001 } else { eta }
            }
            (None, n) => {
                let specular = match n {
                    Some(n) => self.float(n)?,
                    None => 0.5,
                };
                let specular = if transmits && specular == 0.0 {
                    1e-3
                } else {
                    specular
                };
                pr::eta_from_specular(specular)
            }
        };
        Ok(Bsdf::Principled(Principled {
            base_color,
            roughness,
            anisotropic,
            metallic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
            eta,
            spec_srate,
            clearcoat_srate,
            diffuse_srate,
            has,
        }))
    }

    /// Mitsuba's `principledthin`, every property its plugin reads; all but the sampling rates
    /// may be textures.
    fn read_principled_thin(
        &self,
        props: &mut Props<'a, 'input>,
        textures: &mut SideTextures,
    ) -> Result<Bsdf, SceneError> {
        use super::principled_thin::PrincipledThin;
        let (base_color, base_texture) = self.color_param(props, "base_color", 0.5)?;
        textures.diffuse = base_texture;
        let mut scalar = |name: &str, default: f32| -> Result<(f32, Option<u32>), SceneError> {
            match props.take(name) {
                Some(n) => self.float_or_texture(n, name),
                None => Ok((default, None)),
            }
        };
        let (roughness, roughness_texture) = scalar("roughness", 0.5)?;
        textures.alpha_u = roughness_texture;
        let mut values = [0.0; PRINCIPLED_THIN_TEXTURED.len()];
        // The last is eta, which is checked apart.
        let [params @ .., eta_slot] = &PRINCIPLED_THIN_TEXTURED;
        for (i, name) in params.iter().enumerate() {
            (values[i], textures.principled[i]) = scalar(name, 0.0)?;
        }
        let [
            anisotropic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            diff_trans,
            _,
        ] = values;
        let eta = match props.take(eta_slot) {
            Some(n) => {
                let (eta, texture) = self.float_or_texture(n, eta_slot)?;
                if texture.is_none() && (eta.is_nan() || eta <= 0.0) {
                    let message = format!("eta {eta}: must be positive");
                    return Err(self.attr_error(n, "value", message));
                }
                textures.principled[params.len()] = texture;
                eta
            }
            None => 1.5,
        };
        let mut rate = |name: &str| match props.take(name) {
            Some(n) => self.float(n),
            None => Ok(1.0),
        };
        Ok(Bsdf::PrincipledThin(PrincipledThin {
            base_color,
            roughness,
            anisotropic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            diff_trans,
            eta,
            spec_reflect_srate: rate("specular_reflectance_sampling_rate")?,
            spec_trans_srate: rate("specular_transmittance_sampling_rate")?,
            diff_reflect_srate: rate("diffuse_reflectance_sampling_rate")?,
            diff_trans_srate: rate("diffuse_transmittance_sampling_rate")?,
        }))
    }

    /// A colour parameter that may be textured: a constant (`default` when absent), or a
    /// `<texture>` (inline, or a `<ref>` to one declared at top level), which is added to the
    /// scene's textures; the constant is then the texture's mean (Mitsuba's `Texture::mean`,
    /// what plastic's sampling weight uses).
    /// A dielectric's `specular_reflectance` and `specular_transmittance` (1 by default),
    /// textures in the specular and diffuse slots.
    fn dielectric_tint(
        &self,
        props: &mut Props,
        textures: &mut SideTextures,
    ) -> Result<Tint, SceneError> {
        let (reflectance, reflectance_texture) =
            self.color_param(props, "specular_reflectance", 1.0)?;
        let (transmittance, transmittance_texture) =
            self.color_param(props, "specular_transmittance", 1.0)?;
        textures.specular = reflectance_texture;
        textures.diffuse = transmittance_texture;
        Ok(Tint {
            reflectance,
            transmittance,
        })
    }

    fn color_param(
        &self,
        props: &mut Props,
        name: &str,
        default: f32,
    ) -> Result<(Vec3, Option<u32>), SceneError> {
        let Some(node) = props.take(name) else {
            return Ok((Vec3::splat(default), None));
        };
        match self.texture_node(node, name)? {
            Some((mean, index)) => Ok((Vec3::splat(mean), Some(index))),
            None => Ok((self.non_negative_color(node)?, None)),
        }
    }

    /// A scalar parameter `name` given as a number, or as a texture (its mean, and its index in
    /// the scene's textures).
    fn float_or_texture(
        &self,
        node: Node<'a, 'input>,
        name: &str,
    ) -> Result<(f32, Option<u32>), SceneError> {
        match self.texture_node(node, name)? {
            Some((mean, index)) => Ok((mean, Some(index))),
            None => Ok((self.float(node)?, None)),
        }
    }

    /// A `<texture>` or `<ref>` given to parameter `name`: its mean and its index in the
    /// scene's textures (added there the first time); `None` for a node of any other tag.
    fn texture_node(
        &self,
        node: Node<'a, 'input>,
        name: &str,
    ) -> Result<Option<(f32, u32)>, SceneError> {
        let add = |texture: Texture| {
            let mut textures = self.textures.borrow_mut();
            textures.push(texture);
            textures.len() as u32 - 1
        };
        match node.tag_name().name() {
            "texture" => {
                let texture = self.read_texture(node)?;
                let mean = texture.mean();
                Ok(Some((mean, add(texture))))
            }
            "ref" => {
                let id = self.required_attr(node, "id")?;
                let Some((texture, index)) = self.named_textures.get(&id) else {
                    let what = format!("<ref name=\"{name}\" id=\"{id}\">");
                    return Err(self.missing_ref(node, &id, "texture", &what));
                };
                let mut index = index.borrow_mut();
                let i = *index.get_or_insert_with(|| add(texture.clone()));
                Ok(Some((texture.mean(), i)))
            }
            _ => Ok(None),
        }
    }

    fn read_named_texture(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let id = self.required_attr(node, "id")?;
        if self.named_textures.contains_key(&id) {
            return Err(self.attr_error(
                node,
                "id",
                format!("a second <texture id=\"{id}\">: ids must be unique"),
            ));
        }
        let texture = self.read_texture(node).inspect_err(|_| {
            self.failed_ids.insert(id.clone(), self.location(node).line);
        })?;
        self.named_textures
            .insert(id, (texture, RefCell::new(None)));
        Ok(())
    }

    /// A `<texture>`: `checkerboard` or `bitmap`, with Mitsuba's defaults.
    fn read_texture(&self, node: Node<'a, 'input>) -> Result<Texture, SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        let to_uv = match props.take("to_uv") {
            Some(n) => UvTransform::from_mat4(self.transform(n)?),
            None => UvTransform::IDENTITY,
        };
        let texture = match kind.as_str() {
            "checkerboard" => {
                let mut color = |name: &str, default: f32| match props.take(name) {
                    Some(n) => self.non_negative_color(n),
                    None => Ok(Vec3::splat(default)),
                };
                Texture::Checkerboard {
                    color0: color("color0", 0.4)?,
                    color1: color("color1", 0.2)?,
                    to_uv,
                }
            }
            "bitmap" => {
                let Some(file_node) = props.take("filename") else {
                    return Err(self.error(
                        node,
                        "<texture type=\"bitmap\"> needs <string name=\"filename\" value=...>",
                    ));
                };
                let filename = self.string(file_node)?;
                let raw = match props.take("raw") {
                    Some(n) => self.boolean(n)?,
                    None => false,
                };
                // Hardware interpolation on CUDA (Mitsuba's `accel`): no effect here.
                if let Some(n) = props.take("accel") {
                    self.boolean(n)?;
                }
                // The precision Mitsuba stores the texels in: hppm keeps the file's (8-bit
                // images as 8 bits, others as f32), at most one 8-bit or f16 step apart.
                if let Some(n) = props.take("format") {
                    let format = self.string(n)?;
                    if !["auto", "variant", "float16", "fp16", "uint8"].contains(&format.as_str()) {
                        return Err(self.attr_error(
                            n,
                            "value",
                            format!(
                                "bitmap format \"{format}\": expected auto, variant, float16 or \
                                 uint8 (as Mitsuba)"
                            ),
                        ));
                    }
                }
                let wrap = match props.take("wrap_mode") {
                    None => WrapMode::Repeat,
                    Some(n) => match self.string(n)?.as_str() {
                        "repeat" => WrapMode::Repeat,
                        "mirror" => WrapMode::Mirror,
                        "clamp" => WrapMode::Clamp,
                        other => {
                            return Err(self.attr_error(
                                n,
                                "value",
                                format!(
                                    "wrap_mode \"{other}\" is not supported (repeat, mirror, clamp)"
                                ),
                            ));
                        }
                    },
                };
                let filter = match props.take("filter_type") {
                    None => Filter::Bilinear,
                    Some(n) => match self.string(n)?.as_str() {
                        "bilinear" => Filter::Bilinear,
                        "nearest" => Filter::Nearest,
                        other => {
                            return Err(self.attr_error(
                                n,
                                "value",
                                format!(
                                    "filter_type \"{other}\" is not supported (bilinear, nearest)"
                                ),
                            ));
                        }
                    },
                };
                let path = self.relative(&filename);
                let bitmap = Bitmap::load(&path, raw, wrap, filter, to_uv)
                    .map_err(|message| self.attr_error(file_node, "value", message))?;
                Texture::Bitmap(bitmap)
            }
            other => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "texture type \"{other}\" is not supported ({})",
                        plugins::kinds_of("texture")
                    ),
                ));
            }
        };
        let takes = plugins::properties_of("texture", &kind);
        self.finish_with(props, node, Some(&takes))?;
        Ok(texture)
    }

    fn distinct_iors(&self, node: Node, int_ior: f32, ext_ior: f32) -> Result<(), SceneError> {
        if int_ior == ext_ior {
            return Err(self.error(
                node,
                format!(
                    "{}: int_ior and ext_ior are both {int_ior}; they must differ",
                    describe_object(node)
                ),
            ));
        }
        Ok(())
    }

    /// `distribution`, `alpha` or `alpha_u` + `alpha_v`, `sample_visible` as Mitsuba's
    /// MicrofacetDistribution reads them (Beckmann, alpha 0.1 by default).
    /// `anisotropic` BSDFs (rough conductors and dielectrics) also take textured roughness,
    /// recorded in `textures`, as Mitsuba's do (its roughplastic's `alpha` is a number).
    fn microfacet(
        &self,
        props: &mut Props<'a, 'input>,
        node: Node,
        alphas: Alphas,
        textures: &mut SideTextures,
    ) -> Result<Microfacet, SceneError> {
        let distribution = match props.take("distribution") {
            None => Distribution::Beckmann,
            Some(n) => match self.string(n)?.to_ascii_lowercase().as_str() {
                "beckmann" => Distribution::Beckmann,
                "ggx" => Distribution::Ggx,
                other => {
                    return Err(self.attr_error(
                        n,
                        "value",
                        format!("distribution \"{other}\": expected \"beckmann\" or \"ggx\""),
                    ));
                }
            },
        };
        let texture = |r: &Self, n: Node<'a, 'input>| -> Result<Option<(f32, u32)>, SceneError> {
            if alphas != Alphas::Textured {
                return Ok(None);
            }
            r.texture_node(n, "alpha")
        };
        let alpha = |r: &Self, n: Node<'a, 'input>| -> Result<f32, SceneError> {
            let v = r.float(n)?;
            if v.is_nan() || v < 0.0 {
                return Err(r.attr_error(
                    n,
                    "value",
                    format!("{}: must not be negative", describe(n)),
                ));
            }
            Ok(v)
        };
        let (a, au, av) = (
            props.take("alpha"),
            props.take("alpha_u"),
            props.take("alpha_v"),
        );
        let textured = |n: Node<'a, 'input>, slot: &mut Option<u32>| match texture(self, n)? {
            Some((mean, index)) => {
                *slot = Some(index);
                Ok(mean)
            }
            None => alpha(self, n),
        };
        let (mut tu, mut tv) = (None, None);
        let (alpha_u, alpha_v) = match (a, au, av) {
            (Some(a), None, None) => {
                let v = textured(a, &mut tu)?;
                tv = tu;
                (v, v)
            }
            (None, None, None) => (0.1, 0.1),
            (None, Some(u), Some(v)) if alphas != Alphas::Isotropic => {
                (textured(u, &mut tu)?, textured(v, &mut tv)?)
            }
            (None, Some(u), Some(v)) => {
                let (x, y) = (alpha(self, u)?, alpha(self, v)?);
                if x != y {
                    return Err(self.error(
                        node,
                        format!(
                            "{}: anisotropic roughness is not supported by Mitsuba's \
                             roughplastic; give one alpha",
                            describe_object(node)
                        ),
                    ));
                }
                (x, y)
            }
            (Some(a), _, _) => {
                return Err(self.error(a, "give either alpha or alpha_u and alpha_v, not both"));
            }
            (None, u, v) => {
                let given = u.or(v).unwrap_or(node);
                return Err(self.error(given, "alpha_u and alpha_v must both be given"));
            }
        };
        if let Some(n) = props.take("sample_visible")
            && !self.boolean(n)?
        {
            return Err(self.attr_error(
                n,
                "value",
                "sample_visible false is not supported (visible normals are always sampled)",
            ));
        }
        (textures.alpha_u, textures.alpha_v) = (tu, tv);
        Ok(Microfacet {
            distribution,
            alpha_u,
            alpha_v,
        })
    }

    /// A conductor's complex index: `material` (Mitsuba's measured tables at RGB, default
    /// "none", a perfect mirror: eta 0, k 1) or explicit `eta` and `k`.
    fn conductor_index(&self, props: &mut Props) -> Result<(Vec3, Vec3), SceneError> {
        let material = props.take("material");
        let (eta, k) = (props.take("eta"), props.take("k"));
        if let Some(m) = material {
            let name = self.string(m)?;
            if name != "none" {
                if let Some(given) = eta.or(k) {
                    return Err(self.error(
                        given,
                        "give either a conductor material or eta and k, not both",
                    ));
                }
                return bsdf::named_conductor(&name).ok_or_else(|| {
                    let names: Vec<&str> =
                        bsdf::NAMED_CONDUCTORS.iter().map(|(n, _, _)| *n).collect();
                    self.attr_error(
                        m,
                        "value",
                        format!(
                            "conductor material \"{name}\" is not one of Mitsuba's: none, {}",
                            names.join(", ")
                        ),
                    )
                });
            }
        }
        let eta = eta
            .map(|n| self.color(n))
            .transpose()?
            .unwrap_or(Vec3::ZERO);
        let k = k.map(|n| self.color(n)).transpose()?.unwrap_or(Vec3::ONE);
        Ok((eta, k))
    }

    /// An index of refraction: a positive number or one of Mitsuba's named media.
    fn ior(&self, props: &mut Props, name: &str, default: f32) -> Result<f32, SceneError> {
        let Some(n) = props.take(name) else {
            return Ok(default);
        };
        if n.has_tag_name("string") {
            let medium = self.string(n)?;
            return NAMED_IORS
                .iter()
                .find(|(m, _)| *m == medium.to_ascii_lowercase())
                .map(|(_, v)| *v)
                .ok_or_else(|| {
                    let names: Vec<&str> = NAMED_IORS.iter().map(|(m, _)| *m).collect();
                    self.attr_error(
                        n,
                        "value",
                        format!("{name} \"{medium}\" is not one of {}", names.join(", ")),
                    )
                });
        }
        let v = self.float(n)?;
        if v <= 0.0 {
            return Err(self.attr_error(n, "value", format!("{name} {v}: must be positive")));
        }
        Ok(v)
    }

    /// The shape's BSDF (inline or `<ref>`) and area emission, at most one of each.
    fn read_shape_material(&self, node: Node<'a, 'input>) -> Result<Material, SceneError> {
        let mut bsdf = None;
        let mut emission = None;
        for child in node.children().filter(Node::is_element) {
            let tag = child.tag_name().name();
            let is_bsdf = matches!(tag, "bsdf" | "ref");
            if (is_bsdf && bsdf.is_some()) || (tag == "emitter" && emission.is_some()) {
                return Err(self.error(
                    child,
                    format!("{}: a shape has at most one {tag}", describe_object(child)),
                ));
            }
            let medium = matches!(
                self.attr(child, "name")?.as_deref(),
                Some("interior" | "exterior")
            ) || tag == "medium";
            if medium {
                return Err(self.error(
                    child,
                    "a shape's interior or exterior medium: participating media are not supported",
                ));
            }
            match tag {
                "bsdf" => bsdf = Some(self.read_bsdf(child)?),
                "ref" => bsdf = Some(self.bsdf_ref(child)?),
                "emitter" => emission = Some(self.read_area_emitter(child)?),
                _ => {}
            }
        }
        let sides = bsdf.unwrap_or(Sides {
            front: DEFAULT_BSDF,
            back: None,
            textures: MaterialTextures::default(),
        });
        Ok(sides.material(emission.unwrap_or(Vec3::ZERO)))
    }

    fn bsdf_ref(&self, node: Node) -> Result<Sides, SceneError> {
        let id = self.required_attr(node, "id")?;
        self.named_bsdfs
            .get(&id)
            .copied()
            .ok_or_else(|| self.missing_ref(node, &id, "bsdf", &format!("<ref id=\"{id}\">")))
    }

    /// A `<ref>` to an id no `<tag id=...>` before it declares, or to one that failed.
    fn missing_ref(&self, node: Node, id: &str, tag: &str, what: &str) -> SceneError {
        let why = match self.failed_ids.get(id) {
            Some(line) => format!("the <{tag} id=\"{id}\"> at line {line} could not be read"),
            None => format!("no <{tag} id=\"{id}\"> is declared before this"),
        };
        self.attr_error(node, "id", format!("{what}: {why}"))
    }

    fn read_shape(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        match node.attribute("type") {
            Some("shapegroup") => self.read_shapegroup(node),
            Some("instance") => self.read_instance(node),
            _ => self.read_placed_shape(node, Mat4::IDENTITY),
        }
    }

    /// `<shape type="shapegroup" id=...>`: shapes to be placed by instances. It draws nothing
    /// itself; its shapes are checked here, once.
    fn read_shapegroup(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let id = self.required_attr(node, "id")?;
        if self.shape_groups.contains_key(&id) {
            return Err(self.attr_error(
                node,
                "id",
                format!("a second <shape id=\"{id}\">: ids must be unique"),
            ));
        }
        let shapes = self.group_shapes(node).inspect_err(|_| {
            self.failed_ids.insert(id.clone(), self.location(node).line);
        })?;
        self.shape_groups.insert(id, shapes);
        Ok(())
    }

    /// A shapegroup's shapes, each checked by reading it once (its geometry then dropped).
    fn group_shapes(
        &mut self,
        node: Node<'a, 'input>,
    ) -> Result<Vec<Node<'a, 'input>>, SceneError> {
        let props = self.props(node, &["shape"])?;
        self.finish(props, node)?;
        let shapes: Vec<Node<'a, 'input>> = node
            .children()
            .filter(|c| c.has_tag_name("shape"))
            .collect();
        for shape in &shapes {
            if matches!(shape.attribute("type"), Some("shapegroup" | "instance")) {
                return Err(self.error(*shape, "a shapegroup holds plain shapes only"));
            }
            if shape.children().any(|c| c.has_tag_name("emitter")) {
                return Err(
                    self.error(*shape, "shapes in a shapegroup cannot emit (as in Mitsuba)")
                );
            }
        }
        let (triangles, spheres, materials) = (
            self.scene.triangles.len(),
            self.scene.spheres.len(),
            self.materials.borrow().len(),
        );
        self.in_group = true;
        let checked = shapes
            .iter()
            .try_for_each(|shape| self.read_placed_shape(*shape, Mat4::IDENTITY));
        self.in_group = false;
        self.scene.triangles.truncate(triangles);
        self.scene.spheres.truncate(spheres);
        self.materials.borrow_mut().truncate(materials);
        checked.map(|()| shapes)
    }

    /// `<shape type="instance">`: a shapegroup's shapes placed by the instance's `to_world`
    /// after their own. Each instance adds its own copy of the triangles (the BVH has no
    /// instancing), which costs memory as the copies add up.
    fn read_instance(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let reference = self.single_child(node, "ref")?;
        let mut props = self.props(node, &["ref"])?;
        let to_world = match props.take("to_world") {
            Some(n) => self.transform(n)?,
            None => Mat4::IDENTITY,
        };
        self.finish(props, node)?;
        let Some(reference) = reference else {
            return Err(self.error(node, "an instance needs a <ref id=...> to a shapegroup"));
        };
        let id = self.required_attr(reference, "id")?;
        let Some(shapes) = self.shape_groups.get(&id).cloned() else {
            return Err(self.missing_ref(
                reference,
                &id,
                "shape type=\"shapegroup\"",
                &format!("<ref id=\"{id}\">"),
            ));
        };
        self.in_group = true;
        let placed = shapes
            .into_iter()
            .try_for_each(|shape| self.read_placed_shape(shape, to_world));
        self.in_group = false;
        placed
    }

    /// A shape, placed by `outer` after its own `to_world`.
    fn read_placed_shape(&mut self, node: Node<'a, 'input>, outer: Mat4) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if plugins::find("shape", &kind).is_none() {
            return Err(self.attr_error(
                node,
                "type",
                format!(
                    "shape type \"{kind}\" is not supported ({})",
                    plugins::kinds_of("shape")
                ),
            ));
        }
        let material = self.read_shape_material(node)?;
        let mut props = self.props(node, &["bsdf", "ref", "emitter"])?;
        let to_world = props.take("to_world");
        let common = ShapeCommon {
            to_world: outer
                * to_world
                    .map(|n| self.transform(n))
                    .transpose()?
                    .unwrap_or(Mat4::IDENTITY),
            material: self.materials.borrow().len() as u32,
            flip_normals: props
                .take("flip_normals")
                .map(|n| self.boolean(n))
                .transpose()?
                .unwrap_or(false),
        };
        // Weights for Mitsuba's differentiable silhouette sampling: no effect on the image.
        self.ignore(&mut props, &["silhouette_sampling_weight"], |r, n| {
            r.float(n).map(drop)
        })?;
        if kind == "cube" {
            // Its faces are flat either way.
            self.ignore(&mut props, &["face_normals"], |r, n| r.boolean(n).map(drop))?;
        }
        self.materials.borrow_mut().push(material);
        let (triangles, spheres) = (self.scene.triangles.len(), self.scene.spheres.len());
        match kind.as_str() {
            "rectangle" => self.push_mesh_data(mesh::rectangle_mesh(), &common),
            "cube" => self.push_mesh_data(mesh::cube_mesh(), &common),
            "disk" => self.push_mesh_data(mesh::disk_mesh(), &common),
            "cylinder" => self.read_cylinder(&mut props, &common, node)?,
            "sphere" => self.read_sphere(&mut props, &common, to_world, node)?,
            "ply" => self.read_mesh_file(&mut props, &common, node, MeshFormat::Ply)?,
            "serialized" => {
                self.read_mesh_file(&mut props, &common, node, MeshFormat::Serialized)?
            }
            _ => self.read_mesh_file(&mut props, &common, node, MeshFormat::Obj)?,
        }
        let reach = self.scene.reach_since(triangles, spheres);
        if let Some(message) = super::beyond_extent("this shape", reach) {
            return Err(self.error(node, message));
        }
        self.finish(props, node)
    }

    /// Mitsuba's `cylinder`: the unit tube placed between `p0` and `p1` with `radius`, its
    /// axis turned into place by the frame Mitsuba builds around it (which fixes where its
    /// texture's u starts), then by `to_world`.
    fn read_cylinder(
        &mut self,
        props: &mut Props,
        common: &ShapeCommon,
        node: Node,
    ) -> Result<(), SceneError> {
        let point = |props: &mut Props, name: &str, default: Vec3| match props.take(name) {
            Some(n) => self.point(n),
            None => Ok(default),
        };
        let p0 = point(props, "p0", Vec3::ZERO)?;
        let p1 = point(props, "p1", Vec3::Z)?;
        let radius = match props.take("radius") {
            Some(n) => self.float(n)?,
            None => 1.0,
        };
        let axis = p1 - p0;
        let length = axis.length();
        if !(radius > 0.0 && length > 0.0) {
            return Err(self.error(
                node,
                format!("cylinder: radius {radius} and length {length} must be positive"),
            ));
        }
        let n = axis / length;
        let s = orthogonal_to(n);
        let frame = Mat4::from_cols(
            s.extend(0.0),
            n.cross(s).extend(0.0),
            n.extend(0.0),
            Vec4::W,
        );
        let placed = ShapeCommon {
            to_world: common.to_world
                * Mat4::from_translation(p0)
                * frame
                * Mat4::from_scale(Vec3::new(radius, radius, length)),
            ..*common
        };
        self.push_mesh_data(mesh::cylinder_mesh(), &placed);
        Ok(())
    }

    fn read_sphere(
        &mut self,
        props: &mut Props,
        common: &ShapeCommon,
        to_world: Option<Node>,
        shape: Node,
    ) -> Result<(), SceneError> {
        let center = props
            .take("center")
            .map(|n| self.point(n))
            .transpose()?
            .unwrap_or(Vec3::ZERO);
        let radius = match props.take("radius") {
            Some(n) => {
                let r = self.float(n)?;
                if r <= 0.0 {
                    return Err(self.attr_error(
                        n,
                        "value",
                        format!("sphere radius {r}: must be positive"),
                    ));
                }
                r
            }
            None => 1.0,
        };
        let m = common.to_world;
        let Some(scale) = super::similarity_scale(m) else {
            return Err(self.error(
                to_world.unwrap_or(shape),
                "a sphere's to_world may only scale uniformly, rotate and translate",
            ));
        };
        self.scene.spheres.push(Sphere {
            center: m.transform_point3(center),
            radius: radius * scale,
            material: common.material,
            flip_normals: common.flip_normals,
        });
        Ok(())
    }

    /// An `obj` or `ply` shape: its file, relative to the scene's folder.
    fn read_mesh_file(
        &mut self,
        props: &mut Props,
        common: &ShapeCommon,
        node: Node,
        format: MeshFormat,
    ) -> Result<(), SceneError> {
        let name = format.name();
        let Some(file_node) = props.take("filename") else {
            return Err(self.error(
                node,
                format!(
                    "<shape type=\"{}\"> needs <string name=\"filename\" value=\"...\"/>",
                    node.attribute("type").unwrap_or_default()
                ),
            ));
        };
        let file = self.string(file_node)?;
        // As in Mitsuba, vertex normals (the file's, or computed when it has none) shade the
        // mesh smoothly unless face_normals is true.
        let face_normals = props
            .take("face_normals")
            .map(|n| self.boolean(n))
            .transpose()?
            .unwrap_or(false);
        // Mitsuba flips v (v -> 1 - v) by default for OBJ files, not for PLY; its serialized
        // shape keeps the stored uvs and has no such property.
        let flip_tex_coords = match format {
            MeshFormat::Serialized => false,
            _ => props
                .take("flip_tex_coords")
                .map(|n| self.boolean(n))
                .transpose()?
                .unwrap_or(format == MeshFormat::Obj),
        };
        let mesh_path = self.relative(&file);
        let index = match format {
            MeshFormat::Serialized => self.shape_index(props)?,
            _ => 0,
        };
        let key = (mesh_path.clone(), index);
        let cached = self.meshes.borrow().get(&key).cloned();
        let mut mesh = match cached {
            Some(mesh) => mesh,
            None => {
                let loaded = match format {
                    MeshFormat::Obj => super::obj::load_mesh_data(&mesh_path),
                    MeshFormat::Ply => super::ply::load(&mesh_path),
                    // The file's own face-normals flag is not read: Mitsuba 3 shades a
                    // serialized mesh flat only when the face_normals property says so.
                    MeshFormat::Serialized => {
                        super::serialized::load(&mesh_path, index).map(|s| s.mesh)
                    }
                };
                let mesh = loaded.map_err(|e| e.referenced_from(name, &self.location(node)))?;
                if self.in_group {
                    self.meshes.borrow_mut().insert(key, mesh.clone());
                }
                mesh
            }
        };
        if face_normals {
            mesh.normals = None;
        }
        if flip_tex_coords && let Some(uvs) = mesh.uvs.as_mut() {
            for corner in uvs.iter_mut().flatten() {
                corner.y = 1.0 - corner.y;
            }
        }
        self.scene
            .push_mesh_data(mesh, common.to_world, common.material, common.flip_normals);
        Ok(())
    }

    /// A serialized file's `shape_index`: which of its shapes (default the first).
    fn shape_index(&self, props: &mut Props) -> Result<u32, SceneError> {
        let Some(n) = props.take("shape_index") else {
            return Ok(0);
        };
        let index = self.integer(n)?;
        u32::try_from(index).map_err(|_| {
            self.attr_error(
                n,
                "value",
                format!("shape_index {index}: expected 0 or more"),
            )
        })
    }

    fn push_mesh_data(&mut self, mesh: mesh::MeshData, common: &ShapeCommon) {
        self.scene
            .push_mesh_data(mesh, common.to_world, common.material, common.flip_normals);
    }

    /// A file named in the scene: beside the scene's file, else in a `<path>` folder, else
    /// beside an included file (the first that exists; the scene's folder when none does).
    fn relative(&self, file: &str) -> PathBuf {
        let beside_scene = relative_to(self.path, file);
        let candidates = self
            .search_dirs
            .iter()
            .map(|dir| dir.join(file))
            .chain(self.files[1..].iter().map(|f| relative_to(&f.path, file)));
        std::iter::once(beside_scene.clone())
            .chain(candidates)
            .find(|p| p.exists())
            .unwrap_or(beside_scene)
    }

    fn read_area_emitter(&self, node: Node<'a, 'input>) -> Result<Vec3, SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "area" {
            return Err(self.attr_error(
                node,
                "type",
                format!("emitter type \"{kind}\" inside a shape: only \"area\" is supported"),
            ));
        }
        let mut props = self.props(node, &[])?;
        self.ignore_sampling_weight(&mut props)?;
        // Mitsuba's default radiance is 1.
        let radiance = match props.take("radiance") {
            Some(n) => self.non_negative_color(n)?,
            None => Vec3::ONE,
        };
        self.finish(props, node)?;
        Ok(radiance)
    }

    /// Mitsuba's `sampling_weight` of an emitter: how often its light sampling picks it, which
    /// changes only its noise. hppm picks lights by power; the value is checked and dropped.
    fn ignore_sampling_weight(&self, props: &mut Props) -> Result<(), SceneError> {
        if let Some(n) = props.take("sampling_weight") {
            let v = self.float(n)?;
            if !(v >= 0.0 && v.is_finite()) {
                return Err(self.attr_error(
                    n,
                    "value",
                    format!("sampling_weight {v}: expected a number of 0 or more"),
                ));
            }
        }
        Ok(())
    }

    /// A scene-level emitter: `point`, `spot`, `directional`, `constant` or `envmap`.
    fn read_emitter(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        self.ignore_sampling_weight(&mut props)?;
        match kind.as_str() {
            "point" => self.read_point_light(&mut props, node)?,
            "spot" => self.read_spot_light(&mut props, node)?,
            "projector" => self.read_projector(&mut props, node)?,
            "directional" => self.read_directional_light(&mut props, node)?,
            "constant" | "envmap" => {
                if self.scene.emitters.environment.is_some() {
                    return Err(self.error(
                        node,
                        "a second environment emitter (constant or envmap): Mitsuba allows one \
                         per scene",
                    ));
                }
                let environment = if kind == "constant" {
                    // A constant light looks the same turned any way.
                    if let Some(n) = props.take("to_world") {
                        self.transform(n)?;
                    }
                    Environment::Constant {
                        radiance: self.color_or(&mut props, "radiance", Vec3::ONE)?,
                    }
                } else {
                    Environment::Map(self.read_envmap(&mut props, node)?)
                };
                self.scene.emitters.environment = Some(environment);
            }
            "area" => {
                return Err(self.attr_error(
                    node,
                    "type",
                    "an \"area\" emitter goes inside the <shape> that emits",
                ));
            }
            _ => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "emitter type \"{kind}\" is not supported ({}; area inside a shape)",
                        plugins::kinds_of("emitter").replace("area, ", "")
                    ),
                ));
            }
        }
        self.finish(props, node)
    }

    /// A non-negative colour property, or `default` when it is absent.
    fn color_or(&self, props: &mut Props, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        props
            .take(name)
            .map(|n| self.non_negative_color(n))
            .transpose()
            .map(|c| c.unwrap_or(default))
    }

    /// A float property in degrees, or `default`, as radians within [0, 180].
    fn angle_or(&self, props: &mut Props, name: &str, default: f32) -> Result<f32, SceneError> {
        let Some(n) = props.take(name) else {
            return Ok(default.to_radians());
        };
        let degrees = self.float(n)?;
        if !(0.0..=180.0).contains(&degrees) {
            return Err(self.attr_error(
                n,
                "value",
                format!("{}: an angle from 0 to 180 degrees", describe(n)),
            ));
        }
        Ok(degrees.to_radians())
    }

    fn check_light_reach(&self, node: Node, what: &str, position: Vec3) -> Result<(), SceneError> {
        let reach = position.abs().max_element() as f64;
        match super::beyond_extent(what, reach) {
            Some(message) => Err(self.error(node, message)),
            None => Ok(()),
        }
    }

    fn read_point_light(&mut self, props: &mut Props, node: Node) -> Result<(), SceneError> {
        let mut position = props
            .take("position")
            .map(|n| self.point(n))
            .transpose()?
            .unwrap_or(Vec3::ZERO);
        if let Some(n) = props.take("to_world") {
            position = self.transform(n)?.transform_point3(position);
        }
        let intensity = self.color_or(props, "intensity", Vec3::ONE)?;
        self.check_light_reach(node, "this point light", position)?;
        self.scene.point_lights.push(PointLight {
            position,
            intensity,
        });
        Ok(())
    }

    /// A light's texture parameter `name`: a `<texture>` or `<ref>` to one (added to the
    /// scene's textures), as Mitsuba's spot requires ("must be spatially varying"); `None`
    /// when absent.
    fn light_texture(
        &self,
        props: &mut Props<'a, 'input>,
        name: &str,
        what: &str,
    ) -> Result<Option<u32>, SceneError> {
        let Some(n) = props.take(name) else {
            return Ok(None);
        };
        match self.texture_node(n, name)? {
            Some((_, index)) => Ok(Some(index)),
            None => Err(self.error(
                n,
                format!(
                    "{}: {what}'s {name} must be a <texture> (bitmap or checkerboard) or a                      <ref> to one; Mitsuba refuses a constant here",
                    describe(n)
                ),
            )),
        }
    }

    /// Mitsuba's `spot`: it shines along `to_world`'s +z from its translation; a `texture`
    /// is laid across its local x and y.
    fn read_spot_light(
        &mut self,
        props: &mut Props<'a, 'input>,
        node: Node,
    ) -> Result<(), SceneError> {
        let texture = self.light_texture(props, "texture", "a spot light")?;
        let to_world = match props.take("to_world") {
            Some(n) => {
                let m = self.transform(n)?;
                if !is_similarity(Mat3::from_mat4(m)) {
                    return Err(self.error(
                        n,
                        "a spot light's to_world must be a rotation, uniform scale and \
                         translation (its cone would not be round)",
                    ));
                }
                m
            }
            None => Mat4::IDENTITY,
        };
        let intensity = self.color_or(props, "intensity", Vec3::ONE)?;
        let cutoff = self.angle_or(props, "cutoff_angle", 20.0)?;
        let beam_width = self.angle_or(props, "beam_width", cutoff.to_degrees() * 0.75)?;
        if beam_width > cutoff {
            return Err(self.error(
                node,
                "beam_width is larger than cutoff_angle (Mitsuba requires beam_width <= \
                 cutoff_angle)",
            ));
        }
        let position = to_world.transform_point3(Vec3::ZERO);
        let axis = to_world.transform_vector3(Vec3::Z).normalize_or_zero();
        let frame = [Vec3::X, Vec3::Y].map(|v| to_world.transform_vector3(v).normalize_or_zero());
        self.check_light_reach(node, "this spot light", position)?;
        self.scene.emitters.spots.push(SpotLight {
            position,
            axis,
            intensity,
            cutoff,
            beam_width,
            frame,
            texture,
        });
        Ok(())
    }

    /// Mitsuba's `projector`: a pinhole at `to_world`'s translation facing its +z, projecting
    /// `irradiance` (a colour or a texture) times `scale` through the frustum of the
    /// perspective camera with the same `fov` / `fov_axis` / `focal_length` and an image of
    /// the texture's resolution.
    fn read_projector(
        &mut self,
        props: &mut Props<'a, 'input>,
        node: Node<'a, 'input>,
    ) -> Result<(), SceneError> {
        let scale = match props.take("scale") {
            Some(n) => {
                let v = self.float(n)?;
                if v < 0.0 {
                    return Err(self.attr_error(n, "value", "scale must not be negative"));
                }
                v
            }
            None => 1.0,
        };
        let (irradiance, texture) = match props.take("irradiance") {
            None => (Vec3::ONE, None),
            Some(n) => match self.texture_node(n, "irradiance")? {
                Some((_, index)) => (Vec3::ONE, Some(index)),
                None => (self.non_negative_color(n)?, None),
            },
        };
        // Mitsuba's `Texture::resolution`: a bitmap's, (1, 1) for anything else.
        let aspect = match texture.and_then(|t| self.textures.borrow().get(t as usize).cloned()) {
            Some(Texture::Bitmap(b)) => b.width as f64 / b.height as f64,
            _ => 1.0,
        };
        let to_world = match props.take("to_world") {
            Some(n) => {
                let m = self.transform(n)?;
                let linear = Mat3::from_mat4(m);
                // Mitsuba's projector takes the local point's z and the transformed +z (not
                // normalised) as they come, and its photons' directions unnormalised: only a
                // unit scale makes the two agree.
                let unit = is_similarity(linear) && (linear.x_axis.length() - 1.0).abs() < 1e-3;
                if !unit {
                    return Err(self.error(
                        n,
                        "a projector's to_world must be a rotation and translation (Mitsuba's \
                         scaled projector disagrees with itself)",
                    ));
                }
                m
            }
            None => Mat4::IDENTITY,
        };
        let view = self.view_angle(props, node)?;
        let fov_x = self.horizontal_fov(view.axis_node, view.fov, &view.axis, aspect)?;
        let tan_half_fov = (fov_x.to_radians() * 0.5).tan();
        if !(tan_half_fov > 0.0 && tan_half_fov.is_finite()) {
            return Err(self.error(node, "the projector's field of view is empty or too wide"));
        }
        let position = to_world.transform_point3(Vec3::ZERO);
        let frame =
            [Vec3::X, Vec3::Y, Vec3::Z].map(|v| to_world.transform_vector3(v).normalize_or_zero());
        self.check_light_reach(node, "this projector", position)?;
        self.scene.emitters.projectors.push(Projector {
            position,
            frame,
            irradiance: irradiance * scale,
            texture,
            tan_half_fov,
            aspect: aspect as f32,
        });
        Ok(())
    }

    /// Mitsuba's `directional`: `direction` (or `to_world`'s +z) is where its light travels.
    fn read_directional_light(&mut self, props: &mut Props, node: Node) -> Result<(), SceneError> {
        let direction = match (props.take("direction"), props.take("to_world")) {
            (Some(_), Some(n)) => {
                return Err(self.error(
                    n,
                    "give a directional light `direction` or `to_world`, not both",
                ));
            }
            (Some(n), None) => (self.point(n)?, n),
            (None, Some(n)) => (self.transform(n)?.transform_vector3(Vec3::Z), n),
            (None, None) => (Vec3::Z, node),
        };
        let Some(unit) = direction.0.try_normalize() else {
            return Err(self.error(direction.1, "the light's direction is zero"));
        };
        let irradiance = self.color_or(props, "irradiance", Vec3::ONE)?;
        self.scene.emitters.directionals.push(DirectionalLight {
            direction: unit,
            irradiance,
        });
        Ok(())
    }

    /// Mitsuba's `envmap`: a lat-long image (EXR, or Radiance HDR), times `scale`, turned by
    /// `to_world` (a rotation).
    fn read_envmap(&self, props: &mut Props, node: Node) -> Result<EnvMap, SceneError> {
        let Some(file_node) = props.take("filename") else {
            return Err(self.error(
                node,
                "<emitter type=\"envmap\"> needs <string name=\"filename\" value=\"...\"/>",
            ));
        };
        let file = self.relative(&self.string(file_node)?);
        let scale = match props.take("scale") {
            Some(n) => {
                let v = self.float(n)?;
                if !(v >= 0.0 && v.is_finite()) {
                    return Err(self.attr_error(n, "value", "scale must be a non-negative number"));
                }
                v
            }
            None => 1.0,
        };
        let to_world = match props.take("to_world") {
            Some(n) => {
                let m = Mat3::from_mat4(self.transform(n)?);
                if !is_similarity(m) || (m.determinant() - 1.0).abs() > 1e-3 {
                    return Err(self.error(n, "an envmap's to_world must be a rotation"));
                }
                m
            }
            None => Mat3::IDENTITY,
        };
        for name in ["mis_compensation", "filter_type"] {
            if let Some(n) = props.take(name) {
                let ok = match name {
                    "filter_type" => self.string(n)? == "bilinear",
                    _ => !self.boolean(n)?,
                };
                if !ok {
                    return Err(
                        self.error(n, format!("{} is not supported for envmap", describe(n)))
                    );
                }
            }
        }
        let (width, height, texels) =
            texture::read_image(&file, false).map_err(|e| self.error(file_node, e))?;
        if height < 2 {
            return Err(self.error(
                file_node,
                format!(
                    "{}: an environment map needs at least 2 rows",
                    file.display()
                ),
            ));
        }
        Ok(EnvMap {
            width,
            height,
            texels: texels.into_iter().map(|t| t * scale).collect(),
            to_world,
            source: file,
        })
    }
}

/// Whether `m` is a rotation (or reflection) times a uniform scale: its columns orthogonal
/// and of one length.
/// The diagonal field of view, in degrees, of a lens of `millimetres` focal length on a 36 x 24
/// mm frame (Mitsuba's rule for `focal_length`).
fn focal_length_to_fov(millimetres: f64) -> f64 {
    2.0 * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * millimetres))
        .atan()
        .to_degrees()
}

/// A unit vector orthogonal to the unit vector `n`: the first of the frame Mitsuba's
/// `coordinate_system` builds (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT
/// 2017), so that a `<lookat>` without `up` turns the camera as Mitsuba does.
fn orthogonal_to(n: Vec3) -> Vec3 {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x)
}

fn is_similarity(m: Mat3) -> bool {
    let g = m.transpose() * m;
    let s = g.x_axis.x;
    let tol = 1e-4 * s;
    s > 0.0
        && (g.y_axis.y - s).abs() <= tol
        && (g.z_axis.z - s).abs() <= tol
        && g.x_axis.y.abs() <= tol
        && g.x_axis.z.abs() <= tol
        && g.y_axis.z.abs() <= tol
}

/// The mesh files a shape may name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MeshFormat {
    Obj,
    Ply,
    Serialized,
}

impl MeshFormat {
    fn name(self) -> &'static str {
        match self {
            MeshFormat::Obj => "OBJ",
            MeshFormat::Ply => "PLY",
            MeshFormat::Serialized => "serialized mesh",
        }
    }
}

/// `<tag name="...">`, or `<tag>` for an element without a name.
fn describe(node: Node) -> String {
    match node.attribute("name") {
        Some(name) => format!("<{} name=\"{name}\">", node.tag_name().name()),
        None => format!("<{}>", node.tag_name().name()),
    }
}

/// `<tag type="...">`, or `<tag>` for an element without a type.
fn describe_object(node: Node) -> String {
    match node.attribute("type") {
        Some(kind) => format!("<{} type=\"{kind}\">", node.tag_name().name()),
        None => format!("<{}>", node.tag_name().name()),
    }
}

/// Mitsuba's `lookat`: camera space looks down +z with +y up, mapped to world space.
fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - origin).try_normalize()?;
    let left = up.cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    Some(Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}
