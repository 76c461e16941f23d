"""Physical properties of the reference and the physical march (hypothesis).

Tolerances: the reference is asked for ``rel_tol`` and every comparison allows the sum of the two
results' reported error bounds; comparisons between march renders of transformed scenes allow
float64 rounding (1e-9 relative: the same discretisation evaluated in another frame).
"""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vlref.camera import camera_from_settings
from vlref.medium import optical_depth, pack_medium
from vlref.reference.bias import loglog_slope, technique_bias
from vlref.reference.closed_forms import closest_approach, point_light_no_extinction
from vlref.reference.integrand import segment_depth
from vlref.reference.quadrature import render_reference
from vlref.render import render
from vlref.scene.model import (Bounds, CameraSettings, HeightFog, Light, Material, Medium, Noise, Plane,
                               RenderSettings, Scene, ShadowSettings, Sphere)

W, H = 10, 8
EXACT = ShadowSettings(filter="exact")


def _scene(medium, lights, objects=(), camera=None, max_distance=25.0, w=W, h=H):
    return Scene(render=RenderSettings(width=w, height=h, max_distance=max_distance, technique="physical",
                                       sampling="none", steps=32),
                 camera=camera or CameraSettings(position=(0.0, 1.5, -8.0), look_at=(0.0, 1.5, 0.0), fov=60.0),
                 medium=medium, lights=tuple(lights), objects=tuple(objects))


def _base(g=0.3, sigma_s=0.1, sigma_a=0.03):
    light = Light(type="spot", position=(-1.0, 5.0, 1.0), direction=(0.2, -1.0, 0.1), intensity=40.0, range=12.0,
                  spot_angle=60.0, shadows=EXACT)
    objects = (Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0)), Sphere(center=(-0.6, 3.0, 1.0), radius=0.5))
    return _scene(Medium(scattering=sigma_s, absorption=sigma_a, anisotropy=g), [light], objects)


# ----------------------------------------------------------------------------------------- transmittance

media = st.builds(
    lambda ss, sa, fog, k, bounded, noise: Medium(
        scattering=ss, absorption=sa,
        height_fog=HeightFog(base=0.5, falloff=k) if fog else None,
        bounds=Bounds(min=(-3.0, -1.0, -3.0), max=(3.0, 4.0, 5.0)) if bounded else None,
        noise=Noise(scale=0.7, period=8, seed=3) if noise else None),
    st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.booleans(), st.floats(0.0, 1.5), st.booleans(), st.booleans())
points = st.tuples(*[st.floats(-4.0, 4.0)] * 3)


@given(media, points, points, st.floats(0.05, 0.95))
@settings(max_examples=30)
def test_transmittance_is_multiplicative_and_in_unit_interval(medium, p, q, frac):
    mp = pack_medium(_scene(medium, [Light(type="directional")]))
    p, q = np.array(p), np.array(q)
    length = float(np.linalg.norm(q - p))
    if length < 1e-3:
        return
    u = (q - p) / length
    args = (mp.params, mp.noise, *p, *u)
    whole = segment_depth(*args, 0.0, length)
    split = segment_depth(*args, 0.0, frac * length) + segment_depth(*args, frac * length, length)
    assert abs(whole - split) <= 1e-9 * (1.0 + whole)
    t_whole = math.exp(-whole)
    assert 0.0 <= t_whole <= 1.0
    assert abs(t_whole - math.exp(-segment_depth(*args, 0.0, frac * length))
               * math.exp(-segment_depth(*args, frac * length, length))) <= 1e-9
    if medium.noise is None:  # the medium module's own analytic depth agrees
        assert abs(whole - optical_depth(*args, 0.0, length, 1)) <= 1e-9 * (1.0 + whole)
    else:  # its midpoint sums converge to the exact nested quadrature
        assert abs(whole - optical_depth(*args, 0.0, length, 4096)) <= 1e-3 * (1.0 + whole)


# ----------------------------------------------------------------------------------------- reference properties

def _close(a, b):
    return np.all(np.abs(a.inscatter - b.inscatter) <= (a.error + b.error)[..., None] + 1e-15)


@given(st.floats(0.1, 10.0))
@settings(max_examples=5)
def test_inscatter_is_linear_in_light_intensity(k):
    base = _base()
    scaled = base.replace(lights=(dataclasses.replace(base.lights[0], intensity=base.lights[0].intensity * k),))
    a = render_reference(base, abs_tol=0.0)
    b = render_reference(scaled, abs_tol=0.0)
    assert np.allclose(b.inscatter, k * a.inscatter, rtol=2e-4, atol=0.0)
    assert np.all(np.abs(b.inscatter - k * a.inscatter) <= (b.error + k * a.error)[..., None] + 1e-15)


