//! Textures as Mitsuba's src/textures reads them, and the parameters that take a colour, a float
//! or a texture.

use super::*;

/// What a 0.6 bitmap's MIP-mapped filtering becomes.
const MIP_FILTERING: &str = "bitmap: 0.6 filters with MIP-mapping (EWA by default, or \
    trilinear) over the pixel's footprint; read bilinear, as Mitsuba 3 does: the same wherever \
    a pixel covers at most a texel, sharper where the texture is minified (the samples of a \
    pixel then average its texels themselves)";

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
            None if self.legacy(node) => self.legacy_uv_transform(&mut props)?,
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
                let mut raw = match props.take("raw") {
                    Some(n) => self.boolean(n)?,
                    None => false,
                };
                let legacy = self.legacy(node);
                let gamma = if legacy {
                    self.legacy_bitmap_options(&mut props)?
                } else {
                    None
                };
                // 0.6's gamma overrides the file's encoding: 1 is linear, -1 sRGB, others a
                // power law.
                if gamma.is_some_and(|g| g != -1.0) {
                    raw = true;
                }
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
                let wrap = match self.wrap_mode_node(&mut props, legacy)? {
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
                    None if legacy => {
                        self.upgrade(node, MIP_FILTERING);
                        Filter::Bilinear
                    }
                    None => Filter::Bilinear,
                    Some(n) => match self.string(n)?.as_str() {
                        "bilinear" => Filter::Bilinear,
                        "nearest" => Filter::Nearest,
                        "ewa" | "trilinear" if legacy => {
                            self.upgrade(n, MIP_FILTERING);
                            Filter::Bilinear
                        }
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
                let path = self.existing_file(file_node, self.relative(&filename));
                let mut bitmap = Bitmap::load(&path, raw, wrap, filter, to_uv)
                    .map_err(|message| self.attr_error(file_node, "value", message))?;
                match gamma {
                    Some(-1.0) if !bitmap.is_8_bit() => {
                        bitmap = bitmap.decoded_with(texture::srgb_to_linear);
                    }
                    Some(g) if g != 1.0 && g != -1.0 => {
                        bitmap = bitmap.decoded_with(|x| x.max(0.0).powf(g));
                    }
                    _ => {}
                }
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

impl<'a, 'input> Reader<'a, 'input> {
    /// A 0.6 texture's `uoffset`, `voffset`, `uscale`, `vscale` and `uvscale` as a `to_uv`
    /// (0.6's Texture2D: uv * scale + offset).
    fn legacy_uv_transform(
        &self,
        props: &mut Props<'a, 'input>,
    ) -> Result<UvTransform, SceneError> {
        let mut float = |name: &str, default: f32| -> Result<(f32, bool), SceneError> {
            match props.take(name) {
                Some(n) => Ok((self.float(n)?, true)),
                None => Ok((default, false)),
            }
        };
        let (uvscale, _) = float("uvscale", 1.0)?;
        let (su, a) = float("uscale", uvscale)?;
        let (sv, b) = float("vscale", uvscale)?;
        let (ou, c) = float("uoffset", 0.0)?;
        let (ov, d) = float("voffset", 0.0)?;
        if !(a || b || c || d || uvscale != 1.0) {
            return Ok(UvTransform::IDENTITY);
        }
        let m = Mat4::from_translation(Vec3::new(ou, ov, 0.0))
            * Mat4::from_scale(Vec3::new(su, sv, 1.0));
        Ok(UvTransform::from_mat4(m))
    }

    /// A 0.6 bitmap's own properties: `gamma` (returned; 0 is the file's own encoding), and
    /// what only 0.6's filtering read (`max_anisotropy`, `cache`).
    fn legacy_bitmap_options(
        &self,
        props: &mut Props<'a, 'input>,
    ) -> Result<Option<f32>, SceneError> {
        for name in ["max_anisotropy"] {
            if let Some(n) = props.take(name) {
                self.float(n)?;
                self.upgrade(n, format!("{name}: 0.6's EWA filtering only; ignored"));
            }
        }
        if let Some(n) = props.take("cache") {
            self.boolean(n)?;
            self.upgrade(n, "cache: 0.6's MIP-map cache file; ignored");
        }
        if let Some(n) = props.take("channel") {
            return Err(self.attr_error(
                n,
                "value",
                "channel: a bitmap reduced to one channel is not supported; give an image of \
                 that channel",
            ));
        }
        let Some(n) = props.take("gamma") else {
            return Ok(None);
        };
        let gamma = self.float(n)?;
        if gamma == 0.0 {
            return Ok(None);
        }
        if !(gamma == -1.0 || (gamma.is_finite() && gamma > 0.0)) {
            return Err(self.attr_error(
                n,
                "value",
                format!(
                    "bitmap gamma {gamma}: expected -1 (sRGB), 0 (the file's), or a positive number"
                ),
            ));
        }
        Ok(Some(gamma))
    }

    /// The node of a bitmap's wrap mode: `wrap_mode`, or in a 0.6 file `wrap_mode_u` and
    /// `wrap_mode_v`, which must then agree (hppm wraps both axes alike).
    fn wrap_mode_node(
        &self,
        props: &mut Props<'a, 'input>,
        legacy: bool,
    ) -> Result<Option<Node<'a, 'input>>, SceneError> {
        let common = props.take("wrap_mode");
        if !legacy {
            return Ok(common);
        }
        let mut chosen = common;
        for name in ["wrap_mode_u", "wrap_mode_v"] {
            let Some(n) = props.take(name) else { continue };
            let value = self.string(n)?;
            if let Some(c) = chosen
                && self.string(c)? != value
            {
                return Err(self.attr_error(
                    n,
                    "value",
                    format!(
                        "{name} \"{value}\" differs from the other axis' \"{}\" (line {}): \
                         hppm wraps both axes alike",
                        self.string(c)?,
                        self.location(c).line
                    ),
                ));
            }
            chosen = Some(n);
        }
        Ok(chosen)
    }
}
