//! Scene description: what every loader (Mitsuba XML, OBJ, our RON format) produces and what the
//! GPU layout is built from. Geometry is flattened to world-space triangles and analytic spheres;
//! every shape owns one material entry (its BSDF plus its area emission, as in Mitsuba, where the
//! emitter is attached to the shape).

pub mod bsdf;
pub mod bvh;
pub mod emitter;
pub mod filter;

pub mod grid;
pub mod medium;
pub mod mesh;
pub mod plugin;
pub mod sunsky;

pub mod texture;

use std::path::PathBuf;

use glam::Vec3;

use crate::error::Location;

pub use bsdf::Bsdf;

/// A perspective camera: a pinhole, or a thin lens (`lens`). `fov_x_deg` is the full
/// horizontal field of view of the whole film; loaders that read a vertical fov convert it with
/// the film's aspect ratio. `width` x `height` is the rendered image: the whole film, or the
/// window of it that `crop` places.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub origin: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_x_deg: f32,
    pub width: u32,
    pub height: u32,
    /// The pixel reconstruction filter (Mitsuba's `rfilter`).
    pub filter: filter::PixelFilter,
    /// Camera samples may land beyond the film's edge (Mitsuba's `sample_border`); otherwise
    /// the filter of a pixel near the edge is cut off at it, as in Mitsuba.
    pub sample_border: bool,
    /// The image is a window of a larger film (Mitsuba's hdrfilm crop): `None` when it is the
    /// whole film.
    pub crop: Option<Crop>,
    /// A thin lens (Mitsuba's `thinlens`); `None` for a pinhole.
    pub lens: Option<Lens>,
}

/// Where the image lies in the film the camera projects: its top-left pixel at (`x`, `y`) of a
/// `film_width` x `film_height` film. The fov belongs to the whole film; only the window is
/// rendered, and samples of its pixels keep to it as Mitsuba's keep to a crop window (the
/// pixel filter is cut at the window's edges unless `sample_border`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crop {
    pub film_width: u32,
    pub film_height: u32,
    pub x: u32,
    pub y: u32,
}

/// A thin lens as Mitsuba's `thinlens` models it: rays leave a uniform point of a disc of
/// `aperture_radius` around the camera's origin, across the view, and pass through the point
/// the pinhole ray meets on the plane `focus_distance` ahead (measured along the view axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    pub aperture_radius: f32,
    pub focus_distance: f32,
}

impl Camera {
    /// The film the camera projects and where the `width` x `height` image lies in it, both
    /// scaled to an image of `image` pixels (`--size`): each axis by the image's size over the
    /// camera's, so the window keeps its place as a fraction of the film. Without a crop this
    /// is `image` itself at (0, 0).
    pub fn projected_film(&self, image: (u32, u32)) -> ([f64; 2], [f64; 2]) {
        let sx = image.0 as f64 / self.width.max(1) as f64;
        let sy = image.1 as f64 / self.height.max(1) as f64;
        match self.crop {
            None => ([image.0 as f64, image.1 as f64], [0.0, 0.0]),
            Some(c) => (
                [c.film_width as f64 * sx, c.film_height as f64 * sy],
                [c.x as f64 * sx, c.y as f64 * sy],
            ),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// What the front (normal) side sees.
    pub bsdf: Bsdf,
    /// What the back side sees, seen with the normal flipped (Mitsuba `twosided`); `None`: the
    /// back of a reflective BSDF is black, a transmissive one is its own back.
    pub back: Option<Bsdf>,
    /// Radiance emitted on the front (normal) side; zero for non-emitters.
    pub emission: Vec3,
    /// Textures in place of the sides' colour parameters (indices into `Scene::textures`).
    pub textures: MaterialTextures,
    /// The media inside and outside the shapes that use it.
    pub media: medium::MediumInterface,
}

/// How Mitsuba's `normalmap` or `bumpmap` turns the shading frame of the BSDF it wraps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PerturbationKind {
    /// `normalmap`: the texture's RGB, mapped x -> 2x - 1, is the normal in the shading frame.
    Normal,
    /// `bumpmap`: the texture's luminance times `scale` is a height along the shading normal.
    Bump { scale: f32 },
}

/// A side's shading frame perturbed by a texture (src/bsdfs/normalmap/frame.rs is the reference).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FramePerturbation {
    pub kind: PerturbationKind,
    /// Index into `Scene::textures` (a bitmap).
    pub texture: u32,
    /// Mitsuba's `flip_invalid_normals`: a perturbed normal the viewer sees from below has its
    /// tangential part mirrored.
    pub flip_invalid_normals: bool,
    /// Mitsuba's `use_shadowing_function`: Estevez et al.'s shadow terminator.
    pub shadowing: bool,
    /// The back side of a `twosided` the perturbation wraps (`normalmap` > `twosided`): the
    /// frame is perturbed as on the front, then turned over. Inside a `twosided` (`twosided` >
    /// `normalmap`) the back is perturbed in its own, turned-over frame instead.
    pub outside_twosided: bool,
}

