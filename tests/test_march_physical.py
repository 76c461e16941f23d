"""The physical march: closed forms and convergence order, volume clipping, continuity, robustness,
determinism, precision."""

import math

import numba
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry
from vlref.lights import pack_lights
from vlref.lights.shadow_pack import NSF, NSI, SHADOW_EXACT, S_MODE, ShadowMaps
from vlref.march import physical as physical_march
from vlref.march.physical import TILE_H, TILE_W, march_physical
from vlref.medium import M_ST, pack_medium
from vlref.phase import hg
from vlref.scene.model import (Bounds, CameraSettings, HeightFog, Light, Medium, Noise,
                               RenderSettings, Scene)
from vlref.scene.technique_params import PhysicalParams, TechniqueParams
from vlref.techniques.physical import march_buffers


def _scene(lights, medium=None, cam=None, w=4, h=3, max_distance=20.0, extinction=True, precision="float64"):
    return Scene(render=RenderSettings(width=w, height=h, max_distance=max_distance, precision=precision),
                 camera=cam or CameraSettings(position=(0.0, 0.0, 0.0), look_at=(0.0, 0.0, 1.0), fov=40.0),
                 medium=medium or Medium(scattering=0.1, absorption=0.0), lights=tuple(lights),
                 techniques=TechniqueParams(physical=PhysicalParams(light_extinction=extinction)))


def _no_shadows(n):
    return ShadowMaps(np.zeros((n, NSI), np.int64), np.zeros((n, NSF)), np.zeros(0, np.float32),
                      np.zeros((0, 4), np.float32))


def _run(scene, steps, beta, sigma_t=None, distance=None):
    """per-light inscatter (n,H,W,3), transmittance, camera, with a constant offset ``beta``."""
    cam = camera_from_settings(scene.camera, scene.render.width, scene.render.height)
    w, h = scene.render.width, scene.render.height
    medium = pack_medium(scene)
    if sigma_t is not None:
        medium.params[M_ST] = sigma_t
    lights = pack_lights(scene)
    dist = np.full((h, w), np.inf) if distance is None else distance
    per = np.zeros((lights.count, h, w, 3))
    trans = np.empty((h, w))
    march_physical(cam.position, cam.ray_directions(), np.minimum(dist, scene.render.max_distance),
                   np.full((h, w), beta), steps, medium, lights, _no_shadows(lights.count).table,
                   build_geometry(scene).arrays, scene.techniques.physical.light_extinction, 4, per, trans,
                   (np.int64(0), np.int64(h)))
    return per, trans, cam


def _closed_form_point(cam, p, sigma_s, intensity, t0, t1):
    d = cam.ray_directions()
    tc = d @ p
    hvec = p[None, None, :] - tc[..., None] * d
    hh = np.linalg.norm(hvec, axis=-1)
    return sigma_s * intensity / (4 * math.pi * hh) * (np.arctan((t1 - tc) / hh) - np.arctan((t0 - tc) / hh))


def test_point_light_closed_form_and_convergence_order():
    """Point light, no extinction, isotropic phase, no occluders:
    L = σs I/(4π h) (atan((t1 - tc)/h) - atan((t0 - tc)/h)). The rectangle rule at offset β converges
    at first order for β = 0 and at second order for β = 1/2 (midpoint)."""
    p = np.array([0.7, 1.2, 6.0])
    scene = _scene([Light(type="point", position=tuple(p), intensity=5.0, range=1e3)],
                   medium=Medium(scattering=0.3, absorption=0.0, anisotropy=0.0))
    cam = camera_from_settings(scene.camera, 4, 3)
    exact = _closed_form_point(cam, p, 0.3, 5.0, 0.0, 20.0)
    ns = np.array([256, 512, 1024, 2048])  # asymptotic regime for every pixel
    slopes = {}
    for beta in (0.0, 0.5):
        errs = [np.abs(_run(scene, int(n), beta, sigma_t=0.0)[0][0, :, :, 0] / exact - 1).max() for n in ns]
        slopes[beta] = np.polyfit(np.log(ns), np.log(errs), 1)[0]
    assert -1.15 < slopes[0.0] < -0.85
    assert -2.2 < slopes[0.5] < -1.8
    fine = _run(scene, 4096, 0.5, sigma_t=0.0)[0][0, :, :, 0]
    np.testing.assert_allclose(fine, exact, rtol=1e-7)