@given(st.floats(0.0, 0.5), st.floats(-0.9, 0.9))
@settings(max_examples=5)
def test_zero_scattering_gives_zero_inscatter(sigma_a, g):
    scene = _base(g=g, sigma_s=0.0, sigma_a=sigma_a)
    assert not render_reference(scene).inscatter.any()
    assert not render(scene).buffers["inscatter"].any()


@given(st.floats(0.0, 1.0))
@settings(max_examples=5)
def test_inscatter_grows_with_visibility(opacity):
    base = _base()
    sphere = base.objects[1]
    clearer = base.replace(objects=(base.objects[0], dataclasses.replace(sphere, material=Material(opacity=opacity))))
    shadowed = render_reference(base)
    lit = render_reference(clearer)
    assert np.all(lit.inscatter >= shadowed.inscatter - (lit.error + shadowed.error)[..., None])
    if opacity < 1.0:
        assert lit.inscatter.sum() > shadowed.inscatter.sum()


@given(st.floats(0.01, 0.5), st.floats(0.0, 0.5), st.tuples(st.floats(-2, 2), st.floats(0.5, 3), st.floats(-2, 4)))
@settings(max_examples=8)
def test_bounded_by_the_no_extinction_value(sigma_s, sigma_a, pos):
    light = Light(type="point", position=pos, intensity=10.0, range=30.0)
    scene = _scene(Medium(scattering=sigma_s, absorption=sigma_a), [light])
    res = render_reference(scene)
    cam = camera_from_settings(scene.camera, W, H)
    tc, h = closest_approach(cam.position, cam.ray_directions(), np.array(pos))
    bound = point_light_no_extinction(sigma_s, 10.0, tc, h, 0.0, scene.render.max_distance)
    assert np.all(res.inscatter[..., 0] <= bound + res.error)


# ----------------------------------------------------------------------------------------- frame invariance

def _rot_y(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])


def _transform(scene, k, rot, shift):
    """Uniform scale k, rotation rot, translation shift of the whole scene (camera included).

    Lengths ×k, coefficients ×1/k (optical depths unchanged), point/spot intensities ×k² (the
    irradiance I/r² is then unchanged), directional irradiance unchanged, angles unchanged."""
    pt = lambda p: tuple(float(v) for v in k * (rot @ np.asarray(p)) + shift)  # noqa: E731
    vec = lambda v: tuple(float(c) for c in rot @ np.asarray(v))  # noqa: E731
    cam = dataclasses.replace(scene.camera, position=pt(scene.camera.position), look_at=pt(scene.camera.look_at),
                              up=vec(scene.camera.up), near=scene.camera.near * k, far=scene.camera.far * k)
    lights = tuple(dataclasses.replace(l, position=pt(l.position), direction=vec(l.direction), range=l.range * k,
                                       intensity=l.intensity * (k * k if l.type != "directional" else 1.0))
                   for l in scene.lights)
    objects = []
    for o in scene.objects:
        if isinstance(o, Plane):
            objects.append(dataclasses.replace(o, point=pt(o.point), normal=vec(o.normal)))
        else:
            objects.append(dataclasses.replace(o, center=pt(o.center), radius=o.radius * k))
    m = scene.medium
    medium = dataclasses.replace(m, scattering=m.scattering / k, absorption=m.absorption / k)
    render_s = dataclasses.replace(scene.render, max_distance=scene.render.max_distance * k)
    return scene.replace(camera=cam, lights=lights, objects=tuple(objects), medium=medium, render=render_s)


@given(st.floats(0.25, 4.0), st.floats(-180.0, 180.0), st.tuples(*[st.floats(-50.0, 50.0)] * 3))
@settings(max_examples=6)
def test_moving_rotating_scaling_the_scene_leaves_the_image_unchanged(k, yaw, shift):
    base = _base()
    moved = _transform(base, k, _rot_y(yaw), np.array(shift))
    a, b = render(base).buffers, render(moved).buffers
    # same discretisation in another frame: float rounding only (tol covers 1e-9 relative of the largest value)
    assert np.allclose(a["inscatter"], b["inscatter"], rtol=1e-7, atol=1e-9 * a["inscatter"].max())
    assert np.allclose(a["transmittance"], b["transmittance"], rtol=1e-7, atol=1e-12)
    ra, rb = render_reference(base), render_reference(moved)
    assert _close(ra, rb)