/// The textures of one side's colour parameters; `None` keeps the BSDF's constant (which for a
/// textured parameter holds the texture's mean, what plastic's sampling weight uses).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SideTextures {
    /// `reflectance` (diffuse) or `diffuse_reflectance` (plastics).
    pub diffuse: Option<u32>,
    /// `specular_reflectance` (conductors, plastics).
    pub specular: Option<u32>,
    /// Roughness `alpha_u` and `alpha_v` (rough conductors and dielectrics), looked up as
    /// scalars ([`texture::Texture::eval_1`]).
    pub alpha_u: Option<u32>,
    pub alpha_v: Option<u32>,
    /// A `normalmap` or `bumpmap` around the side's BSDF.
    pub frame: Option<FramePerturbation>,
    /// A blend's weight (`blendbsdf`) or opacity (`mask`), looked up as a scalar.
    pub blend_weight: Option<u32>,
    /// Scalar textures on components of the record's `specular`, `eta` and `k`
    /// ([`bsdf::GpuMaterial::field_textures`]), in an order the BSDF defines (`principled`
    /// keeps eight of its parameters there).
    pub fields: [Option<u32>; MAX_FIELD_TEXTURES],
}

/// Field textures a side may have ([`SideTextures::fields`]).
pub const MAX_FIELD_TEXTURES: usize = 8;

impl SideTextures {
    pub fn any(&self) -> bool {
        self.all().any(|t| t.is_some())
    }

    /// Every texture slot of the side, empty ones included.
    pub fn all(&self) -> impl Iterator<Item = Option<u32>> + '_ {
        [
            self.diffuse,
            self.specular,
            self.alpha_u,
            self.alpha_v,
            self.frame.map(|f| f.texture),
            self.blend_weight,
        ]
        .into_iter()
        .chain(self.fields.iter().copied())
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MaterialTextures {
    pub front: SideTextures,
    pub back: SideTextures,
}

impl Material {
    /// A one-sided material.
    pub fn new(bsdf: Bsdf, emission: Vec3) -> Self {
        Material {
            media: Default::default(),
            bsdf,
            back: None,
            emission,
            textures: MaterialTextures::default(),
        }
    }

    /// The BSDFs of both sides.
    pub fn bsdfs(&self) -> impl Iterator<Item = &Bsdf> {
        std::iter::once(&self.bsdf).chain(self.back.as_ref())
    }
}

/// A world-space triangle, counter-clockwise seen from its front (normal) side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    pub v: [Vec3; 3],
    pub material: u32,
    /// Unit vertex normals at the corners, interpolated for shading (Mitsuba's default for a
    /// mesh that has them); `None` shades with the face normal.
    pub normals: Option<[Vec3; 3]>,
    /// Texture coordinates at the corners; `None` gives Mitsuba's default, the barycentrics
    /// ((0,0), (1,0), (0,1) at the corners).
    pub uvs: Option<[glam::Vec2; 3]>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
    /// Normals point inwards (Mitsuba `flip_normals`).
    pub flip_normals: bool,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLight {
    pub position: Vec3,
    /// Radiant intensity in W/sr per RGB channel.
    pub intensity: Vec3,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Integrator {
    /// Longest path in segments (Mitsuba's rule: 1 = emitters seen directly). `None` = unbounded.
    pub max_depth: Option<u32>,
    /// Depth (in segments) from which Russian roulette starts. `None` = never.
    pub rr_depth: Option<u32>,
    /// Mitsuba's `hide_emitters`: camera rays pass through emitting shapes and see no
    /// environment; light still reaches the scene from them.
    pub hide_emitters: bool,
}

impl Default for Integrator {
    fn default() -> Self {
        Self {
            max_depth: Some(12),
            rr_depth: None,
            hide_emitters: false,
        }
    }
}

/// Which material, light and shape kinds a scene uses (only those some shape references).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneFeatures {
    /// The BSDF kinds its materials use ([`bsdf::BsdfModel::kind`]), each once, in the order
    /// first met: which BSDFs' WGSL the kernels compile in.
    pub bsdfs: Vec<&'static str>,
    /// Some BSDF has a delta lobe (S vertices exist).
    pub delta: bool,
    /// Some BSDF has a microfacet lobe (S vertices below a `glossy_threshold`).
    pub microfacet: bool,
    /// The smallest roughness (the larger of alpha_u and alpha_v) of any microfacet lobe, 0 for
    /// a textured one (it may be anything); `None` without microfacet lobes.
    pub smoothest_microfacet: Option<f32>,
    /// Some shape emits (an area light).
    pub area_lights: bool,
    /// Point or spot lights (delta positions).
    pub point_lights: bool,
    pub spot_lights: bool,
    /// Projectors (delta positions too: `point_lights` is then set).
    pub projectors: bool,
    pub directional_lights: bool,
    /// A `constant` or `envmap` emitter: escaping rays see it.
    pub environment: bool,
    pub triangles: bool,
    pub spheres: bool,
    /// Some shape's material or some light has a texture.
    pub textures: bool,
    /// Some shape's material has a `normalmap` or `bumpmap` (textures then too).
    pub normal_maps: bool,
    /// Some shape's material is a blend or mask, or lets light through (`null`).
    pub blends: bool,
    /// Participating media: some shape or the camera has one.
    pub media: bool,
    /// Some medium has a grid of extinction (heterogeneous).
    pub grid_media: bool,
}

impl SceneFeatures {
    /// Some material uses the BSDF kind `kind`.
    pub fn has_bsdf(&self, kind: &str) -> bool {
        self.bsdfs.contains(&kind)
    }

