"""The Python module against the command line and against what each call promises.

Run from a clone after `pip install .` (see README.md): `pytest python/tests`. Renders are
small (32x32 to 128x128) on whatever adapter the machine has (lavapipe in CI).
"""

import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import hppm

REPO = Path(__file__).resolve().parents[2]
GLASS_SPHERE = REPO / "tests/refs/scenes/cornell_glass_sphere/scene.xml"
GLASS_SPHERE_REFERENCE = REPO / "tests/refs/images/cornell_glass_sphere.exr"


def cli_commands():
    """The command lines to compare with: the `hppm` the package installed (run through this
    interpreter, so the one of this venv), and a cargo-built binary named by $HPPM_CLI (CI sets
    it to target/debug/hppm, the build the Rust tests ran)."""
    commands = [[sys.executable, "-m", "hppm"]]
    built = os.environ.get("HPPM_CLI")
    if built:
        commands.append([built])
    return commands


def cli_render(command, tmp_path, scene, graph, *flags):
    out = tmp_path / f"cli-{len(list(tmp_path.iterdir()))}.exr"
    args = [*command, "render", str(scene), "--graph", str(graph), "--out", str(out), *flags]
    done = subprocess.run(args, capture_output=True, text=True, cwd=REPO)
    assert done.returncode == 0, f"{' '.join(args)}\n{done.stderr}"
    return hppm.read_exr(out)


@pytest.mark.parametrize("command", cli_commands(), ids=lambda c: Path(c[-1]).name)
def test_render_of_the_glass_sphere_is_the_cli_image(command, tmp_path):
    """Catches a budget, seed, size or graph the module maps differently from the command line,
    and an array laid out wrong (transposed, flipped rows, BGR, float64). `pt` is deterministic
    on a device, so it must be equal bit for bit; the hybrid adds photon flux with float atomics
    whose order varies from run to run (two CLI runs differ by up to ~1e-6 relative), so it is
    held to that order of noise, far below what any mapping error would make."""
    scene = hppm.load_scene(GLASS_SPHERE)
    pt = hppm.render(scene, "pt", spp=64, seed=5)
    assert pt.shape == (128, 128, 3) and pt.dtype == np.float32
    cli_pt = cli_render(command, tmp_path, GLASS_SPHERE, REPO / "graphs/pt.ron", "--spp", "64", "--seed", "5")
    assert np.array_equal(pt, cli_pt), f"max difference {np.abs(pt - cli_pt).max()}"

    hybrid = hppm.render(scene, hppm.load_graph("hybrid"), spp=64, seed=5)
    assert hybrid.shape == (128, 128, 3) and hybrid.dtype == np.float32
    cli_hybrid = cli_render(command, tmp_path, GLASS_SPHERE, REPO / "graphs/hybrid.ron", "--spp", "64", "--seed", "5")
    assert hppm.relmse(hybrid, cli_hybrid) < 1e-9
    np.testing.assert_allclose(hybrid, cli_hybrid, rtol=1e-4, atol=1e-6)
    # The two graphs differ where the caustic under the sphere is: the comparison can fail.
    assert hppm.relmse(pt, hybrid) > 1e-4


def test_the_render_converges_to_mitsubas_reference():
    """Catches an image that is the right shape but not the scene (dark, mirrored, a lost
    caustic): the hybrid at 256 spp against Mitsuba 3's converged render. Measured here (2-core
    EPYC, lavapipe 25.0.7): relMSE 1.1e-3 and 1.0e-3 with seeds 1 and 2; the same image 10%
    darker 4.2e-3, `pt` at 256 spp (its caustic still fireflies) 9.7e-3, mirrored 0.87."""
    reference = hppm.read_exr(GLASS_SPHERE_REFERENCE)
    image = hppm.render(GLASS_SPHERE, "hybrid", spp=256, seed=1)
    bound = 2.5e-3
    assert hppm.relmse(image, reference) < bound
    assert hppm.relmse(image * 0.9, reference) > bound


def test_mitsuba_parameters_reach_the_scene(tmp_path):
    """Catches `**params` dropped or spelled unlike Mitsuba's `-D` (booleans as `True`)."""
    scene_file = tmp_path / "params.xml"
    scene_file.write_text(
        """<scene version="3.0.0">
    <default name="width" value="16"/>
    <default name="spp" value="4"/>
    <default name="flip" value="false"/>
    <sensor type="perspective">
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="$width"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="constant"/>
    <shape type="sphere"><boolean name="flip_normals" value="$flip"/><bsdf type="diffuse"/></shape>
</scene>
"""
    )
    default = hppm.load_scene(scene_file)
    assert default.size == (16, 8) and default.spp == 4
    changed = hppm.load_scene(scene_file, width=24, spp=9, flip=True)
    assert changed.size == (24, 8) and changed.spp == 9
    # The scene's sample count is the default budget, as for `hppm render`.
    renderer = hppm.Renderer(changed, "pt")
    summary = renderer.run()
    assert summary["spp"] == 9 and summary["stop"] == "count"
    assert renderer.image().shape == (8, 24, 3)


