//! The subset of Mitsuba 3 XML used by the reference scenes (see `tests/refs/README.md`).
//! Like Mitsuba, an unknown tag or an unused property is an error with its line and column, so
//! a typo never silently renders a different scene.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3, Vec4};
use roxmltree::{Document, Node};

use super::{Bsdf, Camera, Integrator, Material, PointLight, Scene, SceneError, Sphere, mesh};
use crate::error::Location;

/// Mitsuba's default BSDF for a shape that names none.
const DEFAULT_BSDF: Bsdf = Bsdf::Diffuse {
    reflectance: Vec3::splat(0.5),
};

pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    parse(path, &text)
}

/// Parses Mitsuba XML `text`; `path` names the file in errors and anchors relative OBJ paths.
pub fn parse(path: &Path, text: &str) -> Result<Scene, SceneError> {
    let doc = Document::parse(text).map_err(|e| {
        let pos = e.pos();
        SceneError::at(
            Location::new(path, pos.row as usize, pos.col as usize),
            format!("XML syntax error: {e}"),
        )
    })?;
    let mut reader = Reader {
        path,
        doc: &doc,
        defaults: HashMap::new(),
        named_bsdfs: HashMap::new(),
        scene: Scene {
            source: path.to_path_buf(),
            camera: Camera {
                origin: Vec3::ZERO,
                target: Vec3::NEG_Z,
                up: Vec3::Y,
                fov_x_deg: 39.3077,
                width: 768,
                height: 576,
            },
            integrator: Integrator {
                max_depth: None,
                rr_depth: Some(5),
            },
            spp_hint: None,
            materials: Vec::new(),
            triangles: Vec::new(),
            spheres: Vec::new(),
            point_lights: Vec::new(),
        },
        has_sensor: false,
    };
    reader.read_scene(doc.root_element())?;
    if !reader.has_sensor {
        return Err(reader.error(doc.root_element(), "the scene has no <sensor>"));
    }
    reader.scene.validate()?;
    Ok(reader.scene)
}

struct Reader<'a, 'input> {
    path: &'a Path,
    doc: &'a Document<'input>,
    defaults: HashMap<String, String>,
    named_bsdfs: HashMap<String, Bsdf>,
    scene: Scene,
    has_sensor: bool,
}

/// The properties of one object (`<float name=...>` and friends), consumed by name; whatever is
/// left over at the end is an unknown property.
struct Props<'a, 'input> {
    entries: Vec<(String, Node<'a, 'input>)>,
}

impl<'a, 'input> Reader<'a, 'input> {
    fn location(&self, node: Node) -> Location {
        let pos = self.doc.text_pos_at(node.range().start);
        Location::new(self.path, pos.row as usize, pos.col as usize)
    }

