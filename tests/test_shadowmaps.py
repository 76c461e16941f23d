"""Shadow maps agree with exact shadow rays away from shadow edges (spot, point cube faces, directional
cascades), coloured transparent occluders, buffer names."""

import math

import numpy as np
import pytest

from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry
from vlref.lights import pack_lights
from vlref.lights.shadow_cast import build_shadow_maps, cascade_splits
from vlref.lights.shadow_lookup import cube_map_coords, pcf_taps, shadow_visibility
from vlref.lights.shadow_pack import CUBE_FACES
from vlref.scene.model import (CameraSettings, Light, Material, Plane, Scene, ShadowSettings, Sphere)

SPHERES = (((0.0, 1.5, 3.0), 0.6), ((2.5, 0.0, 0.0), 0.5), ((-2.0, 0.3, -1.0), 0.5), ((0.0, -2.2, 0.4), 0.6),
           ((0.3, 2.6, 0.0), 0.5), ((1.6, 1.6, -1.6), 0.5), ((-1.5, -1.5, 1.5), 0.45))


def _scene(light, filt, transparent=False):
    objs = [Sphere(center=c, radius=r) for c, r in SPHERES]
    objs.append(Plane(point=(0.0, -4.0, 0.0), normal=(0.0, 1.0, 0.0)))
    if transparent:
        objs.append(Plane(point=(0.0, 0.0, 5.0), normal=(0.0, 0.0, 1.0),
                          material=Material(opacity=0.5, tint=(1.0, 0.4, 0.2))))
    light = Light(**{**light, "shadows": ShadowSettings(filter=filt, resolution=256, bias=0.02)})
    return Scene(lights=(light,), objects=tuple(objs),
                 camera=CameraSettings(position=(0.0, 0.0, -8.0), look_at=(0.0, 0.0, 0.0), far=200.0))


def _edge_distance(points, light, kind):
    """Distance of each shadow ray from the nearest sphere silhouette (|line-centre distance - r|)."""
    out = np.full(len(points), np.inf)
    for c, r in SPHERES:
        c = np.asarray(c)
        if kind == 2:
            src = points - np.asarray(light["direction"]) / np.linalg.norm(light["direction"]) * 1e3
        else:
            src = np.broadcast_to(np.asarray(light["position"]), points.shape)
        seg = points - src
        s = np.clip(((c - src) * seg).sum(1) / (seg * seg).sum(1), 0, 1)
        closest = src + s[:, None] * seg
        out = np.minimum(out, np.abs(np.linalg.norm(closest - c, axis=1) - r))
        out = np.minimum(out, np.abs(np.linalg.norm(points - c, axis=1) - r))  # near a surface
    return out


def _compare(light, kind, points, filt, margin=0.12, transparent=False):
    vis, maps = {}, {}
    for f in (filt, "exact"):
        scene = _scene(light, f, transparent)
        cam = camera_from_settings(scene.camera, 32, 24)
        geo = build_geometry(scene)
        packed = pack_lights(scene)
        sm = maps[f] = build_shadow_maps(scene, cam, geo, packed)
        vis[f] = np.array([shadow_visibility(sm.table, geo.arrays, kind, packed.floats, 0, *p) for p in points])
    away = _edge_distance(points, light, kind) > margin
    assert away.sum() > 0.5 * len(points)
    assert (vis["exact"][away] == 0).any() and (vis["exact"][away] > 0).any()  # the test sees both
    np.testing.assert_allclose(vis[filt][away], vis["exact"][away], atol=1e-6)
    return maps[filt], vis


def _random_points(n, lo, hi, seed=1):
    return np.random.default_rng(seed).uniform(lo, hi, size=(n, 3))


@pytest.mark.parametrize("filt", ["hard", "pcf"])
def test_point_cube_map_matches_exact_visibility_on_every_face(filt):
    light = dict(type="point", position=(0.0, 0.0, 0.0), range=30.0)
    pts = _random_points(900, -3.8, 3.8)
    pts = pts[np.linalg.norm(pts, axis=1) > 0.5]
    sm, vis = _compare(light, 0, pts, filt)
    # the compared points include many near cube-face borders (|x| ~ |y|): no seam there
    assert np.isclose(np.abs(pts[:, 0]), np.abs(pts[:, 1]), atol=0.3).sum() > 20
    assert set(sm.buffers()) == {f"shadow_point_0_face_{s}" for s in ("px", "nx", "py", "ny", "pz", "nz")}