def test_a_scene_error_names_its_file_line_and_column(tmp_path):
    """Catches errors that reach Python as a bare message or a crash, without the place."""
    scene_file = tmp_path / "broken.xml"
    scene_file.write_text(
        '<scene version="3.0.0">\n'
        '    <sensor type="perspective"/><emitter type="constant"/>\n'
        '    <shape type="sphere">\n'
        '        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5"/></bsdf>\n'
        "    </shape>\n"
        "</scene>\n"
    )
    with pytest.raises(hppm.SceneError) as raised:
        hppm.load_scene(scene_file)
    error = raised.value
    assert isinstance(error, hppm.Error)
    assert Path(error.file) == scene_file
    assert error.line == 4 and error.column > 1
    assert f"{scene_file}:4:{error.column}" in str(error)

    with pytest.raises(hppm.SceneError) as missing:
        hppm.load_scene(tmp_path / "nowhere.xml")
    assert Path(missing.value.file) == tmp_path / "nowhere.xml" and missing.value.line is None


def test_a_graph_error_names_its_file_line_and_column(tmp_path):
    """Catches graph errors without their place, and a misspelt kind accepted."""
    text = (REPO / "graphs/pt.ron").read_text()
    broken = text.replace('pass: "path_trace"', 'pass: "path_tracer"', 1)
    assert broken != text
    graph_file = tmp_path / "broken.ron"
    graph_file.write_text(broken)
    line = next(i + 1 for i, l in enumerate(broken.splitlines()) if '"path_tracer"' in l)
    with pytest.raises(hppm.GraphError) as raised:
        hppm.load_graph(graph_file)
    assert Path(raised.value.file) == graph_file and raised.value.line == line
    assert "path_trace" in str(raised.value)  # the did-you-mean

    with pytest.raises(hppm.GraphError) as unknown:
        hppm.load_graph("hybird")
    assert "hybrid" in str(unknown.value)  # the bundled names
    assert unknown.value.file == "hybird" and unknown.value.line is None


def test_bundled_graphs_are_the_files_of_graphs():
    """Catches a bundled graph that is not the repository's file of that name."""
    assert {"pt", "hybrid", "hybrid_pppm"} <= set(hppm.bundled_graphs())
    for name in hppm.bundled_graphs():
        bundled = hppm.load_graph(name)
        on_disk = hppm.load_graph(REPO / "graphs" / f"{name}.ron")
        assert bundled.text == on_disk.text and bundled.nodes == on_disk.nodes


def test_a_progressive_render_is_the_one_shot_render(tmp_path):
    """Catches iterations that restart instead of accumulating, counters that lie, and `run`
    counting its budget from the wrong start."""
    renderer = hppm.Renderer(GLASS_SPHERE, "pt", size=(32, 24), seed=3)
    assert renderer.iterations == 0 and renderer.size == (32, 24)
    assert renderer.error_estimate() is None
    renderer.iterate(2)
    assert renderer.iterations == 2
    assert renderer.spp == 2 * renderer.spp_per_iteration
    estimate = renderer.error_estimate()
    assert estimate is not None and estimate["relmse"] > 0
    assert estimate["per_pixel"].shape == (24, 32, 3)
    summary = renderer.run(spp=8 * renderer.spp_per_iteration)
    assert summary["iterations"] == 8 and summary["stop"] == "count"
    progressive = renderer.image()
    assert progressive.shape == (24, 32, 3)
    one_shot = hppm.render(GLASS_SPHERE, "pt", size=(32, 24), seed=3, spp=8 * renderer.spp_per_iteration)
    assert np.array_equal(progressive, one_shot)
    # Another seed is another image: the comparison above can fail.
    assert not np.array_equal(one_shot, hppm.render(GLASS_SPHERE, "pt", size=(32, 24), seed=4, spp=8))


def test_progress_is_called_each_iteration_and_can_stop_the_render():
    """Catches a callback never called, called with stale counters, an exception swallowed,
    and a False that does not stop the render."""
    seen = []

    def progress(info):
        seen.append(info)
        return len(seen) < 3

    renderer = hppm.Renderer(GLASS_SPHERE, "pt", size=(16, 16))
    summary = renderer.run(spp=1000, progress=progress)
    assert summary["stop"] == "cancelled" and summary["iterations"] == 3
    assert [s["iterations"] for s in seen] == [1, 2, 3]
    assert all(s["spp"] == s["iterations"] * renderer.spp_per_iteration for s in seen)

    def fail(info):
        raise ValueError("stop here")

    with pytest.raises(ValueError, match="stop here"):
        hppm.render(GLASS_SPHERE, "pt", size=(16, 16), spp=1000, progress=fail)


