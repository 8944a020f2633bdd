#define_import_path bsdfs::normalmap

// The shading frame a BSDF is evaluated and sampled in: the surface's own, or the one Mitsuba's
// normalmap and bumpmap perturb from a texture. The CPU reference is src/bsdfs/normalmap/frame.rs
// (which says where each formula comes from in Mitsuba 3.9.1); this must equal it. Without
// NORMAL_MAPS every frame is the surface's and every factor 1.

#import common::sampling::basis_from_normal
#ifdef NORMAL_MAPS
#import common::scene::{Material, scene_info, triangle_at, triangle_uvs_at, spheres}
#import common::surface::Surface
#ifdef TEXTURES
#import common::texture::{texture_eval, texture_eval_1_grad}
#endif
#endif

const FRAME_NONE: u32 = 0u;
const FRAME_NORMAL_MAP: u32 = 1u;
const FRAME_BUMP_MAP: u32 = 2u;
const FRAME_FLAG_FLIP_INVALID: u32 = 1u;
const FRAME_FLAG_SHADOWING: u32 = 2u;
const FRAME_FLAG_OUTSIDE_TWOSIDED: u32 = 4u;

struct ShadingFrame {
    // The BSDF's local axes in world space (columns: tangent, bitangent, normal).
    frame: mat3x3<f32>,
    // The side's unperturbed shading normal: a perturbed frame masks and shadows by it.
    base: vec3<f32>,
    // Estevez et al.'s alpha squared for the perturbed normal; negative without the shadow terminator.
    alpha_sq: f32,
    perturbed: bool,
}

// The surface's own frame around its shading normal `n` (tangents from the normal alone).
fn plain_frame(n: vec3<f32>) -> ShadingFrame {
    return ShadingFrame(basis_from_normal(n), n, -1.0, false);
}

// What Mitsuba's normalmap and bumpmap multiply the nested BSDF's value and sampled weight by
// for the light's direction `light` (unit, world space; the photon's incident direction in
// the photon pass, the sampled or light direction in the camera pass): 0 where the perturbed
// and unperturbed frames put it on different sides, else the shadow terminator
// 2 / (1 + sqrt(1 + alpha^2 tan^2 theta)), theta from the unperturbed normal.
fn frame_factor(f: ShadingFrame, light: vec3<f32>) -> f32 {
#ifdef NORMAL_MAPS
    if !f.perturbed {
        return 1.0;
    }
    let cos_base = dot(light, f.base);
    if !(cos_base * dot(light, f.frame[2]) > 0.0) {
        return 0.0;
    }
    if f.alpha_sq < 0.0 {
        return 1.0;
    }
    let cos_sq = cos_base * cos_base;
    let tan_sq = max(1.0 - cos_sq, 0.0) / cos_sq;
    return 2.0 / (1.0 + sqrt(1.0 + f.alpha_sq * tan_sq));
#else
    return 1.0;
#endif
}

#ifdef NORMAL_MAPS
struct Derivatives {
    dp_du: vec3<f32>,
    dp_dv: vec3<f32>,
}

// dp_du and dp_dv of primitive `prim` at `position` (Mitsuba's mesh: from the corners' texture
// coordinates, the barycentrics' for a triangle without any, coordinate_system of the front
// face normal `normal` where they are degenerate; its sphere: u about +z, v down from +z).
fn surface_derivatives(prim: u32, position: vec3<f32>, normal: vec3<f32>) -> Derivatives {
#ifdef SPHERES
    if prim >= scene_info.num_triangles {
        let sphere = spheres[prim - scene_info.num_triangles];
        let d = normalize(position - sphere.center);
        let dp_du = vec3<f32>(-d.y, d.x, 0.0) * (6.2831853 * sphere.radius);
        let rd = sqrt(d.x * d.x + d.y * d.y);
        var local = vec3<f32>(1.0, 0.0, 0.0);
        if rd != 0.0 {
            local = vec3<f32>(d.z * d.x / rd, d.z * d.y / rd, -rd);
        }
        return Derivatives(dp_du, local * (3.14159265 * sphere.radius));
    }
#endif
    let tri = triangle_at(prim);
    let uvs = triangle_uvs_at(prim);
    let duv0 = uvs.b - uvs.a;
    let duv1 = uvs.c - uvs.a;
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    if det == 0.0 {
        let basis = basis_from_normal(normal);
        return Derivatives(basis[0], basis[1]);
    }
    let inv = 1.0 / det;
    return Derivatives((duv1.y * tri.edge_a - duv0.y * tri.edge_b) * inv, (duv0.x * tri.edge_b - duv1.x * tri.edge_a) * inv);
}