def test_directional_light_closed_form():
    """Directional light, homogeneous unbounded medium (T_l = 1 by convention), no shadows:
    L = σs p(cosθ) E (1 - exp(-σt D))/σt, exact for any step count (constant source per step)."""
    light = Light(type="directional", direction=(0.3, -0.8, 0.52), intensity=2.5, color=(1.0, 0.5, 0.2))
    scene = _scene([light], medium=Medium(scattering=0.15, absorption=0.05, anisotropy=0.6), max_distance=30.0)
    per, trans, cam = _run(scene, 3, 0.37)
    d = cam.ray_directions()
    ldir = np.asarray(light.direction) / np.linalg.norm(light.direction)
    cos = d @ -ldir
    want = 0.15 * hg_np(cos, 0.6) * 2.5 * (1 - math.exp(-0.2 * 30.0)) / 0.2
    np.testing.assert_allclose(per[0, :, :, 0], want, rtol=1e-12)
    np.testing.assert_allclose(per[0, :, :, 2], 0.2 * want, rtol=1e-12)
    np.testing.assert_allclose(trans, math.exp(-0.2 * 30.0), rtol=1e-12)


def test_directional_light_leg_in_a_bounded_medium():
    """A box medium: light straight down, horizontal view rays inside the box: T_l = exp(-σt (ymax - y))."""
    light = Light(type="directional", direction=(0.0, -1.0, 0.0), intensity=1.0)
    medium = Medium(scattering=0.1, absorption=0.1, bounds=Bounds(min=(-50.0, -3.0, -50.0), max=(50.0, 2.0, 50.0)))
    cam = CameraSettings(position=(0.0, 0.5, 0.0), look_at=(0.0, 0.5, 1.0), fov=1e-3)
    scene = _scene([light], medium=medium, cam=cam, w=1, h=1, max_distance=10.0)
    per, trans, _ = _run(scene, 4, 0.5)
    want = 0.1 * hg_np(0.0, 0.0) * (1 - math.exp(-0.2 * 10.0)) / 0.2 * math.exp(-0.2 * 1.5)
    assert per[0, 0, 0, 0] == pytest.approx(want, rel=1e-9)
    off = _run(_scene([light], medium=medium, cam=cam, w=1, h=1, max_distance=10.0, extinction=False), 4, 0.5)[0]
    assert off[0, 0, 0, 0] == pytest.approx(want / math.exp(-0.2 * 1.5), rel=1e-9)


@pytest.mark.parametrize("kind, position, sigma_t", [("point", (0.0, 1.0, 5.0), 0.2), ("point", (0.6, -0.8, 2.0), 0.05),
                                                     ("spot", (0.0, 3.0, 5.0), 0.3)])
def test_the_light_leg_of_a_homogeneous_medium_is_exp_of_sigma_t_times_the_distance(kind, position, sigma_t):
    """A homogeneous unbounded medium (no fog, no noise): one step, its sample at t = 5 on the view axis, x = (0, 0, 5);
    the light leg multiplies the sample's in-scattering by T_l = exp(-σt |x - p|) and nothing else."""
    light = Light(type=kind, position=position, direction=(0.0, -1.0, 0.0), spot_angle=120.0, intensity=3.0,
                  range=1e3)
    medium = Medium(scattering=sigma_t / 2, absorption=sigma_t / 2, anisotropy=0.3)
    cam = CameraSettings(position=(0.0, 0.0, 0.0), look_at=(0.0, 0.0, 1.0), fov=1e-3)
    on, off = (_run(_scene([light], medium=medium, cam=cam, w=1, h=1, max_distance=10.0, extinction=e), 1, 0.5)[0]
               for e in (True, False))
    dist = math.dist((0.0, 0.0, 5.0), position)
    assert off[0, 0, 0, 0] > 0
    assert on[0, 0, 0, 0] / off[0, 0, 0, 0] == pytest.approx(math.exp(-sigma_t * dist), rel=1e-12)


