"""The urp and radial techniques: jitter injection, R16 storage, and the radial sum transcribed from the chapter."""

import dataclasses

import numpy as np
import pytest
from scipy.ndimage import map_coordinates

from vlref.errors import InputError
from vlref.io.exr import write_exr
from vlref.render import prepare_frame
from vlref.scene.load import load_scene
from vlref.techniques import radial, urp


@pytest.fixture(scope="module")
def sun():
    scene = load_scene("urp_sun", ["render.width=24", "render.height=14", "lights.0.shadows.resolution=128",
                                   "render.resolution=\"half\""])
    return scene, prepare_frame(scene)


def _with(scene, **params):
    p = dataclasses.replace(scene.techniques.urp, **params)
    return scene.replace(techniques=dataclasses.replace(scene.techniques, urp=p))


@pytest.mark.parametrize("suffix", [".npy", ".exr"])
def test_jitter_injection_round_trip(sun, tmp_path, suffix):
    scene, frame = sun
    out = urp.render(scene, frame)
    path = tmp_path / f"jitter{suffix}"
    if suffix == ".npy":
        np.save(path, out["jitter"])
    else:
        write_exr(path, out["jitter"].astype(np.float32))
    again = urp.render(_with(scene, jitter_path=str(path)), frame)
    assert np.array_equal(again["jitter"], out["jitter"])
    assert np.array_equal(again["march"], out["march"])
    assert np.array_equal(again["final"], out["final"])


def test_injected_jitter_is_used(sun, tmp_path):
    scene, frame = sun
    path = tmp_path / "zero.npy"
    np.save(path, np.zeros((7, 12)))
    out = urp.render(_with(scene, jitter_path=str(path)), frame)
    assert np.all(out["jitter"] == 0.0)
    np.save(path, np.zeros((3, 3)))
    with pytest.raises(InputError, match="jitter_path"):
        urp.render(_with(scene, jitter_path=str(path)), frame)


def test_r16_storage_and_bounds(sun):
    scene, frame = sun
    out = urp.render(scene, frame)
    for name in ("march", "blur_h", "blur_v", "depth_low"):
        k = out[name] * 65535.0
        assert np.allclose(k, np.rint(k), atol=1e-6) and out[name].min() >= 0 and out[name].max() <= 1
    # F = (lit count) * saturate(HG) / Steps  <=  (Steps - 1) / Steps
    assert out["march"].max() <= (25 - 1) / 25 + 1e-12


def test_urp_needs_a_directional_light():
    scene = load_scene("pillars", ["render.width=8", "render.height=6", "render.technique=\"urp\""])
    with pytest.raises(InputError, match="render.technique"):
        urp.render(scene, None)


def _chapter_sum(image, light_uv, n, density, weight, decay):
    """Listing 13-1 written as its closed form with SciPy's bilinear (clamp) sampler."""
    h, w = image.shape[:2]
    v, u = np.meshgrid((np.arange(h) + 0.5) / h, (np.arange(w) + 0.5) / w, indexing="ij")
    du, dv = (u - light_uv[0]) * density / n, (v - light_uv[1]) * density / n

    def tex(uu, vv):
        return np.stack([map_coordinates(image[..., c], [vv * h - 0.5, uu * w - 0.5], order=1, mode="nearest")
                         for c in range(image.shape[2])], axis=-1)

    total = tex(u, v)
    for i in range(1, n + 1):
        total = total + weight * decay ** (i - 1) * tex(u - i * du, v - i * dv)
    return total


@pytest.fixture(scope="module")
def radial_scene():
    scene = load_scene("radial_sun", ["render.width=32", "render.height=18", "techniques.radial.num_samples=24",
                                      "techniques.radial.decay=0.97"])
    return scene, prepare_frame(scene)


def test_radial_equals_the_chapter_sum(radial_scene):
    scene, frame = radial_scene
    out = radial.render(scene, frame)
    clip = frame.camera.view_projection() @ np.array([*(-np.asarray(scene.lights[0].direction)), 0.0])
    uv = ((clip[0] / clip[3] + 1) / 2, (1 - clip[1] / clip[3]) / 2)
    assert 0 < uv[0] < 1 and 0 < uv[1] < 1
    ref = _chapter_sum(out["light_image"], uv, 24, 0.84, 5.65, 0.97)
    assert out["light_image"].max() > 0
    assert np.allclose(out["radial"], ref, rtol=1e-10, atol=1e-12)
    assert np.allclose(out["inscatter"], ref * 0.0034, rtol=1e-10, atol=1e-14)


def test_radial_light_behind_the_camera_is_off(radial_scene):
    scene, frame = radial_scene
    behind = scene.replace(lights=(dataclasses.replace(scene.lights[0], direction=(0.0, -0.2, 1.0)),))
    out = radial.render(behind, frame)
    assert np.all(out["inscatter"] == 0.0)
    assert np.array_equal(out["final"], frame.scene_colour)


def test_disenone_variant_defaults(radial_scene):
    scene, frame = radial_scene
    p = dataclasses.replace(scene.techniques.radial, variant="disenone", num_samples=None, decay=None)
    s = scene.replace(techniques=dataclasses.replace(scene.techniques, radial=p))
    out = radial.render(s, frame)
    assert radial.variant_params(p)["weight"] == 1.0 / 32.0
    # radiate peaks at 0.5; 31 taps each weighted 1/1024 add at most 31/1024 * 0.5
    assert out["light_image"].max() <= 0.5
    assert out["radial"].max() <= 0.5 * (1 + 31 / 1024) + 1e-12


def test_gpugems_light_disc_is_antialiased_ldr_and_has_the_disc_area():
    """The occlusion pre-pass is an LDR target (values <= 1) and the disc's rim is anti-aliased: its
    coverage sums to the disc's area pi R^2 and some rim pixels are partly covered (a hard test would
    make a staircase rim, which the radial loop magnifies by 1 / (1 - Density))."""
    for radius, uv in ((7.3, (0.41, 0.57)), (12.0, (0.5, 0.5))):
        cov = radial.disc_coverage(96, 64, uv, radius)
        assert cov.min() >= 0.0 and cov.max() <= 1.0
        assert cov.sum() == pytest.approx(np.pi * radius ** 2, rel=0.01)
        rim = (cov > 0.0) & (cov < 1.0)
        assert rim.sum() >= 2 * np.pi * radius * 0.8
    scene = load_scene("pillars", ["render.width=64", "render.height=36", 'render.technique="radial"',
                                   "lights.0.shadows.resolution=64"])
    out = radial.render(scene, prepare_frame(scene))
    assert 0.0 < out["light_image"].max() <= 1.0
