"""Light-volume segments against brute-force membership along the ray."""

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from vlref.march.segments import cone_segment, inside_cone, sphere_segment

coord = st.floats(-6.0, 6.0, allow_nan=False)
unit = st.tuples(coord, coord, coord).filter(lambda v: sum(x * x for x in v) > 1e-2).map(
    lambda v: tuple(np.asarray(v) / np.linalg.norm(v)))


def _brute(inside, ox, oy, oz, dx, dy, dz, t1, n=20001):
    t = np.linspace(0.0, t1, n)
    mask = np.array([inside(ox + s * dx, oy + s * dy, oz + s * dz) for s in t])
    return t, mask


@settings(max_examples=30)
@given(o=st.tuples(coord, coord, coord), d=unit, r=st.floats(0.2, 5.0))
def test_sphere_segment_matches_brute_force(o, d, r):
    a, b = sphere_segment(0.5, -0.2, 0.1, r, *o, *d, 0.0, 15.0)
    t, mask = _brute(lambda x, y, z: (x - 0.5) ** 2 + (y + 0.2) ** 2 + (z - 0.1) ** 2 <= r * r, *o, *d, 15.0)
    step = t[1]
    if b <= a:
        assert mask.sum() <= 1
    else:
        assert abs(t[mask].min() - a) <= 1.01 * step and abs(t[mask].max() - b) <= 1.01 * step


@settings(max_examples=40)
@given(o=st.tuples(coord, coord, coord), d=unit, axis=unit, half=st.floats(2.0, 85.0))
def test_cone_segment_matches_brute_force(o, d, axis, half):
    c = math.cos(math.radians(half))
    radius = 7.0
    a, b = cone_segment(0.0, 0.0, 0.0, *axis, c, radius, *o, *d, 0.0, 15.0)

    def inside(x, y, z):
        return x * x + y * y + z * z <= radius * radius and inside_cone(0.0, 0.0, 0.0, *axis, c, x, y, z)

    t, mask = _brute(inside, *o, *d, 15.0)
    step = t[1]
    if b <= a:
        assert mask.sum() <= 2
    else:
        assert np.all(mask[(t > a + 2 * step) & (t < b - 2 * step)])  # one interval, entirely inside
        assert not np.any(mask[(t < a - 2 * step) | (t > b + 2 * step)])


def test_cone_special_rays():
    c = math.cos(math.radians(30.0))
    # through the apex along the axis, from behind: enters at the apex
    a, b = cone_segment(0, 0, 0, 0, 0, 1, c, 10.0, 0.0, 0.0, -5.0, 0.0, 0.0, 1.0, 0.0, 100.0)
    assert abs(a - 5.0) < 1e-6 and b == 15.0
    # camera inside the cone: starts at 0
    assert cone_segment(0, 0, 0, 0, 0, 1, c, 10.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 100.0) == (0.0, 9.0)
    # the backward nappe is rejected
    a, b = cone_segment(0, 0, 0, 0, 0, 1, c, 10.0, -5.0, 0.0, -3.0, 1.0, 0.0, 0.0, 0.0, 100.0)
    assert b <= a
    # a ray parallel to the cone's surface (quadratic's A = 0) inside the cone
    s, k = math.sin(math.radians(30.0)), math.cos(math.radians(30.0))
    a, b = cone_segment(0, 0, 0, 0, 0, 1, c, 10.0, -0.1, 0.0, 1.0, s, 0.0, k, 0.0, 100.0)
    assert a == 0.0 and b > 5.0
    # along a generator of the surface, just outside (empty) and just inside (from the apex on)
    a, b = cone_segment(0, 0, 0, 0, 0, 1, c, 10.0, 1e-9, 0.0, 0.0, s, 0.0, k, 0.0, 100.0)
    assert b - a < 1e-6
    a, b = cone_segment(0, 0, 0, 0, 0, 1, c, 10.0, -1e-9, 0.0, 0.0, s, 0.0, k, 0.0, 100.0)
    assert a < 1e-6 and abs(b - 10.0) < 1e-6
    # clipped by t_end (scene depth)
    assert cone_segment(0, 0, 0, 0, 0, 1, c, 10.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 3.0) == (0.0, 3.0)