    /// Delta surfaces are the S vertices of caustic paths: without one there are no caustics.
    pub fn has_specular_surface(&self) -> bool {
        self.delta
    }

    /// Surfaces that are S vertices at `glossy_threshold` (delta lobes, or microfacet lobes
    /// smoother than it).
    pub fn has_specular_or_glossy_surface(&self, glossy_threshold: f32) -> bool {
        self.delta || self.has_glossy_lobe_below(glossy_threshold)
    }

    /// Some microfacet lobe may be smoother than `glossy_threshold`.
    pub fn has_glossy_lobe_below(&self, glossy_threshold: f32) -> bool {
        self.smoothest_microfacet
            .is_some_and(|alpha| alpha < glossy_threshold)
    }

    pub fn has_lights(&self) -> bool {
        self.area_lights || self.point_lights || self.directional_lights || self.environment
    }
}

impl std::fmt::Display for SceneFeatures {
    /// One line for the CLI, e.g. "materials diffuse+dielectric, lights area, shapes triangles".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let list = |items: &[(&str, bool)]| {
            let present: Vec<&str> = items.iter().filter(|i| i.1).map(|i| i.0).collect();
            if present.is_empty() {
                "none".to_string()
            } else {
                present.join("+")
            }
        };
        write!(
            f,
            "materials {}, lights {}, shapes {}",
            match self.bsdfs.as_slice() {
                [] => "none".to_string(),
                kinds => kinds.join("+"),
            },
            list(&[
                ("area", self.area_lights),
                ("point", self.point_lights && !self.spot_lights),
                ("point+spot", self.point_lights && self.spot_lights),
                ("projector", self.projectors),
                ("directional", self.directional_lights),
                ("environment", self.environment),
            ]),
            list(&[("triangles", self.triangles), ("spheres", self.spheres)]),
        )?;
        if self.media {
            let kind = if self.grid_media { " (grids)" } else { "" };
            write!(f, ", media{kind}")?;
        }
        Ok(())
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The file the scene was loaded from (for messages).
    pub source: PathBuf,
    pub camera: Camera,
    pub integrator: Integrator,
    /// Samples per pixel the scene file suggests (Mitsuba `sample_count`), if any.
    pub spp_hint: Option<u32>,
    pub materials: Vec<Material>,
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    pub point_lights: Vec<PointLight>,
    /// Spot, directional and environment lights.
    pub emitters: emitter::Emitters,
    /// Textures the materials use (`Material::textures` indexes them).
    pub textures: Vec<texture::Texture>,
    /// Participating media (`Material::media` and the camera refer to them).
    pub media: medium::Media,
}

impl Scene {
    /// Axis-aligned bounds of all geometry and point lights. An empty scene has the bounds of
    /// its camera origin.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        for t in &self.triangles {
            for v in t.v {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        for s in &self.spheres {
            lo = lo.min(s.center - s.radius);
            hi = hi.max(s.center + s.radius);
        }
        let positions = self.point_lights.iter().map(|p| p.position);
        let spots = self.emitters.spots.iter().map(|s| s.position);
        let projectors = self.emitters.projectors.iter().map(|p| p.position);
        for p in positions.chain(spots).chain(projectors) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if lo.x > hi.x {
            return (self.camera.origin, self.camera.origin);
        }
        (lo, hi)
    }

