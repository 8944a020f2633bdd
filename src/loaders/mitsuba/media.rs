//! Participating media as Mitsuba 3's src/media, src/volumes and src/phase read them:
//! `homogeneous` media (their coefficients as numbers, colours or a `constvolume`),
//! `heterogeneous` ones with a `gridvolume` (a `.vol` file) of extinction, phase functions `isotropic`,
//! `hg` and `rayleigh`, declared at top level with an id or nested where they are used (a
//! shape's `interior` / `exterior`, the sensor's medium).

use std::sync::Arc;

use super::*;
use crate::scene::grid::{FilterType, WrapMode};
use crate::scene::medium::{Density, Medium, Phase};

/// What a homogeneous medium's coefficient may be given as.
const COEFFICIENT_TAGS: &[&str] = &["float", "rgb", "spectrum"];

impl<'a, 'input> Reader<'a, 'input> {
    /// A top-level `<medium id=...>`, for `<ref>`s after it.
    pub(super) fn read_named_medium(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        self.read_medium(node).map(drop)
    }

    /// A `<medium>` element: its index in the scene's media. Declared for later `<ref>`s where
    /// it has an `id` (nested ones too, as in Mitsuba).
    pub(super) fn read_medium(&self, node: Node<'a, 'input>) -> Result<u32, SceneError> {
        self.read_declared(&self.named_media, node, "medium", || {
            self.read_medium_kind(node)
        })
    }

    fn read_medium_kind(&self, node: Node<'a, 'input>) -> Result<u32, SceneError> {
        let kind = self.required_attr(node, "type")?;
        if !matches!(kind.as_str(), "homogeneous" | "heterogeneous") {
            return Err(self.attr_error(
                node,
                "type",
                format!(
                    "medium type \"{kind}\" is not supported (hppm reads \"homogeneous\" and \
                     \"heterogeneous\")"
                ),
            ));
        }
        let phase_nodes: Vec<Node> = node
            .children()
            .filter(|c| c.has_tag_name("phase"))
            .collect();
        if let Some(second) = phase_nodes.get(1) {
            return Err(self.error(
                *second,
                "a second <phase>: a medium has one phase function (as Mitsuba requires)",
            ));
        }
        let phase = match phase_nodes.first() {
            Some(p) => self.read_phase(*p)?,
            None => Phase::Isotropic,
        };
        let mut props = self.props(node, &["phase", "volume"])?;
        let volumes: Vec<Node<'a, 'input>> = node
            .children()
            .filter(|c| c.has_tag_name("volume"))
            .collect();
        let legacy = self.legacy(node);
        // 0.6's heterogeneous medium calls its extinction grid "density".
        let extinction_name = if legacy { "density" } else { "sigma_t" };
        let grid_node = volumes.iter().copied().find(|v| {
            v.attribute("name") == Some(extinction_name)
                && v.attribute("type") == Some("gridvolume")
        });
        let (sigma_t, albedo, density) = match grid_node {
            // A heterogeneous medium's extinction may be a grid: sigma_t is then 1 times it.
            Some(v) if kind == "heterogeneous" => {
                // Taken off the list of props as the coefficient would be.
                props.take(extinction_name);
                let albedo = self.medium_coefficient(&mut props, &volumes, "albedo", 0.75)?;
                (Vec3::ONE, albedo, Some(self.grid_volume(v)?))
            }
            _ if legacy && kind == "homogeneous" => {
                let (sigma_t, albedo) = self.legacy_coefficients(&mut props, node)?;
                (sigma_t, albedo, None)
            }
            _ => {
                let albedo = self.medium_coefficient(&mut props, &volumes, "albedo", 0.75)?;
                let sigma_t = self.medium_coefficient(&mut props, &volumes, "sigma_t", 1.0)?;
                (sigma_t, albedo, None)
            }
        };
        let scale = match props.take("scale") {
            Some(n) => {
                let s = self.float(n)?;
                if !(s.is_finite() && s >= 0.0) {
                    return Err(self.attr_error(
                        n,
                        "value",
                        format!("scale {s}: expected a finite number of 0 or more"),
                    ));
                }
                s
            }
            None => 1.0,
        };
        let sample_emitters = props
            .take("sample_emitters")
            .map(|n| self.boolean(n))
            .transpose()?
            .unwrap_or(true);
        // Only how Mitsuba samples distances in colour: the image is the same.
        self.ignore(&mut props, &["has_spectral_extinction"], |r, n| {
            r.boolean(n).map(drop)
        })?;
        if legacy {
            self.drop_legacy_sampling(&mut props)?;
        }
        self.finish(props, node)?;
        if let Some(v) = volumes.iter().find(
            |v| !matches!(v.attribute("name"), Some(n) if n == "albedo" || n == extinction_name),
        ) {
            return Err(self.error(
                *v,
                format!(
                    "{}: a medium takes a volume as \"albedo\" or \"{extinction_name}\" only",
                    describe_object(*v)
                ),
            ));
        }
        let medium = Medium {
            sigma_t: sigma_t * scale,
            albedo,
            phase,
            sample_emitters,
            density,
        };
        let mut media = self.media.borrow_mut();
        media.push(medium);
        Ok(media.len() as u32 - 1)
    }