// The frame `m` gives the side of `surface` seen (after the twosided switch: `back` says
// whether it was made, and `surface`'s normals are then the back's). `toward_viewer` is where
// the camera path came from: with `flip` (camera paths), Mitsuba's flip_invalid_normals
// mirrors the perturbed normal's tangential part when that direction sees it from below;
// photons pass `flip` false, not knowing the viewer yet.
fn shading_frame(m: Material, surface: Surface, prim: u32, back: bool, toward_viewer: vec3<f32>, flip: bool) -> ShadingFrame {
#ifdef TEXTURES
    if m.frame_kind == FRAME_NONE {
        return plain_frame(surface.shading_normal);
    }
    let n_sh = select(surface.shading_normal, -surface.shading_normal, back);
    let geometric = select(surface.normal, -surface.normal, back);
    let d = surface_derivatives(prim, surface.position, geometric);
    // Mitsuba's initialize_sh_frame: the tangent follows dp_du.
    var s = basis_from_normal(n_sh)[0];
    if any(d.dp_du != vec3<f32>(0.0)) {
        s = normalize(d.dp_du - n_sh * dot(n_sh, d.dp_du));
    }
    let t = cross(n_sh, s);
    var local: vec3<f32>;
    if m.frame_kind == FRAME_NORMAL_MAP {
        local = texture_eval(m.frame_texture, surface.uv) * 2.0 - 1.0;
    } else {
        let grad = m.frame_scale * texture_eval_1_grad(m.frame_texture, surface.uv);
        let du = d.dp_du + n_sh * (grad.x - dot(n_sh, d.dp_du));
        let dv = d.dp_dv + n_sh * (grad.y - dot(n_sh, d.dp_dv));
        var n = normalize(cross(du, dv));
        if dot(geometric, n) < 0.0 {
            n = -n;
        }
        local = vec3<f32>(dot(n, s), dot(n, t), dot(n, n_sh));
    }
    let outside = (m.frame_flags & FRAME_FLAG_OUTSIDE_TWOSIDED) != 0u;
    // Inside a twosided the back is perturbed in its own turned-over frame (s, t, -n).
    let frame_n = select(n_sh, -n_sh, back && !outside);
    if flip && (m.frame_flags & FRAME_FLAG_FLIP_INVALID) != 0u {
        let wi = vec3<f32>(dot(toward_viewer, s), dot(toward_viewer, t), dot(toward_viewer, frame_n));
        if wi.z * dot(wi, local) <= 0.0 {
            local = vec3<f32>(-local.x, -local.y, local.z);
        }
    }
    // A texel with no normal (Mitsuba's would be NaN) leaves the frame unperturbed.
    var n = vec3<f32>(0.0, 0.0, 1.0);
    let length_sq = dot(local, local);
    if length_sq > 0.0 {
        n = local * inverseSqrt(length_sq);
    }
    var tangent: vec3<f32>;
    if m.frame_kind == FRAME_NORMAL_MAP {
        tangent = vec3<f32>(1.0, 0.0, 0.0) - n * n.x;
    } else {
        // As bumpmap.cpp has it: world-space dp_du's numbers taken as local ones.
        tangent = d.dp_du - n * dot(n, d.dp_du);
    }
    let tangent_sq = dot(tangent, tangent);
    if tangent_sq > 0.0 {
        tangent *= inverseSqrt(tangent_sq);
    } else {
        tangent = basis_from_normal(n)[0];
    }
    let bitangent = cross(n, tangent);
    let to_world = mat3x3<f32>(s, t, frame_n);
    // Outside a twosided the front's perturbed frame is turned over for the back.
    let turned = select(1.0, -1.0, back && outside);
    var alpha_sq = -1.0;
    if (m.frame_flags & FRAME_FLAG_SHADOWING) != 0u {
        let cos_sq = n.z * n.z;
        alpha_sq = min(0.125 * max(1.0 - cos_sq, 0.0) / cos_sq, 1.0);
    }
    return ShadingFrame(mat3x3<f32>(to_world * tangent, to_world * bitangent, turned * (to_world * n)), select(n_sh, -n_sh, back), alpha_sq, true);
#else
    return plain_frame(surface.shading_normal);
#endif
}
#endif