# ----------------------------------------------------------------------------------------- march convergence

@pytest.mark.parametrize("sampling", ["none", "bayer4", "hash"])
def test_physical_march_converges_at_first_order(sampling):
    """Smooth integrand (no shadows): the per-step rectangle rule at offset β has error
    ≈ (1/2 - β) Δ [f(b) - f(a)], so halving Δ halves the error: slope -1 in log-log."""
    base = _base()
    scene = base.replace(lights=(dataclasses.replace(base.lights[0], shadows=None),),
                         render=dataclasses.replace(base.render, sampling=sampling))
    ref = render_reference(scene, rel_tol=1e-8, abs_tol=1e-13)
    report = technique_bias(scene, "physical", (16, 32, 64, 128, 256), reference=ref)
    assert report.fit_rows == 5
    assert abs(report.slope + 1.0) < 0.05, report.table
    errors = [r["mean_abs"] for r in report.table]
    assert all(1.8 < a / b < 2.2 for a, b in zip(errors[1:], errors[2:]))


def test_physical_march_converges_with_volumetric_shadows():
    """With shadow jumps inside the steps the error still falls as O(Δ) on average (erratically: it
    depends on where each jump falls within its step), so only the fitted slope is pinned."""
    scene = _base()
    ref = render_reference(scene, rel_tol=1e-7, abs_tol=1e-13)
    report = technique_bias(scene, "physical", (16, 32, 64, 128, 256, 512), reference=ref)
    assert -1.4 <= report.slope <= -0.8, report.table
    assert report.table[-1]["mean_rel"] < 0.005
    assert report.concentration["shadow_edges"] > 0.5  # the remaining error sits on shadow edges


def test_loglog_slope():
    assert abs(loglog_slope([1, 2, 4, 8], [1.0, 0.25, 0.0625, 0.015625]) + 2.0) < 1e-12


# ----------------------------------------------------------------------------------------- robustness

lights = st.one_of(
    st.builds(lambda p, i, r: Light(type="point", position=p, intensity=i, range=r, shadows=EXACT),
              st.tuples(st.floats(-3, 3), st.floats(0.2, 4), st.floats(-9, 5)), st.floats(0.0, 100.0),
              st.floats(0.5, 30.0)),
    st.builds(lambda p, d, a, law: Light(type="spot", position=p, direction=d, spot_angle=a, cone=law, range=15.0,
                                         intensity=50.0, shadows=EXACT),
              st.tuples(st.floats(-3, 3), st.floats(0.2, 6), st.floats(-9, 5)),
              st.tuples(st.floats(-1, 1), st.floats(-1, -0.1), st.floats(-1, 1)), st.floats(1.0, 179.0),
              st.sampled_from(["unity", "linear", "smoothstep"])),
    st.builds(lambda d: Light(type="directional", direction=d, intensity=2.0, shadows=EXACT),
              st.tuples(st.floats(-1, 1), st.floats(-1, -0.05), st.floats(-1, 1))))


@given(st.lists(lights, min_size=1, max_size=2), st.floats(-0.99, 0.99), st.floats(0.0, 1.0), st.floats(0.0, 1.0),
       st.booleans())
@settings(max_examples=12)
def test_no_nan_or_inf_on_random_valid_scenes(ls, g, sigma_s, sigma_a, bounded):
    medium = Medium(scattering=sigma_s, absorption=sigma_a, anisotropy=g,
                    bounds=Bounds(min=(-4.0, -1.0, -9.0), max=(4.0, 5.0, 6.0)) if bounded else None)
    scene = _scene(medium, ls, (Plane(), Sphere(center=(0.0, 1.0, 0.0), radius=0.7)), w=6, h=4)
    ref = render_reference(scene, rel_tol=1e-3, max_intervals=800)
    for arr in (ref.inscatter, ref.transmittance, ref.final, ref.error):
        assert np.all(np.isfinite(arr))
    assert np.all(ref.inscatter >= 0.0) and np.all((ref.transmittance >= 0.0) & (ref.transmittance <= 1.0))
    out = render(scene).buffers
    assert np.all(np.isfinite(out["inscatter"])) and np.all(np.isfinite(out["final"]))