    /// How large the scene is for f32 arithmetic: the larger of the largest coordinate
    /// magnitude and the half-diagonal of the bounds of its shapes, point lights and camera
    /// origin (in f64, which cannot overflow). `None` when there is nothing to render.
    pub fn extent(&self) -> Option<f64> {
        if self.triangles.is_empty()
            && self.spheres.is_empty()
            && self.point_lights.is_empty()
            && self.emitters.spots.is_empty()
            && self.emitters.projectors.is_empty()
        {
            return None;
        }
        let (lo, hi) = self.bounds();
        let (lo, hi) = (
            lo.as_dvec3().min(self.camera.origin.as_dvec3()),
            hi.as_dvec3().max(self.camera.origin.as_dvec3()),
        );
        let largest = lo.abs().max(hi.abs()).max_element();
        Some(largest.max(0.5 * (hi - lo).length()))
    }

    /// Refuses a scene whose [`extent`](Self::extent) is outside [`EXTENT_RANGE`], which it
    /// could only render black or wrong. At line 1 of the file: it is the whole scene's size
    /// (the loaders name the shape when one shape alone reaches too far).
    pub fn check_extent(&self) -> Result<(), SceneError> {
        let Some(extent) = self.extent() else {
            return Ok(());
        };
        let (min, max) = EXTENT_RANGE;
        if extent >= min as f64 && extent <= max as f64 {
            return Ok(());
        }
        Err(SceneError::at(
            Location::new(&self.source, 1, 1),
            format!(
                "the scene's extent (largest coordinate or half-diagonal, camera included) is \
                 {extent:.1e}, outside the supported range {min:.0e} to {max:.0e}: {}",
                EXTENT_REASON
            ),
        ))
    }

    /// The largest coordinate magnitude of the triangles from index `triangles` on and the
    /// spheres from index `spheres` on (a shape a loader has just added), in f64.
    pub(crate) fn reach_since(&self, triangles: usize, spheres: usize) -> f64 {
        let tri = self.triangles[triangles..]
            .iter()
            .flat_map(|t| t.v)
            .map(|v| v.abs().max_element() as f64);
        let sph = self.spheres[spheres..]
            .iter()
            .map(|s| s.center.abs().max_element() as f64 + s.radius as f64);
        tri.chain(sph).fold(0.0, f64::max)
    }

    /// The scene uniformly scaled by `s` about the origin. Point-light intensities scale by s^2
    /// so irradiance, and hence the image, stays the same (area emission is radiance, which
    /// does not change with scale).
    ///
    /// `s` must be positive and finite: a negative scale is a point reflection, which mirrors
    /// the image whatever the camera does, and a zero scale collapses the scene (`validate`
    /// rejects the result).
    pub fn scaled(&self, s: f32) -> Scene {
        let mut out = self.clone();
        for t in &mut out.triangles {
            t.v = t.v.map(|v| v * s);
        }
        for sphere in &mut out.spheres {
            sphere.center *= s;
            sphere.radius *= s;
        }
        for p in &mut out.point_lights {
            p.position *= s;
            p.intensity *= s * s;
        }
        for spot in &mut out.emitters.spots {
            spot.position *= s;
            spot.intensity *= s * s;
        }
        // Intensity pi E / cos^3 at unit distance: E scales like a point light's intensity.
        for projector in &mut out.emitters.projectors {
            projector.position *= s;
            projector.irradiance *= s * s;
        }
        out.camera.origin *= s;
        out.camera.target *= s;
        if let Some(lens) = &mut out.camera.lens {
            lens.aperture_radius *= s;
            lens.focus_distance *= s;
        }
        out
    }

    /// Adds an object-space mesh, with its vertex normals if it has them, placed by `to_world`
    /// (see [`place_mesh`]).
    pub fn push_mesh_data(
        &mut self,
        mesh: mesh::MeshData,
        to_world: glam::Mat4,
        material: u32,
        flip_normals: bool,
    ) {
        self.triangles
            .extend(place_mesh(mesh, to_world, material, flip_normals));
    }

    /// Adds object-space triangles placed by `to_world` (see [`place_triangles`]).
    pub fn push_mesh(
        &mut self,
        triangles: Vec<[Vec3; 3]>,
        to_world: glam::Mat4,
        material: u32,
        flip_normals: bool,
    ) {
        self.triangles
            .extend(place_triangles(triangles, to_world, material, flip_normals));
    }

