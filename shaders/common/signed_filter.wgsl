#define_import_path common::signed_filter

// Pixel filters with negative lobes (Lanczos, the Mitchell cubics): their samples are drawn
// from a table of |f| in the scene uniform (src/scene/filter.rs builds it: node j at
// j / nodes-per-pixel holds the integrals of |f| and of f from 0) and carry the weight
// f / (q F_W), q the table's density and F_W the filter's integral over the pixel's window.
// The splat kernel (path_trace.wgsl) weighs such a sample by f over the density of every
// pixel's draws at its position. CPU mirror: WeightedSampler in src/scene/filter.rs.

#import common::scene::scene_info
#import common::pixel_filter::{filter_radius, filter_weight}

// A signed filter's offset from a pixel's centre in the window [lo, hi] (offsets) for the
// uniform pair `u`, and the sample's weight: (offset, weight).
fn signed_filter_offset(u: vec2<f32>, lo: vec2<f32>, hi: vec2<f32>) -> vec3<f32> {
    let x = table_offset(u.x, lo.x, hi.x);
    let y = table_offset(u.y, lo.y, hi.y);
    return vec3<f32>(x.x, y.x, x.y * y.y);
}

// The density, per unit image area, of the signed filter's draws of all pixels at image
// position `position` (each pixel draws one sample from its table density q_p, cut to its
// window on the film): sum_p q_p(position - centre_p), separable in x and y. A sample drawn
// this way and splatted with f / density estimates what a uniformly placed one does
// (path_trace.wgsl `splat`).
fn signed_draw_density(position: vec2<f32>) -> f32 {
    let size = vec2<f32>(f32(scene_info.film_width), f32(scene_info.film_height));
    return draw_density_1d(position.x, size.x) * draw_density_1d(position.y, size.y);
}

fn draw_density_1d(t: f32, size: f32) -> f32 {
    let r = scene_filter_radius();
    let first = max(i32(floor(t - r - 0.5)), 0);
    let last = min(i32(ceil(t + r - 0.5)), i32(size) - 1);
    var total = 0.0;
    for (var p = first; p <= last; p++) {
        let center = f32(p) + 0.5;
        total += table_density(t - center, -center, size - center);
    }
    return total;
}

// The table's piecewise-constant density of |f| at `offset`, normalised on the window
// [lo, hi] cut to the support (0 outside it): what table_offset draws from.
fn table_density(offset: f32, window_lo: f32, window_hi: f32) -> f32 {
    let r = scene_filter_radius();
    let lo = max(window_lo, -r);
    let hi = min(window_hi, r);
    if offset < lo || offset > hi {
        return 0.0;
    }
    let per_pixel = filter_nodes_per_pixel();
    let bins = per_pixel * u32(r);
    let j = min(u32(abs(offset) * f32(per_pixel)), bins - 1u);
    let mass = filter_node(j + 1u).x - filter_node(j).x;
    return mass * f32(per_pixel) / (filter_cumulative(hi, 0u) - filter_cumulative(lo, 0u));
}

// Node j of the signed filter's table: (integral of |f|, integral of f) from 0 to its x.
fn filter_node(j: u32) -> vec2<f32> {
    let v = scene_info.filter_table[j / 2u];
    return select(v.xy, v.zw, (j & 1u) == 1u);
}

fn filter_nodes_per_pixel() -> u32 {
    return 2u * (127u / (2u * u32(scene_filter_radius())));
}

fn scene_filter_radius() -> f32 {
    return filter_radius(scene_info.filter_kind, scene_info.filter_param);
}

// The table's cumulative |f| (k 0) or f (k 1) from 0 to `x`, odd, linear between nodes.
fn filter_cumulative(x: f32, k: u32) -> f32 {
    let per_pixel = filter_nodes_per_pixel();
    let r = scene_filter_radius();
    let bins = per_pixel * u32(r);
    let a = min(abs(x), r) * f32(per_pixel);
    let j = min(u32(a), bins - 1u);
    let t = a - f32(j);
    let here = filter_node(j)[k];
    let next = filter_node(j + 1u)[k];
    let value = here + t * (next - here);
    return select(value, -value, x < 0.0);
}

// A signed filter's offset for `u` in [lo, hi] (cut to its support), drawn from the table's
// piecewise-constant |f|, and its weight f / (q F_W): (offset, weight). The CPU mirror is
// WeightedSampler::sample in src/scene/filter.rs.
fn table_offset(u: f32, window_lo: f32, window_hi: f32) -> vec2<f32> {
    let r = scene_filter_radius();
    let per_pixel = filter_nodes_per_pixel();
    let lo = max(window_lo, -r);
    let hi = min(window_hi, r);
    let c_lo = filter_cumulative(lo, 0u);
    let c_hi = filter_cumulative(hi, 0u);
    let target_value = c_lo + u * (c_hi - c_lo);
    let s = abs(target_value);
    var first = 0u;
    var last = per_pixel * u32(r);
    while last - first > 1u {
        let mid = (first + last) / 2u;
        if filter_node(mid).x <= s {
            first = mid;
        } else {
            last = mid;
        }
    }
    let mass = max(filter_node(first + 1u).x - filter_node(first).x, 1.17549435e-38);
    let a = (f32(first) + (s - filter_node(first).x) / mass) / f32(per_pixel);
    let x = clamp(select(a, -a, target_value < 0.0), lo, hi);
    let density = mass * f32(per_pixel) / (c_hi - c_lo);
    let window = filter_cumulative(hi, 1u) - filter_cumulative(lo, 1u);
    let f = filter_weight(scene_info.filter_kind, vec2<f32>(scene_info.filter_param, scene_info.filter_param_b), x);
    return vec2<f32>(x, f / (density * window));
}