@pytest.mark.parametrize("fog", [None, HeightFog(base=-1.0, falloff=0.3)])
def test_the_pixel_transmittance_is_exp_of_the_optical_depth_to_the_ray_end(fog):
    """An unbounded noiseless medium (the march's view transmittances in a loop of their own): T = exp(-τ(0, t_end)),
    τ = σt t_end, with a height fog σt e^{e(o)} (1 - e^{-k d_y t_end}) / (k d_y), e(o) = -(o_y - base) k; a ray that
    ends at the eye (t_end = 0) keeps T = 1. 19 x 11 pixels: partial tiles on the right and at the bottom."""
    medium = Medium(scattering=0.05, absorption=0.02, height_fog=fog)
    cam = CameraSettings(position=(0.0, 1.0, 0.0), look_at=(0.0, 0.4, 1.0), fov=60.0)
    light = Light(type="point", position=(0.0, 1.0, 3.0), intensity=1.0, range=5.0)
    scene = _scene([light], medium=medium, cam=cam, w=19, h=11, max_distance=20.0)
    distance = np.linspace(0.0, 25.0, 11 * 19).reshape(11, 19)
    trans, c = _run(scene, 4, 0.5, distance=distance)[1:]
    t_end, dy = np.minimum(distance, 20.0), c.ray_directions()[..., 1]
    if fog is None:
        tau = 0.07 * t_end
    else:
        assert (dy < 0).all()
        k = fog.falloff
        tau = 0.07 * math.exp(-(1.0 - fog.base) * k) * -np.expm1(-k * dy * t_end) / (k * dy)
    assert trans[0, 0] == 1.0 and (trans[1:] < 1.0).all()
    np.testing.assert_allclose(trans, np.exp(-tau), rtol=1e-13, atol=0)


def hg_np(c, g):
    return (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * np.asarray(c)) ** 1.5)


def test_phase_sign_looking_into_the_light_is_forward():
    light = Light(type="directional", direction=(0.0, 0.0, -1.0), intensity=1.0)  # travels toward the camera
    scene = _scene([light], medium=Medium(scattering=0.1, anisotropy=0.8), w=1, h=1)
    per = _run(scene, 2, 0.5)[0]
    assert per[0, 0, 0, 0] == pytest.approx(0.1 * hg(1.0, 0.8) * (1 - math.exp(-2.0)) / 0.1, rel=1e-6)


def test_inscatter_is_exactly_zero_outside_the_light_volumes():
    spot = Light(type="spot", position=(0.0, 3.0, 8.0), direction=(0.0, -1.0, 0.0), spot_angle=40.0, range=6.0,
                 intensity=10.0)
    point = Light(type="point", position=(-4.0, -2.0, 9.0), range=1.5, intensity=10.0)
    scene = _scene([spot, point], w=24, h=16, cam=CameraSettings(position=(0.0, 0.0, 0.0), look_at=(0.0, 0.0, 1.0),
                                                                  fov=70.0))
    per, _, cam = _run(scene, 16, 0.5)
    d = cam.ray_directions()
    t = np.linspace(0.0, 20.0, 4001)
    pts = t[None, None, :, None] * d[:, :, None, :]
    w = pts - np.asarray(spot.position)
    dist = np.linalg.norm(w, axis=-1)
    cos = -w[..., 1] / np.maximum(dist, 1e-12)
    in_spot = ((cos > math.cos(math.radians(20.0)) - 1e-3) & (dist < 6.0 + 1e-2)).any(axis=-1)
    assert np.all(per[0][~in_spot] == 0.0) and np.all(per[0][in_spot].sum(axis=-1) >= 0.0)
    assert (~in_spot).sum() > 50 and (per[0][in_spot] > 0).any()
    hvec = np.asarray(point.position)[None, None, :] - (d @ np.asarray(point.position))[..., None] * d
    beyond = np.linalg.norm(hvec, axis=-1) > 1.5
    assert np.all(per[1][beyond] == 0.0) and beyond.sum() > 50 and (per[1][~beyond] > 0).any()