@pytest.mark.parametrize("filt", ["hard", "pcf"])
def test_spot_map_matches_exact_visibility(filt):
    light = dict(type="spot", position=(0.0, 6.0, 0.0), direction=(0.0, -1.0, 0.0), spot_angle=100.0, range=30.0)
    pts = _random_points(900, (-4, -3.9, -4), (4, 4.5, 4))
    w = pts - np.array([0.0, 6.0, 0.0])
    pts = pts[(-w[:, 1] / np.linalg.norm(w, axis=1)) > math.cos(math.radians(48))]
    sm, _ = _compare(light, 1, pts, filt)
    assert list(sm.buffers()) == ["shadow_spot_0"] and sm.buffers()["shadow_spot_0"].shape == (256, 256)


@pytest.mark.parametrize("filt", ["hard", "pcf"])
def test_directional_cascades_match_exact_visibility_across_cascade_borders(filt):
    light = dict(type="directional", direction=(0.3, -1.0, 0.2))
    pts = _random_points(900, (-4, -3.9, -6), (4, 3, 12))
    sm, _ = _compare(light, 2, pts, filt, margin=0.15)
    names = list(sm.buffers())
    assert names == [f"shadow_dir_0_cascade_{k}" for k in range(4)]
    # the points span several cascades
    depth = pts[:, 2] + 8.0
    splits = cascade_splits(0.1, 100.0, 4, 0.75)
    assert len(np.unique(np.searchsorted(splits, depth))) >= 3


def test_cascade_splits_practical_scheme():
    s = cascade_splits(1.0, 100.0, 4, 1.0)
    np.testing.assert_allclose(s, [1.0, 10 ** 0.5, 10.0, 10 ** 1.5, 100.0])
    np.testing.assert_allclose(cascade_splits(1.0, 101.0, 4, 0.0), [1, 26, 51, 76, 101])


def test_transparent_occluder_colours_the_light_in_maps_and_exact_rays():
    light = dict(type="spot", position=(0.0, 0.0, 9.0), direction=(0.0, 0.0, -1.0), spot_angle=60.0, range=30.0)
    pts = np.array([[x, y, 1.5] for x in np.linspace(-1.5, 1.5, 7) for y in np.linspace(0.0, 2.5, 6)])
    pts = pts[_edge_distance(pts, light, 1) > 0.12]
    for filt in ("hard", "pcf"):
        sm, vis = _compare(light, 1, pts, filt, transparent=True)
        lit = vis["exact"][:, 0] > 0
        np.testing.assert_allclose(vis["exact"][lit], [[0.5, 0.2, 0.1]] * lit.sum(), atol=1e-12)
        bufs = sm.buffers()
        assert bufs["shadow_spot_0_transmittance"].shape == (256, 256, 3)
        assert np.isfinite(bufs["shadow_spot_0_transparent_distance"]).any()


@pytest.mark.parametrize("ortho", [False, True])
def test_face_rays_are_the_texel_grid_construction(ortho):
    # the kernel builds each texel's ray itself; the bits are those of the array construction from texel_grid
    from vlref.lights.shadow_cast import _face, _face_ray, texel_grid

    res, near, limit, scale = 5, 0.7, 12.0, 0.83
    origin, fwd = np.array([0.3, 2.0, -1.1]), np.array([0.48, -0.8, 0.36])
    right, up = np.array([0.6, 0.0, -0.8]), np.array([-0.64, -0.6, -0.48])
    x, y = texel_grid(res)
    if ortho:
        o = origin + (x * scale)[:, None] * right + (y * scale)[:, None] * up - near * fwd
        d, start, tmax = np.broadcast_to(fwd, o.shape), np.zeros(len(o)), np.full(len(o), limit)
    else:
        v = fwd[None, :] + (x * scale)[:, None] * right[None, :] + (y * scale)[:, None] * up[None, :]
        length = np.linalg.norm(v, axis=1)
        o, d, start = origin[None, :] + near * v, v / length[:, None], near * length
        tmax = np.maximum(limit - start, 0.0)
    face = _face(origin, fwd, right, up, scale, near, limit)
    got = np.array([_face_ray(face, ortho, res, k) for k in range(res * res)])
    assert np.array_equal(got, np.column_stack([o, d, start, tmax]))