    fn error(&self, node: Node, message: impl Into<String>) -> SceneError {
        SceneError::at(self.location(node), message)
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
                self.error(
                    node,
                    format!("attribute {name}=\"{raw}\": no <default name=\"{key}\">"),
                )
            })?;
            out.push_str(value);
            rest = &tail[end..];
        }
        out.push_str(rest);
        Ok(Some(out))
    }

    fn required_attr(&self, node: Node, name: &str) -> Result<String, SceneError> {
        self.attr(node, name)?.ok_or_else(|| {
            self.error(
                node,
                format!(
                    "<{}> needs a {name}=\"...\" attribute",
                    node.tag_name().name()
                ),
            )
        })
    }

    fn read_scene(&mut self, root: Node<'a, 'input>) -> Result<(), SceneError> {
        if root.tag_name().name() != "scene" {
            return Err(self.error(root, "the root element must be <scene>"));
        }
        for child in root.children().filter(Node::is_element) {
            match child.tag_name().name() {
                "default" => {
                    let name = self.required_attr(child, "name")?;
                    let value = self.required_attr(child, "value")?;
                    self.defaults.insert(name, value);
                }
                "integrator" => self.read_integrator(child)?,
                "sensor" => self.read_sensor(child)?,
                "shape" => self.read_shape(child)?,
                "emitter" => self.read_point_light(child)?,
                "bsdf" => {
                    let id = self.required_attr(child, "id")?;
                    let bsdf = self.read_bsdf(child)?;
                    self.named_bsdfs.insert(id, bsdf);
                }
                other => return Err(self.error(child, format!("unknown tag <{other}> in <scene>"))),
            }
        }
        Ok(())
    }

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
            ];
            if !PROPERTY_TAGS.contains(&tag) {
                return Err(self.error(
                    child,
                    format!("unknown tag <{tag}> in <{}>", node.tag_name().name()),
                ));
            }
            let name = self.required_attr(child, "name")?;
            if let Some((_, first)) = entries.iter().find(|(n, _)| *n == name) {
                return Err(self.error(
                    child,
                    format!(
                        "property \"{name}\" given twice (first at line {})",
                        self.location(*first).line
                    ),
                ));
            }
            entries.push((name, child));
        }
        Ok(Props { entries })
    }

    fn finish(&self, props: Props, owner: Node) -> Result<(), SceneError> {
        if let Some((name, node)) = props.entries.first() {
            let kind = owner.attribute("type").unwrap_or("");
            return Err(self.error(
                *node,
                format!(
                    "unknown property \"{name}\" for <{} type=\"{kind}\">",
                    owner.tag_name().name()
                ),
            ));
        }
        Ok(())
    }

    fn number(&self, node: Node, text: &str) -> Result<f32, SceneError> {
        let value: f32 = text.trim().parse().map_err(|_| {
            self.error(
                node,
                format!("{}: expected a number, got \"{text}\"", describe(node)),
            )
        })?;
        if !value.is_finite() {
            return Err(self.error(
                node,
                format!("{}: {text} is not a finite number", describe(node)),
            ));
        }
        Ok(value)
    }

    fn numbers(&self, node: Node, text: &str) -> Result<Vec<f32>, SceneError> {
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| self.number(node, s))
            .collect()
    }

    fn float(&self, node: Node) -> Result<f32, SceneError> {
        if node.tag_name().name() != "float" && node.tag_name().name() != "integer" {
            return Err(self.error(node, format!("{}: expected <float>", describe(node))));
        }
        let value = self.required_attr(node, "value")?;
        self.number(node, &value)
    }

    fn integer(&self, node: Node) -> Result<i64, SceneError> {
        let value = self.required_attr(node, "value")?;
        value.trim().parse().map_err(|_| {
            self.error(
                node,
                format!(
                    "{}: expected a whole number, got \"{value}\"",
                    describe(node)
                ),
            )
        })
    }

    fn string(&self, node: Node) -> Result<String, SceneError> {
        self.required_attr(node, "value")
    }

    fn boolean(&self, node: Node) -> Result<bool, SceneError> {
        match self.required_attr(node, "value")?.as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            other => Err(self.error(
                node,
                format!(
                    "{}: expected true or false, got \"{other}\"",
                    describe(node)
                ),
            )),
        }
    }

    /// An RGB colour: `<rgb value="r, g, b">`, or one number for grey (`<float>`, `<spectrum>`).
    fn color(&self, node: Node) -> Result<Vec3, SceneError> {
        let value = self.required_attr(node, "value")?;
        let v = self.numbers(node, &value)?;
        match v.as_slice() {
            [x] => Ok(Vec3::splat(*x)),
            [r, g, b] => Ok(Vec3::new(*r, *g, *b)),
            _ => Err(self.error(
                node,
                format!(
                    "{}: expected 1 or 3 numbers, got \"{value}\"",
                    describe(node)
                ),
            )),
        }
    }

    /// `<point x= y= z=>` or `<point value="x, y, z">`.
    fn point(&self, node: Node) -> Result<Vec3, SceneError> {
        if let Some(value) = self.attr(node, "value")? {
            let v = self.numbers(node, &value)?;
            return match v.as_slice() {
                [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                _ => Err(self.error(node, format!("{}: expected 3 numbers", describe(node)))),
            };
        }
        let coord = |axis: &str| -> Result<f32, SceneError> {
            match self.attr(node, axis)? {
                Some(v) => self.number(node, &v),
                None => Ok(0.0),
            }
        };
        Ok(Vec3::new(coord("x")?, coord("y")?, coord("z")?))
    }

    fn vec3_attr(&self, node: Node, name: &str) -> Result<Vec3, SceneError> {
        let value = self.required_attr(node, name)?;
        let v = self.numbers(node, &value)?;
        match v.as_slice() {
            [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
            _ => Err(self.error(
                node,
                format!(
                    "<{}> {name}: expected 3 numbers, got \"{value}\"",
                    node.tag_name().name()
                ),
            )),
        }
    }

    /// A `<transform>`: its children compose left to right, each applied after the previous.
    fn transform(&self, node: Node) -> Result<Mat4, SceneError> {
        let mut m = Mat4::IDENTITY;
        for child in node.children().filter(Node::is_element) {
            let step = match child.tag_name().name() {
                "matrix" => {
                    let value = self.required_attr(child, "value")?;
                    let v = self.numbers(child, &value)?;
                    if v.len() != 16 {
                        return Err(self.error(
                            child,
                            format!("<matrix>: expected 16 numbers, got {}", v.len()),
                        ));
                    }
                    Mat4::from_cols_slice(&v).transpose()
                }
                "translate" => Mat4::from_translation(self.xyz_or_value(child, 0.0)?),
                "scale" => Mat4::from_scale(self.xyz_or_value(child, 1.0)?),
                "rotate" => {
                    let axis = self.xyz_or_value(child, 0.0)?;
                    let angle = match self.attr(child, "angle")? {
                        Some(a) => self.number(child, &a)?,
                        None => return Err(self.error(child, "<rotate> needs angle=\"degrees\"")),
                    };
                    if axis.length_squared() == 0.0 {
                        return Err(self.error(child, "<rotate>: the axis is zero"));
                    }
                    Mat4::from_axis_angle(axis.normalize(), angle.to_radians())
                }
                "lookat" => {
                    let origin = self.vec3_attr(child, "origin")?;
                    let target = self.vec3_attr(child, "target")?;
                    let up = self.vec3_attr(child, "up")?;
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

    /// `x= y= z=` attributes (missing ones take `default`), or a single `value=` (1 or 3 numbers).
    fn xyz_or_value(&self, node: Node, default: f32) -> Result<Vec3, SceneError> {
        if let Some(value) = self.attr(node, "value")? {
            let v = self.numbers(node, &value)?;
            return match v.as_slice() {
                [s] => Ok(Vec3::splat(*s)),
                [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                _ => Err(self.error(
                    node,
                    format!("<{}>: expected 1 or 3 numbers", node.tag_name().name()),
                )),
            };
        }
        let coord = |axis: &str| -> Result<f32, SceneError> {
            match self.attr(node, axis)? {
                Some(v) => self.number(node, &v),
                None => Ok(default),
            }
        };
        Ok(Vec3::new(coord("x")?, coord("y")?, coord("z")?))
    }

    fn read_integrator(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "path" {
            return Err(self.error(
                node,
                format!("integrator type \"{kind}\" is not supported (only \"path\")"),
            ));
        }
        let mut props = self.props(node, &[])?;
        if let Some(n) = props.take("max_depth") {
            let depth = self.integer(n)?;
            self.scene.integrator.max_depth = match depth {
                -1 => None,
                d if d >= 1 && d < u32::MAX as i64 => Some(d as u32),
                _ => {
                    return Err(self.error(
                        n,
                        format!("max_depth {depth}: expected -1 (unbounded) or at least 1"),
                    ));
                }
            };
        }
        if let Some(n) = props.take("rr_depth") {
            let depth = self.integer(n)?;
            if depth < 1 || depth > u32::MAX as i64 - 1 {
                return Err(self.error(n, format!("rr_depth {depth}: expected at least 1")));
            }
            self.scene.integrator.rr_depth = Some(depth as u32);
        }
        // Russian roulette that can never start is no roulette.
        if let (Some(max), Some(rr)) = (
            self.scene.integrator.max_depth,
            self.scene.integrator.rr_depth,
        ) && rr >= max
        {
            self.scene.integrator.rr_depth = None;
        }
        props
            .take("hide_emitters")
            .map(|n| self.boolean(n))
            .transpose()?;
        self.finish(props, node)
    }

    fn read_sensor(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "perspective" {
            return Err(self.error(
                node,
                format!("sensor type \"{kind}\" is not supported (only \"perspective\")"),
            ));
        }
        for child in node.children().filter(Node::is_element) {
            match child.tag_name().name() {
                "sampler" => self.read_sampler(child)?,
                "film" => self.read_film(child)?,
                _ => {}
            }
        }
        let mut props = self.props(node, &["sampler", "film"])?;
        let fov = props
            .take("fov")
            .map(|n| self.float(n).map(|v| (n, v)))
            .transpose()?;
        let fov_axis = props
            .take("fov_axis")
            .map(|n| self.string(n).map(|v| (n, v)))
            .transpose()?;
        for clip in ["near_clip", "far_clip", "focus_distance"] {
            props.take(clip).map(|n| self.float(n)).transpose()?;
        }
        if let Some(n) = props.take("to_world") {
            let m = self.transform(n)?;
            self.scene.camera.origin = m.transform_point3(Vec3::ZERO);
            self.scene.camera.target = m.transform_point3(Vec3::Z);
            self.scene.camera.up = m.transform_vector3(Vec3::Y);
        }
        self.finish(props, node)?;
        if let Some((n, fov)) = fov {
            if !(fov > 0.0 && fov < 180.0) {
                return Err(self.error(n, format!("fov {fov}: expected degrees between 0 and 180")));
            }
            let (w, h) = (
                self.scene.camera.width as f32,
                self.scene.camera.height as f32,
            );
            let axis = fov_axis.as_ref().map_or("x", |(_, a)| a.as_str());
            let to_x = |fov_y: f32| {
                2.0 * ((fov_y.to_radians() * 0.5).tan() * w / h)
                    .atan()
                    .to_degrees()
            };
            self.scene.camera.fov_x_deg = match axis {
                "x" => fov,
                "y" => to_x(fov),
                "smaller" if w <= h => fov,
                "smaller" => to_x(fov),
                "larger" if w >= h => fov,
                "larger" => to_x(fov),
                other => {
                    let n = fov_axis.as_ref().map_or(node, |(n, _)| *n);
                    return Err(self.error(
                        n,
                        format!("fov_axis \"{other}\": expected x, y, smaller or larger"),
                    ));
                }
            };
        }
        self.has_sensor = true;
        Ok(())
    }

    fn read_sampler(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let mut props = self.props(node, &[])?;
        if let Some(n) = props.take("sample_count") {
            let spp = self.integer(n)?;
            if spp < 1 || spp > u32::MAX as i64 {
                return Err(self.error(n, format!("sample_count {spp}: expected at least 1")));
            }
            self.scene.spp_hint = Some(spp as u32);
        }
        props.take("seed").map(|n| self.integer(n)).transpose()?;
        self.finish(props, node)
    }

    fn read_film(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "hdrfilm" {
            return Err(self.error(
                node,
                format!("film type \"{kind}\" is not supported (only \"hdrfilm\")"),
            ));
        }
        for child in node.children().filter(|c| c.has_tag_name("rfilter")) {
            let filter = self.required_attr(child, "type")?;
            if filter != "box" {
                return Err(self.error(
                    child,
                    format!("rfilter \"{filter}\" is not supported (only \"box\")"),
                ));
            }
        }
        let mut props = self.props(node, &["rfilter"])?;
        for (name, slot) in [("width", 0), ("height", 1)] {
            if let Some(n) = props.take(name) {
                let v = self.integer(n)?;
                if !(1..=16384).contains(&v) {
                    return Err(self.error(n, format!("{name} {v}: expected 1 to 16384 pixels")));
                }
                if slot == 0 {
                    self.scene.camera.width = v as u32;
                } else {
                    self.scene.camera.height = v as u32;
                }
            }
        }
        for name in ["pixel_format", "component_format", "file_format"] {
            props.take(name).map(|n| self.string(n)).transpose()?;
        }
        props.take("banner").map(|n| self.boolean(n)).transpose()?;
        self.finish(props, node)
    }

    fn read_bsdf(&self, node: Node<'a, 'input>) -> Result<Bsdf, SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        let bsdf = match kind.as_str() {
            "diffuse" => {
                let reflectance = match props.take("reflectance") {
                    Some(n) => self.color(n)?,
                    None => Vec3::splat(0.5),
                };
                Bsdf::Diffuse { reflectance }
            }
            "dielectric" => {
                let mut ior = |name: &str, default: f32| -> Result<f32, SceneError> {
                    match props.take(name) {
                        Some(n) => {
                            let v = self.float(n)?;
                            if v <= 0.0 {
                                return Err(self.error(n, format!("{name} {v}: must be positive")));
                            }
                            Ok(v)
                        }
                        None => Ok(default),
                    }
                };
                // Mitsuba's defaults: BK7 glass inside, air outside.
                let int_ior = ior("int_ior", 1.5046)?;
                let ext_ior = ior("ext_ior", 1.000277)?;
                Bsdf::Dielectric { int_ior, ext_ior }
            }
            "conductor" => {
                match props.take("material") {
                    Some(n) => {
                        let m = self.string(n)?;
                        if m != "none" {
                            return Err(self.error(n, format!("conductor material \"{m}\" is not supported (only \"none\", a perfect mirror)")));
                        }
                    }
                    None => return Err(self.error(node, "conductor: only material=\"none\" (a perfect mirror) is supported; add <string name=\"material\" value=\"none\"/>")),
                }
                Bsdf::Mirror
            }
            other => return Err(self.error(node, format!("bsdf type \"{other}\" is not supported (diffuse, dielectric, conductor with material none)"))),
        };
        self.finish(props, node)?;
        Ok(bsdf)
    }

    fn read_shape(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut bsdf = None;
        let mut emission = Vec3::ZERO;
        for child in node.children().filter(Node::is_element) {
            match child.tag_name().name() {
                "bsdf" => bsdf = Some(self.read_bsdf(child)?),
                "ref" => {
                    let id = self.required_attr(child, "id")?;
                    let found = self.named_bsdfs.get(&id).copied().ok_or_else(|| {
                        self.error(
                            child,
                            format!("<ref id=\"{id}\">: no <bsdf id=\"{id}\"> defined above"),
                        )
                    })?;
                    bsdf = Some(found);
                }
                "emitter" => emission = self.read_area_emitter(child)?,
                _ => {}
            }
        }
        let material = self.scene.materials.len() as u32;
        self.scene.materials.push(Material {
            bsdf: bsdf.unwrap_or(DEFAULT_BSDF),
            emission,
        });
        let mut props = self.props(node, &["bsdf", "ref", "emitter"])?;
        let to_world = props
            .take("to_world")
            .map(|n| self.transform(n))
            .transpose()?;
        let flip = props
            .take("flip_normals")
            .map(|n| self.boolean(n))
            .transpose()?
            .unwrap_or(false);
        let m = to_world.unwrap_or(Mat4::IDENTITY);
        match kind.as_str() {
            "rectangle" => self.scene.push_mesh(mesh::rectangle(), m, material, flip),
            "cube" => self.scene.push_mesh(mesh::cube(), m, material, flip),
            "sphere" => {
                let center = props
                    .take("center")
                    .map(|n| self.point(n))
                    .transpose()?
                    .unwrap_or(Vec3::ZERO);
                let radius = match props.take("radius") {
                    Some(n) => {
                        let r = self.float(n)?;
                        if r <= 0.0 {
                            return Err(
                                self.error(n, format!("sphere radius {r}: must be positive"))
                            );
                        }
                        r
                    }
                    None => 1.0,
                };
                let scale = m.transform_vector3(Vec3::X).length();
                self.scene.spheres.push(Sphere {
                    center: m.transform_point3(center),
                    radius: radius * scale,
                    material,
                    flip_normals: flip,
                });
            }
            "obj" => {
                let file = match props.take("filename") {
                    Some(n) => self.string(n)?,
                    None => {
                        return Err(self.error(
                            node,
                            "<shape type=\"obj\"> needs <string name=\"filename\">",
                        ));
                    }
                };
                let face_normals = props
                    .take("face_normals")
                    .map(|n| self.boolean(n))
                    .transpose()?;
                if face_normals == Some(false) {
                    eprintln!(
                        "warning: {}: smooth vertex normals are not supported yet; using flat face normals",
                        self.location(node)
                    );
                }
                let obj_path = self.relative(&file);
                let triangles = super::obj::load_triangles(&obj_path).map_err(|e| match e {
                    SceneError::Io { file, source } => self.error(
                        node,
                        format!("cannot read OBJ file {}: {source}", file.display()),
                    ),
                    other => other,
                })?;
                self.scene.push_mesh(triangles, m, material, flip);
            }
            other => {
                return Err(self.error(
                    node,
                    format!(
                        "shape type \"{other}\" is not supported (rectangle, cube, sphere, obj)"
                    ),
                ));
            }
        }
        self.finish(props, node)
    }

    fn relative(&self, file: &str) -> PathBuf {
        let dir = self.path.parent().unwrap_or(Path::new("."));
        dir.join(file)
    }

    fn read_area_emitter(&self, node: Node<'a, 'input>) -> Result<Vec3, SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "area" {
            return Err(self.error(
                node,
                format!("emitter type \"{kind}\" inside a shape: only \"area\" is supported"),
            ));
        }
        let mut props = self.props(node, &[])?;
        let radiance = match props.take("radiance") {
            Some(n) => self.color(n)?,
            None => return Err(self.error(node, "area emitter needs a radiance")),
        };
        if radiance.min_element() < 0.0 {
            return Err(self.error(node, "area emitter radiance must not be negative"));
        }
        self.finish(props, node)?;
        Ok(radiance)
    }

    fn read_point_light(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "point" {
            return Err(self.error(node, format!("emitter type \"{kind}\" at scene level is not supported (only \"point\"; area emitters go inside a shape)")));
        }
        let mut props = self.props(node, &[])?;
        let mut position = props.take("position").map(|n| self.point(n)).transpose()?;
        if let Some(n) = props.take("to_world") {
            position = Some(
                self.transform(n)?
                    .transform_point3(position.unwrap_or(Vec3::ZERO)),
            );
        }
        let intensity = match props.take("intensity") {
            Some(n) => self.color(n)?,
            None => Vec3::ONE,
        };
        if intensity.min_element() < 0.0 {
            return Err(self.error(node, "point light intensity must not be negative"));
        }
        self.finish(props, node)?;
        self.scene.point_lights.push(PointLight {
            position: position.unwrap_or(Vec3::ZERO),
            intensity,
        });
        Ok(())
    }
}

impl<'a, 'input> Props<'a, 'input> {
    fn take(&mut self, name: &str) -> Option<Node<'a, 'input>> {
        let i = self.entries.iter().position(|(n, _)| n == name)?;
        Some(self.entries.remove(i).1)
    }
}

fn describe(node: Node) -> String {
    match node.attribute("name") {
        Some(name) => format!("<{} name=\"{name}\">", node.tag_name().name()),
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
        Vec4::new(origin.x, origin.y, origin.z, 1.0),
    ))
}
