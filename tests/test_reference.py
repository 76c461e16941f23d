"""The quadrature reference against closed forms: the true error must lie within the reported bound."""

import dataclasses
import functools
import math

import numba
import numpy as np
import pytest
from scipy import optimize

from vlref.camera import camera_from_settings
from vlref.reference.closed_forms import closest_approach, directional_homogeneous, point_light_extinction
from vlref.reference.integrand import (MAX_SPREAD, WG, WG1, WG3, WGK, WGK3, WGK7, XGK, XGK3, XGK7, build_context,
                                       peak_substitution)
from vlref.reference.quadrature import bisection_width, prepare_reference, render_reference
from vlref.reference.tiles import render_reference_tiled
from vlref.scene.model import (Bounds, CameraSettings, Light, Medium, RenderSettings, Scene, ShadowSettings,
                               Sphere)
from vlref.render import prepare_frame

W, H = 8, 6


def _scene(medium, lights, objects=(), max_distance=30.0, camera=None):
    return Scene(render=RenderSettings(width=W, height=H, max_distance=max_distance),
                 camera=camera or CameraSettings(position=(0.0, 1.0, -10.0), look_at=(0.0, 1.0, 0.0), fov=50.0),
                 medium=medium, lights=tuple(lights), objects=tuple(objects))


def _rays(scene):
    cam = camera_from_settings(scene.camera, W, H)
    return cam.position, cam.ray_directions()


def _point_exact(scene, light, pieces=None):
    """(c) over the range-sphere chord (pieces: optional list of (H, W) interval arrays to subtract)."""
    m = scene.medium
    o, d = _rays(scene)
    tc, h = closest_approach(o, d, np.array(light.position))
    half = np.sqrt(np.maximum(light.range ** 2 - h * h, 0.0))
    a = np.clip(tc - half, 0.0, scene.render.max_distance)
    b = np.clip(tc + half, 0.0, scene.render.max_distance)
    return point_light_extinction(m.scattering, m.extinction, m.anisotropy, light.intensity, tc, h, a, b)


def _check_bound(result, exact, rel_tol):
    true = np.abs(result.inscatter[..., 0] - exact)
    assert np.all(np.isfinite(result.inscatter)) and result.stats["unconverged"] == 0
    assert np.all(true <= result.error + 1e-15), "true error exceeds the reported bound"
    assert np.all(result.error <= np.maximum(rel_tol * np.abs(result.inscatter).max(axis=-1), 1e-9) * (1 + 1e-9))
    return true


@pytest.mark.parametrize("g", [0.0, 0.7, -0.5])
def test_point_light_matches_airlight_integral(g):
    light = Light(type="point", position=(0.5, 1.3, 0.0), intensity=20.0, range=25.0)
    scene = _scene(Medium(scattering=0.1, absorption=0.05, anisotropy=g), [light])
    res = render_reference(scene)
    exact = _point_exact(scene, light)
    true = _check_bound(res, exact, 1e-4)
    assert np.all(true <= 1e-4 * exact)
    # colour and transmittance
    assert np.allclose(res.inscatter[..., 0], res.inscatter[..., 2])
    assert np.allclose(res.transmittance, math.exp(-0.15 * 30.0), rtol=1e-12)


@pytest.mark.parametrize("nodes, xgk, wgk, wg, degree", [(15, XGK, WGK, WG, 23), (7, XGK7, WGK7, WG3, 11),
                                                      (3, XGK3, WGK3, WG1, 5)])