    /// A coefficient given as a property or as a nested `<volume name=...>` (a constant one:
    /// Mitsuba's homogeneous medium evaluates it at one point).
    fn medium_coefficient(
        &self,
        props: &mut Props<'a, 'input>,
        volumes: &[Node<'a, 'input>],
        name: &str,
        default: f32,
    ) -> Result<Vec3, SceneError> {
        let volume = volumes.iter().find(|v| v.attribute("name") == Some(name));
        let node = props.take(name);
        let value = match (node, volume) {
            (Some(n), Some(v)) => {
                return Err(self.error(
                    *v,
                    format!(
                        "\"{name}\" given twice: as {} (line {}) and as a volume",
                        describe(n),
                        self.location(n).line
                    ),
                ));
            }
            (Some(n), None) => {
                self.expect_tag(n, COEFFICIENT_TAGS)?;
                (self.color(n)?, n)
            }
            (None, Some(v)) => self.constant_volume(*v)?,
            (None, None) => return Ok(Vec3::splat(default)),
        };
        let (c, n) = value;
        if !(c.is_finite() && c.min_element() >= 0.0) {
            return Err(self.attr_error(
                n,
                "value",
                format!(
                    "{} {name} ({}, {}, {}): expected finite numbers of 0 or more",
                    describe(n),
                    c.x,
                    c.y,
                    c.z
                ),
            ));
        }
        Ok(c)
    }

