#define_import_path common::texture

// Mitsuba 3's checkerboard and bitmap textures; the CPU reference is src/scene/texture.rs
// (Texture::eval), which this must equal. Compiled in only for scenes with textures.

#ifdef TEXTURES
#import common::scene::{Material, NO_TEXTURE, bsdf_tables, texture_word, material_alpha_floor}
#import common::sampling::luminance

const TEXTURE_CHECKERBOARD: u32 = 0u;
const TEXTURE_BITMAP: u32 = 1u;
const TEXTURE_BITMAP_SRGB8: u32 = 2u;
const HEADER_WORDS: u32 = 12u;
const WRAP_REPEAT: u32 = 0u;
const WRAP_MIRROR: u32 = 1u;
const FILTER_NEAREST: u32 = 1u;
// Texture coordinates are clamped to this before texel indices are taken (as on the CPU).
const UV_LIMIT: f32 = 1.0e4;

struct TextureHeader {
    kind: u32,
    width: i32,
    height: i32,
    wrap: u32,
    filter_type: u32,
    data: u32,
    to_u: vec3<f32>,
    to_v: vec3<f32>,
}

fn word_f32(i: u32) -> f32 {
    return bitcast<f32>(texture_word(i));
}

fn texture_header(index: u32) -> TextureHeader {
    let h = index * HEADER_WORDS;
    return TextureHeader(
        texture_word(h),
        i32(texture_word(h + 1u)),
        i32(texture_word(h + 2u)),
        texture_word(h + 3u),
        texture_word(h + 4u),
        texture_word(h + 5u),
        vec3<f32>(word_f32(h + 6u), word_f32(h + 7u), word_f32(h + 8u)),
        vec3<f32>(word_f32(h + 9u), word_f32(h + 10u), word_f32(h + 11u)),
    );
}

fn word_rgb(i: u32) -> vec3<f32> {
    return vec3<f32>(word_f32(i), word_f32(i + 1u), word_f32(i + 2u));
}

// Euclidean remainder (the result is in [0, n) for n > 0).
fn rem_euclid(i: i32, n: i32) -> i32 {
    let r = i % n;
    return select(r, r + n, r < 0);
}

// Dr.Jit's tex_wrap for one texel index of a row or column of n.
fn wrap_texel(i: i32, n: i32, mode: u32) -> i32 {
    if mode == WRAP_REPEAT {
        return rem_euclid(i, n);
    }
    if mode == WRAP_MIRROR {
        let m = rem_euclid(i, 2 * n);
        return select(m, 2 * n - 1 - m, m >= n);
    }
    return clamp(i, 0, n - 1);
}

// Mitsuba's sRGB transfer function, the CPU's srgb_to_linear.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

fn texel(t: TextureHeader, x: i32, y: i32) -> vec3<f32> {
    let wx = wrap_texel(x, t.width, t.wrap);
    let wy = wrap_texel(y, t.height, t.wrap);
    let i = u32(wy * t.width + wx);
#ifdef FLOAT_TEXELS
    if t.kind == TEXTURE_BITMAP {
        return word_rgb(t.data + 3u * i);
    }
#endif
    // One word a texel: the file's 8-bit channels, decoded here as the CPU decoded them.
    let w = texture_word(t.data + i);
    let c = vec3<f32>(f32(w & 255u), f32((w >> 8u) & 255u), f32((w >> 16u) & 255u)) / 255.0;
    return select(c, srgb_to_linear(c), t.kind == TEXTURE_BITMAP_SRGB8);
}

fn upper_half(x: f32) -> bool {
    return x - floor(x) > 0.5;
}

// `uv` through the texture's to_uv (UvTransform::apply).
fn to_uv(t: TextureHeader, uv: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(dot(t.to_u, vec3<f32>(uv, 1.0)), dot(t.to_v, vec3<f32>(uv, 1.0)));
}

// A bitmap's `uv` after to_uv, in texels (Bitmap::texel_space): a NaN coordinate (which equals
// nothing) reads 0, an infinite one the limit, as on the CPU.
fn texel_space(t: TextureHeader, uv: vec2<f32>) -> vec2<f32> {
    var p = to_uv(t, uv);
    p = select(p, vec2<f32>(0.0), p != p);
    p = clamp(p, vec2<f32>(-UV_LIMIT), vec2<f32>(UV_LIMIT));
    return p * vec2<f32>(f32(t.width), f32(t.height));
}

// A bitmap's colour at `uv`: its nearest texel, or the bilinear mean of four.
fn bitmap_eval(t: TextureHeader, uv: vec2<f32>) -> vec3<f32> {
    let p = texel_space(t, uv);
    if t.filter_type == FILTER_NEAREST {
        let i = floor(p);
        return texel(t, i32(i.x), i32(i.y));
    }
    let f = p - 0.5;
    let i = floor(f);
    let w1 = f - i;
    let w0 = vec2<f32>(1.0) - w1;
    let x = i32(i.x);
    let y = i32(i.y);
    return texel(t, x, y) * (w0.x * w0.y) + texel(t, x + 1, y) * (w1.x * w0.y) + texel(t, x, y + 1) * (w0.x * w1.y) + texel(t, x + 1, y + 1) * (w1.x * w1.y);
}