def test_cube_map_coords_are_the_face_table_lookup():
    """The selects of cube_map_coords give the face of the major axis (ties: x, then y, then z) and the very
    (u, v) of the face table's axes (CUBE_FACES: sc = w · right / ma, tc = w · up / ma), bit for bit, on random
    points, points on the axes and on the diagonals where the major axis ties; no face for w = 0."""
    rng = np.random.default_rng(3)
    pts = np.concatenate([rng.normal(size=(4000, 3)), np.eye(3), -np.eye(3), [[1, 1, 0], [-1, 0, -1], [0, 2, -2],
                          [1, -1, 1], [-3, 3, 3], [0.5, 0.0, -0.0], [-0.0, 0.0, 0.25]]])
    table = np.array([[r, u, f] for _, r, u, f in CUBE_FACES], dtype=np.float64)
    for w in pts:
        x, y, z = (float(c) for c in w)
        face, u, v, d_ref, on_face = cube_map_coords(x, y, z)
        a = np.abs(w)
        want = int(np.argmax(a)) * 2 + int(w[int(np.argmax(a))] < 0)  # argmax takes the first of tied axes
        assert face == want and on_face and d_ref == math.sqrt(x * x + y * y + z * z)
        right, up, fwd = table[face]
        ma = abs(w[0] * fwd[0] + w[1] * fwd[1] + w[2] * fwd[2])
        assert u == 0.5 + 0.5 * ((w[0] * right[0] + w[1] * right[1] + w[2] * right[2]) / ma)
        assert v == 0.5 - 0.5 * ((w[0] * up[0] + w[1] * up[1] + w[2] * up[2]) / ma)
    assert cube_map_coords(0.0, 0.0, 0.0)[4] is False


@pytest.mark.parametrize("res", [8, 1024, 8192])
def test_pcf_taps_are_the_clamped_texels_around_the_point_and_their_bilinear_weights(res):
    """pcf_taps: with ``s = u · res - 1/2`` (and ``t`` for ``v``), the columns ``floor(s)`` and ``floor(s) + 1``
    and the rows likewise, each clamped to the face, as offsets ``row · res + column``, and the weights of
    ``s - floor(s)``, ``t - floor(t)``, bit for bit; points far outside the map (beyond 2^63 texels too, and
    infinite) read the edge texels on their side, NaN reads texel 0. Independently: NumPy's floor and clip on int64
    texel indices."""
    rng = np.random.default_rng(5)
    edge = [-1e300, -np.inf, -3.0, -1.0 / res, 0.0, 0.5 / res, 0.5, 1.0 - 0.5 / res, 1.0, 2.5, 1e19, 1e300, np.inf,
            np.nan]
    us = np.concatenate([rng.uniform(-0.2, 1.2, 300), edge, rng.uniform(0.0, 1.0, len(edge))])
    vs = np.concatenate([rng.uniform(-0.2, 1.2, 300), rng.uniform(0.0, 1.0, len(edge)), edge])
    for u, v in zip(us, vs):
        (k00, k10, k01, k11), weights = pcf_taps(float(u), float(v), res)
        s, t = u * res - 0.5, v * res - 0.5

        def texels(x):
            if np.isnan(x):
                return 0, 0
            f = np.floor(x)
            return tuple(int(np.clip(f + d, 0, res - 1)) if np.isfinite(f) else (0 if f < 0 else res - 1)
                         for d in (0.0, 1.0))

        (c0, c1), (r0, r1) = texels(s), texels(t)
        assert (k00, k10, k01, k11) == (r0 * res + c0, r0 * res + c1, r1 * res + c0, r1 * res + c1), (u, v)
        if np.isfinite(s) and np.isfinite(t):
            wu, wv = s - np.floor(s), t - np.floor(t)
            assert weights == ((1 - wu) * (1 - wv), wu * (1 - wv), (1 - wu) * wv, wu * wv)
