//! Mitsuba 3's textures (`src/textures/checkerboard.cpp`, `bitmap.cpp` and Dr.Jit's
//! `texture_impl.h` are the specification): the CPU reference of each lookup, which the WGSL
//! twin (`shaders/common/texture.wgsl`) must equal, and the loading of image files.

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec2, Vec3};

/// Mitsuba's `to_uv`: an affine map of the plane, `u' = m[0] . (u, v, 1)`, `v' = m[1] . (u, v, 1)`.
/// A 4x4 `<transform>` keeps its upper-left 2x2 block and the x, y of its translation (Mitsuba's
/// `Transform::extract`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvTransform {
    pub rows: [[f32; 3]; 2],
}

impl UvTransform {
    pub const IDENTITY: Self = Self {
        rows: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
    };

    pub fn from_mat4(m: Mat4) -> Self {
        let row = |r: usize| {
            let row = m.row(r);
            [row.x, row.y, row.w]
        };
        Self {
            rows: [row(0), row(1)],
        }
    }

    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [a, b] = self.rows;
        Vec2::new(
            a[0] * uv.x + a[1] * uv.y + a[2],
            b[0] * uv.x + b[1] * uv.y + b[2],
        )
    }
}

/// What a bitmap lookup outside [0, 1] reads (Mitsuba's `wrap_mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WrapMode {
    Repeat,
    Mirror,
    Clamp,
}

impl WrapMode {
    /// Texel index `i` of a row or column of `n` texels, wrapped as Dr.Jit's `tex_wrap` does.
    pub fn wrap(self, i: i32, n: i32) -> i32 {
        match self {
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Repeat => i.rem_euclid(n),
            // The texture and its mirror image alternate: period 2n.
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m >= n { 2 * n - 1 - m } else { m }
            }
        }
    }

    fn code(self) -> u32 {
        match self {
            WrapMode::Repeat => 0,
            WrapMode::Mirror => 1,
            WrapMode::Clamp => 2,
        }
    }
}

/// Mitsuba's `filter_type`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    Bilinear,
    Nearest,
}

/// An image in linear RGB, row 0 at the top of the file (Mitsuba's v = 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Bitmap {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
    /// The file's own bytes when it stores 8 bits a channel: the GPU keeps these (a third of
    /// the float texels' size) and decodes each texel as it reads it.
    pub bytes: Option<EncodedTexels>,
    pub wrap: WrapMode,
    pub filter: Filter,
    pub to_uv: UvTransform,
    /// The file it was read from (for messages).
    pub source: PathBuf,
}

