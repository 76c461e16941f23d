"""G-buffer ray casting: analytic depth of a plane/sphere scene, far-plane cut, transparency,
meshes against the equivalent analytic box, bit-identical results for 1 and 2 threads, and the rays left out of
the primitive tree (those that cannot cross its root box) giving the same bits as every ray through it."""

from pathlib import Path

import numba
import numpy as np
import pytest

from vlref.bench.config import bench_scene
from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry, raycast
from vlref.geometry.raycast import GBuffer, _cast_rows, _raycast_kernel, kernel_args, tree_spans
from vlref.geometry.meshgen import box_mesh
from vlref.geometry.obj import write_obj
from vlref.parallel import COUNTER, work
from vlref.scene.model import Box, CameraSettings, Cylinder, Light, Material, Mesh, Plane, Scene, Sphere

DATA = Path(__file__).resolve().parents[1] / "data" / "scenes"
LIGHTS = (Light(type="point"),)


def plane_sphere_scene(far=1000.0):
    return Scene(lights=LIGHTS, camera=CameraSettings(position=(0.5, 1.5, -6.0), look_at=(0.0, 1.0, 0.0), far=far),
                 objects=(Plane(material=Material(albedo=(0.2, 0.3, 0.4))),
                          Sphere(center=(0.0, 1.0, 1.0), radius=1.2,
                                 material=Material(albedo=(0.9, 0.5, 0.1), emission=(2.0, 0.0, 1.0)))))


def analytic(cam, centre, radius):
    """Textbook closest hit of every pixel ray with the plane y = 0 and the sphere: (t, id, normal)."""
    d = cam.ray_directions()
    o = cam.position
    with np.errstate(divide="ignore", invalid="ignore"):
        tp = np.where(d[..., 1] < 0, -o[1] / d[..., 1], np.inf)
    oc = o - np.asarray(centre)
    b = d @ oc
    disc = b * b - (oc @ oc - radius ** 2)
    root = np.sqrt(np.maximum(disc, 0.0))
    ts = np.where(disc >= 0, np.where(-b - root > 0, -b - root, -b + root), np.inf)
    ts = np.where(ts > 0, ts, np.inf)
    tmax = cam.far / (d @ cam.forward)
    t = np.minimum(tp, ts)
    ids = np.where(t >= tmax, -1, np.where(ts < tp, 1, 0))
    t = np.where(ids < 0, np.inf, t)
    n = np.where((ids == 1)[..., None], (o + ts[..., None] * d - centre) / radius, [0.0, 1.0, 0.0])
    return t, ids, np.where((ids >= 0)[..., None], n, 0.0)


@pytest.mark.parametrize("far", [1000.0, 9.0])
def test_plane_sphere_depth_matches_analytic(far):
    scene = plane_sphere_scene(far)
    cam = camera_from_settings(scene.camera, 32, 24)
    gb = raycast(scene, cam)
    t, ids, n = analytic(cam, (0.0, 1.0, 1.0), 1.2)
    d = cam.ray_directions()
    assert np.array_equal(gb.object_id, ids) and gb.object_id.dtype == np.int32
    assert {0, 1, -1} <= set(np.unique(ids)) or far == 1000.0
    hit = ids >= 0
    assert np.allclose(gb.distance[hit], t[hit], rtol=1e-12)
    assert np.allclose(gb.depth[hit], (t * (d @ cam.forward))[hit], rtol=1e-12)
    assert np.all(gb.depth[hit] <= far * (1 + 1e-12))
    assert np.all(np.isinf(gb.depth[~hit])) and np.all(np.isinf(gb.distance[~hit]))
    assert np.allclose(gb.position[hit], (cam.position + t[..., None] * d)[hit], atol=1e-10)
    # position is derived from what the kernel stores, o + t d with the stored t, bit for bit
    assert np.array_equal(gb.position[hit], (cam.position + gb.distance[..., None] * d)[hit])
    assert np.allclose(gb.normal, n, atol=1e-10)
    mats = np.array([[0.2, 0.3, 0.4], [0.9, 0.5, 0.1], [0.0, 0.0, 0.0]])
    assert np.array_equal(gb.albedo, mats[ids])
    assert np.array_equal(gb.emission[..., 0], np.where(ids == 1, 2.0, 0.0))
    assert np.all(gb.position[~hit] == 0.0) and np.all(gb.normal[~hit] == 0.0)
    assert not np.isnan(gb.position).any() and not np.isnan(gb.normal).any()