def test_camera_crossing_a_cone_boundary_changes_the_image_continuously():
    spot = Light(type="spot", position=(0.0, 4.0, 0.0), direction=(0.0, -1.0, 0.0), spot_angle=60.0, range=10.0,
                 intensity=20.0, cone="unity")
    edge = 4.0 * math.tan(math.radians(30.0))  # cone radius at y = 0
    values = []
    for x in np.linspace(edge - 0.05, edge + 0.05, 41):
        cam = CameraSettings(position=(x, 0.0, 0.0), look_at=(x, 0.0, 1.0), fov=60.0)
        values.append(_run(_scene([spot], cam=cam, w=3, h=3), 32, 0.5)[0][0].copy())
    values = np.array(values)
    jumps = np.abs(np.diff(values, axis=0)).max()
    assert values.max() > 0 and jumps < 0.05 * values.max()


finite = dict(allow_nan=False, allow_infinity=False)


@settings(max_examples=25)
@given(kind=st.sampled_from(["point", "spot", "directional"]),
       lpos=st.tuples(*[st.floats(-4, 4, **finite)] * 3),
       ldir=st.tuples(*[st.floats(-1, 1, **finite)] * 3).filter(lambda v: sum(x * x for x in v) > 1e-3),
       g=st.sampled_from([-0.99, 0.0, 0.5, 0.99]), scattering=st.sampled_from([0.0, 0.05, 2.0]),
       absorption=st.sampled_from([0.0, 0.3]), angle=st.floats(1.0, 179.0),
       fog=st.booleans(), noise=st.booleans(), inside=st.booleans(), precision=st.sampled_from(["float64", "float32"]))
def test_no_nan_or_inf_for_random_valid_scenes(kind, lpos, ldir, g, scattering, absorption, angle, fog, noise,
                                               inside, precision):
    light = Light(type=kind, position=lpos, direction=ldir, spot_angle=angle, range=5.0, intensity=100.0)
    medium = Medium(scattering=scattering, absorption=absorption, anisotropy=g,
                    height_fog=HeightFog(base=0.0, falloff=0.5) if fog else None,
                    noise=Noise(scale=0.7, period=4) if noise else None)
    cam_pos = lpos if inside else (0.0, 0.0, -6.0)
    cam = CameraSettings(position=cam_pos, rotation=(10.0, 200.0, 0.0), fov=90.0)
    scene = _scene([light], medium=medium, cam=cam, w=5, h=4, precision=precision)
    geo = build_geometry(scene).arrays
    c = camera_from_settings(scene.camera, 5, 4)
    distance = np.full((4, 5), np.inf)
    distance[0, 0] = 0.0
    distance[1, 1] = 1e-9
    per, trans = march_buffers(scene, c, distance, pack_lights(scene), _no_shadows(1), geo, 5, "bayer4")
    assert per.dtype == np.dtype(precision) and trans.dtype == np.dtype(precision)
    assert np.all(np.isfinite(per)) and np.all(per >= 0) and np.all((trans >= 0) & (trans <= 1))


def _busy_scene(precision="float64"):
    lights = [Light(type="spot", position=(0.0, 4.0, 6.0), direction=(0.1, -1.0, 0.1), spot_angle=50.0, range=9.0,
                    intensity=30.0),
              Light(type="point", position=(1.0, 1.0, 4.0), range=4.0, intensity=5.0, attenuation="windowed"),
              Light(type="directional", direction=(0.2, -0.5, 1.0), intensity=0.5)]
    medium = Medium(scattering=0.2, absorption=0.05, anisotropy=0.4, height_fog=HeightFog(base=0.0, falloff=0.2),
                    noise=Noise(scale=0.5, period=8))
    return _scene(lights, medium=medium, w=16, h=12, precision=precision)


