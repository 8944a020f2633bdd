//! Textures as Mitsuba's src/textures reads them, and the parameters that take a colour, a float
//! or a texture.

use super::*;

impl<'a, 'input> Reader<'a, 'input> {
    /// A float or a texture given to parameter `name`: the number, or the texture's mean and
    /// its index in the scene's textures.
    pub(super) fn float_or_texture(
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
    pub(super) fn texture_node(
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
                let texture = self.read_declared_texture(node)?;
                let mean = texture.mean();
                let index = add(texture);
                // A `<ref>` to its id later shares this one.
                if let Some(id) = self.attr(node, "id")? {
                    self.texture_indices.borrow_mut().insert(id, index);
                }
                Ok(Some((mean, index)))
            }
            "ref" => {
                let id = self.required_attr(node, "id")?;
                let Some(texture) = self.named_textures.get(&id) else {
                    let what = format!("<ref name=\"{name}\" id=\"{id}\">");
                    return Err(self.missing_ref(node, &id, "texture", &what));
                };
                let mut indices = self.texture_indices.borrow_mut();
                let i = *indices.entry(id).or_insert_with(|| add(texture.clone()));
                Ok(Some((texture.mean(), i)))
            }
            _ => Ok(None),
        }
    }

    /// A top-level `<texture>`, which needs an id to be used.
    pub(super) fn read_named_texture(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        self.required_attr(node, "id")?;
        self.read_declared_texture(node).map(drop)
    }

    /// A `<texture>`, declared for later `<ref>`s where it has an `id` (nested ones too).
    fn read_declared_texture(&self, node: Node<'a, 'input>) -> Result<Texture, SceneError> {
        self.read_declared(&self.named_textures, node, "texture", || {
            self.read_texture(node)
        })
    }

    /// A `<texture>`: `checkerboard` or `bitmap`, with Mitsuba's defaults.
    pub(super) fn read_texture(&self, node: Node<'a, 'input>) -> Result<Texture, SceneError> {
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
}