    /// What kinds of material, light and shape occur: what the graph and the shaders may leave
    /// out. O(shapes); the renderer computes it once when it is built.
    pub fn features(&self) -> SceneFeatures {
        let mut f = SceneFeatures {
            triangles: !self.triangles.is_empty(),
            spheres: !self.spheres.is_empty(),
            point_lights: !self.point_lights.is_empty()
                || !self.emitters.spots.is_empty()
                || !self.emitters.projectors.is_empty(),
            spot_lights: !self.emitters.spots.is_empty(),
            projectors: !self.emitters.projectors.is_empty(),
            // A light's texture is uploaded with the materials' (`gpu_layout`).
            textures: self.emitters.spots.iter().any(|s| s.texture.is_some())
                || self.emitters.projectors.iter().any(|p| p.texture.is_some()),
            directional_lights: !self.emitters.directionals.is_empty(),
            environment: self.emitters.environment.is_some(),
            media: !self.media.is_empty(),
            grid_media: self.media.list.iter().any(|m| m.density.is_some()),
            ..SceneFeatures::default()
        };
        let shape_materials = self
            .triangles
            .iter()
            .map(|t| t.material)
            .chain(self.spheres.iter().map(|s| s.material));
        let mut seen = vec![false; self.materials.len()];
        for m in shape_materials.flat_map(|m| self.with_nested(m)) {
            if std::mem::replace(&mut seen[m.0], true) {
                continue;
            }
            let m = m.1;
            for bsdf in m.bsdfs() {
                if !f.has_bsdf(bsdf.kind()) {
                    f.bsdfs.push(bsdf.kind());
                }
                f.blends |= !bsdf.children().is_empty() || bsdf.lobes().pass_through;
                f.delta |= bsdf.is_delta();
                f.microfacet |= bsdf.has_microfacet_lobe();
                if let Some(alpha) = bsdf.microfacet_roughness() {
                    let sides = [m.textures.front, m.textures.back];
                    let textured = sides
                        .iter()
                        .any(|t| t.alpha_u.is_some() || t.alpha_v.is_some());
                    let alpha = if textured { 0.0 } else { alpha };
                    let smoothest = f.smoothest_microfacet.get_or_insert(alpha);
                    *smoothest = smoothest.min(alpha);
                }
            }
            f.area_lights |= m.emission.max_element() > 0.0;
            f.textures |= m.textures.front.any() || m.textures.back.any();
            f.normal_maps |= m.textures.front.frame.is_some() || m.textures.back.frame.is_some();
        }
        f
    }

    /// The material at `index` and every material its blends and masks may choose, each with
    /// its index (blends of blends included; a blend's children always come before it, so
    /// this ends). Empty for an index out of range.
    pub fn with_nested(&self, index: u32) -> Vec<(usize, &Material)> {
        let mut out = Vec::new();
        let mut pending = vec![index as usize];
        while let Some(i) = pending.pop() {
            let Some(m) = self.materials.get(i) else {
                continue;
            };
            out.push((i, m));
            for bsdf in m.bsdfs() {
                let children = bsdf.children();
                if children.iter().all(|&c| (c as usize) < i) {
                    pending.extend(children.iter().map(|&c| c as usize));
                }
            }
        }
        out
    }

    /// Some shape emits or a point light exists (either may still have zero power).
    pub fn has_lights(&self) -> bool {
        self.features().has_lights()
    }

    /// What a render of a scene without a light is warned of (by `hppm render` and Python
    /// alike), or None when it has one.
    pub fn no_light_warning(&self) -> Option<String> {
        (!self.has_lights()).then(|| {
            format!(
                "{} has no light (no emitting shape, no point light): the image will be black",
                self.source.display()
            )
        })
    }