def test_the_gil_is_released_while_the_gpu_works():
    """Catches a render that holds the GIL: another Python thread would stand still."""
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    thread = threading.Thread(target=count)
    renderer = hppm.Renderer(GLASS_SPHERE, "hybrid", size=(64, 64))
    renderer.iterate()  # compiles the pipelines
    thread.start()
    started = time.perf_counter()
    renderer.run(time=1.5)
    ended = time.perf_counter()
    done.set()
    thread.join()
    during = [t for t in ticks if started <= t <= ended]
    # 5 ms sleeps: ~300 ticks in 1.5 s when the thread runs freely; a held GIL allows none
    # between the first and the last iteration.
    assert len(during) > 50, len(during)


def test_aovs_are_the_terms_of_the_image():
    """Catches AOVs swapped or taken from the wrong node: the hybrid's image is its path-traced
    part plus its caustic, and the error estimate is as large as the image."""
    image, aovs = hppm.render(GLASS_SPHERE, "hybrid", spp=16, size=(48, 48), aovs=True)
    assert {"pt", "caustic", "error"} <= set(aovs)
    np.testing.assert_allclose(image, aovs["pt"] + aovs["caustic"], rtol=1e-5, atol=1e-6)
    assert aovs["caustic"].max() > 0.1 and aovs["error"].shape == image.shape


def test_time_budget_and_target_error():
    """Catches a time budget ignored and a target error that ends the render before its
    estimate is below it."""
    started = time.perf_counter()
    renderer = hppm.Renderer(GLASS_SPHERE, "pt", size=(32, 32))
    summary = renderer.run(time=1.0)
    assert summary["stop"] == "time" and time.perf_counter() - started < 20
    target = hppm.Renderer(GLASS_SPHERE, "pt", size=(32, 32))
    summary = target.run(target_error=0.05, spp=100_000)
    assert summary["stop"] == "target_error"
    assert target.error_estimate()["relmse"] < 0.05
    with pytest.raises(hppm.Error, match="time"):
        renderer.run(time=-1.0)


def test_images_round_trip_and_relmse_is_compares(tmp_path):
    """Catches a writer or reader that reorders rows or channels, and a relMSE other than
    `hppm compare`'s definition."""
    rng = np.random.default_rng(1)
    image = rng.random((5, 7, 3), dtype=np.float32)
    hppm.write_image(tmp_path / "x.exr", image)
    assert np.array_equal(hppm.read_exr(tmp_path / "x.exr"), image)
    reference = rng.random((5, 7, 3), dtype=np.float32)
    expected = np.mean((image.astype(np.float64) - reference) ** 2 / (reference.astype(np.float64) ** 2 + 0.01))
    assert hppm.relmse(image, reference) == pytest.approx(expected, rel=1e-6)
    with pytest.raises(ValueError):
        hppm.relmse(image[..., :2].copy(), reference)


