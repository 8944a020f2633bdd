//! Mitsuba 3 XML scenes, read as Mitsuba 3 reads them. The plugins and properties read are
//! listed in `plugins.rs` (the table of docs/scenes.md, `hppm plugins`); the readers are split
//! by plugin family as Mitsuba's sources are (sensors, bsdfs, textures, shapes, emitters).
//! `<default>` and `$name`, `<include>`, `<path>`, `<alias>`, `<ref>` and top-level
//! declarations with an `id` work as in Mitsuba, and a file older than version 2.0 has its
//! property names upgraded as Mitsuba 3 upgrades them.
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

use crate::bsdfs::BsdfRegistry;
use crate::error::{Location, edit_distance};
use crate::loaders::{Report, plugins, spectrum};
use crate::scene::emitter::{DirectionalLight, EnvMap, Environment, Projector, SpotLight};
use crate::scene::filter::{
    DEFAULT_GAUSSIAN_STDDEV, DEFAULT_LANCZOS_LOBES, DEFAULT_MITCHELL_B_C, DEFAULT_TENT_RADIUS,
    PixelFilter,
};
use crate::scene::sunsky::{self, SunSkyMap};
use crate::scene::texture::{self, Bitmap, Filter, Texture, UvTransform, WrapMode};
use crate::scene::{
    Camera, Crop, Integrator, Lens, Material, PointLight, Scene, SceneError, Sphere, mesh,
};
use legacy::LEGACY_PROPERTIES;

pub use legacy::{RULES as LEGACY_RULES, RuleSet};

mod bsdfs;
mod emitters;
mod ids;
mod legacy;
mod media;
mod sensors;
mod shapes;
mod textures;

/// Mitsuba's default BSDF for a shape that names none: diffuse, reflectance 0.5, or 0 for an
/// area light (src/render/shape.cpp); in a 0.6 file a medium boundary's is null instead
/// (0.6's src/librender/shape.cpp).
fn default_bsdf(emits: bool, medium_boundary_06: bool) -> crate::bsdfs::Sides {
    let bsdf = if emits {
        crate::bsdfs::diffuse::Diffuse::bsdf(Vec3::ZERO)
    } else if medium_boundary_06 {
        crate::bsdfs::null::Null::bsdf()
    } else {
        crate::bsdfs::diffuse::Diffuse::bsdf(Vec3::splat(0.5))
    };
    crate::bsdfs::Sides::one(bsdf, Default::default())
}

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
    check_file_with(path, defines, BsdfRegistry::builtin_ref())
}

/// [`check_with`] reading BSDFs with the units of `bsdfs`.
pub fn check_file_with(path: &Path, defines: &[(String, String)], bsdfs: &BsdfRegistry) -> Report {
    match crate::loaders::read_text(path) {
        Ok(text) => check_text_with(path, &text, defines, bsdfs),
        Err(e) => Report::failed(e),
    }
}

/// [`check_with`] on `text` (`path` names it in messages and anchors relative paths).
pub fn check_text(path: &Path, text: &str, defines: &[(String, String)]) -> Report {
    check_text_with(path, text, defines, BsdfRegistry::builtin_ref())
}

/// [`check_text`] reading BSDFs with the units of `bsdfs` (a program's own among them).
pub fn check_text_with(
    path: &Path,
    text: &str,
    defines: &[(String, String)],
    bsdfs: &BsdfRegistry,
) -> Report {
    let texts = with_includes(path, text, defines);
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
            version: None,
        })
        .collect();
    let doc = &docs[0].1;
    let mut reader = Reader {
        path,
        bsdfs,
        files,
        search_dirs: Vec::new(),
        defaults: defines.iter().cloned().collect(),
        defined: defines.iter().map(|(k, _)| k.clone()).collect(),
        used: RefCell::new(HashSet::new()),
        declared: Vec::new(),
        named_bsdfs: ids::Ids::new(),
        failed_ids: RefCell::new(HashMap::new()),
        shape_groups: HashMap::new(),
        meshes: RefCell::new(HashMap::new()),
        in_group: false,
        named_textures: ids::Ids::new(),
        texture_indices: RefCell::new(HashMap::new()),
        named_media: ids::Ids::new(),
        media: RefCell::new(Vec::new()),
        textures: RefCell::new(Vec::new()),
        materials: RefCell::new(Vec::new()),
        scene: empty_scene(path),
        has_integrator: false,
        has_sensor: false,
        errors: RefCell::new(Vec::new()),
        warnings: RefCell::new(Vec::new()),
        upgrades: RefCell::new(Vec::new()),
        properties_read: RefCell::new(BTreeMap::new()),
    };
    reader.check_attributes();
    reader.check_unique_ids();
    let read = reader.read_scene(doc.root_element());
    reader.keep(read);
    let unused = reader.check_defines_used(defines);
    reader.keep(unused);
    reader.scene.textures = reader.textures.take();
    reader.scene.materials = reader.materials.take();
    reader.scene.media.list = reader.media.take();
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
    let mut upgrades = reader.upgrades.take();
    upgrades.sort_by_key(by_place);
    let rule_sets = reader.rule_sets();
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
        rule_sets,
        upgrades,
        properties_read: reader.properties_read.take(),
    }
}

