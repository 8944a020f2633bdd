//! Emitters as Mitsuba's src/emitters reads them: area, point, spot, projector, directional,
//! constant, envmap and sunsky.

use super::*;

impl<'a, 'input> Reader<'a, 'input> {
    pub(super) fn read_area_emitter(&self, node: Node<'a, 'input>) -> Result<Vec3, SceneError> {
        let kind = self.required_attr(node, "type")?;
        if kind != "area" {
            return Err(self.attr_error(
                node,
                "type",
                format!("emitter type \"{kind}\" inside a shape: only \"area\" is supported"),
            ));
        }
        let mut props = self.props(node, &[])?;
        self.ignore_sampling_weight(&mut props)?;
        // Mitsuba's default radiance is 1.
        let radiance = match props.take("radiance") {
            Some(n) => self.non_negative_color(n)?,
            None => Vec3::ONE,
        };
        self.finish(props, node)?;
        Ok(radiance)
    }

    /// Mitsuba's `sampling_weight` of an emitter: how often its light sampling picks it, which
    /// changes only its noise. hppm picks lights by power; the value is checked and dropped.
    pub(super) fn ignore_sampling_weight(&self, props: &mut Props) -> Result<(), SceneError> {
        if let Some(n) = props.take("sampling_weight") {
            let v = self.float(n)?;
            if !(v >= 0.0 && v.is_finite()) {
                return Err(self.attr_error(
                    n,
                    "value",
                    format!("sampling_weight {v}: expected a number of 0 or more"),
                ));
            }
        }
        Ok(())
    }