@pytest.mark.skipif(shutil.which("python3") is None, reason="no python3 on PATH")
def test_the_example_plots_error_against_time(tmp_path):
    """Catches the README's example going stale: it runs (briefly) and writes its plot."""
    pytest.importorskip("matplotlib")
    plot = tmp_path / "error.png"
    done = subprocess.run(
        [sys.executable, str(REPO / "python/examples/error_vs_time.py"), "--quick", "--out", str(plot)],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    assert done.returncode == 0, done.stderr
    assert plot.stat().st_size > 1000


def test_the_type_stubs_name_what_the_module_has():
    """Catches `_hppm.pyi` going stale: a call added, renamed or removed on one side only, and
    a Renderer method or property missing from the stubs."""
    import ast
    import inspect

    stubs = ast.parse((REPO / "python/hppm/_hppm.pyi").read_text())
    stubbed = {n.name for n in stubs.body if isinstance(n, (ast.ClassDef, ast.FunctionDef))}
    module = {name for name in dir(hppm._hppm) if not name.startswith("_")}
    assert stubbed == module
    renderer = next(n for n in stubs.body if isinstance(n, ast.ClassDef) and n.name == "Renderer")
    members = {n.name for n in renderer.body if isinstance(n, ast.FunctionDef)}
    members |= {n.target.id for n in renderer.body if isinstance(n, ast.AnnAssign)}
    public = {name for name, _ in inspect.getmembers(hppm.Renderer) if not name.startswith("_")}
    assert public <= members, public - members


def test_ctrl_c_stops_a_render_within_an_iteration():
    """Catches a render that ignores Ctrl-C until its budget ends (signals are checked after
    every iteration), and a renderer left unusable by the interruption."""
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    # A shell starts a background job with SIGINT ignored, and Python then keeps it ignored:
    # the render would run its whole budget. The handler a terminal gives is what is tested.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        interrupt_and_resume()
    finally:
        signal.signal(signal.SIGINT, previous)


def interrupt_and_resume():
    renderer = hppm.Renderer(GLASS_SPHERE, "pt", size=(16, 16))
    renderer.iterate()
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    started = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        renderer.run(spp=10_000_000)
    timer.join()
    assert time.perf_counter() - started < 10
    done = renderer.iterations
    assert 1 < done < 10_000_000
    renderer.iterate()
    assert renderer.iterations == done + 1 and renderer.image().shape == (16, 16, 3)


def test_a_renderer_serves_any_thread_one_call_at_a_time():
    """Catches a renderer tied to the thread that made it (a worker could not render what the
    main thread prepared, or the main thread not read the result), and a second call during a
    render that deadlocks instead of being refused."""
    renderer = hppm.Renderer(GLASS_SPHERE, "pt", size=(16, 16))
    failures = []

    def work():
        try:
            renderer.run(spp=8)
        except Exception as e:  # reported below, in the main thread
            failures.append(e)

    worker = threading.Thread(target=work)
    worker.start()
    worker.join()
    assert not failures, failures
    assert renderer.spp == 8 and renderer.image().shape == (16, 16, 3)

    refused = []

    def peek(info):
        try:
            renderer.image()
        except RuntimeError as e:
            refused.append(str(e))
        return False

    renderer.run(spp=1000, progress=peek)
    assert len(refused) == 1 and "borrow" in refused[0], refused


DARK_SCENE = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <shape type="rectangle"><bsdf type="diffuse"/></shape>
</scene>
"""


@pytest.mark.parametrize("command", cli_commands(), ids=lambda c: Path(c[-1]).name)
def test_a_scene_without_light_is_warned_of_as_the_cli_does(command, tmp_path):
    """Catches a black render with no word from Python, and a Python warning that drifts from
    the command line's: both come from one place (`Scene::no_light_warning`), and the CLI's
    "warning: ..." line must be the Python warning's text."""
    scene = tmp_path / "dark.xml"
    scene.write_text(DARK_SCENE)
    with pytest.warns(UserWarning, match="has no light") as caught:
        image = hppm.render(scene, "pt", spp=1)
    assert not image.any(), "a scene without light renders black"
    (warning,) = [str(w.message) for w in caught if "has no light" in str(w.message)]
    assert warning.startswith(str(scene)), warning
    args = [*command, "render", str(scene), "--graph", "pt", "--spp", "1", "--out", str(tmp_path / "dark.exr")]
    done = subprocess.run(args, capture_output=True, text=True, cwd=REPO)
    assert done.returncode == 0, done.stderr
    assert f"warning: {warning}" in done.stderr.splitlines(), done.stderr


def test_what_the_cli_warns_of_python_warns_of():
    """Catches a Python render that silently misses light the CLI warns about: `pt` cannot
    path trace a point light's caustic through glass (the image lacks it, and so does its error
    estimate); the hybrid traces photons and is not warned."""
    scene = REPO / "tests/refs/scenes/point_light_caustic/scene.xml"
    with pytest.warns(UserWarning, match="cannot be path traced"):
        hppm.Renderer(scene, "pt", size=(16, 16))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hppm.Renderer(scene, "hybrid", size=(16, 16))


VEACH = REPO / "tests/data/mitsuba06/lajolla/veach_mi/mi.xml"


def test_auto_chooses_as_the_cli_does_and_says_so(caplog):
    """graph="auto" pilots pt, hybrid and hybrid_pppm as `hppm render` does and goes on with the
    winner: on the Veach scene of glossy plates (no caustic) that is pt, predicted 6-10x ahead,
    so the image is pt's own with the same seed and samples (pt is deterministic on a device).
    Catches "auto" read as a graph file name, the choice not logged, the pilot's samples lost or
    counted twice."""
    caplog.set_level("INFO", logger="hppm")
    chosen = hppm.render(VEACH, "auto", spp=64, seed=5, size=(32, 18))
    assert any("auto: chose pt by" in r.getMessage() for r in caplog.records), caplog.text
    pt = hppm.render(VEACH, "pt", spp=64, seed=5, size=(32, 18))
    assert np.array_equal(chosen, pt), f"max difference {np.abs(chosen - pt).max()}"