def test_the_kronrod_rules_integrate_polynomials_to_their_degree_exactly(nodes, xgk, wgk, wg, degree):
    """Each rule's nodes and weights (K on all nodes; its embedded Gauss rule on the odd entries and the centre)
    integrate ``x^d`` over [-1, 1] exactly: K up to ``degree``, Gauss up to ``2 n - 1`` for its ``n`` nodes (the
    Gauss rule's accuracy against which the error is estimated), and neither beyond."""
    x = np.concatenate([-xgk[:-1], xgk[::-1]])
    wk = np.concatenate([wgk[:-1], wgk[::-1]])
    gauss = np.arange(xgk.size)[1::2]
    xg = np.concatenate([-xgk[gauss[:-1]], xgk[gauss[::-1]]])
    wgs = np.concatenate([wg[:-1], wg[::-1]])
    assert x.size == nodes and xg.size == (nodes - 1) // 2
    exact = lambda d: 2.0 / (d + 1) if d % 2 == 0 else 0.0  # noqa: E731
    for d in range(degree + 1):
        assert abs(np.dot(wk, x ** d) - exact(d)) < 1e-15
    for d in range(xg.size * 2):
        assert abs(np.dot(wgs, xg ** d) - exact(d)) < 1e-15
    assert abs(np.dot(wk, x ** (degree + 1)) - exact(degree + 1)) > 1e-12
    assert abs(np.dot(wgs, xg ** (2 * xg.size)) - exact(2 * xg.size)) > 1e-12


@pytest.mark.parametrize("rule, tolerances", [(15, (1e-1, 1e-3, 1e-6, 1e-9)), (7, (1e-1, 1e-3, 1e-6, 1e-9)),
                                              (3, (1.0, 1e-1, 1e-2, 1e-4))])
def test_tighter_tolerance_tightens_the_error(rule, tolerances):
    """The true error of the closed form within the reported bound, and the bound within ``rel_tol``, for each rule
    over the tolerances it is meant for (G1–K3: the coarse end; its embedded midpoint rule makes tight tolerances
    cost many intervals)."""
    light = Light(type="point", position=(0.2, 1.1, 3.0), intensity=5.0, range=8.0)
    scene = _scene(Medium(scattering=0.3, absorption=0.1, anisotropy=0.3), [light])
    exact = _point_exact(scene, light)
    for tol in tolerances:
        res = render_reference(scene, rel_tol=tol, abs_tol=1e-14, rule=rule)
        true = _check_bound(res, exact, tol)
        assert np.all(true <= tol * exact)


def test_the_coarse_rule_spends_fewer_evaluations_at_a_coarse_tolerance():
    """G3–K7 evaluates the integrand 7 times per interval, G7–K15 15 times: at ``rel_tol = 1e-1`` most pixels
    converge on the first pass with either, so the coarse rule needs fewer evaluations in all (and stays within its
    bound of the closed form, as the test above checks)."""
    light = Light(type="point", position=(0.2, 1.1, 3.0), intensity=5.0, range=8.0)
    scene = _scene(Medium(scattering=0.3, absorption=0.1, anisotropy=0.3), [light])
    fine, coarse, coarsest = (render_reference(scene, rel_tol=1e-1, rule=rule) for rule in (15, 7, 3))
    assert coarse.stats["intervals"] * 7 < 0.75 * fine.stats["intervals"] * 15
    assert coarsest.stats["intervals"] * 3 < 0.75 * coarse.stats["intervals"] * 7
    assert [r.stats["rule"] for r in (fine, coarse, coarsest)] == [15, 7, 3]


def test_tiles_solve_with_the_rule_asked_for():
    light = Light(type="point", position=(0.2, 1.1, 3.0), intensity=5.0, range=8.0)
    scene = _scene(Medium(scattering=0.3, absorption=0.1, anisotropy=0.3), [light])
    whole = render_reference(scene, rel_tol=1e-1, rule=7)
    tiled = render_reference_tiled(scene, 1e-1, rows_per_tile=4, quiet=True, rule=7)
    assert tiled.stats["rule"] == 7 and tiled.stats["intervals"] == whole.stats["intervals"]
    np.testing.assert_array_equal(tiled.inscatter, whole.inscatter)
    assert not np.array_equal(whole.inscatter, render_reference(scene, rel_tol=1e-1).inscatter)


