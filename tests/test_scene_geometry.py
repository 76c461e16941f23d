"""Packed scene geometry: closest_hit, shadow_transmittance (opaque, transparent, closed solids,
shared mesh edges, self-intersection epsilon), trace_distances, bounds and mesh errors."""

import math

import numpy as np
import pytest

from vlref.errors import InputError
from vlref.geometry import build_geometry, closest_hit, shadow_transmittance, trace_distances
from vlref.geometry.meshgen import box_mesh
from vlref.geometry.obj import write_obj
from vlref.scene.model import Box, Cylinder, Light, Material, Mesh, Plane, Scene, Sphere

LIGHTS = (Light(type="point"),)
GLASS = Material(opacity=0.4, tint=(1.0, 0.5, 0.25))
CLEAR = np.array([0.6, 0.3, 0.15])  # (1 - opacity) * tint of GLASS


def scene_of(*objects, source=""):
    return Scene(lights=LIGHTS, objects=objects, source=source)


def test_closest_hit_normal_faces_the_origin_and_opaque_only_skips_glass():
    geo = build_geometry(scene_of(Sphere(center=(0, 0, 0), radius=2.0), Sphere(center=(0, 0, -1.5), radius=0.2,
                                                                                 material=GLASS))).arrays
    t, obj, *n = closest_hit(geo, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, math.inf, False)
    assert obj == 1 and t == pytest.approx(1.3)
    assert n == pytest.approx([0.0, 0.0, 1.0])  # glass front face, facing the origin
    t, obj, *n = closest_hit(geo, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, math.inf, True)
    assert obj == 0 and t == pytest.approx(2.0)
    assert n == pytest.approx([0.0, 0.0, 1.0])  # inside the big sphere: flipped inward
    assert closest_hit(geo, 5.0, 5.0, 5.0, 1.0, 0.0, 0.0, 0.0, math.inf, False) == (math.inf, -1, 0.0, 0.0, 0.0)


def test_shadow_opaque_blocks_and_the_origin_surface_does_not():
    geo = build_geometry(scene_of(Plane(), Box(center=(0, 3, 0)))).arrays
    assert shadow_transmittance(geo, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 10.0) == (0.0, 0.0, 0.0)
    assert shadow_transmittance(geo, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 2.4) == (1.0, 1.0, 1.0)  # stops short
    assert shadow_transmittance(geo, 3.0, 0.0, 0.0, 0.1, 1.0, 0.0, 10.0) == (1.0, 1.0, 1.0)  # on the plane
    # a shadow ray toward the light with an unnormalised direction (tmax = 1 at the light)
    assert shadow_transmittance(geo, 0.0, 0.0, 0.0, 0.0, 20.0, 0.0, 1.0) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("solid", [
    Sphere(center=(0, 2, 0), radius=0.5, material=GLASS),
    Box(center=(0, 2, 0), rotation=(0, 45, 0), material=GLASS),
    Cylinder(center=(0, 2, 0), rotation=(90, 0, 0), material=GLASS),
])
def test_closed_transparent_solid_counts_two_crossings(solid):
    geo = build_geometry(scene_of(Plane(), solid)).arrays
    got = shadow_transmittance(geo, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 10.0)
    assert got == pytest.approx(CLEAR ** 2, rel=1e-14)
    got = shadow_transmittance(geo, 0.0, 2.0, 0.0, 0.0, 1.0, 0.0, 10.0)  # starts inside: leaves once
    assert got == pytest.approx(CLEAR, rel=1e-14)


def test_transparent_mesh_counts_shared_edges_once(tmp_path):
    v, f = box_mesh((0.0, 2.0, 0.0), (1.0, 1.0, 1.0))
    write_obj(tmp_path / "cube.obj", v, f)
    geo = build_geometry(scene_of(Plane(material=GLASS), Mesh(path="cube.obj", material=GLASS),
                                  source=str(tmp_path / "s.toml"))).arrays
    # through the face centres: each face is split along its diagonal, so the ray meets shared edges
    got = shadow_transmittance(geo, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 10.0)
    assert got == pytest.approx(CLEAR ** 2, rel=1e-14)
    got = shadow_transmittance(geo, 0.1, -1.0, 0.2, 0.0, 1.0, 0.0, 10.0)  # glass plane too
    assert got == pytest.approx(CLEAR ** 3, rel=1e-14)


def test_trace_distances_matches_closest_hit():
    geo = build_geometry(scene_of(Plane(), Sphere(center=(0, 1, 3)), Cylinder(center=(2, 1, 0), material=GLASS))).arrays
    rng = np.random.default_rng(0)
    o = rng.uniform(-3, 3, size=(200, 3)) + [0, 2, 0]
    d = rng.normal(size=(200, 3))
    tmax = rng.uniform(1, 8, size=200)
    for opaque_only in (True, False):
        t, obj = trace_distances(geo, o, d, tmax, opaque_only)
        assert obj.dtype == np.int32 and t.shape == (200,)
        for k in range(200):
            ref = closest_hit(geo, *o[k], *d[k], 0.0, tmax[k], opaque_only)
            assert (t[k], obj[k]) == ref[:2]
        assert 0 < np.mean(obj >= 0) < 1
    t1, _ = trace_distances(geo, o[0], d, 5.0)  # broadcasting one origin and a scalar tmax
    assert t1.shape == (200,) and np.all(t1[np.isfinite(t1)] < 5.0)


def test_bounds_and_counts(tmp_path):
    v, f = box_mesh((5.0, 0.0, 0.0), (1.0, 2.0, 1.0))
    write_obj(tmp_path / "m.obj", v, f)
    g = build_geometry(scene_of(Plane(), Sphere(center=(0, 1, 0), radius=0.5),
                                Mesh(path=str(tmp_path / "m.obj"), scale=(2, 1, 1)),
                                Cylinder(center=(0, 0, -3), radius=0.5, height=2.0, rotation=(0, 0, 90))))
    assert g.n_objects == 4 and g.n_triangles == 12
    assert np.allclose(g.bounds_min, [-1.0, -1.0, -3.5]) and np.allclose(g.bounds_max, [11.0, 1.5, 0.5])
    empty = build_geometry(scene_of(Plane()))
    assert np.array_equal(empty.bounds_min, np.zeros(3)) and empty.n_triangles == 0


def test_bad_mesh_file_raises_input_error_naming_it(tmp_path):
    (tmp_path / "bad.obj").write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(InputError) as err:
        build_geometry(scene_of(Mesh(path="bad.obj"), source=str(tmp_path / "s.toml")))
    assert err.value.file.endswith("bad.obj") and err.value.path == "line 2"