    /// `<volume type="constvolume">` and its `value` (and the node that gave it).
    fn constant_volume(
        &self,
        node: Node<'a, 'input>,
    ) -> Result<(Vec3, Node<'a, 'input>), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "constvolume" {
            let why = if kind == "gridvolume" {
                "a grid is read as a heterogeneous medium's sigma_t only (grids of albedo, and \
                 grids in a homogeneous medium, are not supported yet)"
            } else {
                "unknown volume type"
            };
            return Err(self.attr_error(node, "type", format!("volume type \"{kind}\": {why}")));
        }
        let mut props = self.props(node, &[])?;
        let value = props.take("value");
        self.ignore(&mut props, &["to_world"], |r, n| r.transform(n).map(drop))?;
        self.finish(props, node)?;
        match value {
            Some(n) => {
                self.expect_tag(n, COEFFICIENT_TAGS)?;
                Ok((self.color(n)?, n))
            }
            None => Ok((Vec3::ONE, node)),
        }
    }

    /// A homogeneous medium's (sigma_t, albedo) in a 0.6 file, as 0.6's `lookupMaterial` forms
    /// them: a preset (`material`, default `skin1`), then `sigma_s` and `sigma_a`, or `sigma_t`
    /// and `albedo`, each replacing the preset's value where given.
    fn legacy_coefficients(
        &self,
        props: &mut Props<'a, 'input>,
        node: Node<'a, 'input>,
    ) -> Result<(Vec3, Vec3), SceneError> {
        let given = |names: [&'static str; 2]| {
            names
                .into_iter()
                .find(|n| props.entries.iter().any(|(e, _)| e == n))
        };
        let scattering = given(["sigma_s", "sigma_a"]);
        let extinction = given(["sigma_t", "albedo"]);
        let material = props.take("material");
        if let (Some(m), Some(other)) = (material, scattering.or(extinction)) {
            return Err(self.attr_error(
                m,
                "value",
                format!(
                    "give either a preset material or coefficients (\"{other}\" is given too), \
                     not both (as Mitsuba 0.6 requires)"
                ),
            ));
        }
        if let (Some(a), Some(b)) = (scattering, extinction) {
            let at = props.take(b).unwrap_or(node);
            return Err(self.error(
                at,
                format!(
                    "\"{a}\" and \"{b}\" both given: give sigma_s and sigma_a, or sigma_t and \
                     albedo (as Mitsuba 0.6 requires)"
                ),
            ));
        }
        let name = match material {
            Some(m) => self.string(m)?,
            None => legacy::DEFAULT_PRESET.to_string(),
        };
        let (mut sigma_s, mut sigma_a) = legacy::medium_preset(&name).ok_or_else(|| {
            self.attr_error(
                material.unwrap_or(node),
                "value",
                format!(
                    "medium material \"{name}\" is not one of Mitsuba 0.6's presets: {}",
                    legacy::medium_preset_names()
                ),
            )
        })?;
        // The coefficients the file leaves to the preset, for the note.
        let mut from_preset = Vec::new();
        let mut coefficient = |props: &mut Props<'a, 'input>, name: &'static str, preset: Vec3| {
            if props.entries.iter().any(|(e, _)| e == name) {
                self.medium_coefficient(props, &[], name, 0.0)
            } else {
                from_preset.push(name);
                Ok(preset)
            }
        };
        if extinction.is_some() {
            let preset_t = sigma_s + sigma_a;
            let preset_albedo = albedo_of(sigma_s, preset_t);
            let sigma_t = coefficient(props, "sigma_t", preset_t)?;
            let albedo = coefficient(props, "albedo", preset_albedo)?;
            sigma_s = albedo * sigma_t;
            sigma_a = sigma_t - sigma_s;
        } else {
            sigma_s = coefficient(props, "sigma_s", sigma_s)?;
            sigma_a = coefficient(props, "sigma_a", sigma_a)?;
        }
        if !from_preset.is_empty() {
            let default = if material.is_none() {
                ", 0.6's default"
            } else {
                ""
            };
            self.upgrade(
                material.unwrap_or(node),
                format!(
                    "homogeneous medium: {} from Mitsuba 0.6's preset \"{name}\"{default} \
                     (the medium: sigma_s {sigma_s}, sigma_a {sigma_a} per unit; 0.6's table is in mm^-1, times 100)",
                    from_preset.join(" and ")
                ),
            );
        }
        let sigma_t = sigma_s + sigma_a;
        Ok((sigma_t, albedo_of(sigma_s, sigma_t)))
    }

    /// 0.6's choices of how to sample distances in a medium: they change its noise, not its
    /// image (but `monochromatic`, which keeps one colour channel's coefficients, is refused).
    fn drop_legacy_sampling(&self, props: &mut Props<'a, 'input>) -> Result<(), SceneError> {
        for name in ["strategy", "method"] {
            if let Some(n) = props.take(name) {
                self.string(n)?;
                self.upgrade(
                    n,
                    format!("{name}: 0.6's distance sampling; hppm samples its own way"),
                );
            }
        }
        for name in ["medium_sampling_weight", "sampling_density", "step_size"] {
            if let Some(n) = props.take(name) {
                self.float(n)?;
                self.upgrade(
                    n,
                    format!("{name}: 0.6's distance sampling; hppm samples its own way"),
                );
            }
        }
        if let Some(n) = props.take("channel") {
            self.integer(n)?;
            self.upgrade(
                n,
                "channel: 0.6's distance sampling; hppm samples its own way",
            );
        }
        if let Some(n) = props.take("monochromatic")
            && self.boolean(n)?
        {
            return Err(self.attr_error(
                n,
                "value",
                "monochromatic: 0.6 then keeps one colour channel's coefficients for a \
                 per-channel render; hppm renders all channels at once (remove it)",
            ));
        }
        Ok(())
    }

    /// `<volume type="gridvolume">`: its `.vol` file (relative to the scene's folder), placed by
    /// `to_world` (and the file's box with `use_grid_bbox`), filtered and wrapped as Mitsuba's
    /// gridvolume does (src/scene/grid.rs).
    fn grid_volume(&self, node: Node<'a, 'input>) -> Result<Density, SceneError> {
        let mut props = self.props(node, &[])?;
        let file_node = props.take("filename").ok_or_else(|| {
            self.error(
                node,
                "<volume type=\"gridvolume\"> needs a \"filename\" (a .vol file)",
            )
        })?;
        let filename = self.string(file_node)?;
        let to_world = props
            .take("to_world")
            .map(|n| self.transform(n))
            .transpose()?
            .unwrap_or(Mat4::IDENTITY);
        let mut choice = |name: &str, options: &[&str]| -> Result<usize, SceneError> {
            let Some(n) = props.take(name) else {
                return Ok(0);
            };
            let value = self.string(n)?;
            options.iter().position(|o| *o == value).ok_or_else(|| {
                self.attr_error(
                    n,
                    "value",
                    format!("{name} \"{value}\": expected {}", options.join(" or ")),
                )
            })
        };
        let filter = match choice("filter_type", &["trilinear", "nearest"])? {
            1 => FilterType::Nearest,
            _ => FilterType::Trilinear,
        };
        let wrap = match choice("wrap_mode", &["clamp", "repeat", "mirror"])? {
            1 => WrapMode::Repeat,
            2 => WrapMode::Mirror,
            _ => WrapMode::Clamp,
        };
        let legacy = self.legacy(node);
        // 0.6 places the grid in the box its file gives (or `min`/`max`), Mitsuba 3 in the
        // unit cube unless asked.
        let use_bbox = props
            .take("use_grid_bbox")
            .map(|n| self.boolean(n))
            .transpose()?
            .unwrap_or(legacy);
        let legacy_box = if legacy {
            self.ignore(&mut props, &["send_data"], |r, n| r.boolean(n).map(drop))?;
            match (props.take("min"), props.take("max")) {
                (Some(lo), Some(hi)) => Some((self.point(lo)?, self.point(hi)?)),
                (None, None) => None,
                (Some(one), None) | (None, Some(one)) => {
                    return Err(self.error(
                        one,
                        "a gridvolume's box needs both \"min\" and \"max\" (0.6 ignores one alone)",
                    ));
                }
            }
        } else {
            None
        };
        // `raw` changes only spectral variants' colours; `accel` only Mitsuba's GPU lookups.
        self.ignore(&mut props, &["raw", "accel"], |r, n| r.boolean(n).map(drop))?;
        self.finish(props, node)?;
        if to_world.determinant().abs() < 1e-30 || !to_world.is_finite() {
            return Err(self.error(node, "the gridvolume's to_world is not invertible"));
        }
        let path = self.existing_file(file_node, self.relative(&filename));
        let mut grid = crate::loaders::vol::read_vol(&path)
            .map_err(|why| self.attr_error(file_node, "value", format!("{filename}: {why}")))?;
        if let Some((lo, hi)) = legacy_box {
            (grid.bbox_min, grid.bbox_max) = (lo, hi);
        }
        let mut to_local = to_world.inverse();
        if use_bbox {
            let bbox = grid.bbox_transform().ok_or_else(|| {
                self.error(
                    node,
                    format!(
                        "{filename}: use_grid_bbox with a box that is not one (a side not positive)"
                    ),
                )
            })?;
            to_local = bbox * to_local;
        }
        if legacy {
            // 0.6 puts the first and last voxels' values at the box's faces, Mitsuba 3 (and
            // hppm's lookup) at half a voxel inside them.
            let size = Vec3::from(grid.size.map(|n| n as f32));
            let to_centres = Mat4::from_translation(0.5 / size)
                * Mat4::from_scale((size - 1.0).max(Vec3::ZERO) / size);
            to_local = to_centres * to_local;
            self.upgrade(
                node,
                "gridvolume: placed as 0.6 places it (the file's box or min/max, with voxel \
                 values at the box's faces)",
            );
        }
        Ok(Density {
            grid: Arc::new(grid),
            to_local,
            filter,
            wrap,
        })
    }

    /// `<phase type=...>`: isotropic, hg (`g`, default 0.8, in (-1, 1)) or rayleigh.
    pub(super) fn read_phase(&self, node: Node<'a, 'input>) -> Result<Phase, SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        let phase = match kind.as_str() {
            "isotropic" => Phase::Isotropic,
            "rayleigh" => Phase::Rayleigh,
            "hg" => {
                let g = match props.take("g") {
                    Some(n) => {
                        let g = self.float(n)?;
                        if !(g > -1.0 && g < 1.0) {
                            return Err(self.attr_error(
                                n,
                                "value",
                                format!("g {g}: expected a number between -1 and 1, exclusive (as Mitsuba requires)"),
                            ));
                        }
                        g
                    }
                    None => 0.8,
                };
                Phase::HenyeyGreenstein { g }
            }
            other => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "phase function type \"{other}\" is not supported (hppm reads isotropic, hg and rayleigh)"
                    ),
                ));
            }
        };
        self.finish(props, node)?;
        Ok(phase)
    }

    /// `<ref id=...>` to a medium declared before.
    pub(super) fn medium_ref(&self, node: Node) -> Result<u32, SceneError> {
        let id = self.required_attr(node, "id")?;
        self.named_media
            .get(&id)
            .ok_or_else(|| self.missing_ref(node, &id, "medium", &format!("<ref id=\"{id}\">")))
    }

    /// A medium given inside an object: a nested `<medium>` or a `<ref>` to one.
    pub(super) fn nested_medium(&self, node: Node<'a, 'input>) -> Result<u32, SceneError> {
        if node.has_tag_name("ref") {
            self.medium_ref(node)
        } else {
            self.read_medium(node)
        }
    }
}

/// Single-scattering albedo sigma_s / sigma_t per channel (0 where nothing is there).
fn albedo_of(sigma_s: Vec3, sigma_t: Vec3) -> Vec3 {
    Vec3::select(sigma_t.cmpgt(Vec3::ZERO), sigma_s / sigma_t, Vec3::ZERO)
}
