//! BSDFs as Mitsuba's src/bsdfs reads them: one-sided kinds, `twosided`, blends and masks,
//! normal and bump maps, principled, and the shared readers of roughness and indices.

use super::*;

impl<'a, 'input> Reader<'a, 'input> {
    pub(super) fn read_named_bsdf(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
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
    pub(super) fn read_bsdf(&self, node: Node<'a, 'input>) -> Result<Sides, SceneError> {
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
    pub(super) fn read_twosided(&self, node: Node<'a, 'input>) -> Result<Sides, SceneError> {
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
    pub(super) fn add_material(&self, material: Material) -> u32 {
        let mut materials = self.materials.borrow_mut();
        materials.push(material);
        materials.len() as u32 - 1
    }

    /// Whether `bsdf`, or any BSDF a blend or mask of it may choose, transmits.
    pub(super) fn transmits(&self, bsdf: &Bsdf) -> bool {
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
    pub(super) fn read_blend(
        &self,
        node: Node<'a, 'input>,
        kind: &str,
    ) -> Result<Sides, SceneError> {
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
    pub(super) fn read_perturbed(
        &self,
        node: Node<'a, 'input>,
        kind: &str,
    ) -> Result<Sides, SceneError> {
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
    pub(super) fn perturbed(
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
    pub(super) fn read_one_sided(
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
    pub(super) fn read_principled(
        &self,
        props: &mut Props<'a, 'input>,
        textures: &mut SideTextures,
    ) -> Result<Bsdf, SceneError> {
        use crate::scene::principled::{self as pr, Principled};
        let (base_color, base_texture) = self.color_param(props, "base_color", 0.5)?;
        textures.diffuse = base_texture;
        let mut has = 0;
        // (value, texture), and whether Mitsuba counts it as given (m_has_*: a texture, or a
        // float other than 0; every parameter with a bit defaults to 0).
        let mut scalar =
            |name: &str, default: f32, bit: u32| -> Result<(f32, Option<u32>), SceneError> {
                let (value, texture) = self.scalar_param(props, name, default)?;
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
    pub(super) fn read_principled_thin(
        &self,
        props: &mut Props<'a, 'input>,
        textures: &mut SideTextures,
    ) -> Result<Bsdf, SceneError> {
        use crate::scene::principled_thin::PrincipledThin;
        let (base_color, base_texture) = self.color_param(props, "base_color", 0.5)?;
        textures.diffuse = base_texture;
        let (roughness, roughness_texture) = self.scalar_param(props, "roughness", 0.5)?;
        textures.alpha_u = roughness_texture;
        let mut values = [0.0; PRINCIPLED_THIN_TEXTURED.len()];
        // The last is eta, which is checked apart.
        let [params @ .., eta_slot] = &PRINCIPLED_THIN_TEXTURED;
        for (i, name) in params.iter().enumerate() {
            (values[i], textures.principled[i]) = self.scalar_param(props, name, 0.0)?;
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
    pub(super) fn dielectric_tint(
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

    pub(super) fn distinct_iors(
        &self,
        node: Node,
        int_ior: f32,
        ext_ior: f32,
    ) -> Result<(), SceneError> {
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
    pub(super) fn microfacet(
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
    pub(super) fn conductor_index(&self, props: &mut Props) -> Result<(Vec3, Vec3), SceneError> {
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
    pub(super) fn ior(
        &self,
        props: &mut Props,
        name: &str,
        default: f32,
    ) -> Result<f32, SceneError> {
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
}
