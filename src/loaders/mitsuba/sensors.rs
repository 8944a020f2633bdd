//! The integrator (its path depths), the sensor (perspective and thin lens), sampler, film and
//! pixel filter, as Mitsuba's src/integrators, src/sensors, src/samplers, src/films and
//! src/rfilters read them.

use super::*;

impl<'a, 'input> Reader<'a, 'input> {
    pub(super) fn read_integrator(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        if std::mem::replace(&mut self.has_integrator, true) {
            return Err(self.error(node, "a second <integrator>: only one is allowed"));
        }
        self.read_integrator_settings(node)
    }

    /// The integrator's settings. In hppm the render graph chooses the algorithm, so any
    /// integrator is advice: its path depths and `hide_emitters` are taken, the rest of another
    /// integrator's properties belong to its algorithm and are left with one warning. One that
    /// wraps another (`aov`, `moment`) gives the wrapped one's settings.
    pub(super) fn read_integrator_settings(
        &mut self,
        node: Node<'a, 'input>,
    ) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let nested = self.single_child(node, "integrator")?;
        let mut props = self.props(node, &["integrator"])?;
        if let Some(n) = props.take("max_depth") {
            self.scene.integrator.max_depth = match self.integer(n)? {
                -1 => None,
                d => Some(self.depth(n, d, "max_depth")?),
            };
        } else if kind == "direct" {
            // Emitters seen directly and lit directly: paths of at most two segments.
            self.scene.integrator.max_depth = Some(2);
        }
        if let Some(n) = props.take("rr_depth") {
            let d = self.integer(n)?;
            self.scene.integrator.rr_depth = Some(self.depth(n, d, "rr_depth")?);
        }
        // Russian roulette that can never start is no roulette.
        if let (Some(max), Some(rr)) = (
            self.scene.integrator.max_depth,
            self.scene.integrator.rr_depth,
        ) && rr >= max
        {
            self.scene.integrator.rr_depth = None;
        }
        if let Some(n) = props.take("hide_emitters") {
            self.scene.integrator.hide_emitters = self.boolean(n)?;
        }
        // Media are rendered as `volpath` renders them (and its depth rule): its settings are
        // hppm's whatever the scene holds.
        if matches!(kind.as_str(), "path" | "volpath" | "volpathmis") {
            return self.finish(props, node);
        }
        self.note_read(&props, node);
        let mut message = format!(
            "integrator \"{kind}\": the render graph chooses the algorithm; rendering with \
             its path depths"
        );
        if kind == "direct" {
            message.push_str(" (direct lighting only: max_depth 2)");
        }
        if !props.entries.is_empty() {
            let rest: Vec<&str> = props.entries.iter().map(|(n, _)| n.as_str()).collect();
            message.push_str(&format!(", without {}", rest.join(", ")));
        }
        self.warn(node, message);
        match nested {
            Some(inner) => self.read_integrator_settings(inner),
            None => Ok(()),
        }
    }

    /// A path depth: at least 1 (-1 for "unbounded" is handled by the caller).
    pub(super) fn depth(&self, node: Node, depth: i64, name: &str) -> Result<u32, SceneError> {
        u32::try_from(depth)
            .ok()
            .filter(|d| (1..u32::MAX).contains(d))
            .ok_or_else(|| {
                self.attr_error(
                    node,
                    "value",
                    format!("{name} {depth}: expected -1 (unbounded) or at least 1"),
                )
            })
    }

    pub(super) fn read_sensor(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        if std::mem::replace(&mut self.has_sensor, true) {
            return Err(self.error(node, "a second <sensor>: only one is supported"));
        }
        let kind = self.required_attr(node, "type")?;
        if kind != "perspective" && kind != "thinlens" {
            return Err(self.attr_error(
                node,
                "type",
                format!(
                    "sensor type \"{kind}\" is not supported (only \"perspective\" and \
                     \"thinlens\")"
                ),
            ));
        }
        // The film first: the fov conversion needs its aspect ratio.
        let sampler = self.single_child(node, "sampler")?;
        let film = self.single_child(node, "film")?;
        // A failed sampler or film is reported and the sensor read on, so that its other
        // problems are listed too.
        if let Some(s) = sampler {
            let read = self.read_sampler(s);
            self.keep(read);
        }
        if let Some(f) = film {
            let read = self.read_film(f);
            self.keep(read);
        }
        let mut props = self.props(node, &["sampler", "film", "ref", "medium"])?;
        self.read_sensor_medium(node)?;
        let view = self.view_angle(&mut props, node)?;
        // Checked as Mitsuba checks them, not applied: camera rays are not cut at the clip
        // planes (only what lies within near_clip of the camera or beyond far_clip would show
        // the difference), and nothing moves while the shutter is open.
        let near = props.take("near_clip");
        let far = props.take("far_clip");
        let near_clip = near.map(|n| self.float(n)).transpose()?.unwrap_or(0.01);
        let far_clip = far.map(|n| self.float(n)).transpose()?.unwrap_or(1e4);
        if let Some(n) = near
            && (near_clip <= 0.0 || near_clip.is_nan())
        {
            return Err(self.attr_error(
                n,
                "value",
                format!("near_clip {near_clip}: expected more than 0 (Mitsuba refuses it too)"),
            ));
        }
        if let Some(n) = far.or(near)
            && (near_clip >= far_clip || far_clip.is_nan())
        {
            return Err(self.attr_error(
                n,
                "value",
                format!(
                    "near_clip {near_clip} is not below far_clip {far_clip} (Mitsuba refuses it \
                     too)"
                ),
            ));
        }
        let focus = props.take("focus_distance");
        let focus_distance = focus.map(|n| self.float(n)).transpose()?;
        self.ignore(&mut props, &["shutter_open", "shutter_close"], |r, n| {
            r.float(n).map(drop)
        })?;
        if kind == "thinlens" {
            // Mitsuba focuses on the far clip plane unless told.
            let focus_distance = focus_distance.unwrap_or(far_clip);
            self.scene.camera.lens = self.read_lens(node, &mut props, focus, focus_distance)?;
        } else {
            // A pinhole renders everything in focus, so the focal distance changes nothing.
            for name in ["principal_point_offset_x", "principal_point_offset_y"] {
                if let Some(n) = props.take(name)
                    && self.float(n)? != 0.0
                {
                    return Err(self.attr_error(
                        n,
                        "value",
                        format!("{name}: an off-centre principal point is not supported"),
                    ));
                }
            }
        }
        if let Some(n) = props.take("srf") {
            self.warn(
                n,
                "sensor srf: a spectral response applies to spectral rendering only; hppm \
                 renders RGB, as Mitsuba's RGB variants do, without it",
            );
        }
        if let Some(n) = props.take("to_world") {
            self.read_camera_transform(n)?;
        }
        self.finish(props, node)?;
        // The fov is the whole film's, whatever window of it a crop renders.
        let camera = &self.scene.camera;
        let (film_w, film_h) = camera.crop.map_or((camera.width, camera.height), |c| {
            (c.film_width, c.film_height)
        });
        let aspect = film_w as f64 / film_h as f64;
        self.scene.camera.fov_x_deg =
            self.horizontal_fov(view.axis_node, view.fov, &view.axis, aspect)?;
        Ok(())
    }

    /// A camera's or projector's view angle as given: `fov` along `fov_axis` (x by default),
    /// or a 35 mm `focal_length` (50 mm by default) as a diagonal fov; both together are
    /// refused, as Mitsuba refuses them.
    pub(super) fn view_angle(
        &self,
        props: &mut Props<'a, 'input>,
        node: Node<'a, 'input>,
    ) -> Result<ViewAngle<'a, 'input>, SceneError> {
        let fov = props
            .take("fov")
            .map(|n| self.float(n).map(|v| (n, v)))
            .transpose()?;
        let fov_axis = props
            .take("fov_axis")
            .map(|n| self.string(n).map(|v| (n, v)))
            .transpose()?;
        match (fov, props.take("focal_length")) {
            (Some((n, _)), Some(_)) => Err(self.error(
                n,
                "give either fov or focal_length, not both (Mitsuba refuses both too)",
            )),
            (Some((n, fov)), None) => {
                let (axis_node, axis) = match fov_axis {
                    Some((axis_node, axis)) => (axis_node, axis.to_ascii_lowercase()),
                    None => (n, "x".to_string()),
                };
                Ok(ViewAngle {
                    fov: fov as f64,
                    axis_node,
                    axis,
                })
            }
            (None, focal) => Ok(ViewAngle {
                fov: match focal {
                    Some(n) => self.focal_length_fov(n)?,
                    None => focal_length_to_fov(50.0),
                },
                axis_node: node,
                axis: "diagonal".to_string(),
            }),
        }
    }

    /// A `thinlens` sensor's lens: `aperture_radius` (which Mitsuba requires) and the focus
    /// distance. A zero aperture is a pinhole (Mitsuba warns and uses a radius of 1e-7).
    pub(super) fn read_lens(
        &self,
        sensor: Node,
        props: &mut Props<'a, 'input>,
        focus: Option<Node>,
        focus_distance: f32,
    ) -> Result<Option<Lens>, SceneError> {
        let Some(n) = props.take("aperture_radius") else {
            return Err(self.error(
                sensor,
                "a thinlens sensor needs aperture_radius (Mitsuba has no default for it)",
            ));
        };
        let aperture_radius = self.float(n)?;
        if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
            return Err(self.attr_error(
                n,
                "value",
                format!("aperture_radius {aperture_radius}: expected 0 or more scene units"),
            ));
        }
        // Without one the default (far_clip) is already checked to lie beyond near_clip > 0.
        if let Some(f) = focus
            && !(focus_distance > 0.0 && focus_distance.is_finite())
        {
            return Err(self.attr_error(
                f,
                "value",
                format!(
                    "focus_distance {focus_distance}: expected a positive distance along the view"
                ),
            ));
        }
        if aperture_radius == 0.0 {
            self.warn(
                n,
                "aperture_radius 0: rendered as a pinhole (Mitsuba warns and uses 1e-7)",
            );
            return Ok(None);
        }
        Ok(Some(Lens {
            aperture_radius,
            focus_distance,
        }))
    }

    /// `focal_length` ("50mm", or a bare number of millimetres) as the diagonal field of view
    /// of a 36 x 24 mm frame.
    pub(super) fn focal_length_fov(&self, node: Node) -> Result<f64, SceneError> {
        let text = self.string(node)?;
        let millimetres = text.trim().strip_suffix("mm").unwrap_or(text.trim());
        match millimetres.trim().parse::<f64>() {
            Ok(f) if f > 0.0 => Ok(focal_length_to_fov(f)),
            _ => Err(self.attr_error(
                node,
                "value",
                format!("focal_length \"{text}\": expected millimetres, such as 50mm"),
            )),
        }
    }

    /// The child of `node` with tag `tag`, if any; two are an error.
    pub(super) fn single_child(
        &self,
        node: Node<'a, 'input>,
        tag: &str,
    ) -> Result<Option<Node<'a, 'input>>, SceneError> {
        let mut found = node.children().filter(|c| c.has_tag_name(tag));
        let first = found.next();
        if let Some(second) = found.next() {
            return Err(self.error(
                second,
                format!("a second <{tag}> in {}", describe_object(node)),
            ));
        }
        Ok(first)
    }

    pub(super) fn read_camera_transform(&mut self, node: Node) -> Result<(), SceneError> {
        let m = self.transform(node)?;
        // The camera is stored as origin/target/up, which cannot express a mirror image.
        if Mat3::from_mat4(m).determinant() < 0.0 {
            return Err(self.error(
                node,
                "a mirroring sensor to_world (negative determinant) is not supported",
            ));
        }
        let camera = &mut self.scene.camera;
        camera.origin = m.transform_point3(Vec3::ZERO);
        camera.target = m.transform_point3(Vec3::Z);
        camera.up = m.transform_vector3(Vec3::Y);
        // Far from the origin a unit step rounds away in f32 and the view direction vanishes.
        let view = camera.target - camera.origin;
        if !(view.is_finite() && view.cross(camera.up).length_squared() > 0.0) {
            return Err(self.error(
                node,
                "the sensor's to_world gives no view direction in f32 (an origin too far from 0, \
                 or a zero scale)",
            ));
        }
        let reach = camera.origin.abs().max_element() as f64;
        if let Some(message) = crate::scene::beyond_extent("the camera", reach) {
            return Err(self.error(node, message));
        }
        Ok(())
    }

    /// The horizontal fov for a `fov` given along `axis` (x, y, diagonal, smaller or larger)
    /// of a film of `aspect` (width / height), as Mitsuba's projective cameras convert it.
    pub(super) fn horizontal_fov(
        &self,
        node: Node,
        fov: f64,
        axis: &str,
        aspect: f64,
    ) -> Result<f32, SceneError> {
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.attr_error(
                node,
                "value",
                format!("fov {fov}: expected degrees between 0 and 180"),
            ));
        }
        let half_tan = (fov.to_radians() * 0.5).tan();
        let axis = match axis {
            "smaller" if aspect > 1.0 => "y",
            "smaller" => "x",
            "larger" if aspect > 1.0 => "x",
            "larger" => "y",
            other => other,
        };
        let x_half_tan = match axis {
            "x" => half_tan,
            "y" => half_tan * aspect,
            "diagonal" => half_tan / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
            other => {
                return Err(self.attr_error(
                    node,
                    "value",
                    format!("fov_axis \"{other}\": expected x, y, diagonal, smaller or larger"),
                ));
            }
        };
        Ok((2.0 * x_half_tan.atan()).to_degrees() as f32)
    }

    /// Any sampler gives the sample count; hppm draws independent random numbers, so another
    /// sampler's pattern (stratified, low-discrepancy) is left with a warning.
    pub(super) fn read_sampler(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        if let Some(n) = props.take("sample_count") {
            let spp = self.integer(n)?;
            let spp = u32::try_from(spp).ok().filter(|&s| s >= 1).ok_or_else(|| {
                self.attr_error(
                    n,
                    "value",
                    format!("sample_count {spp}: expected at least 1"),
                )
            })?;
            self.scene.spp_hint = Some(spp);
        }
        self.ignore(&mut props, &["seed"], |r, n| r.integer(n).map(drop))?;
        if kind == "independent" {
            return self.finish(props, node);
        }
        self.note_read(&props, node);
        self.warn(
            node,
            format!(
                "sampler \"{kind}\": hppm draws independent samples; its sample_count is taken, \
                 its pattern is not"
            ),
        );
        Ok(())
    }

    pub(super) fn read_film(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let legacy_film = self.legacy(node) && matches!(kind.as_str(), "ldrfilm" | "tiledhdrfilm");
        if kind != "hdrfilm" && !legacy_film {
            let old = if self.legacy(node) {
                " and Mitsuba 0.6's \"ldrfilm\" and \"tiledhdrfilm\""
            } else {
                ""
            };
            return Err(self.attr_error(
                node,
                "type",
                format!("film type \"{kind}\" is not supported (only \"hdrfilm\"{old})"),
            ));
        }
        if legacy_film {
            self.upgrade(
                node,
                format!(
                    "film \"{kind}\": read as hdrfilm (hppm's image is linear radiance; its \
                     PNG output applies the sRGB curve)"
                ),
            );
        }
        if let Some(filter) = self.single_child(node, "rfilter")? {
            match self.read_rfilter(filter) {
                Ok(filter) => self.scene.camera.filter = filter,
                // Reported, and the film read on for its other problems.
                Err(e) => self.report(e),
            }
        }
        let mut props = self.props(node, &["rfilter"])?;
        if let Some(n) = props.take("width") {
            self.scene.camera.width = self.film_side(n, "width")?;
        }
        if let Some(n) = props.take("height") {
            self.scene.camera.height = self.film_side(n, "height")?;
        }
        self.ignore(
            &mut props,
            &["pixel_format", "component_format", "file_format"],
            |r, n| r.string(n).map(drop),
        )?;
        if self.legacy(node) {
            self.drop_legacy_film(&mut props, &kind)?;
        }
        if let Some(n) = props.take("compensate") {
            self.boolean(n)?;
            self.warn(
                n,
                "hdrfilm compensate: Mitsuba 3 removed error-compensated accumulation and \
                 ignores it; so does hppm",
            );
        }
        if let Some(n) = props.take("sample_border") {
            self.scene.camera.sample_border = self.boolean(n)?;
        }
        let (x, width) = self.crop_window(
            self.scene.camera.width,
            ("crop_offset_x", props.take("crop_offset_x")),
            ("crop_width", props.take("crop_width")),
        )?;
        let (y, height) = self.crop_window(
            self.scene.camera.height,
            ("crop_offset_y", props.take("crop_offset_y")),
            ("crop_height", props.take("crop_height")),
        )?;
        let camera = &mut self.scene.camera;
        if (x, y, width, height) != (0, 0, camera.width, camera.height) {
            camera.crop = Some(Crop {
                film_width: camera.width,
                film_height: camera.height,
                x,
                y,
            });
            camera.width = width;
            camera.height = height;
        }
        self.finish(props, node)
    }

    /// What 0.6's films read for their output files only: `ldrfilm`'s tonemapping and any
    /// film's `gamma` (0.6's hdrfilm ignored it). Each is noted; a tonemap that would change
    /// the PNG 0.6 wrote is a warning.
    fn drop_legacy_film(
        &self,
        props: &mut Props<'a, 'input>,
        kind: &str,
    ) -> Result<(), SceneError> {
        if let Some(n) = props.take("gamma") {
            let gamma = self.float(n)?;
            if kind == "ldrfilm" && gamma > 0.0 {
                self.warn(
                    n,
                    format!(
                        "ldrfilm gamma {gamma}: 0.6 encoded its PNG with this gamma; hppm's \
                         image is linear (EXR) or sRGB-encoded (PNG)"
                    ),
                );
            } else {
                self.upgrade(
                    n,
                    format!("{kind} gamma: read by 0.6 for low dynamic range output only; ignored"),
                );
            }
        }
        if kind != "ldrfilm" {
            return Ok(());
        }
        let tonemap = match props.take("tonemap_method") {
            Some(n) => (self.string(n)?, Some(n)),
            None => ("gamma".to_string(), None),
        };
        for (name, neutral) in [("exposure", 0.0), ("key", 0.18), ("burn", 0.0)] {
            let Some(n) = props.take(name) else { continue };
            let value = self.float(n)?;
            let used = (name == "exposure") == (tonemap.0 == "gamma");
            if used && value != neutral {
                self.warn(
                    n,
                    format!(
                        "ldrfilm {name} {value}: 0.6 tonemapped its PNG with it; hppm writes the \
                         image untonemapped"
                    ),
                );
            } else {
                self.upgrade(
                    n,
                    format!("ldrfilm {name}: no effect on the image; ignored"),
                );
            }
        }
        if let (method, Some(n)) = tonemap {
            if method == "reinhard" {
                self.warn(
                    n,
                    "ldrfilm tonemap_method \"reinhard\": 0.6 tonemapped its PNG; hppm writes the \
                     image untonemapped",
                );
            } else if method != "gamma" {
                return Err(self.attr_error(
                    n,
                    "value",
                    format!("tonemap_method \"{method}\": 0.6 knows \"gamma\" and \"reinhard\""),
                ));
            }
        }
        Ok(())
    }

    /// One axis of hdrfilm's crop window, (offset, size) on a film `film` pixels long: Mitsuba's
    /// defaults (offset 0, the whole film) and its rule that the window lies inside the film.
    pub(super) fn crop_window(
        &self,
        film: u32,
        (offset_name, offset): (&str, Option<Node>),
        (size_name, size): (&str, Option<Node>),
    ) -> Result<(u32, u32), SceneError> {
        let read = |name: &str, node: Node, least: i64| -> Result<u32, SceneError> {
            let v = self.integer(node)?;
            if v < least || v > film as i64 {
                return Err(self.attr_error(
                    node,
                    "value",
                    format!("{name} {v}: expected {least} to {film} (the film's side)"),
                ));
            }
            Ok(v as u32)
        };
        let at = offset
            .map(|n| read(offset_name, n, 0))
            .transpose()?
            .unwrap_or(0);
        // Mitsuba's default size is the whole film even beside an offset (the window then runs
        // off the film, which it refuses).
        let length = size
            .map(|n| read(size_name, n, 1))
            .transpose()?
            .unwrap_or(film);
        // Past the film only with an offset given: blame the size if given, else the offset.
        if let Some(blame) = size.or(offset)
            && at as u64 + length as u64 > film as u64
        {
            return Err(self.attr_error(
                blame,
                "value",
                format!(
                    "crop window: {offset_name} {at} + {size_name} {length} runs past the \
                     film's {film} pixels (Mitsuba refuses it too)"
                ),
            ));
        }
        Ok((at, length))
    }

    pub(super) fn film_side(&self, node: Node, name: &str) -> Result<u32, SceneError> {
        let v = self.integer(node)?;
        if !(1..=crate::scene::MAX_FILM_SIDE as i64).contains(&v) {
            return Err(self.attr_error(
                node,
                "value",
                format!(
                    "film {name} {v}: expected 1 to {} pixels",
                    crate::scene::MAX_FILM_SIDE
                ),
            ));
        }
        Ok(v as u32)
    }

    /// `box`, `tent` (`radius`), `gaussian` (`stddev`), `lanczos` (`lobes`), `mitchell` (`B`,
    /// `C`) or `catmullrom`, with Mitsuba 3's defaults.
    pub(super) fn read_rfilter(&self, node: Node<'a, 'input>) -> Result<PixelFilter, SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        let filter = match kind.as_str() {
            "box" => PixelFilter::Box,
            "tent" => PixelFilter::Tent {
                radius: self.filter_width(&mut props, "radius", DEFAULT_TENT_RADIUS)?,
            },
            "gaussian" => PixelFilter::Gaussian {
                stddev: self.filter_width(&mut props, "stddev", DEFAULT_GAUSSIAN_STDDEV)?,
            },
            "lanczos" => PixelFilter::Lanczos {
                lobes: self.lanczos_lobes(&mut props)?,
            },
            "mitchell" => {
                let mut coefficient = |name: &str| match props.take(name) {
                    Some(n) => self.float(n),
                    None => Ok(DEFAULT_MITCHELL_B_C),
                };
                PixelFilter::Mitchell {
                    b: coefficient("B")?,
                    c: coefficient("C")?,
                }
            }
            "catmullrom" => PixelFilter::CATMULL_ROM,
            other => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "rfilter \"{other}\" is not supported ({})",
                        plugins::kinds_of("rfilter")
                    ),
                ));
            }
        };
        self.finish(props, node)?;
        Ok(filter)
    }

    /// Lanczos's lobes (its radius in pixels): Mitsuba's default 3, at most 16 as for the other
    /// filters' widths.
    pub(super) fn lanczos_lobes(&self, props: &mut Props) -> Result<u32, SceneError> {
        let Some(n) = props.take("lobes") else {
            return Ok(DEFAULT_LANCZOS_LOBES);
        };
        let v = self.integer(n)?;
        if !(1..=MAX_FILTER_WIDTH as i64).contains(&v) {
            return Err(self.attr_error(
                n,
                "value",
                format!("rfilter lobes {v}: expected 1 to {MAX_FILTER_WIDTH} lobes"),
            ));
        }
        Ok(v as u32)
    }

    /// A filter's radius or standard deviation: positive, and at most 16 pixels (a sanity
    /// bound: wider filters blur the image away and only typos ask for them).
    pub(super) fn filter_width(
        &self,
        props: &mut Props,
        name: &str,
        default: f32,
    ) -> Result<f32, SceneError> {
        let Some(n) = props.take(name) else {
            return Ok(default);
        };
        let v = self.float(n)?;
        if !(v > 0.0 && v <= MAX_FILTER_WIDTH) {
            return Err(self.attr_error(
                n,
                "value",
                format!(
                    "rfilter {name} {v}: expected more than 0 and at most {MAX_FILTER_WIDTH} pixels"
                ),
            ));
        }
        Ok(v)
    }

    /// The medium around the sensor (a nested `<medium>` or a `<ref>` to one, any name, as
    /// Mitsuba's endpoints take it): where camera paths start.
    fn read_sensor_medium(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let mut media = node
            .children()
            .filter(|c| c.has_tag_name("medium") || c.has_tag_name("ref"));
        let Some(first) = media.next() else {
            return Ok(());
        };
        if let Some(second) = media.next() {
            return Err(self.error(
                second,
                "a second medium in <sensor>: a sensor has one (as Mitsuba requires)",
            ));
        }
        self.scene.media.camera = Some(self.nested_medium(first)?);
        Ok(())
    }
}