    /// Checks what every loader must guarantee: finite numbers, valid material indices, a
    /// camera that looks somewhere, an extent f32 can render.
    pub fn validate(&self) -> Result<(), SceneError> {
        let fail = |message: String| {
            Err(SceneError::File {
                file: self.source.clone(),
                message,
            })
        };
        let finite = |v: Vec3| v.is_finite();
        let cam = &self.camera;
        if !(finite(cam.origin)
            && finite(cam.target)
            && finite(cam.up)
            && cam.fov_x_deg.is_finite())
        {
            return fail("the camera has a non-finite number".into());
        }
        if (cam.target - cam.origin).length_squared() == 0.0 {
            return fail("the camera's origin equals its target".into());
        }
        if (cam.target - cam.origin).cross(cam.up).length_squared() == 0.0 {
            return fail("the camera's up vector is zero or parallel to its view direction".into());
        }
        if !(cam.fov_x_deg > 0.0 && cam.fov_x_deg < 180.0) {
            return fail(format!(
                "camera fov {} is not between 0 and 180 degrees",
                cam.fov_x_deg
            ));
        }
        if cam.width == 0 || cam.height == 0 {
            return fail("the film has zero size".into());
        }
        if let Some(c) = cam.crop
            && (c.x as u64 + cam.width as u64 > c.film_width as u64
                || c.y as u64 + cam.height as u64 > c.film_height as u64)
        {
            return fail(format!(
                "the crop window {}x{} at ({}, {}) does not fit the {}x{} film",
                cam.width, cam.height, c.x, c.y, c.film_width, c.film_height
            ));
        }
        if let Some(l) = cam.lens
            && !(l.aperture_radius.is_finite()
                && l.aperture_radius >= 0.0
                && l.focus_distance.is_finite()
                && l.focus_distance > 0.0)
        {
            return fail(format!(
                "the lens has aperture radius {} and focus distance {}: expected a radius of at \
                 least 0 and a positive distance",
                l.aperture_radius, l.focus_distance
            ));
        }
        // Field textures carry the index as a float, exact below 2^24.
        let texture_ok =
            |t: Option<u32>| t.is_none_or(|t| (t as usize) < self.textures.len() && t < 1 << 24);
        for (i, m) in self.materials.iter().enumerate() {
            let sides = [m.textures.front, m.textures.back];
            // A blend's children come before it: choosing among them always ends.
            let children_ok = m
                .bsdfs()
                .all(|b| b.children().iter().all(|&c| (c as usize) < i));
            let ok = finite(m.emission)
                && children_ok
                && m.bsdfs().all(|b| b.is_valid())
                && sides.iter().all(|s| s.all().all(texture_ok))
                && sides.iter().all(|s| {
                    s.frame.is_none_or(|f| match f.kind {
                        PerturbationKind::Bump { scale } => scale.is_finite(),
                        PerturbationKind::Normal => true,
                    })
                });
            if !ok {
                return fail(format!(
                    "material {i} has a non-finite or non-positive value"
                ));
            }
        }
        let material_ok = |m: u32| (m as usize) < self.materials.len();
        for (i, t) in self.triangles.iter().enumerate() {
            if !t.v.iter().all(|&v| finite(v)) || !material_ok(t.material) {
                return fail(format!(
                    "triangle {i} has a non-finite vertex or a bad material"
                ));
            }
        }
        for (i, s) in self.spheres.iter().enumerate() {
            if !finite(s.center)
                || !s.radius.is_finite()
                || s.radius <= 0.0
                || !material_ok(s.material)
            {
                return fail(format!(
                    "sphere {i} has a non-finite centre, a bad radius or a bad material"
                ));
            }
        }
        for (i, p) in self.point_lights.iter().enumerate() {
            if !finite(p.position) || !finite(p.intensity) {
                return fail(format!("point light {i} has a non-finite number"));
            }
        }
        for (i, l) in self.emitters.spots.iter().enumerate() {
            let angles_ok =
                l.beam_width >= 0.0 && l.beam_width <= l.cutoff && l.cutoff <= std::f32::consts::PI;
            let frame_ok = l.frame.iter().all(|v| finite(*v)) && texture_ok(l.texture);
            if !finite(l.position)
                || !finite(l.intensity)
                || !finite(l.axis)
                || !angles_ok
                || !frame_ok
            {
                return fail(format!(
                    "spot light {i} has a non-finite number or bad angles"
                ));
            }
        }
        for (i, l) in self.emitters.projectors.iter().enumerate() {
            let frame_ok = l.frame.iter().all(|v| finite(*v)) && texture_ok(l.texture);
            let shape_ok = l.tan_half_fov > 0.0 && l.aspect > 0.0;
            if !finite(l.position) || !finite(l.irradiance) || !frame_ok || !shape_ok {
                return fail(format!(
                    "projector {i} has a non-finite number or a bad field of view"
                ));
            }
        }
        for (i, l) in self.emitters.directionals.iter().enumerate() {
            if !finite(l.direction) || !finite(l.irradiance) {
                return fail(format!("directional light {i} has a non-finite number"));
            }
        }
        if let Some(env) = &self.emitters.environment {
            let ok = match (env, env.map()) {
                (emitter::Environment::Constant { radiance }, _) => finite(*radiance),
                (_, Some(map)) => {
                    map.width >= 1
                        && map.height >= 2
                        && map.texels.len() == (map.width * map.height) as usize
                        && map.texels.iter().all(|t| finite(*t))
                }
                (_, None) => false,
            };
            if !ok {
                return fail("the environment light has a non-finite number or a bad size".into());
            }
        }
        self.check_extent()
    }
}

