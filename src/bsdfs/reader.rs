//! What a BSDF unit reads its properties through. The Mitsuba loader gives each `<bsdf>`
//! element one; it takes each property once, knows where each is in the file (so a unit's
//! error lands at file:line:col) and reports what no unit took as unknown, with a did-you-mean.

use glam::Vec3;

use crate::scene::bsdf::Bsdf;
use crate::scene::medium::Phase;
use crate::scene::{Material, MaterialTextures, SceneError};

/// A `<bsdf>` as a shape uses it: the front BSDF and, for `twosided`, the back's, with the
/// textures of their parameters.
#[derive(Debug, Clone)]
pub struct Sides {
    pub front: Bsdf,
    pub back: Option<Bsdf>,
    pub textures: MaterialTextures,
}

impl Sides {
    /// One side's BSDF with its textures.
    pub fn one(front: Bsdf, textures: crate::scene::SideTextures) -> Self {
        Sides {
            front,
            back: None,
            textures: MaterialTextures {
                front: textures,
                back: Default::default(),
            },
        }
    }

    pub fn material(self, emission: Vec3) -> Material {
        Material {
            media: Default::default(),
            bsdf: self.front,
            back: self.back,
            emission,
            textures: self.textures,
        }
    }
}

/// The properties and nested objects of one `<bsdf>` element. Each property is taken once;
/// `Ok(None)` is a property the file does not give (the unit applies Mitsuba's default).
pub trait BsdfReader {
    /// The `type` the element gives (one unit may read several: `blendbsdf` and `mask`).
    fn plugin(&self) -> &str;

    /// Whether the file gives property `name` (not yet taken).
    fn has(&self, name: &str) -> bool;

    /// Whether property `name` is given as a `<string>` (an index of refraction by name).
    fn is_string(&self, name: &str) -> bool;

    fn float(&mut self, name: &str) -> Result<Option<f32>, SceneError>;

    fn boolean(&mut self, name: &str) -> Result<Option<bool>, SceneError>;

    fn string(&mut self, name: &str) -> Result<Option<String>, SceneError>;

    /// A colour: `<rgb>`, a spectrum, or a `<float>` for grey; no texture.
    fn color(&mut self, name: &str) -> Result<Option<Vec3>, SceneError>;

    /// A colour or a texture (inline or a `<ref>`), `default` when absent: the colour, or the
    /// texture's mean (Mitsuba's `Texture::mean`, what a plastic's lobe weights use) and the
    /// texture's index in the scene.
    fn color_or_texture(
        &mut self,
        name: &str,
        default: f32,
    ) -> Result<(Vec3, Option<u32>), SceneError>;

    /// A number or a scalar texture, `default` when absent, as [`Self::color_or_texture`].
    fn scalar_or_texture(
        &mut self,
        name: &str,
        default: f32,
    ) -> Result<(f32, Option<u32>), SceneError>;

    /// A texture given as property `name`: its index, or an error when it is something else.
    fn texture(&mut self, name: &str) -> Result<Option<u32>, SceneError>;

    /// Textures given as objects (a `<texture>` child of any name, or a `<ref>` to one), for
    /// a unit that lists `texture` among its objects.
    fn texture_objects(&mut self) -> Result<Vec<u32>, SceneError>;

    /// Whether texture `index` is a bitmap (the others have no gradient and no RGB lookup).
    fn is_bitmap(&self, index: u32) -> bool;

    /// Texture `index`'s mean colour and its largest value per channel (Mitsuba 0.6's
    /// `getAverage` and `getMaximum`, which its `phong` and `ward` weigh and scale their
    /// reflectances by); `None` where the reader cannot say.
    fn texture_average_and_maximum(&self, _index: u32) -> Option<(Vec3, Vec3)> {
        None
    }

    /// The `version` the element's file declares (`<scene version="0.5.0">`: the file itself,
    /// not the scene that includes it), or `None` when it declares none.
    fn file_version(&self) -> Option<String> {
        None
    }

    /// The BSDFs nested in the element (`<bsdf>` children and `<ref>`s to declared ones), each
    /// read through the registry, in file order.
    fn nested(&mut self) -> Result<Vec<Sides>, SceneError>;

    /// The `<phase>` nested in the element (a unit that lists `phase` among its objects, as
    /// Mitsuba 0.6's `hk`), read as a medium's; `None` when it has none, an error for two.
    fn phase(&mut self) -> Result<Option<Phase>, SceneError> {
        Ok(None)
    }

    /// Mitsuba 0.6's medium preset `name` (src/medium/materials.h, matched ignoring case):
    /// sigma_s and sigma_a as 0.6 applies them (times 100) and the anisotropy g; `None` where
    /// there is no such preset.
    fn medium_preset(&self, _name: &str) -> Option<(Vec3, Vec3, Vec3)> {
        None
    }

    /// The names of 0.6's medium presets, for messages.
    fn medium_preset_names(&self) -> String {
        String::new()
    }

    /// Adds a material for a blend to choose (its children come before it); its index.
    fn add_material(&mut self, material: Material) -> u32;

    /// A material added before, by index.
    fn material(&self, index: u32) -> Option<Material>;

    /// An error at property `name` (its value), or at the element when it is not given.
    fn error_at(&self, name: &str, message: String) -> SceneError;

    /// An error at the `index`-th nested BSDF.
    fn error_at_nested(&self, index: usize, message: String) -> SceneError;

    /// An error at the element.
    fn error(&self, message: String) -> SceneError;

    /// How messages name the element: `<bsdf type="roughplastic">`.
    fn describe(&self) -> String;

    /// How messages name property `name` as the file gives it: `<float name="alpha">`.
    fn describe_property(&self, name: &str) -> String;

    /// The element is in a Mitsuba 0.5/0.6 file (version below 2.0): a unit applies 0.6's
    /// defaults and properties where 0.6's plugin differs from Mitsuba 3's.
    fn legacy(&self) -> bool {
        false
    }

    /// Records what reading a 0.6 file changed, at property `name` (or the element), for
    /// `hppm check --verbose`.
    fn upgrade(&self, name: &str, message: String) {
        let _ = (name, message);
    }
}
