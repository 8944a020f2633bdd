//! `<bsdf>` elements: each is read by the BSDF unit of the registry that reads its `type`
//! (src/bsdfs/), through an [`Element`], which hands the unit its properties and nested objects
//! and places the unit's errors in the file.

use super::*;
use crate::bsdfs::{BsdfPlugin, BsdfReader, Sides};

impl<'a, 'input> Reader<'a, 'input> {
    /// A top-level `<bsdf>`. Mitsuba allows one without an id; nothing can use it, but it is
    /// checked.
    pub(super) fn read_named_bsdf(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        self.read_bsdf(node).map(drop)
    }

    /// A `<bsdf>`, read by the unit its `type` names, and declared for later `<ref>`s where it
    /// has an `id` (nested ones too, as in Mitsuba).
    pub(super) fn read_bsdf(&self, node: Node<'a, 'input>) -> Result<Sides, SceneError> {
        self.read_declared(&self.named_bsdfs, node, "bsdf", || {
            self.read_bsdf_unit(node)
        })
    }

    fn read_bsdf_unit(&self, node: Node<'a, 'input>) -> Result<Sides, SceneError> {
        let kind = self.required_attr(node, "type")?;
        let Some(unit) = self.bsdfs.reader_of(&kind) else {
            return Err(self.attr_error(
                node,
                "type",
                format!(
                    "bsdf type \"{kind}\" is not supported ({})",
                    self.bsdfs.types()
                ),
            ));
        };
        let mut element = Element::new(self, node, kind, unit)?;
        let read = (unit.read)(&mut element);
        let takes = unit.properties_of(&element.kind);
        if read.is_err() {
            // A property the plugin never reads is the likelier cause (a misspelt name), so it
            // is reported rather than what its absence made the unit say; those the unit did not
            // get to before its error are not unknown.
            let kind = element.kind.clone();
            element
                .props
                .entries
                .retain(|(name, _)| !unit.has_property(&kind, name));
        }
        self.finish_with(element.props, node, Some(&takes))?;
        read
    }

    /// Adds a material the scene's shapes or blends refer to; its index.
    pub(super) fn add_material(&self, material: Material) -> u32 {
        let mut materials = self.materials.borrow_mut();
        materials.push(material);
        materials.len() as u32 - 1
    }
}

/// One `<bsdf>` element as its unit reads it: the properties not yet taken, the ones taken (to
/// place a unit's error at its property), and the children it reads as objects.
struct Element<'r, 'a, 'input> {
    reader: &'r Reader<'a, 'input>,
    node: Node<'a, 'input>,
    kind: String,
    props: Props<'a, 'input>,
    taken: Vec<(String, Node<'a, 'input>)>,
    objects: Vec<Node<'a, 'input>>,
    /// The nodes of the BSDFs `nested` returned, in its order.
    nested_nodes: Vec<Node<'a, 'input>>,
}

impl<'r, 'a, 'input> Element<'r, 'a, 'input> {
    /// A child whose tag the unit lists among its objects is an object, unless its `name` is
    /// a property of this type (a `<ref name="weight">`, a `<texture name="normalmap">`).
    fn new(
        reader: &'r Reader<'a, 'input>,
        node: Node<'a, 'input>,
        kind: String,
        unit: &'static BsdfPlugin,
    ) -> Result<Self, SceneError> {
        let is_object = |child: Node| {
            unit.objects.contains(&child.tag_name().name())
                && !child
                    .attribute("name")
                    .is_some_and(|name| unit.has_property(&kind, name))
        };
        let objects = node
            .children()
            .filter(|c| c.is_element() && is_object(*c))
            .collect();
        let props = reader.props_where(node, is_object)?;
        Ok(Element {
            reader,
            node,
            kind,
            props,
            taken: Vec::new(),
            objects,
            nested_nodes: Vec::new(),
        })
    }

    fn take(&mut self, name: &str) -> Option<Node<'a, 'input>> {
        let node = self.props.take(name)?;
        self.taken.push((name.to_string(), node));
        Some(node)
    }

    /// A given property's node, taken or not.
    fn property(&self, name: &str) -> Option<Node<'a, 'input>> {
        let taken = self.taken.iter().find(|(n, _)| n == name);
        let given = self.props.entries.iter().find(|(n, _)| n == name);
        taken.or(given).map(|(_, node)| *node)
    }

    fn read<T>(
        &mut self,
        name: &str,
        read: impl Fn(&Reader<'a, 'input>, Node) -> Result<T, SceneError>,
    ) -> Result<Option<T>, SceneError> {
        match self.take(name) {
            Some(node) => read(self.reader, node).map(Some),
            None => Ok(None),
        }
    }

    /// A `<ref>` object naming a declared texture (a bump map's height), not a BSDF.
    fn names_texture(&self, node: Node) -> bool {
        node.has_tag_name("ref")
            && self.objects_take_textures()
            && node.attribute("id").is_some_and(|id| {
                !self.reader.named_bsdfs.contains(id) && self.reader.named_textures.contains(id)
            })
    }

    fn objects_take_textures(&self) -> bool {
        self.reader
            .bsdfs
            .reader_of(&self.kind)
            .is_some_and(|u| u.objects.contains(&"texture"))
    }
}