def test_directional_light_in_a_bounded_box_matches_closed_form():
    lo, hi = (-9.0, -2.0, -8.0), (6.0, 3.0, 8.0)
    m = Medium(scattering=0.08, absorption=0.04, anisotropy=0.5, bounds=Bounds(min=lo, max=hi))
    light = Light(type="directional", direction=(0.3, -1.0, 0.2), intensity=3.0)
    scene = _scene(m, [light], camera=CameraSettings(position=(0.0, 1.0, -3.0), look_at=(1.0, 0.5, 4.0), fov=60.0))
    res = render_reference(scene)
    o, d = _rays(scene)
    l = -np.array(light.direction) / np.linalg.norm(light.direction)
    # the ray starts inside the box; it leaves through some face at t1
    with np.errstate(divide="ignore"):
        ts = np.stack([(np.array(hi)[k] - o[k]) / d[..., k] for k in range(3)]
                      + [(np.array(lo)[k] - o[k]) / d[..., k] for k in range(3)], axis=-1)
    t1 = np.min(np.where(ts > 0, ts, np.inf), axis=-1)
    # light leg: from x(t) toward l to the top face (l_y > 0 and the box is wide enough here)
    ly = l[1]
    leg0 = (hi[1] - o[1]) / ly
    rate = -d[..., 1] / ly
    exact = directional_homogeneous(0.08, 0.12, 0.5, d @ l, 3.0, 0.0, t1, leg0, rate)
    # every light leg leaves through the top face: check it at both ends of each ray (the leg is affine)
    for t in (np.zeros_like(t1), t1):
        xs = o + t[..., None] * d
        exit_pts = xs + (hi[1] - xs[..., 1])[..., None] / ly * l
        for k in (0, 2):
            assert np.all((exit_pts[..., k] >= lo[k]) & (exit_pts[..., k] <= hi[k]))
    true = _check_bound(res, exact, 1e-4)
    assert np.all(true <= 1e-4 * exact)


def _sphere_shadow_edges(o, d, p, c, r, t0, t1, n=4000):
    """``[t0, roots..., t1]``: the points where the segment x(t) -> p starts or stops passing through the sphere
    (c, r), sign changes of its distance to c minus r refined by brentq (independent of the reference's visibility
    bisection)."""
    def gap(t):
        x = o + t * d
        u = p - x
        s = np.clip(np.dot(c - x, u) / np.dot(u, u), 0.0, 1.0)
        return np.linalg.norm(x + s * u - c) - r
    ts = np.linspace(t0, t1, n)
    gs = np.array([gap(t) for t in ts])
    roots = [optimize.brentq(gap, ts[i], ts[i + 1], xtol=1e-14, rtol=1e-15)
             for i in range(n - 1) if gs[i] * gs[i + 1] < 0]
    return [t0] + roots + [t1], gap


def _sphere_shadow_intervals(o, d, p, c, r, t0, t1, n=4000):
    """The lit pieces of ``[t0, t1]`` (:func:`_sphere_shadow_edges`)."""
    edges, gap = _sphere_shadow_edges(o, d, p, c, r, t0, t1, n)
    return [(edges[i], edges[i + 1]) for i in range(len(edges) - 1) if gap(0.5 * (edges[i] + edges[i + 1])) > 0]


