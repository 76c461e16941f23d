"""Camera conventions: matrices, pixel rays and depth encodings (docs/CONVENTIONS.md)."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vlref.camera import (Camera, _length, cross, euler_matrix, linear_to_raw, look_rotation, pixel_rays,
                          raw_to_linear, unity_linear_eye_depth, zbuffer_params)
from vlref.row_blocks import MAX_BLOCK_ROWS

near_far = st.tuples(st.floats(0.01, 10.0), st.floats(1.5, 1e4)).map(lambda nf: (nf[0], nf[0] * nf[1]))


def make_camera(w=8, h=6, fov=60.0, rot=(10.0, 20.0, 5.0), pos=(1.0, 2.0, -3.0)):
    return Camera(np.array(pos), euler_matrix(rot), fov, w, h, 0.1, 100.0)


def test_euler_is_unity_zxy_order():
    # Unity: a positive y rotation turns +z toward +x; a positive x rotation pitches +z downward.
    np.testing.assert_allclose(euler_matrix((0, 90, 0)) @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(euler_matrix((90, 0, 0)) @ [0, 0, 1], [0, -1, 0], atol=1e-15)
    # z is applied first, then x, then y
    r = euler_matrix((30, 40, 50))
    rx, ry, rz = euler_matrix((30, 0, 0)), euler_matrix((0, 40, 0)), euler_matrix((0, 0, 50))
    np.testing.assert_allclose(r, ry @ rx @ rz, atol=1e-15)


@given(st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 1e-3))
def test_look_rotation_is_a_left_handed_orthonormal_frame(forward):
    r = look_rotation(forward)
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(r), 1.0, atol=1e-12)
    np.testing.assert_allclose(r[:, 2], np.array(forward) / np.linalg.norm(forward), atol=1e-12)
    assert r[1, 1] >= -1e-12 or abs(forward[1]) > 0.99 * np.linalg.norm(forward)  # up stays up



def test_cross_has_the_bits_of_numpys_cross():
    rng = np.random.default_rng(11)
    for shape in ((3,), (1, 3), (45, 3), (4, 5, 3)):
        for _ in range(50):
            a = rng.normal(size=shape) * 10.0 ** rng.uniform(-8, 8)
            b = rng.normal(size=shape) * 10.0 ** rng.uniform(-8, 8)
            assert cross(a, b).tobytes() == np.cross(a, b).tobytes(), shape
    assert cross((1, 0, 0), (0, 1, 0)).tolist() == [0.0, 0.0, 1.0]  # tuples of ints, like NumPy's


def test_length_has_the_bits_of_numpys_norm():
    rng = np.random.default_rng(12)
    for _ in range(2000):
        v = rng.normal(size=3) * 10.0 ** rng.uniform(-150, 150)
        assert np.float64(_length(v)).tobytes() == np.linalg.norm(v).tobytes()


def test_view_matrix_puts_the_camera_at_origin_looking_down_plus_z():
    cam = make_camera()
    v = cam.view_matrix()
    np.testing.assert_allclose(v @ np.append(cam.position, 1), [0, 0, 0, 1], atol=1e-12)
    p = cam.position + 5.0 * cam.forward
    np.testing.assert_allclose(v @ np.append(p, 1), [0, 0, 5, 1], atol=1e-12)


def test_rays_go_through_pixel_centres_with_row_zero_at_the_top():
    cam = make_camera(w=8, h=6)
    d = cam.ray_directions()
    assert d.shape == (6, 8, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-14)
    ndc = cam.world_to_ndc(cam.position + d * 7.0)
    xs = (np.arange(8) + 0.5) / 8 * 2 - 1
    ys = 1 - (np.arange(6) + 0.5) / 6 * 2
    np.testing.assert_allclose(ndc[..., 0], np.broadcast_to(xs, (6, 8)), atol=1e-12)
    np.testing.assert_allclose(ndc[..., 1], np.broadcast_to(ys[:, None], (6, 8)), atol=1e-12)
    up = cam.rotation[:, 1]
    assert (d[0] @ up).min() > (d[-1] @ up).max()  # top row looks up


def test_rays_are_computed_once_per_size_and_handed_out_as_copies():
    import pickle

    cam = make_camera(w=8, h=6)
    first = cam.ray_directions()
    first[...] = 0.0  # the caller's array is its own: the camera's stays intact
    again = cam.ray_directions()
    fresh = make_camera(w=8, h=6).ray_directions()
    assert np.array_equal(again, fresh) and again.flags.writeable
    assert np.array_equal(cam.ray_directions(4, 3), make_camera(w=8, h=6).ray_directions(4, 3))
    assert set(cam._rays) == {(8, 6), (4, 3)}
    shared = cam.ray_directions(copy=False)  # the camera's own array, for a reader: the same one on every call
    assert shared is cam.ray_directions(copy=False) and np.array_equal(shared, fresh)
    copy = pickle.loads(pickle.dumps(cam))  # the stored rays do not travel (Dask workers get small cameras)
    assert copy._rays == {} and np.array_equal(copy.ray_directions(), fresh)


def whole_frame_rays(cam, width, height):
    """The rays as one NumPy expression over the whole frame (what the camera computed before its blocks)."""
    nx, ny = cam.pixel_ndc(width, height)
    t = cam.tan_half_fov
    d = np.stack([nx * t * cam.aspect, ny * t, np.ones_like(nx)], axis=-1) @ cam.rotation.T
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def test_rays_in_blocks_on_threads_have_the_bits_of_the_whole_frame_expression():
    # matmul calls BLAS once per row and the rest is per pixel: any block split or thread count, the same bits
    rng = np.random.default_rng(7)
    heights = (1, 2, 17, MAX_BLOCK_ROWS, MAX_BLOCK_ROWS + 1, 2 * MAX_BLOCK_ROWS + 45)
    for k, h in enumerate(heights):
        rot = euler_matrix(rng.uniform(-180.0, 180.0, 3)) if k % 2 else look_rotation(rng.normal(size=3))
        w = int(rng.integers(1, 300))
        cam = Camera(rng.normal(size=3), rot, float(rng.uniform(5.0, 150.0)), w, h, 0.1, 100.0)
        for size in ((w, h), (max(1, w // 2), max(1, h // 3))):
            expected = whole_frame_rays(cam, *size).tobytes()
            for threads in (1, 2, 5, 16):
                assert pixel_rays(cam, *size, threads).tobytes() == expected, (w, h, size, threads)
            assert cam.ray_directions(*size).tobytes() == expected
    cam = make_camera(w=1920, h=1080, rot=(4.0, -30.0, 0.0))
    assert cam.ray_directions(copy=False).tobytes() == whole_frame_rays(cam, 1920, 1080).tobytes()


def test_eye_depth_to_distance_round_trip():
    cam = make_camera()
    d = cam.ray_directions()
    depth = np.full((6, 8), 4.0)
    t = cam.eye_depth_to_distance(depth, d)
    points = cam.position + d * t[..., None]
    np.testing.assert_allclose((cam.view_matrix() @ np.concatenate([points, np.ones((6, 8, 1))], -1)[..., None])
                               [..., 2, 0], 4.0, atol=1e-12)


@pytest.mark.parametrize("convention", ["d3d", "gl", "reversed"])
@given(nf=near_far, frac=st.floats(0.0, 1.0))
def test_depth_conversions_round_trip(convention, nf, frac):
    n, f = nf
    z = n + frac * (f - n)
    raw = linear_to_raw(z, n, f, convention)
    np.testing.assert_allclose(raw_to_linear(raw, n, f, convention), z, rtol=1e-9)


@pytest.mark.parametrize("convention, near_value, far_value", [("d3d", 0, 1), ("gl", -1, 1), ("reversed", 1, 0)])
def test_depth_conventions_at_the_planes(convention, near_value, far_value):
    assert linear_to_raw(0.3, 0.3, 50.0, convention) == pytest.approx(near_value, abs=1e-12)
    assert linear_to_raw(50.0, 0.3, 50.0, convention) == pytest.approx(far_value, abs=1e-12)


@pytest.mark.parametrize("convention", ["d3d", "gl", "reversed"])
def test_projection_matrix_produces_the_raw_depth(convention):
    cam = make_camera()
    points = cam.position + cam.ray_directions() * 9.0
    ndc = cam.world_to_ndc(points, convention)
    eye = (points - cam.position) @ cam.forward
    np.testing.assert_allclose(ndc[..., 2], linear_to_raw(eye, cam.near, cam.far, convention), atol=1e-12)


@given(nf=near_far, frac=st.floats(0.0, 1.0), reverse=st.booleans())
def test_unity_linear_eye_depth_formula(nf, frac, reverse):
    n, f = nf
    z = n + frac * (f - n)
    raw = linear_to_raw(z, n, f, "reversed" if reverse else "d3d")
    zp = zbuffer_params(n, f, reversed_z=reverse)
    np.testing.assert_allclose(unity_linear_eye_depth(raw, zp), z, rtol=1e-9)
    # Linear01 = 1 / (x z + y) = eye depth / far
    np.testing.assert_allclose(1.0 / (zp[0] * raw + zp[1]), z / f, rtol=1e-9)
