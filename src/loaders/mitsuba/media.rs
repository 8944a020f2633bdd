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
        let albedo = self.medium_coefficient(&mut props, &volumes, "albedo", 0.75)?;
        // A heterogeneous medium's extinction may be a grid: sigma_t is then 1 times it.
        let grid_node = volumes.iter().copied().find(|v| {
            v.attribute("name") == Some("sigma_t") && v.attribute("type") == Some("gridvolume")
        });
        let density = match grid_node {
            Some(v) if kind == "heterogeneous" => {
                // Taken off the list of props as the coefficient would be.
                props.take("sigma_t");
                Some(self.grid_volume(v)?)
            }
            _ => None,
        };
        let sigma_t = if density.is_some() {
            Vec3::ONE
        } else {
            self.medium_coefficient(&mut props, &volumes, "sigma_t", 1.0)?
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
        self.finish(props, node)?;
        if let Some(v) = volumes
            .iter()
            .find(|v| !matches!(v.attribute("name"), Some("albedo" | "sigma_t")))
        {
            return Err(self.error(
                *v,
                format!(
                    "{}: a homogeneous medium takes a volume as \"albedo\" or \"sigma_t\" only",
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
        let use_bbox = props
            .take("use_grid_bbox")
            .map(|n| self.boolean(n))
            .transpose()?
            .unwrap_or(false);
        // `raw` changes only spectral variants' colours; `accel` only Mitsuba's GPU lookups.
        self.ignore(&mut props, &["raw", "accel"], |r, n| r.boolean(n).map(drop))?;
        self.finish(props, node)?;
        if to_world.determinant().abs() < 1e-30 || !to_world.is_finite() {
            return Err(self.error(node, "the gridvolume's to_world is not invertible"));
        }
        let grid = crate::loaders::vol::read_vol(&self.relative(&filename))
            .map_err(|why| self.attr_error(file_node, "value", format!("{filename}: {why}")))?;
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
        Ok(Density {
            grid: Arc::new(grid),
            to_local,
            filter,
            wrap,
        })
    }

    /// `<phase type=...>`: isotropic, hg (`g`, default 0.8, in (-1, 1)) or rayleigh.
    fn read_phase(&self, node: Node<'a, 'input>) -> Result<Phase, SceneError> {
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