@functools.cache  # three tests share it (the brentq roots take seconds)
def _sphere_case():
    """A point light and a sphere casting a volumetric shadow: the scene, and per pixel ``(edges, lit)``: the
    light's interval along the ray cut at every shadow boundary, and its lit pieces (:func:`_sphere_shadow_edges`)."""
    light = Light(type="point", position=(0.0, 4.0, 0.0), intensity=30.0, range=20.0,
                  shadows=ShadowSettings(filter="exact"))
    blocker = Sphere(center=(0.3, 2.4, 0.5), radius=0.6)
    m = Medium(scattering=0.1, absorption=0.02, anisotropy=0.2)
    scene = _scene(m, [light], [blocker], max_distance=20.0,
                   camera=CameraSettings(position=(0.0, 0.5, -8.0), look_at=(0.0, 1.2, 0.0), fov=40.0))
    o, d = _rays(scene)
    p, c = np.array(light.position), np.array(blocker.center)
    pixels = {}
    for y in range(H):
        for x in range(W):
            dd = d[y, x]
            tc, h = closest_approach(o, dd, p)
            half = math.sqrt(max(light.range ** 2 - h * h, 0.0))
            a, b = max(0.0, tc - half), min(20.0, tc + half)
            # a view ray that hits the sphere ends on it
            oc = o - c
            bb = np.dot(oc, dd)
            disc = bb * bb - (np.dot(oc, oc) - blocker.radius ** 2)
            if disc >= 0.0 and -bb - math.sqrt(disc) > 0.0:
                b = min(b, -bb - math.sqrt(disc))
            edges, _ = _sphere_shadow_edges(o, dd, p, c, blocker.radius, a, b)
            pixels[y, x] = edges, _sphere_shadow_intervals(o, dd, p, c, blocker.radius, a, b)
    return scene, pixels


def _sphere_exact(scene, pixels):
    o, d = _rays(scene)
    light = scene.lights[0]
    exact = np.zeros((H, W))
    for (y, x), (_, lit) in pixels.items():
        tc, h = closest_approach(o, d[y, x], np.array(light.position))
        exact[y, x] = sum(point_light_extinction(0.1, 0.12, 0.2, 30.0, tc, h, u, v) for u, v in lit)
    return exact


@pytest.mark.parametrize("rule, rel_tol", [(15, 1e-4), (7, 1e-4), (7, 1e-2), (7, 1.0), (3, 1e-2), (3, 1.0)])
def test_sphere_shadow_boundaries_are_located(rule, rel_tol):
    """Every shadow boundary split, the result within its bound of the closed form and the bound within ``rel_tol``;
    at ``rel_tol = 1`` the boundaries are bisected only to ``1e-3 max(1, t)`` (:func:`bisection_width`), and their
    term in the bound must still cover the misplacement."""
    scene, pixels = _sphere_case()
    res = render_reference(scene, rel_tol=rel_tol, rule=rule)
    assert sum(len(lit) > 1 for _, lit in pixels.values()) > 5, "the scene must cast volumetric shadows"
    exact = _sphere_exact(scene, pixels)
    true = _check_bound(res, exact, rel_tol)
    assert np.all(true <= rel_tol * exact)


def test_boundaries_are_bisected_to_a_width_set_by_the_tolerance():
    """The bracket's relative width: 1e-12 (a converged answer's) for every ``rel_tol <= 1e-3``, so those results
    keep their bits, and ``1e-3 rel_tol³`` above, monotone in between."""
    assert [bisection_width(t) for t in (1e-9, 1e-4, 1e-3)] == [1e-12] * 3
    widths = [bisection_width(t) for t in (2e-3, 1e-2, 1e-1, 1.0)]
    assert widths == sorted(widths) and widths[0] > 1e-12 and widths[-1] == 1e-3


@pytest.mark.parametrize("samples", [6, 16])
def test_a_coarse_shadow_grid_splits_every_run_longer_than_its_spacing(samples):
    """``shadow_samples``' stated resolution (docs/PHYSICS.md, "Shadow boundaries"): along a pixel ray whose lit
    and shadowed runs are all longer than the grid spacing ``(light interval) / shadow_samples``, every boundary is
    found, and the result is within its reported bound of the closed form (which stays within rel_tol)."""
    scene, pixels = _sphere_case()
    res = render_reference(scene, rel_tol=1e-6, shadow_samples=samples)
    exact = _sphere_exact(scene, pixels)
    resolved = shadowed = 0
    for (y, x), (edges, _) in pixels.items():
        if min(np.diff(edges)) <= (edges[-1] - edges[0]) / samples:
            continue  # a run the grid may step over: the documented resolution limit
        resolved += 1
        shadowed += len(edges) > 2
        assert res.stats["shadow_boundaries"][y, x] == len(edges) - 2
        assert abs(res.inscatter[y, x, 0] - exact[y, x]) <= res.error[y, x] <= 1e-6 * res.inscatter[y, x, 0]
    assert shadowed >= 4 and resolved >= H * W // 2, "the grid must resolve most pixels, shadowed ones among them"


