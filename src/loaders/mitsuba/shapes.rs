//! Shapes as Mitsuba's src/shapes reads them: meshes (OBJ, PLY, serialized), analytic spheres,
//! rectangles, cubes, disks and cylinders, shape groups and instances.

use super::*;
use crate::scene::medium::MediumInterface;

impl<'a, 'input> Reader<'a, 'input> {
    /// The shape's BSDF (inline or `<ref>`), area emission and media (`interior`,
    /// `exterior`: nested or `<ref>`), at most one of each.
    pub(super) fn read_shape_material(
        &self,
        node: Node<'a, 'input>,
    ) -> Result<Material, SceneError> {
        let mut bsdf = None;
        let mut emission = None;
        let mut media = MediumInterface::default();
        for child in node.children().filter(Node::is_element) {
            let tag = child.tag_name().name();
            let side = match self.attr(child, "name")?.as_deref() {
                Some("interior") if matches!(tag, "ref" | "medium") => Some(&mut media.interior),
                Some("exterior") if matches!(tag, "ref" | "medium") => Some(&mut media.exterior),
                _ if tag == "medium" || (tag == "ref" && self.names_medium(child)) => {
                    return Err(self.error(
                        child,
                        format!(
                            "{}: a medium given to a shape needs name=\"interior\" or \
                             name=\"exterior\" (as Mitsuba requires)",
                            describe(child)
                        ),
                    ));
                }
                _ => None,
            };
            if let Some(side) = side {
                if side.is_some() {
                    return Err(self.error(child, format!("{}: given twice", describe(child))));
                }
                *side = Some(self.nested_medium(child)?);
                continue;
            }
            let is_bsdf = matches!(tag, "bsdf" | "ref");
            if (is_bsdf && bsdf.is_some()) || (tag == "emitter" && emission.is_some()) {
                return Err(self.error(
                    child,
                    format!("{}: a shape has at most one {tag}", describe_object(child)),
                ));
            }
            match tag {
                "bsdf" => bsdf = Some(self.read_bsdf(child)?),
                "ref" => bsdf = Some(self.bsdf_ref(child)?),
                "emitter" => emission = Some(self.read_area_emitter(child)?),
                _ => {}
            }
        }
        let boundary_06 =
            self.legacy(node) && (media.interior.is_some() || media.exterior.is_some());
        let sides = bsdf.unwrap_or_else(|| default_bsdf(emission.is_some(), boundary_06));
        let mut material = sides.material(emission.unwrap_or(Vec3::ZERO));
        material.media = media;
        Ok(material)
    }

    /// A `<ref>` whose id is a medium's, not a BSDF's.
    fn names_medium(&self, node: Node) -> bool {
        node.attribute("id")
            .is_some_and(|id| self.named_media.contains(id) && !self.named_bsdfs.contains(id))
    }

    pub(super) fn bsdf_ref(&self, node: Node) -> Result<crate::bsdfs::Sides, SceneError> {
        let id = self.required_attr(node, "id")?;
        self.named_bsdfs
            .get(&id)
            .ok_or_else(|| self.missing_ref(node, &id, "bsdf", &format!("<ref id=\"{id}\">")))
    }

    /// A `<ref>` to an id no `<tag id=...>` before it declares, or to one that failed.
    pub(super) fn missing_ref(&self, node: Node, id: &str, tag: &str, what: &str) -> SceneError {
        let why = match self.failed_ids.borrow().get(id) {
            Some(line) => format!("the <{tag} id=\"{id}\"> at line {line} could not be read"),
            None => format!("no <{tag} id=\"{id}\"> is declared before this"),
        };
        self.attr_error(node, "id", format!("{what}: {why}"))
    }

    pub(super) fn read_shape(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        match node.attribute("type") {
            Some("shapegroup") => self.read_shapegroup(node),
            Some("instance") => self.read_instance(node),
            _ => self.read_placed_shape(node, Mat4::IDENTITY),
        }
    }

    /// `<shape type="shapegroup" id=...>`: shapes to be placed by instances. It draws nothing
    /// itself; its shapes are checked here, once.
    pub(super) fn read_shapegroup(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let id = self.required_attr(node, "id")?;
        if self.shape_groups.contains_key(&id) {
            return Err(self.attr_error(
                node,
                "id",
                format!("a second <shape id=\"{id}\">: ids must be unique"),
            ));
        }
        let shapes = self.group_shapes(node).inspect_err(|_| {
            self.failed_ids
                .borrow_mut()
                .insert(id.clone(), self.location(node).line);
        })?;
        self.shape_groups.insert(id, shapes);
        Ok(())
    }

    /// A shapegroup's shapes, each checked by reading it once (its geometry then dropped).
    pub(super) fn group_shapes(
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
    pub(super) fn read_instance(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
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
    pub(super) fn read_placed_shape(
        &mut self,
        node: Node<'a, 'input>,
        outer: Mat4,
    ) -> Result<(), SceneError> {
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
        let mut props = self.props(node, &["bsdf", "ref", "emitter", "medium"])?;
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
        if let Some(message) = crate::scene::beyond_extent("this shape", reach) {
            return Err(self.error(node, message));
        }
        self.finish(props, node)
    }

    /// Mitsuba's `cylinder`: the unit tube placed between `p0` and `p1` with `radius`, its
    /// axis turned into place by the frame Mitsuba builds around it (which fixes where its
    /// texture's u starts), then by `to_world`.
    pub(super) fn read_cylinder(
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

    pub(super) fn read_sphere(
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
        let Some(scale) = crate::scene::similarity_scale(m) else {
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
    pub(super) fn read_mesh_file(
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
        let mesh_path = self.existing_file(file_node, self.relative(&file));
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
                    MeshFormat::Obj => crate::loaders::obj::load_mesh_data(&mesh_path),
                    MeshFormat::Ply => crate::loaders::ply::load(&mesh_path),
                    // The file's own face-normals flag is not read: Mitsuba 3 shades a
                    // serialized mesh flat only when the face_normals property says so.
                    MeshFormat::Serialized => {
                        crate::loaders::serialized::load(&mesh_path, index).map(|s| s.mesh)
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
    pub(super) fn shape_index(&self, props: &mut Props) -> Result<u32, SceneError> {
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

    pub(super) fn push_mesh_data(&mut self, mesh: mesh::MeshData, common: &ShapeCommon) {
        self.scene
            .push_mesh_data(mesh, common.to_world, common.material, common.flip_normals);
    }

    /// A file named in the scene: beside the scene's file, else in a `<path>` folder, else
    /// beside an included file (the first that exists; the scene's folder when none does).
    pub(super) fn relative(&self, file: &str) -> PathBuf {
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
}