def test_bit_identical_for_any_thread_count():
    scene = _busy_scene()
    c = camera_from_settings(scene.camera, 16, 12)
    geo = build_geometry(scene).arrays
    dist = np.full((12, 16), np.inf)
    results = []
    before = numba.get_num_threads()
    try:
        for n in sorted({1, numba.config.NUMBA_NUM_THREADS}):
            numba.set_num_threads(n)
            results.append(march_buffers(scene, c, dist, pack_lights(scene), _no_shadows(3), geo, 8, "hash"))
    finally:
        numba.set_num_threads(before)
    for per, trans in results[1:]:
        assert np.array_equal(per, results[0][0]) and np.array_equal(trans, results[0][1])


def test_float32_precision_matches_float64():
    out = {}
    for precision in ("float64", "float32"):
        scene = _busy_scene(precision)
        c = camera_from_settings(scene.camera, 16, 12)
        out[precision] = march_buffers(scene, c, np.full((12, 16), np.inf), pack_lights(scene), _no_shadows(3),
                                       build_geometry(scene).arrays, 8, "bayer4")
    assert out["float32"][0].dtype == np.float32
    scale = out["float64"][0].max()
    np.testing.assert_allclose(out["float32"][0], out["float64"][0], atol=1e-4 * scale)
    np.testing.assert_allclose(out["float32"][1], out["float64"][1], atol=1e-5)


def test_technique_render_composites_and_exposes_per_light_buffers():
    from vlref.render import render
    from vlref.scene import load_scene

    scene = load_scene("pillars", ["render.width=32", "render.height=18", "render.steps=8"])
    res = render(scene, stages=True)
    b = res.buffers
    np.testing.assert_allclose(b["final"], b["scene_colour"] * b["transmittance"][..., None] + b["inscatter"])
    np.testing.assert_array_equal(b["inscatter"], b["inscatter_light_0"])
    assert b["inscatter"].max() > 0 and "shadow_spot_0" in b
    assert np.all(np.isfinite(b["final"]))


def _step_sum_reference(cam, p, intensity, ss, st, g, base, falloff, steps, beta, t_end):
    """NumPy evaluation of the module docstring's step sum for one inverse-square point light whose ball
    holds the whole view ray, in an unbounded noiseless height fog, light-leg extinction on."""
    d = cam.ray_directions()
    cap = 60.0
    expo = lambda y: np.minimum(-(y - base) * falloff, cap)  # noqa: E731
    delta = t_end / steps
    trans = np.ones(d.shape[:2])
    out = np.zeros(d.shape[:2])
    for i in range(steps):
        x = ((i + beta) * delta) * d
        ea = expo(x[..., 1])
        rho = np.exp(ea)
        w = p - x
        d2 = (w * w).sum(axis=-1)
        dist = np.sqrt(d2)
        ldir = w / dist[..., None]
        eb = expo(x[..., 1] + dist * ldir[..., 1])
        gap = np.abs(ea - eb)
        ratio = np.where(gap < 1e-6, 1.0 - 0.5 * gap, -np.expm1(-np.maximum(gap, 1e-300)) / np.maximum(gap, 1e-300))
        leg = np.exp(-st * dist * np.exp(np.maximum(ea, eb)) * ratio)
        cos = (d * ldir).sum(axis=-1)
        phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * cos) ** 1.5)
        sig = st * rho
        s_int = np.where(sig == 0.0, delta, -np.expm1(-sig * delta) / np.where(sig == 0.0, 1.0, sig))
        out += trans * ss * rho * phase * leg * intensity / np.maximum(d2, 1e-4) * s_int
        trans = trans * np.exp(-st * rho * delta)
    return out


