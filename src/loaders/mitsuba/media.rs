//! Participating media as Mitsuba 3's src/media and src/phase read them: `homogeneous` media
//! (their coefficients as numbers, colours or a `constvolume`), phase functions `isotropic`,
//! `hg` and `rayleigh`, declared at top level with an id or nested where they are used (a
//! shape's `interior` / `exterior`, the sensor's medium).

use super::*;
use crate::scene::medium::{Medium, Phase};

/// What a homogeneous medium's coefficient may be given as.
const COEFFICIENT_TAGS: &[&str] = &["float", "rgb", "spectrum"];

impl<'a, 'input> Reader<'a, 'input> {
    /// A top-level `<medium id=...>`, for `<ref>`s after it.
    pub(super) fn read_named_medium(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let id = self.attr(node, "id")?;
        if let Some(id) = &id
            && self.named_media.contains_key(id)
        {
            return Err(self.attr_error(
                node,
                "id",
                format!("a second <medium id=\"{id}\">: ids must be unique"),
            ));
        }
        let index = self.read_medium(node).inspect_err(|_| {
            if let Some(id) = &id {
                self.failed_ids.insert(id.clone(), self.location(node).line);
            }
        })?;
        if let Some(id) = id {
            self.named_media.insert(id, index);
        }
        Ok(())
    }

    /// A `<medium>` element: its index in the scene's media.
    pub(super) fn read_medium(&self, node: Node<'a, 'input>) -> Result<u32, SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "homogeneous" {
            let why = if kind == "heterogeneous" {
                "heterogeneous media (grid volumes) are not supported yet"
            } else {
                "unknown medium type"
            };
            return Err(self.attr_error(
                node,
                "type",
                format!("medium type \"{kind}\": {why} (hppm reads \"homogeneous\")"),
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
        let sigma_t = self.medium_coefficient(&mut props, &volumes, "sigma_t", 1.0)?;
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
        if let Some(v) = volumes.iter().find(|v| {
            !matches!(v.attribute("name"), Some("albedo" | "sigma_t"))
        }) {
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
        let volume = volumes
            .iter()
            .find(|v| v.attribute("name") == Some(name));
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
    fn constant_volume(&self, node: Node<'a, 'input>) -> Result<(Vec3, Node<'a, 'input>), SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "constvolume" {
            let why = if kind == "gridvolume" {
                "grid volumes are not supported yet"
            } else {
                "unknown volume type"
            };
            return Err(self.attr_error(
                node,
                "type",
                format!("volume type \"{kind}\": {why} (hppm reads \"constvolume\")"),
            ));
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
        self.named_media.get(&id).copied().ok_or_else(|| {
            self.missing_ref(node, &id, "medium", &format!("<ref id=\"{id}\">"))
        })
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