/// An 8-bit image's texels as stored: `r | g << 8 | b << 16` per texel, row by row from the
/// top, and whether they are sRGB-encoded (else linear, `raw`).
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedTexels {
    pub words: Vec<u32>,
    pub srgb: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Texture {
    /// `color0` where the fractional parts of u' and v' are both above one half or both not,
    /// `color1` elsewhere (Mitsuba's `Checkerboard::eval`).
    Checkerboard {
        color0: Vec3,
        color1: Vec3,
        to_uv: UvTransform,
    },
    Bitmap(Bitmap),
}

/// Texture coordinates beyond this are clamped before texel indices are taken, so that they
/// stay inside i32 on the CPU and the GPU alike (times a width of at most 16384 texels).
pub const UV_LIMIT: f32 = 1.0e4;
/// The largest bitmap side accepted.
pub const MAX_SIDE: u32 = 16384;

impl Texture {
    /// The value at texture coordinates `uv`.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let p = to_uv.apply(uv);
                let upper = |x: f32| x - x.floor() > 0.5;
                if upper(p.x) == upper(p.y) {
                    *color0
                } else {
                    *color1
                }
            }
            Texture::Bitmap(b) => b.eval(uv),
        }
    }

    /// The scalar value at `uv` (Mitsuba's `eval_1`, what a roughness reads): a bitmap's
    /// luminance; a checkerboard's colour's luminance, with the colours the other way round
    /// from [`eval`](Self::eval), as Mitsuba's `Checkerboard::eval_1` has them (`color0` where
    /// exactly one of the fractional parts is above one half).
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        match self {
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let p = to_uv.apply(uv);
                let upper = |x: f32| x - x.floor() > 0.5;
                luminance(if upper(p.x) != upper(p.y) {
                    *color0
                } else {
                    *color1
                })
            }
            Texture::Bitmap(b) => luminance(b.eval(uv)),
        }
    }

    /// The gradient of [`eval_1`](Self::eval_1) in (u, v) as Mitsuba's `eval_1_grad` gives it
    /// (what a bump map reads); only Mitsuba's bitmap has one, here a checkerboard's is zero.
    pub fn eval_1_grad(&self, uv: Vec2) -> Vec2 {
        match self {
            Texture::Checkerboard { .. } => Vec2::ZERO,
            Texture::Bitmap(b) => b.eval_1_grad(uv),
        }
    }

    /// The mean colour, per channel (Mitsuba 0.6's `Texture::getAverage`: a checkerboard's two
    /// colours averaged, a bitmap's texels), what its `phong` and `ward` weigh their lobes by.
    pub fn average(&self) -> Vec3 {
        match self {
            Texture::Checkerboard { color0, color1, .. } => 0.5 * (*color0 + *color1),
            Texture::Bitmap(b) => {
                let sum = b.texels.iter().fold([0.0f64; 3], |s, t| {
                    [s[0] + t.x as f64, s[1] + t.y as f64, s[2] + t.z as f64]
                });
                let n = b.texels.len().max(1) as f64;
                Vec3::new(
                    (sum[0] / n) as f32,
                    (sum[1] / n) as f32,
                    (sum[2] / n) as f32,
                )
            }
        }
    }

    /// The largest value of each channel (Mitsuba 0.6's `Texture::getMaximum`: a checkerboard's
    /// colours, a bitmap's texels), what its energy-conservation check scales by.
    pub fn maximum(&self) -> Vec3 {
        match self {
            Texture::Checkerboard { color0, color1, .. } => color0.max(*color1),
            Texture::Bitmap(b) => b
                .texels
                .iter()
                .fold(Vec3::splat(f32::NEG_INFINITY), |m, t| m.max(*t))
                .max(Vec3::ZERO),
        }
    }

    /// The scalar mean Mitsuba's `Texture::mean` gives (what plastic's sampling weight uses):
    /// a checkerboard's colours' channel means averaged, a bitmap's mean luminance.
    pub fn mean(&self) -> f32 {
        let channels = |c: Vec3| (c.x + c.y + c.z) / 3.0;
        match self {
            Texture::Checkerboard { color0, color1, .. } => {
                0.5 * (channels(*color0) + channels(*color1))
            }
            Texture::Bitmap(b) => {
                let sum: f64 = b.texels.iter().map(|t| luminance(*t) as f64).sum::<f64>();
                (sum / b.texels.len().max(1) as f64) as f32
            }
        }
    }
}

/// Rec. 709 luminance of linear RGB (Mitsuba's `luminance`): a texture's scalar lookup, what an
/// environment map is sampled by, a principled BSDF's tint.
pub fn luminance(c: Vec3) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}

/// sRGB's transfer function inverted: an encoded value in [0, 1] to linear.
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

impl Bitmap {
    fn texel(&self, x: i32, y: i32) -> Vec3 {
        let (w, h) = (self.width as i32, self.height as i32);
        let (x, y) = (self.wrap.wrap(x, w), self.wrap.wrap(y, h));
        self.texels[(y * w + x) as usize]
    }

    /// `uv` after `to_uv`, in texels: a NaN coordinate reads 0 (on the GPU too), an infinite
    /// one the limit.
    fn texel_space(&self, uv: Vec2) -> Vec2 {
        let limit = |x: f32| {
            if x.is_nan() {
                0.0
            } else {
                x.clamp(-UV_LIMIT, UV_LIMIT)
            }
        };
        let p = self.to_uv.apply(uv);
        Vec2::new(limit(p.x), limit(p.y)) * Vec2::new(self.width as f32, self.height as f32)
    }

