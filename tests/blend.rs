//! Mitsuba's `mask` and `null` pass-throughs on the GPU, where the scene-level tests
//! (tests/furnace.rs's blend furnace, tests/differential's `blendbsdf` and `mask` scenes) cannot
//! see them: the depth a pass-through spends.

mod common;

use common::*;

/// A diffuse wall lit by an area light in front of it, both seen through a `null` panel that
/// covers the whole view (the light faces the wall, so the camera never sees it).
fn wall_behind_panel(max_depth: i32, panel: bool) -> String {
    let panel = if panel {
        r#"<shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="1"/></transform><bsdf type="null"/></shape>"#
    } else {
        ""
    };
    format!(
        r#"<scene version="3.0.0">
        <integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>
        <sensor type="perspective"><float name="fov" value="30"/>
            <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <shape type="rectangle"><transform name="to_world"><scale value="3"/></transform>
            <bsdf type="diffuse"/></shape>
        {panel}
        <shape type="rectangle"><transform name="to_world"><scale value="0.3"/><rotate x="1" angle="180"/><translate y="1.2" z="0.6"/></transform>
            <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>
        </scene>"#
    )
}

fn wall_mean(max_depth: i32, panel: bool) -> f64 {
    let scene = hppm::loaders::mitsuba::parse(
        &repo_path("tests/data/scenes/null_panel.xml"),
        &wall_behind_panel(max_depth, panel),
    )
    .expect("scene loads");
    let gpu = gpu();
    let mut r = renderer(&gpu, &scene, load_graph("graphs/pt.ron"), 1);
    render_to(&mut r, 16).mean()[0]
}

/// As in Mitsuba, a pass-through is a vertex of the path: with `max_depth` 2 (direct light)
/// the wall behind a `null` panel is black, since the panel took the first bounce, and with 3
/// it is lit as the bare wall is with 2 (Mitsuba 3.9.1 at 256 spp: 0.0659, 0 and 0.0658;
/// hppm 0.0659, 0 and 0.0659). Would catch a pass-through that spends no depth
/// (the wall lit at 2), or one that ends the path (black at 3).
#[test]
fn a_pass_through_spends_a_bounce_as_in_mitsuba() {
    let bare = wall_mean(2, false);
    let hidden = wall_mean(2, true);
    let through = wall_mean(3, true);
    eprintln!(
        "bare wall at depth 2: {bare:.5}; behind the panel at 2: {hidden:.5}, at 3: {through:.5}"
    );
    assert!(bare > 0.01, "the wall is lit: {bare}");
    assert_eq!(
        hidden, 0.0,
        "behind the panel at max_depth 2 the wall gets no light"
    );
    assert!(
        (through / bare - 1.0).abs() < 0.05,
        "behind the panel at max_depth 3 the wall is lit as the bare wall at 2: {through} vs {bare}"
    );
}