def test_zero_scattering_is_black_and_deterministic():
    light = Light(type="point", position=(0.0, 1.0, 0.0), intensity=20.0, range=25.0)
    scene = _scene(Medium(scattering=0.0, absorption=0.2), [light])
    res = render_reference(scene)
    assert not res.inscatter.any() and res.max_error == 0.0
    assert np.allclose(res.transmittance, math.exp(-0.2 * 30.0))
    a = render_reference(dataclasses.replace(scene, medium=Medium(scattering=0.2)))
    b = render_reference(dataclasses.replace(scene, medium=Medium(scattering=0.2)))
    assert np.array_equal(a.inscatter, b.inscatter) and np.array_equal(a.error, b.error)


def test_the_peak_is_integrated_across_in_the_angle_about_the_closest_approach():
    """The only point light's closest approach is no split point: the pixel's piece is integrated in
    ``u = atan((t - tc) / h)``, where ``f dt/du`` is smooth (:func:`peak_substitution`). ``(tc, h)`` are the closed
    forms' (``closest_approach``); there is none with two point lights, a directional light alone, an empty
    interval, or a ray within ``1 / MAX_SPREAD`` of the light relative to its interval."""
    light = Light(type="point", position=(0.5, 1.3, 0.0), intensity=20.0, range=25.0)
    scene = _scene(Medium(scattering=0.1, absorption=0.05), [light])
    o, d = _rays(scene)
    ray = (*o, *d[2, 3])

    def sub(sc, ray, a=0.0, b=30.0):
        return peak_substitution(ray, a, b, build_context(sc, prepare_frame(sc)).lights)

    k, tc, h = sub(scene, ray)
    tc_ref, h_ref = closest_approach(o, d[2, 3], np.array(light.position))
    assert k == 0 and tc == pytest.approx(tc_ref, rel=1e-14) and h == pytest.approx(h_ref, rel=1e-12)
    assert sub(scene, ray, 3.0, 3.0)[0] == -1
    two = dataclasses.replace(scene, lights=(light, dataclasses.replace(light, position=(-1.0, 1.0, 2.0))))
    assert sub(two, ray) == (-1, 0.0, 0.0)
    sun = dataclasses.replace(scene, lights=(Light(type="directional", direction=(0.0, -1.0, 0.0)),))
    assert sub(sun, ray) == (-1, 0.0, 0.0)
    through = (*o, *((np.array(light.position) - o) / np.linalg.norm(np.array(light.position) - o)))
    assert sub(scene, through)[0] == -1
    reach = MAX_SPREAD * h_ref  # the interval's farthest end from tc just within the limit, and just beyond it
    assert [sub(scene, ray, tc_ref, tc_ref + reach * f)[0] for f in (1 - 1e-9, 1 + 1e-9)] == [0, -1]