    /// Dr.Jit's lookup: texel centres at (i + 1/2) / resolution; bilinear weights of the four
    /// texels around the point, each index wrapped by itself.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        let p = self.texel_space(uv);
        match self.filter {
            Filter::Nearest => {
                let i = p.floor();
                self.texel(i.x as i32, i.y as i32)
            }
            Filter::Bilinear => {
                let f = p - 0.5;
                let i = f.floor();
                let w1 = f - i;
                let w0 = Vec2::ONE - w1;
                let (x, y) = (i.x as i32, i.y as i32);
                self.texel(x, y) * (w0.x * w0.y)
                    + self.texel(x + 1, y) * (w1.x * w0.y)
                    + self.texel(x, y + 1) * (w0.x * w1.y)
                    + self.texel(x + 1, y + 1) * (w1.x * w1.y)
            }
        }
    }

    /// Mitsuba's `eval_1_grad` (bitmap.cpp): the luminance's bilinear interpolant
    /// differentiated in texel units, taken to (u, v) through the transpose of `to_uv`'s
    /// linear part and then scaled by the resolution, in that order as Mitsuba has it (the
    /// chain rule would scale first; the two differ only for a rotating `to_uv` on a texture
    /// that is not square). Zero for nearest-neighbour lookups.
    pub fn eval_1_grad(&self, uv: Vec2) -> Vec2 {
        if self.filter == Filter::Nearest {
            return Vec2::ZERO;
        }
        let f = self.texel_space(uv) - 0.5;
        let i = f.floor();
        let w1 = f - i;
        let w0 = Vec2::ONE - w1;
        let (x, y) = (i.x as i32, i.y as i32);
        let l = |x: i32, y: i32| luminance(self.texel(x, y));
        let (f00, f10, f01, f11) = (l(x, y), l(x + 1, y), l(x, y + 1), l(x + 1, y + 1));
        let dx = w0.y * (f10 - f00) + w1.y * (f11 - f01);
        let dy = w0.x * (f01 - f00) + w1.x * (f11 - f10);
        let [a, b] = self.to_uv.rows;
        let res = Vec2::new(self.width as f32, self.height as f32);
        res * Vec2::new(a[0] * dx + b[0] * dy, a[1] * dx + b[1] * dy)
    }

    /// Reads `path` (see [`read_image`]) as a bitmap texture. The error names the file.
    pub fn load(
        path: &Path,
        raw: bool,
        wrap: WrapMode,
        filter: Filter,
        to_uv: UvTransform,
    ) -> Result<Self, String> {
        let (width, height, texels, bytes) =
            read_image_bytes(path, raw).map_err(|e| format!("bitmap texture {e}"))?;
        Ok(Self {
            width,
            height,
            texels,
            bytes: bytes.map(|words| EncodedTexels { words, srgb: !raw }),
            wrap,
            filter,
            to_uv,
            source: path.to_path_buf(),
        })
    }
}

impl Bitmap {
    /// This bitmap's texels (read `raw`) decoded by `decode` per channel, kept as floats: an
    /// encoding the file does not declare (Mitsuba 0.6's `gamma` on a bitmap).
    pub fn decoded_with(mut self, decode: impl Fn(f32) -> f32) -> Self {
        for t in &mut self.texels {
            *t = Vec3::new(decode(t.x), decode(t.y), decode(t.z));
        }
        self.bytes = None;
        self
    }

    /// The file's texels were stored as 8-bit values (PNG, JPEG, BMP), not as floats.
    pub fn is_8_bit(&self) -> bool {
        self.bytes.is_some()
    }
}