impl BsdfReader for Element<'_, '_, '_> {
    fn plugin(&self) -> &str {
        &self.kind
    }

    fn has(&self, name: &str) -> bool {
        self.props.entries.iter().any(|(n, _)| n == name)
    }

    fn is_string(&self, name: &str) -> bool {
        self.props
            .entries
            .iter()
            .any(|(n, node)| n == name && node.has_tag_name("string"))
    }

    fn float(&mut self, name: &str) -> Result<Option<f32>, SceneError> {
        self.read(name, |r, n| r.float(n))
    }

    fn boolean(&mut self, name: &str) -> Result<Option<bool>, SceneError> {
        self.read(name, |r, n| r.boolean(n))
    }

    fn string(&mut self, name: &str) -> Result<Option<String>, SceneError> {
        self.read(name, |r, n| r.string(n))
    }

    fn color(&mut self, name: &str) -> Result<Option<Vec3>, SceneError> {
        self.read(name, |r, n| r.color(n))
    }

    fn color_or_texture(
        &mut self,
        name: &str,
        default: f32,
    ) -> Result<(Vec3, Option<u32>), SceneError> {
        let Some(node) = self.take(name) else {
            return Ok((Vec3::splat(default), None));
        };
        match self.reader.texture_node(node, name)? {
            Some((mean, index)) => Ok((Vec3::splat(mean), Some(index))),
            None => Ok((self.reader.non_negative_color(node)?, None)),
        }
    }

    fn scalar_or_texture(
        &mut self,
        name: &str,
        default: f32,
    ) -> Result<(f32, Option<u32>), SceneError> {
        match self.take(name) {
            Some(node) => self.reader.float_or_texture(node, name),
            None => Ok((default, None)),
        }
    }

    fn texture(&mut self, name: &str) -> Result<Option<u32>, SceneError> {
        let Some(node) = self.take(name) else {
            return Ok(None);
        };
        match self.reader.texture_node(node, name)? {
            Some((_, index)) => Ok(Some(index)),
            None => Err(self
                .reader
                .error(node, format!("{}: expected a <texture>", self.kind))),
        }
    }

    fn texture_objects(&mut self) -> Result<Vec<u32>, SceneError> {
        let mut textures = Vec::new();
        for &node in &self.objects {
            if node.has_tag_name("texture") || self.names_texture(node) {
                let Some((_, index)) = self.reader.texture_node(node, "texture")? else {
                    continue;
                };
                textures.push(index);
            }
        }
        Ok(textures)
    }

    fn is_bitmap(&self, index: u32) -> bool {
        matches!(
            self.reader.textures.borrow().get(index as usize),
            Some(Texture::Bitmap(_))
        )
    }

    fn texture_average_and_maximum(&self, index: u32) -> Option<(Vec3, Vec3)> {
        let textures = self.reader.textures.borrow();
        let texture = textures.get(index as usize)?;
        Some((texture.average(), texture.maximum()))
    }

    fn file_version(&self) -> Option<String> {
        let root = self.node.document().root_element();
        self.reader.attr(root, "version").ok().flatten()
    }

    fn nested(&mut self) -> Result<Vec<Sides>, SceneError> {
        let mut nested = Vec::new();
        self.nested_nodes.clear();
        for &node in &self.objects {
            let sides = match node.tag_name().name() {
                "bsdf" => self.reader.read_bsdf(node)?,
                "ref" if self.names_texture(node) => continue,
                "ref" => self.reader.bsdf_ref(node)?,
                _ => continue,
            };
            nested.push(sides);
            self.nested_nodes.push(node);
        }
        Ok(nested)
    }

    fn phase(&mut self) -> Result<Option<crate::scene::medium::Phase>, SceneError> {
        let phases: Vec<Node> = self
            .objects
            .iter()
            .copied()
            .filter(|n| n.has_tag_name("phase"))
            .collect();
        if let Some(second) = phases.get(1) {
            return Err(self.reader.error(
                *second,
                format!(
                    "{}: a second <phase> (it has one phase function)",
                    self.kind
                ),
            ));
        }
        phases
            .first()
            .map(|&node| self.reader.read_phase(node))
            .transpose()
    }

    fn medium_preset(&self, name: &str) -> Option<(Vec3, Vec3, Vec3)> {
        super::legacy::medium_preset_with_anisotropy(name)
    }

    fn medium_preset_names(&self) -> String {
        super::legacy::medium_preset_names()
    }

    fn add_material(&mut self, material: Material) -> u32 {
        self.reader.add_material(material)
    }

    fn material(&self, index: u32) -> Option<Material> {
        self.reader.materials.borrow().get(index as usize).cloned()
    }

    fn error_at(&self, name: &str, message: String) -> SceneError {
        match self.property(name) {
            Some(node) => self.reader.attr_error(node, "value", message),
            None => self.reader.error(self.node, message),
        }
    }

    fn error_at_nested(&self, index: usize, message: String) -> SceneError {
        let node = self.nested_nodes.get(index).copied().unwrap_or(self.node);
        self.reader.error(node, message)
    }

    fn error(&self, message: String) -> SceneError {
        self.reader.error(self.node, message)
    }

    fn describe(&self) -> String {
        describe_object(self.node)
    }

    fn describe_property(&self, name: &str) -> String {
        self.property(name)
            .map_or_else(|| format!("\"{name}\""), describe)
    }

    fn legacy(&self) -> bool {
        self.reader.legacy(self.node)
    }

    fn upgrade(&self, name: &str, message: String) {
        let node = self.property(name).unwrap_or(self.node);
        self.reader.upgrade(node, message);
    }
}
