"""Tests of vlref.notebook: display arrays, controls, timing, the frame-reusing preview renderer and the
bundled port-validation example."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vlref.io.images import read_image
from vlref.io.tonemap import srgb8
from vlref.notebook import (EXAMPLE_FILES, Choice, PreviewRenderer, Slider, Toggle, auto_exposure,
                            display_buffer, display_rgb, display_scalar, examples_dir, interact_or_static,
                            live_widgets, make_port_example, plot_images, scaled_light_intensity, time_call)
from vlref.oracle import compare_files
from vlref.render import render
from vlref.scene import load_scene

SMALL = ["render.width=32", "render.height=24", "render.steps=6", "lights.0.shadows.resolution=64"]


# --------------------------------------------------------------------------- display

def test_auto_exposure_maps_percentile_of_brightest_channel_to_one():
    rng = np.random.default_rng(1)
    img = rng.uniform(0.0, 4.0, (20, 30, 3))
    img[0, 0] = np.inf  # ignored
    peak = img.max(axis=2)
    expected = 1.0 / np.percentile(peak[np.isfinite(peak)], 99.0)
    assert auto_exposure(img) == pytest.approx(expected, rel=1e-12)
    assert auto_exposure(np.zeros((4, 4, 3))) == 1.0
    assert auto_exposure(np.full((4, 4), 0.5), percentile=50.0) == pytest.approx(2.0)


def test_display_rgb_is_the_png_tone_map():
    rng = np.random.default_rng(2)
    img = rng.uniform(0.0, 2.0, (8, 9, 3))
    out = display_rgb(img)
    assert out.dtype == np.uint8 and out.shape == (8, 9, 3)
    np.testing.assert_array_equal(out, srgb8(img, auto_exposure(img)))
    np.testing.assert_array_equal(display_rgb(img, exposure=0.25), srgb8(img, 0.25))
    grey = display_rgb(img[:, :, 0], exposure=1.0)
    assert grey.shape == (8, 9, 3) and np.all(grey[..., 0] == grey[..., 2])


def test_display_scalar_normalises_and_marks_non_finite():
    depth = np.array([[1.0, 2.0, 3.0], [np.inf, 5.0, -np.inf]])
    out = display_scalar(depth, vmin=1.0, vmax=5.0)
    np.testing.assert_allclose(out[0], [0.0, 0.25, 0.5])
    assert out[1, 1] == 1.0 and np.isnan(out[1, 0]) and np.isnan(out[1, 2])
    clipped = display_scalar(np.array([[0.0, 10.0]]), vmin=2.0, vmax=4.0)
    np.testing.assert_array_equal(clipped, [[0.0, 1.0]])
    ramp = np.arange(101, dtype=float).reshape(1, -1)
    auto = display_scalar(ramp)
    assert auto[0, 1] == pytest.approx(0.0) and auto[0, 99] == pytest.approx(1.0)
    assert auto[0, 50] == pytest.approx((50 - 1) / 98)
    assert np.all(display_scalar(np.full((3, 3), 7.0)) == 0.0)
    assert np.all(np.isnan(display_scalar(np.full((2, 2), np.inf))))


def test_display_buffer_dispatches_on_shape():
    rgb = np.full((4, 5, 3), 0.5)
    np.testing.assert_array_equal(display_buffer(rgb, exposure=2.0), srgb8(rgb, 2.0))
    depth = np.array([[1.0, np.inf], [3.0, 5.0]])
    np.testing.assert_array_equal(display_buffer(depth, vmin=1.0, vmax=5.0), display_scalar(depth, 1.0, 5.0))
    with pytest.raises(ValueError):
        display_buffer(np.zeros((2, 2, 4)))


def test_plot_images_one_panel_per_image():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rgb = display_rgb(np.random.default_rng(3).uniform(0, 1, (6, 8, 3)))
    scalar = display_scalar(np.array([[0.0, 1.0], [np.inf, 0.5]]))
    fig = plot_images({"a": rgb, "b": scalar, "c": rgb}, ncols=2)
    try:
        titled = [ax for ax in fig.axes if ax.get_title()]
        assert [ax.get_title() for ax in titled] == ["a", "b", "c"]
        assert len(fig.axes) == 4  # 2 x 2 grid, the last panel empty
        np.testing.assert_array_equal(titled[0].images[0].get_array(), rgb)
        shown = titled[1].images[0].get_array()
        assert np.ma.is_masked(shown) and shown.mask[1, 0]
    finally:
        plt.close(fig)
    with pytest.raises(ValueError):
        plot_images({})


# --------------------------------------------------------------------------- controls and timing

def test_static_interact_calls_once_with_control_values():
    calls = []

    def fn(a, b, c):
        calls.append((a, b, c))
        return a * 2

    controls = {"a": Slider(0.0, 1.0, 0.25), "b": Choice(("x", "y"), "y"), "c": Toggle(True)}
    assert interact_or_static(fn, controls, live=False) == 0.5
    assert calls == [(0.25, "y", True)]


def test_live_widgets_false_under_ci_and_outside_a_kernel(monkeypatch):
    monkeypatch.setenv("CI", "true")
    assert live_widgets() is False
    monkeypatch.delenv("CI")
    monkeypatch.delenv("VLREF_STATIC", raising=False)
    assert live_widgets() is False  # pytest is no IPython kernel


def test_live_interact_builds_widgets_and_runs_the_function():
    import ipywidgets as w

    calls = []

    def fn(steps, g, mode, blur):
        calls.append((steps, g, mode, blur))

    controls = {"steps": Slider(1, 64, 16, integer=True), "g": Slider(-0.9, 0.9, 0.3, step=0.1),
                "mode": Choice(("full", "half"), "half"), "blur": Toggle(False)}
    ui = interact_or_static(fn, controls, live=True)
    assert isinstance(ui, w.interactive)
    kinds = {c.description: type(c) for c in ui.children[:-1]}
    assert kinds == {"steps": w.IntSlider, "g": w.FloatSlider, "mode": w.Dropdown, "blur": w.Checkbox}
    assert calls == [(16, pytest.approx(0.3), "half", False)]
    ui.children[0].value = 32
    assert len(calls) == 2 and calls[-1][0] == 32
    log = interact_or_static(lambda s: None, {"s": Slider(0.01, 10.0, 1.0, log=True)}, live=True)
    assert isinstance(log.children[0], w.FloatLogSlider) and log.children[0].value == pytest.approx(1.0)


def test_time_call_counts_and_orders():
    n = []
    result, t = time_call(lambda: n.append(1) or len(n), repeat=4, warmup=2)
    assert len(n) == 6 and result == 6
    assert len(t.runs) == 4 and t.best == min(t.runs) and t.best <= t.median <= max(t.runs)
    assert "ms" in str(t)
    with pytest.raises(ValueError):
        time_call(lambda: None, repeat=0)


def test_scaled_light_intensity():
    scene = load_scene("coloured_lights")
    doubled = scaled_light_intensity(scene, 2.0)
    assert [l.intensity for l in doubled.lights] == [2.0 * l.intensity for l in scene.lights]
    assert doubled.medium == scene.medium
    with pytest.raises(ValueError, match="scale factor"):
        scaled_light_intensity(scene, -1.0)


# --------------------------------------------------------------------------- preview renderer

def _with(scene, **render_changes):
    return scene.replace(render=dataclasses.replace(scene.render, **render_changes))


@pytest.mark.parametrize("technique", ["physical", "killzone"])
def test_preview_renderer_matches_full_render_bit_for_bit(technique):
    base = _with(load_scene("pillars", SMALL), technique=technique)
    variants = [
        ("first", base, {"frame": 1, "shading": 0, "shadow_maps": 0}),
        ("medium", base.replace(medium=dataclasses.replace(base.medium, scattering=0.2, absorption=0.05,
                                                           anisotropy=-0.3)), {"frame": 1, "shading": 0}),
        ("march", _with(base, steps=3, sampling="bayer2"), {"frame": 1, "shading": 0}),
        ("power", scaled_light_intensity(base, 0.5), {"frame": 1, "shading": 1, "shadow_maps": 0}),
        ("moved", base.replace(lights=(dataclasses.replace(base.lights[0], position=(0.5, 6.0, 9.0)),)),
         {"frame": 1, "shading": 2, "shadow_maps": 1}),
        ("resized", _with(base, width=20, height=16), {"frame": 2}),
    ]
    preview = PreviewRenderer()
    for name, scene, counts in variants:
        got = preview.render(scene)
        want = render(scene, stages=True).buffers
        for key in ("final", "inscatter", "transmittance", "depth", "scene_colour"):
            np.testing.assert_array_equal(got[key], want[key], err_msg=f"{name}: {key}")
        assert set(got) >= {k for k in want if not k.startswith("shadow_")} - {"normal", "albedo", "object_id"}
        for key, value in counts.items():
            assert preview.rebuilds[key] == value, (name, preview.rebuilds)


def test_preview_frame_keeps_shadow_maps_across_medium_changes():
    base = load_scene("pillars", SMALL)
    preview = PreviewRenderer()
    maps = preview.frame(base).shadow_maps()
    denser = base.replace(medium=dataclasses.replace(base.medium, scattering=0.3))
    assert preview.frame(denser).shadow_maps() is maps
    assert preview.frame(scaled_light_intensity(denser, 3.0)).shadow_maps() is maps


# --------------------------------------------------------------------------- bundled example

def test_bundled_example_fails_with_the_bug_and_passes_without():
    folder = examples_dir()
    sizes = [(folder / f).stat().st_size for f in EXAMPLE_FILES.values()]
    assert sum(sizes) < 1_000_000
    ref = folder / EXAMPLE_FILES["reference"]
    bug = compare_files(ref, folder / EXAMPLE_FILES["port_bug"], "float32", flip=False)
    fixed = compare_files(ref, folder / EXAMPLE_FILES["port_fixed"], "float32", flip=False)
    assert not bug.passed and bug.metrics["frac_failing"] > 0.1
    assert fixed.passed and fixed.metrics["frac_failing"] <= fixed.tolerance.max_fail_fraction
    depth = read_image(folder / EXAMPLE_FILES["depth"], channels=1)
    assert depth.shape[:2] == bug.ref.shape[:2] and np.isinf(depth).any() and np.isfinite(depth).any()


def test_examples_dir_honours_environment(tmp_path, monkeypatch):
    (tmp_path / EXAMPLE_FILES["reference"]).write_bytes(b"")
    monkeypatch.setenv("VLREF_EXAMPLES", str(tmp_path))
    assert examples_dir() == tmp_path


def test_make_port_example_plants_a_phase_sign_bug(tmp_path):
    paths = make_port_example(tmp_path, width=24, height=16, steps=8)
    assert set(paths) == set(EXAMPLE_FILES)
    ref, bug, fixed = (read_image(paths[k]) for k in ("reference", "port_bug", "port_fixed"))
    scene = load_scene("pillars", ["render.width=24", "render.height=16", "render.steps=8",
                                   "render.sampling=\"none\""])
    flipped = scene.replace(medium=dataclasses.replace(scene.medium, anisotropy=-scene.medium.anisotropy),
                            render=dataclasses.replace(scene.render, precision="float32"))
    np.testing.assert_array_equal(ref, render(scene).buffers["final"].astype(np.float32))
    np.testing.assert_array_equal(bug, render(flipped).buffers["final"].astype(np.float32))
    assert np.max(np.abs(fixed - ref)) <= 1e-4 * np.max(np.abs(ref))
    assert np.max(np.abs(bug - ref)) > 1e-2 * np.max(np.abs(ref))