/// Reads an image as linear RGB texels, row by row from the top: OpenEXR and Radiance HDR as
/// they are, PNG, JPEG and BMP (8 or 16 bits, grey or colour; alpha dropped) decoded from sRGB
/// unless `raw`. Refuses empty images, images over [`MAX_SIDE`] a side and non-finite texels;
/// the error begins with the file's name.
/// Decodes an image by what its bytes are, not what its name says: downloaded scenes have JPEGs
/// named .png and the other way round, which Mitsuba reads all the same.
fn decode_image(path: &Path) -> Result<::image::DynamicImage, String> {
    ::image::io::Reader::open(path)
        .map_err(|e| e.to_string())?
        .with_guessed_format()
        .map_err(|e| e.to_string())?
        .decode()
        .map_err(|e| e.to_string())
}

/// A Radiance HDR file's texels as the floats it stores. (The `image` crate's generic decoding
/// of these files tonemaps them to 8 bits: its own HDR reader keeps them.)
fn read_radiance(path: &Path) -> Result<(u32, u32, Vec<Vec3>), String> {
    let mut bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    radiance_signature(&mut bytes);
    let decoder = ::image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let meta = decoder.metadata();
    let texels = decoder
        .read_image_hdr()
        .map_err(|e| e.to_string())?
        .into_iter()
        .map(|p| Vec3::from_array(p.0))
        .collect();
    Ok((meta.width, meta.height, texels))
}

/// Radiance HDR files begin `#?RADIANCE`, but many tools write `#?RGBE` (or another program
/// name) there, which Radiance's own readers and Mitsuba accept and the `image` crate does not:
/// such a first line is rewritten to the one it knows.
fn radiance_signature(bytes: &mut Vec<u8>) {
    const SIGNATURE: &[u8] = b"#?RADIANCE";
    let Some(end) = bytes.iter().position(|&b| b == b'\n') else {
        return;
    };
    let first = &bytes[..end];
    let rgbe_header = bytes.windows(7).take(512).any(|w| w == b"FORMAT=");
    if first.starts_with(b"#?") && first != SIGNATURE && rgbe_header {
        bytes.splice(..end, SIGNATURE.iter().copied());
    }
}

pub fn read_image(path: &Path, raw: bool) -> Result<(u32, u32, Vec<Vec3>), String> {
    read_image_bytes(path, raw).map(|(w, h, texels, _)| (w, h, texels))
}

/// [`read_image`], with an 8-bit image's bytes as [`EncodedTexels::words`].
fn read_image_bytes(path: &Path, raw: bool) -> Result<Decoded, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let fail = |why: String| format!("{}: {why}", path.display());
    let (width, height, texels, bytes): Decoded = match ext.as_str() {
        "exr" => {
            let image = crate::image::Image::read_exr(path).map_err(|e| fail(e.to_string()))?;
            let texels = image.pixels.iter().map(|p| Vec3::from_array(*p)).collect();
            (image.width, image.height, texels, None)
        }
        "hdr" => {
            let (width, height, texels) = read_radiance(path).map_err(fail)?;
            (width, height, texels, None)
        }
        "png" | "jpg" | "jpeg" | "bmp" => {
            let image = decode_image(path).map_err(fail)?;
            let rgb = image.to_rgb32f();
            let decode = |x: f32| if raw { x } else { srgb_to_linear(x) };
            let texels = rgb
                .pixels()
                .map(|p| Vec3::new(decode(p.0[0]), decode(p.0[1]), decode(p.0[2])))
                .collect();
            let eight_bits = matches!(
                image.color(),
                ::image::ColorType::L8
                    | ::image::ColorType::La8
                    | ::image::ColorType::Rgb8
                    | ::image::ColorType::Rgba8
            );
            let bytes = eight_bits.then(|| {
                let pack = |p: &::image::Rgb<u8>| {
                    p.0[0] as u32 | (p.0[1] as u32) << 8 | (p.0[2] as u32) << 16
                };
                image.to_rgb8().pixels().map(pack).collect()
            });
            (rgb.width(), rgb.height(), texels, bytes)
        }
        _ => {
            return Err(fail(
                "unknown image format (supported: .png, .jpg, .jpeg, .bmp, .exr, .hdr)".into(),
            ));
        }
    };
    if width == 0 || height == 0 {
        return Err(fail("the image is empty".into()));
    }
    if width.max(height) > MAX_SIDE {
        return Err(fail(format!(
            "{width}x{height} texels: at most {MAX_SIDE} a side are supported"
        )));
    }
    if let Some(i) = texels.iter().position(|t| !t.is_finite()) {
        return Err(fail(format!(
            "texel ({}, {}) is not a finite number",
            i as u32 % width,
            i as u32 / width
        )));
    }
    Ok((width, height, texels, bytes))
}