// Texture `index` at `uv`: its colour, or with `scalar` Mitsuba's eval_1 (what a roughness
// reads) in every channel: a bitmap's luminance, a checkerboard's with its colours the other way
// round from the colour's, as Mitsuba has them.
fn texture_lookup(index: u32, uv: vec2<f32>, scalar: bool) -> vec3<f32> {
    let t = texture_header(index);
    var colour: vec3<f32>;
    if t.kind == TEXTURE_CHECKERBOARD {
        let p = to_uv(t, uv);
        let first = (upper_half(p.x) == upper_half(p.y)) != scalar;
        colour = select(word_rgb(t.data + 3u), word_rgb(t.data), first);
    } else {
        colour = bitmap_eval(t, uv);
    }
    return select(colour, vec3<f32>(luminance(colour)), scalar);
}

// Texture `index` at texture coordinates `uv`.
fn texture_eval(index: u32, uv: vec2<f32>) -> vec3<f32> {
    return texture_lookup(index, uv, false);
}

// The scalar value at `uv` (Mitsuba's eval_1), see texture_lookup.
fn texture_eval_1(index: u32, uv: vec2<f32>) -> f32 {
    return texture_lookup(index, uv, true).x;
}

// Mitsuba's eval_1_grad of a bitmap (what a bump map reads; a checkerboard has none): the
// luminance's bilinear interpolant differentiated in texel units, through the transpose of
// to_uv's linear part, then times the resolution (Bitmap::eval_1_grad, src/scene/texture.rs).
fn texture_eval_1_grad(index: u32, uv: vec2<f32>) -> vec2<f32> {
    let t = texture_header(index);
    if t.kind == TEXTURE_CHECKERBOARD || t.filter_type == FILTER_NEAREST {
        return vec2<f32>(0.0);
    }
    let res = vec2<f32>(f32(t.width), f32(t.height));
    let f = texel_space(t, uv) - 0.5;
    let i = floor(f);
    let w1 = f - i;
    let w0 = vec2<f32>(1.0) - w1;
    let x = i32(i.x);
    let y = i32(i.y);
    let f00 = luminance(texel(t, x, y));
    let f10 = luminance(texel(t, x + 1, y));
    let f01 = luminance(texel(t, x, y + 1));
    let f11 = luminance(texel(t, x + 1, y + 1));
    let dx = w0.y * (f10 - f00) + w1.y * (f11 - f01);
    let dy = w0.x * (f01 - f00) + w1.x * (f11 - f10);
    return res * vec2<f32>(t.to_u.x * dx + t.to_v.x * dy, t.to_u.y * dx + t.to_v.y * dy);
}

// The material with its textured colours looked up at `uv`: everything after the lookup (BSDF
// evaluation and sampling, hit-point weights, photon bounces) sees the surface's own values.
fn textured_material(m: Material, uv: vec2<f32>) -> Material {
    var out = m;
    // The floor the untextured roughness gets too when packed; a kind may keep its roughness
    // there as given (principled floors its alphas itself).
    let floor = material_alpha_floor(m.kind);
    let slots = array<u32, 4>(m.diffuse_texture, m.specular_texture, m.alpha_u_texture, m.alpha_v_texture);
    var textured = 0u;
    for (var slot = 0u; slot < 4u; slot++) {
        textured |= select(0u, 1u << slot, slots[slot] != NO_TEXTURE);
    }
    // specular, eta and k as one array for field textures (one component each), taken once the
    // fixed slots are done (which come first).
    var fields: array<f32, 9>;
    var field = 0u;
    // One lookup site for every slot and field texture, in a loop whose trip count the compiler
    // cannot know (so it is not unrolled): lavapipe inlines each call, and a lookup is much code
    // (four texels, each a chunked load). Slots 2 and 3 (roughnesses) and fields are scalars.
    loop {
        var slot = 4u;
        var texture = NO_TEXTURE;
        if textured != 0u {
            slot = firstTrailingBit(textured);
            textured &= textured - 1u;
            texture = slots[slot];
        } else if field < m.field_texture_count {
            if field == 0u {
                fields = array<f32, 9>(
                    out.specular.x, out.specular.y, out.specular.z,
                    out.eta.x, out.eta.y, out.eta.z,
                    out.k.x, out.k.y, out.k.z
                );
            }
            let entry = m.field_textures + 2u * field;
            slot = 4u + u32(bsdf_tables[entry]);
            texture = u32(bsdf_tables[entry + 1u]);
            field += 1u;
        } else {
            break;
        }
        let value = texture_lookup(texture, uv, slot >= 2u);
        switch slot {
            case 0u: {
                out.albedo = value;
            }
            case 1u: {
                out.specular = value;
            }
            case 2u: {
                out.alpha_u = max(value.x, floor);
            }
            case 3u: {
                out.alpha_v = max(value.x, floor);
            }
            default: {
                fields[min(slot - 4u, 8u)] = value.x;
            }
        }
    }
    if m.field_texture_count != 0u {
        out.specular = vec3<f32>(fields[0], fields[1], fields[2]);
        out.eta = vec3<f32>(fields[3], fields[4], fields[5]);
        out.k = vec3<f32>(fields[6], fields[7], fields[8]);
    }
    return out;
}
#endif