def test_eye_depth_converts_to_distance_with_the_camera():
    scene = plane_sphere_scene()
    cam = camera_from_settings(scene.camera, 16, 12)
    gb = raycast(scene, cam)
    hit = gb.hit
    assert np.allclose(cam.eye_depth_to_distance(gb.depth)[hit], gb.distance[hit], rtol=1e-13)


def test_transparent_objects_write_nothing():
    scene = plane_sphere_scene()
    glass = Box(center=(0.0, 1.0, -3.0), size=(3.0, 3.0, 0.2), material=Material(opacity=0.5, tint=(1, 0.5, 0.5)))
    cam = camera_from_settings(scene.camera, 24, 16)
    with_glass = raycast(scene.replace(objects=scene.objects + (glass,)), cam)
    without = raycast(scene, cam)
    for name in ("depth", "distance", "position", "normal", "albedo", "emission", "object_id"):
        assert np.array_equal(getattr(with_glass, name), getattr(without, name))


def test_size_override_equals_camera_with_size():
    scene = plane_sphere_scene()
    cam = camera_from_settings(scene.camera, 32, 24)
    geo = build_geometry(scene)
    a = raycast(scene, cam, geo, width=16, height=10)
    b = raycast(scene, cam.with_size(16, 10), geo)
    assert a.depth.shape == (10, 16) and np.array_equal(a.depth, b.depth)