    /// A scene-level emitter: `point`, `spot`, `directional`, `constant` or `envmap`.
    pub(super) fn read_emitter(&mut self, node: Node<'a, 'input>) -> Result<(), SceneError> {
        let kind = self.required_attr(node, "type")?;
        let mut props = self.props(node, &[])?;
        self.ignore_sampling_weight(&mut props)?;
        match kind.as_str() {
            "point" => self.read_point_light(&mut props, node)?,
            "spot" => self.read_spot_light(&mut props, node)?,
            "projector" => self.read_projector(&mut props, node)?,
            "directional" => self.read_directional_light(&mut props, node)?,
            "constant" | "envmap" | "sunsky" => {
                if self.scene.emitters.environment.is_some() {
                    return Err(self.error(
                        node,
                        "a second environment emitter (constant, envmap or sunsky): Mitsuba \
                         allows one per scene",
                    ));
                }
                let environment = match kind.as_str() {
                    "constant" => {
                        // A constant light looks the same turned any way.
                        if let Some(n) = props.take("to_world") {
                            self.transform(n)?;
                        }
                        Environment::Constant {
                            radiance: self.color_or(&mut props, "radiance", Vec3::ONE)?,
                        }
                    }
                    "envmap" => Environment::Map(self.read_envmap(&mut props, node)?),
                    _ => Environment::SunSky(Box::new(self.read_sunsky(&mut props, node)?)),
                };
                self.scene.emitters.environment = Some(environment);
            }
            "area" => {
                return Err(self.attr_error(
                    node,
                    "type",
                    "an \"area\" emitter goes inside the <shape> that emits",
                ));
            }
            _ => {
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "emitter type \"{kind}\" is not supported ({}; area inside a shape)",
                        plugins::kinds_of("emitter").replace("area, ", "")
                    ),
                ));
            }
        }
        self.finish(props, node)
    }

    /// A non-negative colour property, or `default` when it is absent.
    pub(super) fn color_or(
        &self,
        props: &mut Props,
        name: &str,
        default: Vec3,
    ) -> Result<Vec3, SceneError> {
        props
            .take(name)
            .map(|n| self.non_negative_color(n))
            .transpose()
            .map(|c| c.unwrap_or(default))
    }

    /// A float property in degrees, or `default`, as radians within [0, 180].
    pub(super) fn angle_or(
        &self,
        props: &mut Props,
        name: &str,
        default: f32,
    ) -> Result<f32, SceneError> {
        let Some(n) = props.take(name) else {
            return Ok(default.to_radians());
        };
        let degrees = self.float(n)?;
        if !(0.0..=180.0).contains(&degrees) {
            return Err(self.attr_error(
                n,
                "value",
                format!("{}: an angle from 0 to 180 degrees", describe(n)),
            ));
        }
        Ok(degrees.to_radians())
    }

    pub(super) fn check_light_reach(
        &self,
        node: Node,
        what: &str,
        position: Vec3,
    ) -> Result<(), SceneError> {
        let reach = position.abs().max_element() as f64;
        match crate::scene::beyond_extent(what, reach) {
            Some(message) => Err(self.error(node, message)),
            None => Ok(()),
        }
    }

    pub(super) fn read_point_light(
        &mut self,
        props: &mut Props,
        node: Node,
    ) -> Result<(), SceneError> {
        let mut position = props
            .take("position")
            .map(|n| self.point(n))
            .transpose()?
            .unwrap_or(Vec3::ZERO);
        if let Some(n) = props.take("to_world") {
            position = self.transform(n)?.transform_point3(position);
        }
        let intensity = self.color_or(props, "intensity", Vec3::ONE)?;
        self.check_light_reach(node, "this point light", position)?;
        self.scene.point_lights.push(PointLight {
            position,
            intensity,
        });
        Ok(())
    }

    /// A light's texture parameter `name`: a `<texture>` or `<ref>` to one (added to the
    /// scene's textures), as Mitsuba's spot requires ("must be spatially varying"); `None`
    /// when absent.
    pub(super) fn light_texture(
        &self,
        props: &mut Props<'a, 'input>,
        name: &str,
        what: &str,
    ) -> Result<Option<u32>, SceneError> {
        let Some(n) = props.take(name) else {
            return Ok(None);
        };
        match self.texture_node(n, name)? {
            Some((_, index)) => Ok(Some(index)),
            None => Err(self.error(
                n,
                format!(
                    "{}: {what}'s {name} must be a <texture> (bitmap or checkerboard) or a                      <ref> to one; Mitsuba refuses a constant here",
                    describe(n)
                ),
            )),
        }
    }

    /// Mitsuba's `spot`: it shines along `to_world`'s +z from its translation; a `texture`
    /// is laid across its local x and y.
    pub(super) fn read_spot_light(
        &mut self,
        props: &mut Props<'a, 'input>,
        node: Node,
    ) -> Result<(), SceneError> {
        let texture = self.light_texture(props, "texture", "a spot light")?;
        let to_world = match props.take("to_world") {
            Some(n) => {
                let m = self.transform(n)?;
                if !is_similarity(Mat3::from_mat4(m)) {
                    return Err(self.error(
                        n,
                        "a spot light's to_world must be a rotation, uniform scale and \
                         translation (its cone would not be round)",
                    ));
                }
                m
            }
            None => Mat4::IDENTITY,
        };
        let intensity = self.color_or(props, "intensity", Vec3::ONE)?;
        let cutoff = self.angle_or(props, "cutoff_angle", 20.0)?;
        let beam_width = self.angle_or(props, "beam_width", cutoff.to_degrees() * 0.75)?;
        if beam_width > cutoff {
            return Err(self.error(
                node,
                "beam_width is larger than cutoff_angle (Mitsuba requires beam_width <= \
                 cutoff_angle)",
            ));
        }
        let position = to_world.transform_point3(Vec3::ZERO);
        let axis = to_world.transform_vector3(Vec3::Z).normalize_or_zero();
        let frame = [Vec3::X, Vec3::Y].map(|v| to_world.transform_vector3(v).normalize_or_zero());
        self.check_light_reach(node, "this spot light", position)?;
        self.scene.emitters.spots.push(SpotLight {
            position,
            axis,
            intensity,
            cutoff,
            beam_width,
            frame,
            texture,
        });
        Ok(())
    }

    /// Mitsuba's `projector`: a pinhole at `to_world`'s translation facing its +z, projecting
    /// `irradiance` (a colour or a texture) times `scale` through the frustum of the
    /// perspective camera with the same `fov` / `fov_axis` / `focal_length` and an image of
    /// the texture's resolution.
    pub(super) fn read_projector(
        &mut self,
        props: &mut Props<'a, 'input>,
        node: Node<'a, 'input>,
    ) -> Result<(), SceneError> {
        let scale = match props.take("scale") {
            Some(n) => {
                let v = self.float(n)?;
                if v < 0.0 {
                    return Err(self.attr_error(n, "value", "scale must not be negative"));
                }
                v
            }
            None => 1.0,
        };
        let (irradiance, texture) = match props.take("irradiance") {
            None => (Vec3::ONE, None),
            Some(n) => match self.texture_node(n, "irradiance")? {
                Some((_, index)) => (Vec3::ONE, Some(index)),
                None => (self.non_negative_color(n)?, None),
            },
        };
        // Mitsuba's `Texture::resolution`: a bitmap's, (1, 1) for anything else.
        let aspect = match texture.and_then(|t| self.textures.borrow().get(t as usize).cloned()) {
            Some(Texture::Bitmap(b)) => b.width as f64 / b.height as f64,
            _ => 1.0,
        };
        let to_world = match props.take("to_world") {
            Some(n) => {
                let m = self.transform(n)?;
                let linear = Mat3::from_mat4(m);
                // Mitsuba's projector takes the local point's z and the transformed +z (not
                // normalised) as they come, and its photons' directions unnormalised: only a
                // unit scale makes the two agree.
                let unit = is_similarity(linear) && (linear.x_axis.length() - 1.0).abs() < 1e-3;
                if !unit {
                    return Err(self.error(
                        n,
                        "a projector's to_world must be a rotation and translation (Mitsuba's \
                         scaled projector disagrees with itself)",
                    ));
                }
                m
            }
            None => Mat4::IDENTITY,
        };
        let view = self.view_angle(props, node)?;
        let fov_x = self.horizontal_fov(view.axis_node, view.fov, &view.axis, aspect)?;
        let tan_half_fov = (fov_x.to_radians() * 0.5).tan();
        if !(tan_half_fov > 0.0 && tan_half_fov.is_finite()) {
            return Err(self.error(node, "the projector's field of view is empty or too wide"));
        }
        let position = to_world.transform_point3(Vec3::ZERO);
        let frame =
            [Vec3::X, Vec3::Y, Vec3::Z].map(|v| to_world.transform_vector3(v).normalize_or_zero());
        self.check_light_reach(node, "this projector", position)?;
        self.scene.emitters.projectors.push(Projector {
            position,
            frame,
            irradiance: irradiance * scale,
            texture,
            tan_half_fov,
            aspect: aspect as f32,
        });
        Ok(())
    }

    /// Mitsuba's `directional`: `direction` (or `to_world`'s +z) is where its light travels.
    pub(super) fn read_directional_light(
        &mut self,
        props: &mut Props,
        node: Node,
    ) -> Result<(), SceneError> {
        let direction = match (props.take("direction"), props.take("to_world")) {
            (Some(_), Some(n)) => {
                return Err(self.error(
                    n,
                    "give a directional light `direction` or `to_world`, not both",
                ));
            }
            (Some(n), None) => (self.point(n)?, n),
            (None, Some(n)) => (self.transform(n)?.transform_vector3(Vec3::Z), n),
            (None, None) => (Vec3::Z, node),
        };
        let Some(unit) = direction.0.try_normalize() else {
            return Err(self.error(direction.1, "the light's direction is zero"));
        };
        let irradiance = self.color_or(props, "irradiance", Vec3::ONE)?;
        self.scene.emitters.directionals.push(DirectionalLight {
            direction: unit,
            irradiance,
        });
        Ok(())
    }

    /// Mitsuba's `envmap`: a lat-long image (EXR, or Radiance HDR), times `scale`, turned by
    /// `to_world` (a rotation).
    pub(super) fn read_envmap(&self, props: &mut Props, node: Node) -> Result<EnvMap, SceneError> {
        let Some(file_node) = props.take("filename") else {
            return Err(self.error(
                node,
                "<emitter type=\"envmap\"> needs <string name=\"filename\" value=\"...\"/>",
            ));
        };
        let file = self.existing_file(file_node, self.relative(&self.string(file_node)?));
        let scale = match props.take("scale") {
            Some(n) => {
                let v = self.float(n)?;
                if !(v >= 0.0 && v.is_finite()) {
                    return Err(self.attr_error(n, "value", "scale must be a non-negative number"));
                }
                v
            }
            None => 1.0,
        };
        let to_world = match props.take("to_world") {
            Some(n) => {
                let m = Mat3::from_mat4(self.transform(n)?);
                if !is_similarity(m) || (m.determinant() - 1.0).abs() > 1e-3 {
                    return Err(self.error(n, "an envmap's to_world must be a rotation"));
                }
                m
            }
            None => Mat3::IDENTITY,
        };
        for name in ["mis_compensation", "filter_type"] {
            if let Some(n) = props.take(name) {
                let ok = match name {
                    "filter_type" => self.string(n)? == "bilinear",
                    _ => !self.boolean(n)?,
                };
                if !ok {
                    return Err(
                        self.error(n, format!("{} is not supported for envmap", describe(n)))
                    );
                }
            }
        }
        let (width, height, texels) =
            texture::read_image(&file, false).map_err(|e| self.error(file_node, e))?;
        if height < 2 {
            return Err(self.error(
                file_node,
                format!(
                    "{}: an environment map needs at least 2 rows",
                    file.display()
                ),
            ));
        }
        Ok(EnvMap {
            width,
            height,
            texels: texels.into_iter().map(|t| t * scale).collect(),
            to_world,
            source: file,
        })
    }
    /// Mitsuba's `sunsky` (include/mitsuba/render/sunsky.h's `BaseSunskyEmitter` and
    /// src/emitters/sunsky.cpp's `SunskyEmitter` in Mitsuba 3.9.1): every property it reads,
    /// checked as Mitsuba checks it (turbidity in [1, 10], albedo a colour in [0, 1] and not a
    /// texture, non-negative scales, an aperture in (0, 180) degrees, `sun_direction` or place
    /// and time but not both) and beyond it where Mitsuba computes on with a meaningless value
    /// (a zero `sun_direction`, latitude past the poles, a month 13, a day 31 in June, a
    /// `to_world` that is not a rotation, which Mitsuba's sun direction mishandles). The sky
    /// and sun are baked into an environment map here, at load (src/scene/sunsky).
    pub(super) fn read_sunsky(
        &self,
        props: &mut Props<'a, 'input>,
        node: Node<'a, 'input>,
    ) -> Result<SunSkyMap, SceneError> {
        let number = |props: &mut Props<'a, 'input>,
                      name: &str,
                      default: f32,
                      ok: &dyn Fn(f32) -> bool,
                      expected: &str|
         -> Result<f32, SceneError> {
            let Some(n) = props.take(name) else {
                return Ok(default);
            };
            let v = self.float(n)?;
            if !ok(v) {
                return Err(self.attr_error(n, "value", format!("{name} {v}: {expected}")));
            }
            Ok(v)
        };
        let turbidity = number(
            props,
            "turbidity",
            3.0,
            &|v| (1.0..=10.0).contains(&v),
            "Mitsuba's sky model takes a turbidity from 1 to 10",
        )?;
        let albedo = match props.take("albedo") {
            None => Vec3::splat(0.3),
            Some(n) if n.has_tag_name("texture") || n.has_tag_name("ref") => {
                return Err(self.error(
                    n,
                    "the sunsky's albedo must be a colour, not a texture (Mitsuba: it must not \
                     vary spatially)",
                ));
            }
            Some(n) => {
                let c = self.color(n)?;
                if c.min_element() < 0.0 || c.max_element() > 1.0 {
                    return Err(self.attr_error(
                        n,
                        "value",
                        format!(
                            "albedo {} {} {}: each channel must lie in [0, 1], as Mitsuba \
                             requires",
                            c.x, c.y, c.z
                        ),
                    ));
                }
                c
            }
        };
        let non_negative = "must not be negative (0 turns it off)";
        let sun_scale = number(props, "sun_scale", 1.0, &|v| v >= 0.0, non_negative)?;
        let sky_scale = number(props, "sky_scale", 1.0, &|v| v >= 0.0, non_negative)?;
        let sun_aperture = number(
            props,
            "sun_aperture",
            sunsky::DEFAULT_SUN_APERTURE,
            &|v| v > 0.0 && v < 180.0,
            "the sun's aperture (its full angle, in degrees) must lie in (0, 180), as Mitsuba \
             requires",
        )?;
        let complex_sun = match props.take("complex_sun") {
            Some(n) => self.boolean(n)?,
            None => false,
        };
        let to_world = match props.take("to_world") {
            Some(n) => {
                let m = Mat3::from_mat4(self.transform(n)?);
                if !is_similarity(m) || (m.determinant() - 1.0).abs() > 1e-3 {
                    return Err(self.error(
                        n,
                        "a sunsky's to_world must be a rotation (Mitsuba takes the sun's local \
                         direction through a scaled one inconsistently)",
                    ));
                }
                m
            }
            None => Mat3::IDENTITY,
        };

        // The place and time (Mitsuba's defaults: Tokyo, 2010-07-10 15:00, UTC+9), or a
        // direction.
        let defaults = sunsky::PlaceTime::default();
        let mut given = None;
        let mut place_number = |props: &mut Props<'a, 'input>,
                                name: &'static str,
                                default: f32,
                                range: (f32, f32),
                                what: &str|
         -> Result<f32, SceneError> {
            let Some(n) = props.take(name) else {
                return Ok(default);
            };
            given.get_or_insert((name, n));
            let v = self.float(n)?;
            if !(range.0..=range.1).contains(&v) {
                return Err(self.attr_error(
                    n,
                    "value",
                    format!("{name} {v}: {what} lies in [{}, {}]", range.0, range.1),
                ));
            }
            Ok(v)
        };
        let latitude = place_number(
            props,
            "latitude",
            defaults.latitude,
            (-90.0, 90.0),
            "a latitude",
        )?;
        let longitude = place_number(
            props,
            "longitude",
            defaults.longitude,
            (-180.0, 180.0),
            "a longitude",
        )?;
        let timezone = place_number(
            props,
            "timezone",
            defaults.timezone,
            (-12.0, 14.0),
            "a timezone",
        )?;
        let hour = place_number(props, "hour", defaults.hour, (0.0, 24.0), "an hour")?;
        let minute = place_number(props, "minute", defaults.minute, (0.0, 60.0), "a minute")?;
        let second = place_number(props, "second", defaults.second, (0.0, 60.0), "a second")?;
        let integer = |props: &mut Props<'a, 'input>,
                       name: &'static str,
                       default: i32,
                       range: (i64, i64),
                       what: &str|
         -> Result<(i32, Option<Node<'a, 'input>>), SceneError> {
            let Some(n) = props.take(name) else {
                return Ok((default, None));
            };
            let v = self.integer(n)?;
            if !(range.0..=range.1).contains(&v) {
                return Err(self.attr_error(
                    n,
                    "value",
                    format!("{name} {v}: {what} lies in [{}, {}]", range.0, range.1),
                ));
            }
            Ok((v as i32, Some(n)))
        };
        let (year, year_node) = integer(props, "year", defaults.year, (1, 9999), "a year")?;
        let (month, month_node) = integer(props, "month", defaults.month, (1, 12), "a month")?;
        let leap = year % 4 == 0 && (year % 100 != 0 || year % 400 == 0);
        let days = [
            31,
            if leap { 29 } else { 28 },
            31,
            30,
            31,
            30,
            31,
            31,
            30,
            31,
            30,
            31,
        ];
        let (day, day_node) = integer(
            props,
            "day",
            defaults.day,
            (1, days[month as usize - 1]),
            &format!("a day of month {month} of {year}"),
        )?;
        for (name, n) in [
            ("year", year_node),
            ("month", month_node),
            ("day", day_node),
        ] {
            if let Some(n) = n {
                given.get_or_insert((name, n));
            }
        }
        let sun = match (props.take("sun_direction"), given) {
            (Some(n), Some((name, other))) => {
                return Err(self.error(
                    n,
                    format!(
                        "give the sunsky sun_direction or a place and time, not both \
                         ({name} at line {}), as Mitsuba requires",
                        self.location(other).line
                    ),
                ));
            }
            (Some(n), None) => {
                let d = self.point(n)?;
                if d.try_normalize().is_none() {
                    return Err(self.error(n, "the sun_direction is zero"));
                }
                sunsky::SunPosition::Direction(d)
            }
            (None, _) => sunsky::SunPosition::PlaceTime(sunsky::PlaceTime {
                latitude,
                longitude,
                timezone,
                year,
                month,
                day,
                hour,
                minute,
                second,
            }),
        };
        let model = sunsky::SunSky::new(sunsky::SunSkyParams {
            turbidity,
            albedo,
            sun,
            sun_scale,
            sky_scale,
            sun_aperture,
            complex_sun,
            to_world,
            rgb_matching: sunsky::WAVELENGTHS.map(spectrum::linear_rgb_rec),
        });
        if !model.sun_is_up() {
            self.warn(
                node,
                "the sun is below the horizon: Mitsuba renders this sunsky black, its sky too",
            );
        }
        Ok(SunSkyMap::new(model))
    }
}