/// Object-space triangles placed in the world by `to_world`. A mirroring transform (negative
/// determinant) reverses the winding, so it is swapped back to keep the front where the
/// transformed normal points; `flip_normals` swaps it on purpose.
pub fn place_triangles(
    triangles: Vec<[Vec3; 3]>,
    to_world: glam::Mat4,
    material: u32,
    flip_normals: bool,
) -> impl Iterator<Item = Triangle> {
    let mesh = mesh::MeshData {
        triangles,
        ..mesh::MeshData::default()
    };
    place_mesh(mesh, to_world, material, flip_normals)
}

/// [`place_triangles`] for a mesh that may have vertex normals and texture coordinates: normals
/// are carried by the inverse transpose of `to_world` (so they stay perpendicular to the surface
/// under any affine map) and turned with the front side by `flip_normals`; a triangle with a
/// normal that is zero or not a number after the transform shades flat. Texture coordinates
/// follow their corners.
pub fn place_mesh(
    mesh: mesh::MeshData,
    to_world: glam::Mat4,
    material: u32,
    flip_normals: bool,
) -> impl Iterator<Item = Triangle> {
    let mirrored = to_world.determinant() < 0.0;
    let swap = mirrored != flip_normals;
    let normal_map = glam::Mat3::from_mat4(to_world).inverse().transpose();
    let sign = if flip_normals { -1.0 } else { 1.0 };
    // Not where the scene asked for face normals (`normals` dropped).
    let recomputed = mesh
        .computed_normal_vertices
        .as_ref()
        .filter(|_| mesh.normals.is_some())
        .map(|vertices| world_vertex_normals(&mesh.triangles, vertices, to_world, mirrored));
    let normals = mesh.normals;
    let uvs = mesh.uvs;
    mesh.triangles
        .into_iter()
        .enumerate()
        .map(move |(i, corners)| {
            let [a, b, c] = corners.map(|p| to_world.transform_point3(p));
            let v = if swap { [a, c, b] } else { [a, b, c] };
            let normals = normals.as_ref().and_then(|n| {
                let world = recomputed
                    .as_ref()
                    .and_then(|r| r.get(i).copied().flatten());
                let placed = match world {
                    Some(w) => w.map(|n| (sign * n).try_normalize()),
                    None => n.get(i)?.map(|n| (sign * (normal_map * n)).try_normalize()),
                };
                let [Some(na), Some(nb), Some(nc)] = placed else {
                    return None;
                };
                Some(if swap { [na, nc, nb] } else { [na, nb, nc] })
            });
            // Without texture coordinates Mitsuba's are the barycentrics of the corners in the
            // file's order (and so are its dp_du, dp_dv): a swapped triangle keeps that order's.
            let uvs = uvs
                .as_ref()
                .and_then(|uv| uv.get(i))
                .map(|&[a, b, c]| if swap { [a, c, b] } else { [a, b, c] })
                .or_else(|| swap.then_some([glam::Vec2::ZERO, glam::Vec2::Y, glam::Vec2::X]));
            Triangle {
                v,
                material,
                normals,
                uvs,
            }
        })
}

/// Vertex normals computed from the faces after `to_world` has placed them, per triangle corner
/// in the file's order, for the triangles `vertices` names (see
/// `MeshData::computed_normal_vertices`); outward under a mirroring `to_world`, whose winding
/// `place_mesh` reverses.
fn world_vertex_normals(
    triangles: &[[Vec3; 3]],
    vertices: &[Option<[usize; 3]>],
    to_world: glam::Mat4,
    mirrored: bool,
) -> Vec<Option<[Vec3; 3]>> {
    let count = vertices
        .iter()
        .flatten()
        .flatten()
        .max()
        .map_or(0, |&v| v + 1);
    let mut positions = vec![Vec3::ZERO; count];
    let mut faces = Vec::new();
    for (corners, ids) in triangles.iter().zip(vertices) {
        if let Some(ids) = ids {
            for k in 0..3 {
                positions[ids[k]] = to_world.transform_point3(corners[k]);
            }
            faces.push(if mirrored {
                [ids[0], ids[2], ids[1]]
            } else {
                *ids
            });
        }
    }
    let mut computed = mesh::angle_weighted_normals(&positions, &faces).into_iter();
    vertices
        .iter()
        .map(|ids| {
            ids.and_then(|_| computed.next())
                .map(|n| if mirrored { [n[0], n[2], n[1]] } else { n })
        })
        .collect()
}