@pytest.mark.parametrize("offset", [1e-2, 2e-2])
@pytest.mark.parametrize("rule, rel_tol", [(15, 1e-6), (3, 1e-2)])
def test_a_ray_passing_next_to_the_light_is_within_its_bound(offset, rule, rel_tol):
    """A point light ``offset`` metres beside one pixel's ray (no closer: the inverse-square law is clamped at
    ``MIN_DISTANCE`` = 1 cm, which the closed form does not model): its ``1/r²`` peak, of width ``offset`` on the ray's
    21 m beyond ``tc``, integrated in the angle about it: within the reported bound of the closed form, the bound
    within ``rel_tol``. (Split at ``tc`` and integrated in ``t``, as before the change of variable, both pixels'
    errors at rule 3 were 20x their bounds: no node of either piece fell inside the peak.)"""
    cam = CameraSettings(position=(0.0, 1.0, -10.0), look_at=(0.0, 1.0, 0.0), fov=50.0)
    o, d = _rays(_scene(Medium(), [], camera=cam))
    side = np.cross(d[2, 3], (0.0, 1.0, 0.0))
    position = o + 9.0 * d[2, 3] + offset * side / np.linalg.norm(side)
    light = Light(type="point", position=tuple(position), intensity=1e-3, range=25.0)
    scene = _scene(Medium(scattering=0.3, absorption=0.1, anisotropy=0.4), [light], camera=cam)
    res = render_reference(scene, rel_tol=rel_tol, abs_tol=1e-14, rule=rule)
    exact = _point_exact(scene, light)
    true = _check_bound(res, exact, rel_tol)
    assert np.all(true <= rel_tol * exact)
    assert exact[2, 3] > 100 * np.median(exact)  # the peak pixel


def test_shadows_outside_the_medium_box_are_not_searched():
    """``f = 0`` outside the medium box: a sphere behind the box, whose shadow the pixel rays cross only beyond the
    box, adds no shadow boundary and changes no bit of the inscatter (the grid of 512 samples found its edges
    behind the box before); in the same medium without its box they are found."""
    m = Medium(scattering=0.1, absorption=0.02, anisotropy=0.3, bounds=Bounds(min=(-3.0, -2.0, -3.0),
                                                                              max=(3.0, 4.0, 3.0)))
    light = Light(type="point", position=(0.0, 1.0, 0.0), intensity=10.0, range=40.0,
                  shadows=ShadowSettings(filter="exact"))
    bare = _scene(m, [light])
    behind = _scene(m, [light], [Sphere(center=(0.0, 1.0, 6.0), radius=2.5)])
    a, b = (render_reference(sc, rel_tol=1e-3, shadow_samples=512, rule=7) for sc in (bare, behind))
    assert not b.stats["shadow_boundaries"].any()
    np.testing.assert_array_equal(a.inscatter, b.inscatter)
    assert np.any(prepare_reference(behind).t_end < prepare_reference(bare).t_end)  # the rays that see it end on it
    unbounded = _scene(dataclasses.replace(m, bounds=None), [light], [Sphere(center=(0.0, 1.0, 6.0), radius=2.5)])
    assert render_reference(unbounded, rel_tol=1e-3, shadow_samples=512, rule=7).stats["shadow_boundaries"].sum() > 4


def test_a_prepared_frame_gives_the_scenes_bits_for_every_setting():
    """:func:`prepare_reference` once, several settings: each result equals the scene's own call bit for bit, with
    any thread count (which thread solves a pixel changes nothing), and the frame is reported reused."""
    scene, _ = _sphere_case()
    prepared = prepare_reference(scene)
    threads = numba.get_num_threads()
    for kw in ({"rel_tol": 1.0, "shadow_samples": 1, "rule": 3}, {"rel_tol": 1e-4, "shadow_samples": 16}):
        whole = render_reference(scene, **kw)
        for n in sorted({1, threads}):
            numba.set_num_threads(n)
            try:
                again = render_reference(prepared, **kw)
            finally:
                numba.set_num_threads(threads)
            for name in ("inscatter", "transmittance", "final", "error"):
                np.testing.assert_array_equal(getattr(again, name), getattr(whole, name))
            assert again.stats["frame_reused"] and not whole.stats["frame_reused"]
            assert again.stats["intervals"] == whole.stats["intervals"]
    rows = prepare_reference(scene, rows=(2, 5))
    np.testing.assert_array_equal(render_reference(rows, rel_tol=1e-2).inscatter,
                                  render_reference(scene, rel_tol=1e-2).inscatter[2:5])
    with pytest.raises(ValueError, match="rows"):
        render_reference(prepared, rows=(0, 2))