@pytest.mark.parametrize("base, falloff, look_down", [(0.0, 0.3, 0.2), (-13.0, 58.0, 1.0), (-2.0, 12.0, 1.0)])
def test_height_fog_march_equals_its_step_sum(base, falloff, look_down):
    """The specialised height-fog evaluation (geometric fog factor, shared expm1, closed-form leg) equals
    the plain per-step sum to rounding: a gentle fog, a steep one whose first samples underflow
    (e^{-754}), and one whose lower samples reach the exponent cap (both take the per-step exp)."""
    p = np.array([0.7, 1.2, 6.0])
    ss, sa, g, steps, beta = 0.02, 0.01, 0.3, 48, 0.375
    scene = _scene([Light(type="point", position=tuple(p), intensity=5.0, range=1e3)],
                   cam=CameraSettings(position=(0.0, 0.0, 0.0), look_at=(0.0, -look_down, 1.0), fov=40.0),
                   medium=Medium(scattering=ss, absorption=sa, anisotropy=g,
                                 height_fog=HeightFog(base=base, falloff=falloff)), w=6, h=5)
    per, _, cam = _run(scene, steps, beta)
    ref = _step_sum_reference(cam, p, 5.0, ss, ss + sa, g, base, falloff, steps, beta, 20.0)
    assert ref.max() > 0
    np.testing.assert_allclose(per[0, :, :, 0], ref, rtol=1e-11, atol=1e-13 * ref.max())


def test_steps_are_placed_inside_the_medium_box():
    """A point light of range 1000 m inside an 8 m ``medium.bounds`` box (inverse square, g = 0.3).
    The march clips each segment to the box before placing its steps, so 1024 steps resolve the 8 m of
    medium rather than 1000 m of empty space: median relative error < 1e-3, max < 1e-2 against the
    quadrature reference (whose error bound is 1e-7 relative)."""
    from vlref.reference import render_reference

    scene = Scene(render=RenderSettings(width=32, height=18, max_distance=40.0, steps=1024, sampling="none"),
                  camera=CameraSettings(position=(0.0, 1.0, -10.0), look_at=(0.0, 1.0, 0.0), fov=50.0),
                  medium=Medium(scattering=0.2, absorption=0.05, anisotropy=0.3,
                                bounds=Bounds(min=(-4.0, -2.0, -4.0), max=(4.0, 4.0, 4.0))),
                  lights=(Light(type="point", position=(0.0, 2.0, 0.0), intensity=20.0, range=1000.0),))
    ref = render_reference(scene, rel_tol=1e-7)
    per, trans, _ = _run(scene, 1024, 0.5)
    lit = ref.inscatter[..., 0] > 0.0
    assert lit.sum() > 0.5 * lit.size  # most rays cross the box
    assert np.all(per[0][~lit] == 0.0)
    rel = np.abs(per[0][lit] / ref.inscatter[lit] - 1.0)
    assert np.median(rel) < 1e-3 and rel.max() < 1e-2
    np.testing.assert_allclose(trans, ref.transmittance, rtol=1e-12)


def test_exact_shadows_need_the_geometry():
    scene = _scene([Light(type="point", position=(0.0, 0.0, 3.0))], w=4, h=3)
    table = _no_shadows(1)
    table.ints[0, S_MODE] = SHADOW_EXACT
    per, trans = np.zeros((1, 3, 4, 3)), np.empty((3, 4))
    cam = camera_from_settings(scene.camera, 4, 3)
    with pytest.raises(ValueError, match="exact shadows, and geo is None"):
        march_physical(cam.position, cam.ray_directions(), np.full((3, 4), 50.0), np.full((3, 4), 0.5), 4,
                       pack_medium(scene), pack_lights(scene), table.table, None, True, 2, per, trans,
                       (np.int64(0), np.int64(3)))


def test_the_march_refuses_rows_outside_the_image():
    scene = _scene([Light(type="point", position=(0.0, 0.0, 3.0))], w=4, h=3)
    table = _no_shadows(1)
    per, trans = np.zeros((1, 3, 4, 3)), np.empty((3, 4))
    cam = camera_from_settings(scene.camera, 4, 3)
    for first, end in ((0, 4), (2, 1), (-1, 2)):  # past the last row, backwards, before the first row
        with pytest.raises(ValueError, match="rows must satisfy"):
            march_physical(cam.position, cam.ray_directions(), np.full((3, 4), 50.0), np.full((3, 4), 0.5), 4,
                           pack_medium(scene), pack_lights(scene), table.table, None, True, 2, per, trans,
                           (np.int64(first), np.int64(end)))