/// Deepest nesting of `<include>`s followed (Mitsuba's limit is similar); deeper ones, and
/// cycles, are reported where they are included.
const MAX_INCLUDE_DEPTH: usize = 16;

/// The scene's text and every file it `<include>`s, directly or not, that can be read, each once.
/// An include that cannot be read is left out here and reported where the scene includes it.
/// An include's file name may use `$name`s: they are the `-D` parameters and the `<default>`s
/// of the files read so far (as the reader will have them where the include stands).
fn with_includes(path: &Path, text: &str, defines: &[(String, String)]) -> Vec<(PathBuf, String)> {
    let mut files = vec![(path.to_path_buf(), text.to_string())];
    let mut values: HashMap<String, String> = HashMap::new();
    let mut next = 0;
    while next < files.len() && files.len() <= MAX_INCLUDE_DEPTH * 4 {
        let found: Vec<PathBuf> = match Document::parse(&files[next].1) {
            Ok(doc) => {
                for n in doc.descendants().filter(|n| n.has_tag_name("default")) {
                    if let (Some(k), Some(v)) = (n.attribute("name"), n.attribute("value")) {
                        values.entry(k.to_string()).or_insert_with(|| v.to_string());
                    }
                }
                values.extend(defines.iter().cloned());
                doc.descendants()
                    .filter(|n| n.has_tag_name("include"))
                    .filter_map(|n| n.attribute("filename"))
                    .map(|f| {
                        // A name without a value is reported where the reader meets it.
                        let name = substitute(f, |k| values.get(k).map(String::as_str))
                            .unwrap_or_else(|_| f.to_string());
                        relative_to(&files[next].0, &name)
                    })
                    .collect()
            }
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

/// `raw` with each `$name` replaced by `value(name)`; the first name it has no value for is
/// the error.
fn substitute<'v>(
    raw: &str,
    mut value: impl FnMut(&str) -> Option<&'v str>,
) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = raw;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let tail = &rest[i + 1..];
        let end = tail
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(tail.len());
        let key = &tail[..end];
        out.push_str(value(key).ok_or_else(|| key.to_string())?);
        rest = &tail[end..];
    }
    out.push_str(rest);
    Ok(out)
}

/// `file` as named in `from`: relative to `from`'s folder unless absolute.
fn relative_to(from: &Path, file: &str) -> PathBuf {
    from.parent().unwrap_or(Path::new(".")).join(file)
}

