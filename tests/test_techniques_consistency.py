"""Cross-technique consistency: with quirks neutralised and the same attenuation law, ``slightlymad``,
``killzone`` and ``physical`` at full resolution agree with the single-scattering integral.

Derivation of the bound. The scene has one unshadowed point light, a homogeneous medium and no
occluder in the light's ball, so along a pixel ray the exact in-scattered radiance is
``I = ∫_a^b f(t) dt`` with ``f(t) = σs p(dot(d, l(t)); g) E(t) e^{-σt t}``. Each technique takes one
sample per step cell of width ``Δ`` (killzone and neutralised slightlymad: ``f(t_i) Δ`` at the
left end, offset 0; physical: a per-cell value times the exact cell integral of ``e^{-σt t}``).
For any rule with one sample per cell, ``|Σ - ∫| <= Σ_cells Δ · osc_cell(f) <= Δ · TV(f)``, ``TV``
the total variation of ``f`` on the ray. The test computes ``TV`` and ``I`` per pixel with NumPy
on a dense grid and asserts ``|technique - I| <= Δ_technique · TV + 1e-9``; killzone and neutralised
slightlymad evaluate the same left sums, so they also agree with each other to rounding.
"""

import numpy as np
import pytest

from vlref.phase import hg_array
from vlref.render import prepare_frame
from vlref.scene.load import load_scene
from vlref.techniques import killzone, physical, slightlymad

SCENE = """
[render]
width = 20
height = 12
sampling = "none"
resolution = "full"
max_distance = 50.0
[camera]
position = [0.0, 2.0, -5.0]
look_at = [0.0, 2.0, 0.0]
fov = 50.0
[medium]
scattering = 0.1
absorption = 0.02
anisotropy = 0.3
[[lights]]
type = "point"
position = [0.5, 2.2, 3.0]
color = [1.0, 0.8, 0.6]
intensity = 4.0
range = 6.0
attenuation = "unity"
[[objects]]
shape = "plane"
point = [0.0, 0.0, 12.0]
normal = [0.0, 0.0, -1.0]
[techniques.killzone]
blur = false
transmittance = true
[techniques.slightlymad]
blur = false
fp16 = false
dither = "none"
right_endpoint = false
initial_half_tau = false
point_spot_alpha_zero = false
point_srgb_quirk = false
attenuation = "scene"
scattering = 0.1
extinction = 0.12
mie_g = 0.3
[techniques.physical]
light_extinction = false
"""
STEPS = 48


def _reference(frame, scene):
    """Dense NumPy integral I and total variation TV of f per pixel, and each ray's ball segment."""
    cam = frame.camera
    light = scene.lights[0]
    p = np.asarray(light.position)
    d = cam.ray_directions()
    o = cam.position
    v = o - p
    beta = -(d @ v)
    h2 = np.sum((v + beta[..., None] * d) ** 2, axis=-1)
    s = np.sqrt(np.maximum(light.range ** 2 - h2, 0.0))
    a, b = np.maximum(beta - s, 0.0), beta + s
    m = 20000
    t = a[..., None] + (b - a)[..., None] * (np.arange(m + 1) / m)
    x = o + t[..., None] * d[:, :, None, :]
    w = p - x
    dist2 = np.sum(w * w, axis=-1)
    u = dist2 / light.range ** 2
    att = np.clip(5.0 * (1.0 - np.sqrt(u)), 0.0, 1.0) / (1.0 + 25.0 * u)
    att = np.where(u < 1.0, att, 0.0)
    cos = np.sum(d[:, :, None, :] * w, axis=-1) / np.sqrt(dist2)
    med = scene.medium
    f = med.scattering * hg_array(cos, med.anisotropy) * att * np.exp(-med.extinction * t)
    dt = (b - a)[..., None] / m
    integral = np.sum(0.5 * (f[..., 1:] + f[..., :-1]) * dt, axis=-1)
    tv = np.sum(np.abs(np.diff(f, axis=-1)), axis=-1)
    return integral, tv, a, b


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    path = tmp_path_factory.mktemp("consistency") / "scene.toml"
    path.write_text(SCENE)
    scene = load_scene(str(path), [f"render.steps={STEPS}"])
    frame = prepare_frame(scene)
    return scene, frame, _reference(frame, scene)


def _channel0(out, scene):
    return out["inscatter"][..., 0] / (scene.lights[0].color[0] * scene.lights[0].intensity)


def test_killzone_and_slightlymad_match_the_integral_within_the_riemann_bound(setup):
    scene, frame, (integral, tv, a, b) = setup
    kz = _channel0(killzone.render(scene, frame), scene)
    vl = _channel0(slightlymad.render(scene, frame), scene)
    bound = (b - a) / STEPS * tv + 1e-9
    hit = b > a
    assert hit.sum() > 50 and integral.max() > 1e-3
    assert np.all(np.abs(kz - integral) <= bound)
    assert np.all(np.abs(vl - integral) <= bound)
    assert np.allclose(kz, vl, rtol=1e-9, atol=1e-12)
    # the bound is not vacuous: the sums differ from the integral by less than a tenth of it
    assert np.max(np.abs(kz - integral)[hit]) < 0.1 * integral.max()


def test_physical_matches_the_integral_within_its_riemann_bound(setup):
    scene, frame, (integral, tv, a, b) = setup
    ph = _channel0(physical.render(scene, frame), scene)
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    bound = t_end / STEPS * tv + 1e-9
    assert np.all(np.abs(ph - integral) <= bound)


def test_view_transmittance_agrees(setup):
    scene, frame, _ = setup
    kz = killzone.render(scene, frame)["transmittance"]
    vl = slightlymad.render(scene, frame)["transmittance"]
    ph = physical.render(scene, frame)["transmittance"]
    t = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    exact = np.exp(-scene.medium.extinction * t)
    assert np.allclose(kz, exact, rtol=1e-12)
    assert np.allclose(ph, exact, rtol=1e-9)
    assert np.allclose(vl, exact, rtol=1e-9)