def test_mesh_object_matches_the_analytic_box(tmp_path):
    v, f = box_mesh((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    write_obj(tmp_path / "cube.obj", v, f)
    pose = dict(rotation=(20.0, 35.0, -10.0))
    cam_settings = CameraSettings(position=(0.3, 1.8, -2.5), look_at=(0.0, 1.0, 0.0))
    mesh = Scene(lights=LIGHTS, camera=cam_settings, source=str(tmp_path / "scene.toml"),
                 objects=(Mesh(path="cube.obj", position=(0.0, 1.0, 0.0), scale=(1.5, 0.8, 2.0), **pose),))
    box = Scene(lights=LIGHTS, camera=cam_settings,
                objects=(Box(center=(0.0, 1.0, 0.0), size=(1.5, 0.8, 2.0), **pose),))
    cam = camera_from_settings(cam_settings, 40, 30)
    gm, gb = raycast(mesh, cam), raycast(box, cam)
    assert 0.1 < gb.hit.mean() < 0.9
    assert np.array_equal(gm.object_id, gb.object_id)
    assert np.allclose(gm.depth[gb.hit], gb.depth[gb.hit], rtol=1e-12)
    assert np.allclose(gm.normal, gb.normal, atol=1e-12)


def test_same_bits_for_one_and_two_threads():
    scene = Scene(lights=LIGHTS, camera=CameraSettings(position=(1.0, 3.0, -9.0), look_at=(0.0, 2.5, 0.0)),
                  source=str(DATA / "scene.toml"),
                  objects=(Plane(), Mesh(path="colonnade.obj"), Cylinder(center=(3.0, 1.0, -2.0), rotation=(0, 0, 80)),
                           Sphere(center=(-2.0, 1.0, -2.0)), Box(center=(0.0, 0.5, -3.0), rotation=(10, 20, 30))))
    cam = camera_from_settings(scene.camera, 48, 27)
    geo = build_geometry(scene)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = raycast(scene, cam, geo)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = raycast(scene, cam, geo)
    finally:
        numba.set_num_threads(before)
    assert set(np.unique(one.object_id)) == {-1, 0, 1, 2, 3, 4}
    for name in ("depth", "distance", "position", "normal", "albedo", "emission", "object_id"):
        a, b = getattr(one, name), getattr(two, name)
        assert a.tobytes() == b.tobytes(), name


def _cameras(seed, count):
    """Cameras around, above and inside the bench scene's objects, looking every way (``count`` of them)."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        position = rng.uniform((-6.0, 0.2, -9.0), (6.0, 5.0, 6.0))
        look_at = position + rng.normal(size=3)
        yield CameraSettings(position=tuple(position), look_at=tuple(look_at), fov=float(rng.uniform(20.0, 100.0)))


def _crosses_root_box(geo, origin, dirs):
    """(H, W) bool: the ray from ``origin`` along each of ``dirs`` crosses the primitive tree's root box at some
    ``t >= 0`` (slab test in NumPy, exact but for rounding)."""
    lo, hi = geo.pnode_min[0] - origin, geo.pnode_max[0] - origin
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = lo / dirs, hi / dirs
    near = np.where(dirs == 0.0, np.where((lo <= 0.0) & (hi >= 0.0), -np.inf, np.inf), np.minimum(t0, t1))
    far = np.where(dirs == 0.0, np.where((lo <= 0.0) & (hi >= 0.0), np.inf, -np.inf), np.maximum(t0, t1))
    return np.maximum(near.max(axis=-1), 0.0) <= far.min(axis=-1)


def test_tree_spans_hold_every_ray_that_crosses_the_primitive_tree():
    scene = bench_scene(96, 54, 8, "four", 64)
    geo = build_geometry(scene).arrays
    culled = []
    for settings in (scene.camera, *_cameras(1, 40)):
        cam = camera_from_settings(settings, 96, 54)
        dirs = cam.ray_directions()
        spans = tree_spans(geo, cam.position, dirs)
        inside = np.zeros(dirs.shape[:2], dtype=bool)
        for y, (x0, x1) in enumerate(spans):
            inside[y, x0:x1] = True
        crossing = _crosses_root_box(geo, cam.position, dirs)
        assert not np.any(crossing & ~inside)
        culled.append(1.0 - inside.mean())
    assert culled[0] > 0.8  # the bench view: the objects cover a tenth of the frame's rays
    assert max(culled[1:]) > 0.5 and min(culled[1:]) == 0.0  # views of them from afar, and from among them


def test_rays_left_out_of_the_primitive_tree_give_the_same_bits():
    """Also: the kernel writes every element of its buffers, the sky's zero normals included (they are allocated
    empty): buffers filled with NaN before the kernel come out equal to the ray cast's."""
    scene = bench_scene(64, 36, 8, "four", 64)
    geometry = build_geometry(scene)
    geo = geometry.arrays
    sky = 0
    for settings in (scene.camera, *_cameras(2, 12)):
        cam = camera_from_settings(settings, 64, 36)
        culled = raycast(scene, cam, geometry)
        every = GBuffer(**{name: np.empty_like(getattr(culled, name)) for name in ("depth", "distance", "normal",
                                                                                    "object_id")},
                        origin=culled.origin, directions=culled.directions, object_albedo=geo.albedo,
                        object_emission=geo.emission)
        for name in ("depth", "distance", "normal"):
            getattr(every, name)[...] = np.nan
        every.object_id[...] = -7
        args = list(kernel_args(geo, cam, every))
        args[1] = np.tile(np.array([0, 64], dtype=np.int64), (36, 1))  # every ray through the tree
        _raycast_kernel(*args, work(_cast_rows, COUNTER, *args), 2)
        for name in ("depth", "distance", "normal", "object_id"):
            assert getattr(culled, name).tobytes() == getattr(every, name).tobytes(), name
        assert np.all(every.normal[~culled.hit] == 0.0)
        sky += int((~culled.hit).sum())
    assert sky > 0  # the views see sky