@pytest.mark.parametrize("precision", ["float64", "float32"])
def test_a_pixel_does_not_depend_on_its_packet(precision):
    """The march runs packets of rays through vectorised lane loops (and a scalar remainder loop) in tiles of
    pixels: a pixel marched alone (lane 0 of a one-lane packet) gets the same bits as inside a full frame,
    whose size (27 x 19) leaves partial tiles on the right and at the bottom."""
    import dataclasses

    from vlref.bench.config import bench_scene
    from vlref.march.patterns import offsets
    from vlref.render import prepare_frame

    base = bench_scene(27, 19, 8, "four", 64)
    scene = dataclasses.replace(base, render=dataclasses.replace(base.render, precision=precision))
    frame = prepare_frame(scene)
    dtype = np.dtype(precision)
    dirs = frame.camera.ray_directions().astype(dtype)
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance).astype(dtype)
    beta = offsets("bayer4", 27, 19, 0).astype(dtype)
    origin = np.asarray(frame.camera.position, dtype=dtype)
    args = (pack_medium(scene, dtype), frame.lights.astype(dtype), frame.shadow_maps().table, frame.geometry.arrays,
            True, 3)
    per = np.full((4, 19, 27, 3), np.nan, dtype=dtype)
    trans = np.full((19, 27), np.nan, dtype=dtype)
    everything = (np.int64(0), np.int64(19))
    march_physical(origin, dirs, t_end, beta, 8, *args, per, trans, everything)
    assert 27 % TILE_W and 19 % TILE_H  # partial tiles
    assert not np.isnan(trans).any() and not np.isnan(per).any()  # the march writes every pixel of every light
    assert per.max() > 0 and np.count_nonzero(per.sum(axis=-1), axis=(1, 2)).min() > 20
    # no light traces shadow rays: the kernel compiled without the ray tracer (geo None) gives the same bits
    lean, lean_t = np.zeros_like(per), np.empty_like(trans)
    march_physical(origin, dirs, t_end, beta, 8, *args[:3], None, *args[4:], lean, lean_t, everything)
    assert np.array_equal(lean, per) and np.array_equal(lean_t, trans)
    # a band of rows (not a multiple of the tile's height, starting inside a tile) is written in place, and only it
    band, band_t = np.full_like(per, np.nan), np.full_like(trans, np.nan)
    march_physical(origin, dirs, t_end, beta, 8, *args, band, band_t, (np.int64(5), np.int64(12)))
    assert np.array_equal(band[:, 5:12], per[:, 5:12]) and np.array_equal(band_t[5:12], trans[5:12])
    assert np.isnan(band[:, :5]).all() and np.isnan(band[:, 12:]).all()
    assert np.isnan(band_t[:5]).all() and np.isnan(band_t[12:]).all()
    for i in range(19):
        for j in range(27):
            one = np.zeros((4, 1, 1, 3), dtype=dtype)
            one_t = np.empty((1, 1), dtype=dtype)
            march_physical(origin, np.ascontiguousarray(dirs[i:i + 1, j:j + 1]),
                           np.ascontiguousarray(t_end[i:i + 1, j:j + 1]),
                           np.ascontiguousarray(beta[i:i + 1, j:j + 1]), 8, *args, one, one_t,
                           (np.int64(0), np.int64(1)))
            assert np.array_equal(one[:, 0, 0], per[:, i, j]) and one_t[0, 0] == trans[i, j], (i, j)


def test_the_packet_scratch_rows_tile_the_scratch_without_overlap():
    """Each named row of the march's scratch (a vector or colour row takes three) is its own: the rows of
    vlref.march.physical tile [0, ROWS·LANES) exactly, so no stage overwrites another quantity's lanes."""
    triple = {"R_DIR", "R_POS", "R_TO_LIGHT", "R_E_RGB", "R_VIS", "R_L"}
    rows = {name: getattr(physical_march, name) for name in dir(physical_march) if name.startswith("R_")}
    assert triple <= set(rows)
    lanes = physical_march.LANES
    cells = sorted(off + k * lanes for name, off in rows.items() for k in range(3 if name in triple else 1))
    assert cells == list(range(0, physical_march.ROWS * lanes, lanes))