/// Width, height, linear texels and, for an 8-bit image, its bytes.
type Decoded = (u32, u32, Vec<Vec3>, Option<Vec<u32>>);

/// `GpuMaterial`'s texture fields when the parameter has none.
pub const NO_TEXTURE: u32 = u32::MAX;
pub const TEXTURE_CHECKERBOARD: u32 = 0;
pub const TEXTURE_BITMAP: u32 = 1;
/// Bitmaps kept as their 8-bit bytes ([`EncodedTexels`]), sRGB-encoded or linear.
pub const TEXTURE_BITMAP_SRGB8: u32 = 2;
pub const TEXTURE_BITMAP_LINEAR8: u32 = 3;
/// Words per texture header in the GPU's texture buffer.
pub const HEADER_WORDS: usize = 12;

/// Every texture as the GPU reads it, one array of 32-bit words (a single scene binding):
/// a header of [`HEADER_WORDS`] per texture (kind, width, height, wrap, filter, offset of its
/// data, the six numbers of `to_uv` as f32 bits), then the data: a checkerboard's two colours,
/// a bitmap's texels row by row from the top, as its 8-bit bytes one word a texel where the file
/// has them, else as linear f32 RGB.
/// Whether a bitmap of `textures` is kept as float texels (an OpenEXR, HDR or 16-bit image):
/// the shaders read float texels only where one is.
pub fn has_float_bitmaps(textures: &[Texture]) -> bool {
    textures
        .iter()
        .any(|t| matches!(t, Texture::Bitmap(b) if b.bytes.is_none()))
}

pub fn gpu_words(textures: &[Texture]) -> Vec<u32> {
    let mut words = vec![0u32; HEADER_WORDS * textures.len()];
    for (i, t) in textures.iter().enumerate() {
        let data = words.len() as u32;
        let (kind, width, height, wrap, filter, to_uv) = match t {
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                words.extend(color0.to_array().iter().map(|c| c.to_bits()));
                words.extend(color1.to_array().iter().map(|c| c.to_bits()));
                (TEXTURE_CHECKERBOARD, 0, 0, 0, 0, to_uv)
            }
            Texture::Bitmap(b) => {
                let kind = match &b.bytes {
                    Some(bytes) => {
                        words.extend_from_slice(&bytes.words);
                        if bytes.srgb {
                            TEXTURE_BITMAP_SRGB8
                        } else {
                            TEXTURE_BITMAP_LINEAR8
                        }
                    }
                    None => {
                        words.extend(b.texels.iter().flat_map(|t| t.to_array().map(f32::to_bits)));
                        TEXTURE_BITMAP
                    }
                };
                let filter = match b.filter {
                    Filter::Bilinear => 0,
                    Filter::Nearest => 1,
                };
                let (w, h) = (b.width, b.height);
                (kind, w, h, b.wrap.code(), filter, &b.to_uv)
            }
        };
        let header = &mut words[HEADER_WORDS * i..HEADER_WORDS * (i + 1)];
        header[..6].copy_from_slice(&[kind, width, height, wrap, filter, data]);
        for (slot, value) in header[6..].iter_mut().zip(to_uv.rows.iter().flatten()) {
            *slot = value.to_bits();
        }
    }
    words
}
