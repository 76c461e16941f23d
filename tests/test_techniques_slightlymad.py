"""The slightlymad technique: VL's dither table and each quirk switch's documented direction."""

import numpy as np
import pytest

from vlref.march.slightlymad import dither_offsets, dither_table, spot_profile_cookie
from vlref.post.composite import fp16
from vlref.render import prepare_frame
from vlref.scene.load import load_scene
from vlref.techniques import slightlymad

# SOURCES §1.5, rows y = 0..7 from the texture's bottom (v = 0)
VL_DITHER_8 = """
  3 192  51 239  15 204  62 251
129  66 176 113 141  78 188 125
 35 223  19 207  47 235  31 219
160  98 145  82 172 109 156  94
 11 200  58 247   7 196  54 243
137  74 184 121 133  70 180 117
 43 231  27 215  39 227  23 211
168 105 153  90 164 102 149  86
"""
VL_DITHER_4 = "0 127 31 159 191 63 223 95 47 175 15 143 239 111 207 79"


def test_dither_bytes_equal_the_table():
    assert dither_table(8).tolist() == np.array(VL_DITHER_8.split(), dtype=int).reshape(8, 8).tolist()
    assert dither_table(4).tolist() == np.array(VL_DITHER_4.split(), dtype=int).reshape(4, 4).tolist()


def test_dither_offsets_count_rows_from_the_bottom():
    beta = dither_offsets(16, 11, 8, True, "bottom")
    table = dither_table(8) / 255.0
    assert np.array_equal(beta[10, :8], table[0])        # our bottom row is Unity's y = 0
    assert np.array_equal(beta[10 - 9, 8:16], table[1])  # wraps every 8
    top = dither_offsets(16, 11, 8, True, "top")
    assert np.array_equal(top[0, :8], table[0])


def test_spot_profile_cookie_follows_the_measured_table():
    c = spot_profile_cookie(128)[..., 0]
    assert c[64, 64] == pytest.approx(1.0)
    assert c.min() == 0.0 and np.all((c >= 0) & (c <= 1))


BASE = ["render.width=24", "render.height=14", "render.technique=\"slightlymad\"", "lights.0.shadows.resolution=64"]


@pytest.fixture(scope="module")
def pillars():
    scene = load_scene("pillars", BASE)
    return scene, prepare_frame(scene)


def _render(scene, frame, **params):
    import dataclasses
    p = dataclasses.replace(scene.techniques.slightlymad, **params)
    s = scene.replace(techniques=dataclasses.replace(scene.techniques, slightlymad=p))
    return slightlymad.render(s, frame)


def test_half_tau_quirk_brightens(pillars):
    scene, frame = pillars
    q = _render(scene, frame, initial_half_tau=True, fp16=False)["light0"]
    n = _render(scene, frame, initial_half_tau=False, fp16=False)["light0"]
    assert np.all(q >= n) and np.any(q > n)


def test_right_endpoint_quirk_darkens(pillars):
    scene, frame = pillars
    q = _render(scene, frame, right_endpoint=True, fp16=False)["light0"]
    n = _render(scene, frame, right_endpoint=False, fp16=False)["light0"]
    assert np.all(q <= n) and np.any(q < n)


def test_alpha_zero_quirk_leaves_the_scene_unattenuated(pillars):
    scene, frame = pillars
    q = _render(scene, frame)["transmittance"]
    n = _render(scene, frame, point_spot_alpha_zero=False)["transmittance"]
    assert np.all(q == 1.0)
    assert np.all(n <= 1.0) and np.any(n < 1.0)


def test_fp16_storage_rounds_every_stored_buffer(pillars):
    scene, frame = pillars
    out = _render(scene, frame)
    for name in ("march", "blur_h", "blur_v", "upsample"):
        assert np.array_equal(out[name], fp16(out[name])), name
    raw = _render(scene, frame, fp16=False)["march"]
    assert not np.array_equal(raw, fp16(raw))


def test_point_srgb_quirk_darkens_a_dim_point_light():
    scene = load_scene("cage", ["render.width=16", "render.height=10", "render.technique=\"slightlymad\"",
                                "techniques.slightlymad.fp16=false", "techniques.slightlymad.resolution=\"full\"",
                                "techniques.slightlymad.blur=false"])
    assert scene.lights[0].type == "point"
    dim = scene.replace(lights=(__import__("dataclasses").replace(scene.lights[0], intensity=0.5, shadows=None),))
    frame = prepare_frame(dim)
    q = _render(dim, frame, point_srgb_quirk=True)["inscatter"]
    n = _render(dim, frame, point_srgb_quirk=False)["inscatter"]
    assert np.all(q <= n) and np.any(q < n)
    # the march is linear in the light's colour x intensity c, so each channel scales by exactly
    # srgb_to_linear(c) / c (to rounding)
    c = np.asarray(dim.lights[0].color) * dim.lights[0].intensity
    lit = n > 0.0
    expected = np.broadcast_to(slightlymad.srgb_to_linear(c) / c, n.shape)
    assert lit.any()
    np.testing.assert_allclose(q[lit] / n[lit], expected[lit], rtol=1e-12, atol=0.0)


def test_skybox_extinction_quirk_lifts_sky_alpha():
    scene = load_scene("forest", ["render.width=24", "render.height=14", "render.technique=\"slightlymad\"",
                                  "lights.0.shadows.resolution=64", "techniques.slightlymad.fp16=false",
                                  "techniques.slightlymad.extinction=0.05"])
    frame = prepare_frame(scene)
    q = _render(scene, frame)["march"][..., 3]
    n = _render(scene, frame, skybox_extinction_quirk=False)["march"][..., 3]
    assert np.all(q >= n) and np.any(q > n)


def test_unity_mesh_start_lies_inside_the_analytic_cone(pillars):
    """The 16-gon pyramid is inscribed in the +1 degree cone: fewer pixels, a later start or an earlier end."""
    scene, frame = pillars
    cam = frame.camera
    dirs = cam.ray_directions()
    t_surf = np.minimum(frame.gbuffer.distance, 1e4)
    p = scene.techniques.slightlymad
    light = scene.lights[0]
    a0, al, ac = slightlymad.light_segments(light, cam.position, dirs, t_surf, p, 400.0)
    m0, ml, mc = slightlymad.light_segments(light, cam.position, dirs, t_surf,
                                            __import__("dataclasses").replace(p, light_mesh="unity"), 400.0)
    assert ac.sum() > 10 and np.all(ac[mc])
    assert np.all(m0[mc] >= a0[mc] - 1e-9)
    assert np.all(m0[mc] + ml[mc] <= a0[mc] + al[mc] + 1e-9)
    assert np.any(m0[mc] + ml[mc] < a0[mc] + al[mc] - 1e-6) or mc.sum() < ac.sum()
    mesh = _render(scene, frame, light_mesh="unity")["final"]
    assert np.isfinite(mesh).all()