/// The uniform scale of an affine transform made only of uniform scaling, rotation, mirroring
/// and translation (which maps spheres to spheres), or `None` for any other transform.
pub fn similarity_scale(m: glam::Mat4) -> Option<f32> {
    let linear = glam::Mat3::from_mat4(m);
    let columns = [linear.x_axis, linear.y_axis, linear.z_axis];
    let scale = columns[0].length();
    let tolerance = 1e-4 * scale * scale;
    let uniform = columns
        .iter()
        .all(|c| (c.length_squared() - scale * scale).abs() <= tolerance);
    let orthogonal = columns[0].dot(columns[1]).abs() <= tolerance
        && columns[1].dot(columns[2]).abs() <= tolerance
        && columns[2].dot(columns[0]).abs() <= tolerance;
    (scale > 0.0 && scale.is_finite() && uniform && orthogonal).then_some(scale)
}

/// The scene extents ([`Scene::extent`]) the loaders and the renderer accept. Rendering in f32
/// was measured to hold from an extent of about 4e-18 to 4e18 (the Cornell box scaled by 1e-18
/// to 1e18 renders the unscaled image, through every graph; tests/offsets.rs): beyond, squared
/// distances and areas overflow f32 (squares past 3.4e38) or sink into denormals (below
/// 1.2e-38) and the image goes black. Three orders of magnitude are kept from both ends, also
/// for GPUs that flush denormals to zero (a photon's flux is an area over the photon count).
pub const EXTENT_RANGE: (f32, f32) = (1e-15, 1e15);

/// Why scenes are limited to [`EXTENT_RANGE`], for the messages.
pub(crate) const EXTENT_REASON: &str = "rendering is in f32, whose squared distances and areas \
    overflow near 1e19 and underflow near 1e-19; scale the scene";

/// The message for a shape (or light, or camera) of the loader's that reaches `reach` from the
/// origin, if that is beyond [`EXTENT_RANGE`].
pub(crate) fn beyond_extent(what: &str, reach: f64) -> Option<String> {
    let max = EXTENT_RANGE.1;
    (reach.is_finite() && reach > max as f64).then(|| {
        format!(
            "{what} reaches {reach:.1e} from the origin, beyond the supported scene extent \
             {max:.0e}: {EXTENT_REASON}"
        )
    })
}

/// Largest film side any loader accepts (and `--size`), a sanity bound against typos.
pub const MAX_FILM_SIDE: u32 = 16384;

/// A scene file's text, or an error naming it.
/// A scene that could not be loaded. Every variant names the file; parse errors carry a line and
/// column.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{location}: {message}")]
    At { location: Location, message: String },
    #[error("{file}: {message}")]
    File { file: PathBuf, message: String },
    /// Every problem a scene file has, when there is more than one, in file order.
    #[error("{} problems:\n{}", .0.len(), list_problems(.0))]
    Several(Vec<SceneError>),
}

fn list_problems(problems: &[SceneError]) -> String {
    problems
        .iter()
        .map(|p| format!("  {p}"))
        .collect::<Vec<_>>()
        .join("\n")
}

impl SceneError {
    pub fn at(location: Location, message: impl Into<String>) -> Self {
        SceneError::At {
            location,
            message: message.into(),
        }
    }

    /// One error for `problems`: the problem itself when there is one.
    pub fn from_problems(mut problems: Vec<SceneError>) -> Self {
        if problems.len() == 1 {
            problems.remove(0)
        } else {
            SceneError::Several(problems)
        }
    }

    /// This error, met reading a `what` file (an OBJ, a PLY) that the scene refers to at
    /// `used_at`: the message says where it was used; an unreadable file is reported there.
    pub fn referenced_from(self, what: &str, used_at: &Location) -> SceneError {
        match self {
            SceneError::Io { file, source } => SceneError::at(
                used_at.clone(),
                format!("cannot read {what} file {}: {source}", file.display()),
            ),
            SceneError::At { location, message } => SceneError::At {
                location,
                message: format!("{message} ({what} used at {used_at})"),
            },
            SceneError::File { file, message } => SceneError::File {
                file,
                message: format!("{message} ({what} used at {used_at})"),
            },
            SceneError::Several(all) => SceneError::Several(
                all.into_iter()
                    .map(|e| e.referenced_from(what, used_at))
                    .collect(),
            ),
        }
    }

    /// The problems this error stands for, one per entry.
    pub fn problems(&self) -> Vec<&SceneError> {
        match self {
            SceneError::Several(all) => all.iter().collect(),
            one => vec![one],
        }
    }
}