/// What a scene is before its elements are read: Mitsuba's defaults where it has them.
fn empty_scene(path: &Path) -> Scene {
    Scene {
        media: Default::default(),
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
    /// The file declares a Mitsuba version before 2.0: it is read with 0.6's rules where 0.6
    /// and Mitsuba 3 differ (legacy.rs), its property names upgraded as Mitsuba 3 upgrades them.
    before_v2: bool,
    /// Its `<scene version=...>`, if it gives one.
    version: Option<String>,
}

struct Reader<'a, 'input> {
    path: &'a Path,
    /// The BSDF units `<bsdf>` types are read by.
    bsdfs: &'a BsdfRegistry,
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
    /// BSDFs, textures and media declared with an `id`, at top level or nested.
    named_bsdfs: ids::Ids<crate::bsdfs::Sides>,
    named_textures: ids::Ids<Texture>,
    /// A named texture's index in `textures` once a `<ref>` has used it.
    texture_indices: RefCell<HashMap<String, u32>>,
    /// Media by id: their index in `media`.
    named_media: ids::Ids<u32>,
    /// The scene's media, in the order read (top level and nested).
    media: RefCell<Vec<crate::scene::medium::Medium>>,
    /// The textures the scene's materials use, in the order first used.
    textures: RefCell<Vec<Texture>>,
    /// The scene's materials: each shape's, and the ones blends and masks choose among
    /// (pushed while their BSDF is read, so before the blend that uses them).
    materials: RefCell<Vec<Material>>,
    /// The ids of objects that could not be read (BSDFs, textures, media, shapegroups; top
    /// level or nested), and their lines: a reference to one is reported as such, not as an
    /// undeclared id.
    failed_ids: RefCell<HashMap<String, usize>>,
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
    /// What reading a 0.5/0.6 file changed (see [`Report::upgrades`]).
    upgrades: RefCell<Vec<SceneError>>,
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
        // An <animation>'s keyframes are refused with it, not attribute by attribute.
        let keyframe = |n: &Node| {
            n.parent_element()
                .is_some_and(|p| p.has_tag_name("animation"))
        };
        for node in all.filter(|n| n.is_element() && !keyframe(n)) {
            let tag = self.tag_of(node);
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
        let mut used = Vec::new();
        let out = substitute(raw, |key| {
            let value = self.defaults.get(key)?;
            used.push(key.to_string());
            Some(value.as_str())
        })
        .map_err(|key| {
            self.attr_error(
                node,
                name,
                format!(
                    "{}: {name}=\"{raw}\" uses ${key}, but there is no <default name=\"{key}\">",
                    describe(node)
                ),
            )
        })?;
        self.used.borrow_mut().extend(used);
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
        if self.named_bsdfs.contains(&alias) || self.named_textures.contains(&alias) {
            return Err(self.attr_error(
                node,
                "as",
                format!("<alias>: the id \"{alias}\" is taken already"),
            ));
        }
        let at = self.location(node);
        if let Some(bsdf) = self.named_bsdfs.get(&id) {
            self.named_bsdfs.insert(alias, bsdf, at);
        } else if let Some(texture) = self.named_textures.get(&id) {
            self.named_textures.insert(alias, texture, at);
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
                "medium" => self.read_named_medium(child),
                "phase" | "volume" => Err(self.error(
                    child,
                    format!(
                        "<{}> at top level: give it inside the <medium> that uses it",
                        child.tag_name().name()
                    ),
                )),
                tag if PROPERTY_TAGS.contains(&tag) && self.legacy(child) => {
                    self.warn(
                        child,
                        format!(
                            "{}: a property of the scene itself, which reads none; ignored, as \
                             Mitsuba 0.6 ignored an unqueried property (this file's version is \
                             below 2.0)",
                            describe(child)
                        ),
                    );
                    Ok(())
                }
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
        self.files[index].version = Some(version);
        Ok(())
    }

    /// The property children of `node`, by name; children whose tag is in `nested` are objects
    /// the caller reads itself. Anything else is an unknown tag.
    fn props(
        &self,
        node: Node<'a, 'input>,
        nested: &[&str],
    ) -> Result<Props<'a, 'input>, SceneError> {
        self.props_where(node, |child| nested.contains(&child.tag_name().name()))
    }

    /// [`Self::props`], with the caller's test of which children are objects.
    fn props_where(
        &self,
        node: Node<'a, 'input>,
        is_object: impl Fn(Node) -> bool,
    ) -> Result<Props<'a, 'input>, SceneError> {
        let mut entries: Vec<(String, Node)> = Vec::new();
        for child in node.children().filter(Node::is_element) {
            let tag = child.tag_name().name();
            if is_object(child) {
                continue;
            }
            if tag == "animation" {
                return Err(self.error(
                    child,
                    "<animation>: a transform that changes while the shutter is open (motion \
                     blur) is not supported",
                ));
            }
            if !PROPERTY_TAGS.contains(&tag) {
                return Err(self.error(
                    child,
                    format!("unknown tag <{tag}> in {}", describe_object(node)),
                ));
            }
            let mut name = self.required_attr(child, "name")?;
            if self.file_of(child).before_v2 {
                name = self.upgraded_name(node, child, &name);
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
            if self.legacy(owner) {
                self.unqueried(&props, owner, name, *node);
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
            (Some(value), None) if self.legacy(node) && !value.contains(':') => {
                if let Some(rgb) = self.legacy_rgb_spectrum(node, &value)? {
                    return Ok(rgb);
                }
                spectrum::parse_spectrum_value(&value).map_err(|why| fail("value", why))?
            }
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
            let step = match self.tag_of(child) {
                "matrix" => self.matrix(child)?,
                "translate" => Mat4::from_translation(self.xyz_or_value(child, 0.0, false)?),
                "scale" => Mat4::from_scale(self.xyz_or_value(child, 1.0, true)?),
                "rotate" => self.rotation(child)?,
                "lookat" => {
                    if child.tag_name().name() != "lookat" {
                        self.upgrade(child, "<lookAt> read as <lookat>");
                    }
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
}

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

/// Whether `m` is a rotation (or reflection) times a uniform scale: its columns orthogonal
/// and of one length.
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
