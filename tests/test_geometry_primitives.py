"""Ray-primitive intersections against independent NumPy references (candidate enumeration).

Each reference enumerates the candidate crossings (face planes, quadratic roots, caps) in the
textbook way and keeps the smallest ``t`` in ``(tmin, tmax)`` whose point lies on the surface;
the kernels use interval (slab) logic and the robust quadratic instead. Rays whose hit/miss
status changes when the shape grows or shrinks by 1e-7 (grazing an edge or a silhouette) are
ambiguous at rounding level: there only the invariants (point on surface, unit outward normal)
are checked.
"""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vlref.camera import euler_matrix
from vlref.geometry.primitives import (hit_box, hit_cylinder, hit_plane, hit_sphere, hit_triangle, pack_box,
                                       pack_cylinder, pack_plane, pack_sphere, triangle_normal)

GROW = 1e-7
coord = st.floats(-4.0, 4.0)
vec = st.tuples(coord, coord, coord)
near = st.floats(-1.5, 1.5)
offset = st.tuples(near, near, near)  # aim point relative to the shape's centre
positive = st.floats(0.2, 3.0)
angle = st.floats(-180.0, 180.0)
rot = st.tuples(angle, angle, angle)
tmins = st.sampled_from([0.0, 0.0, 0.5])
# direction = aim - origin + jitter: many rays hit, some miss, some have exact zero components
jitter = st.tuples(st.sampled_from([0.0, 0.0, 0.3]), st.sampled_from([0.0, -0.2]), st.sampled_from([0.0, 0.1]))


def ray_from(origin, aim, jit):
    """Ray from ``origin`` toward ``aim`` (+ jitter); a zero direction is replaced by the caller."""
    d = np.asarray(aim, float) - np.asarray(origin, float) + np.asarray(jit, float)
    return np.asarray(origin, float), d


def first(cands, tmin, tmax):
    """Smallest candidate (t, normal) with tmin < t < tmax, or (inf, None)."""
    best = (math.inf, None)
    for t, n in cands:
        if tmin < t < tmax and t < best[0]:
            best = (t, n)
    return best


def sphere_ref(c, r, o, d, tmin, tmax, grow=0.0):
    r = r * (1 + grow)
    a = d @ d
    oc = o - c
    b = oc @ d / a
    disc = b * b - (oc @ oc - r * r) / a
    if disc < 0:
        return math.inf, None
    roots = (-b - math.sqrt(disc), -b + math.sqrt(disc))
    return first([(t, (o + t * d - c) / r) for t in roots], tmin, tmax)


@np.errstate(all="ignore")
def box_ref(c, size, rotation, o, d, tmin, tmax, grow=0.0):
    rm = euler_matrix(rotation)
    h = 0.5 * np.asarray(size) * (1 + grow)
    lo, ld = rm.T @ (o - c), rm.T @ d
    cands = []
    for a in range(3):
        if ld[a] == 0:
            continue
        for s in (-1.0, 1.0):
            t = (s * h[a] - lo[a]) / ld[a]
            p = lo + t * ld
            others = [k for k in range(3) if k != a]
            if all(abs(p[k]) <= h[k] for k in others):
                n = np.zeros(3)
                n[a] = s
                cands.append((t, rm @ n))
    return first(cands, tmin, tmax)


@np.errstate(all="ignore")
def cylinder_ref(c, r, height, rotation, o, d, tmin, tmax, grow=0.0):
    rm = euler_matrix(rotation)
    r, hh = r * (1 + grow), 0.5 * height * (1 + grow)
    lo, ld = rm.T @ (o - c), rm.T @ d
    cands = []
    a = ld[0] ** 2 + ld[2] ** 2
    if a > 0:
        b = (lo[0] * ld[0] + lo[2] * ld[2]) / a
        disc = b * b - (lo[0] ** 2 + lo[2] ** 2 - r * r) / a
        if disc >= 0:
            for t in (-b - math.sqrt(disc), -b + math.sqrt(disc)):
                p = lo + t * ld
                if abs(p[1]) <= hh:
                    cands.append((t, rm @ np.array([p[0], 0.0, p[2]]) / r))
    if ld[1] != 0:
        for s in (-1.0, 1.0):
            t = (s * hh - lo[1]) / ld[1]
            p = lo + t * ld
            if p[0] ** 2 + p[2] ** 2 <= r * r:
                cands.append((t, rm @ np.array([0.0, s, 0.0])))
    return first(cands, tmin, tmax)


def plane_ref(p, n, o, d, tmin, tmax, grow=0.0):
    n = np.asarray(n, float) / np.linalg.norm(n)
    p = np.asarray(p, float) + grow * n
    den = d @ n
    if den == 0:
        return math.inf, None
    return first([((p - o) @ n / den, n)], tmin, tmax)


def triangle_ref(v, o, d, tmin, tmax, grow=0.0):
    cen = v.mean(axis=0)
    v = cen + (v - cen) * (1 + grow)
    e1, e2 = v[1] - v[0], v[2] - v[0]
    m = np.stack([e1, e2, -d], axis=1)
    if abs(np.linalg.det(m)) < 1e-300:
        return math.inf, None
    u, w, t = np.linalg.solve(m, o - v[0])
    if u < 0 or w < 0 or u + w > 1:
        return math.inf, None
    n = np.cross(e1, e2)
    return first([(t, n / np.linalg.norm(n))], tmin, tmax)


def check(kernel, ref, o, d, tmin, tmax, on_surface):
    """Compare a kernel result (t, nx, ny, nz) with the reference; see the module docstring."""
    t, *n = kernel
    n = np.array(n)
    assert not math.isnan(t) and not np.any(np.isnan(n))
    if t != math.inf:
        assert tmin < t < tmax
        assert abs(np.linalg.norm(n) - 1.0) < 1e-12
        assert on_surface(o + t * d) < 1e-9
    else:
        assert np.all(n == 0.0)
    lo_t, _ = ref(-GROW)
    hi_t, _ = ref(GROW)
    t_ref, n_ref = ref(0.0)
    robust = (np.isinf(lo_t) == np.isinf(hi_t) == np.isinf(t_ref)
              and (np.isinf(t_ref) or min(t_ref - tmin, tmax - t_ref) > 1e-6 * (1 + abs(t_ref))))
    if not robust:
        return False
    if np.isinf(t_ref):
        assert t == math.inf
    else:
        assert t == pytest.approx(t_ref, rel=1e-9, abs=1e-9)
        assert np.allclose(n, n_ref, atol=1e-7)
    return True


@given(c=vec, r=positive, o=vec, aim=offset, jit=jitter, tmin=tmins)
def test_sphere_matches_closed_form(c, r, o, aim, jit, tmin):
    c = np.array(c)
    o, d = ray_from(o, c + aim, jit)
    if not d.any():
        d = np.array([0.0, 0.0, 1.0])
    k = hit_sphere(pack_sphere(c, r), *o, *d, tmin, math.inf)
    check(k, lambda g: sphere_ref(c, r, o, d, tmin, math.inf, g), o, d, tmin, math.inf,
          lambda p: abs(np.linalg.norm(p - c) - r))


@given(c=vec, size=st.tuples(positive, positive, positive), rotation=rot, o=vec, aim=offset, jit=jitter,
       tmin=tmins)
def test_box_matches_face_enumeration(c, size, rotation, o, aim, jit, tmin):
    c = np.array(c)
    o, d = ray_from(o, c + aim, jit)
    if not d.any():
        d = np.array([1.0, 0.0, 0.0])
    rm = euler_matrix(rotation)
    h = 0.5 * np.array(size)
    k = hit_box(pack_box(c, size, rotation), *o, *d, tmin, math.inf)
    check(k, lambda g: box_ref(c, size, rotation, o, d, tmin, math.inf, g), o, d, tmin, math.inf,
          lambda p: abs(np.max(np.abs(rm.T @ (p - c)) / h) - 1.0))


@given(c=vec, r=positive, height=positive, rotation=rot, o=vec, aim=offset, jit=jitter, tmin=tmins)
def test_cylinder_matches_side_and_cap_enumeration(c, r, height, rotation, o, aim, jit, tmin):
    c = np.array(c)
    o, d = ray_from(o, c + aim, jit)
    if not d.any():
        d = np.array([0.0, 1.0, 0.0])
    rm = euler_matrix(rotation)

    def dist(p):
        q = rm.T @ (p - c)
        return abs(max(math.hypot(q[0], q[2]) / r, abs(q[1]) / (0.5 * height)) - 1.0)

    k = hit_cylinder(pack_cylinder(c, r, height, rotation), *o, *d, tmin, math.inf)
    check(k, lambda g: cylinder_ref(c, r, height, rotation, o, d, tmin, math.inf, g), o, d, tmin, math.inf, dist)


@given(p=vec, n=vec, o=vec, aim=vec, jit=jitter, tmin=tmins, tmax=st.sampled_from([math.inf, 3.0]))
def test_plane_matches_closed_form(p, n, o, aim, jit, tmin, tmax):
    n = np.array(n)
    if not np.linalg.norm(n) > 1e-3:
        n = np.array([0.0, 1.0, 0.0])
    o, d = ray_from(o, aim, jit)
    if not d.any():
        d = np.array([0.0, -1.0, 0.0])
    nu = n / np.linalg.norm(n)
    k = hit_plane(pack_plane(p, n), *o, *d, tmin, tmax)
    check(k, lambda g: plane_ref(p, n, o, d, tmin, tmax, g), o, d, tmin, tmax, lambda q: abs((q - p) @ nu))


@given(a=vec, b=vec, c=vec, o=vec, bary=st.tuples(st.floats(-0.1, 0.8), st.floats(-0.1, 0.8)), jit=jitter,
       tmin=tmins)
def test_triangle_matches_linear_solve(a, b, c, o, bary, jit, tmin):
    v = np.array([a, b, c])
    e1, e2 = v[1] - v[0], v[2] - v[0]
    area = np.linalg.norm(np.cross(e1, e2))
    if area < 1e-3:
        v = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 2.0]])
        e1, e2 = v[1] - v[0], v[2] - v[0]
    aim = v[0] + bary[0] * e1 + bary[1] * e2
    o, d = ray_from(o, aim, jit)
    if not d.any():
        d = np.array([0.0, 0.0, 1.0])
    t = hit_triangle(v[0:1], e1[None], e2[None], 0, *o, *d, tmin, math.inf)
    n = triangle_normal(e1[None], e2[None], 0) if t != math.inf else (0.0, 0.0, 0.0)
    nu = np.cross(e1, e2) / np.linalg.norm(np.cross(e1, e2))

    def dist(p):
        w = np.linalg.lstsq(np.stack([e1, e2], 1), p - v[0], rcond=None)[0]
        assert w.min() > -1e-9 and w.sum() < 1 + 1e-9
        return abs((p - v[0]) @ nu)

    check((t, *n), lambda g: triangle_ref(v, o, d, tmin, math.inf, g), o, d, tmin, math.inf, dist)


def test_origin_inside_hits_the_far_side():
    o, d = np.array([0.1, -0.2, 0.3]), np.array([0.0, 0.0, 1.0])
    t, *n = hit_sphere(pack_sphere((0, 0, 0), 2.0), *o, *d, 0.0, math.inf)
    assert t == pytest.approx(math.sqrt(4 - 0.05) - 0.3) and n[2] > 0.9
    t, *n = hit_box(pack_box((0, 0, 0), (2, 2, 2), (0, 30, 0)), *o, *d, 0.0, math.inf)
    assert t == pytest.approx((1 - 0.1 * math.sin(math.radians(30))) / math.cos(math.radians(30)) - 0.3)
    assert n == pytest.approx([math.sin(math.radians(30)), 0.0, math.cos(math.radians(30))])
    t, *n = hit_cylinder(pack_cylinder((0, 0, 0), 1.0, 4.0), *o, *d, 0.0, math.inf)
    assert t == pytest.approx(math.sqrt(1 - 0.01) - 0.3)
    t, *n = hit_cylinder(pack_cylinder((0, 0, 0), 1.0, 4.0), *o, 0.0, 1.0, 0.0, 0.0, math.inf)
    assert t == pytest.approx(2.2) and n == pytest.approx([0, 1, 0])


@pytest.mark.parametrize("fn,row", [
    (hit_sphere, pack_sphere((0, 0, 0), 1.0)),
    (hit_box, pack_box((0, 0, 0), (2, 2, 2))),
    (hit_cylinder, pack_cylinder((0, 0, 0), 1.0, 2.0)),
])
@pytest.mark.parametrize("o,d", [
    ((-5.0, 1.0, 0.0), (1.0, 0.0, 0.0)),      # tangent to the sphere, in the box's top face plane
    ((-5.0, 1.0, 1.0), (1.0, 0.0, 0.0)),      # along a box edge / the cylinder's cap rim line
    ((1.0, -5.0, 0.0), (0.0, 1.0, 0.0)),      # along the cylinder's side line
    ((-5.0, 1.0 + 1e-12, 0.0), (1.0, 0.0, 0.0)),
    ((-5.0, -5.0, -5.0), (1.0, 1.0, 1.0)),    # through corners / the centre
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),       # zero direction
])
def test_grazing_rays_give_no_nan(fn, row, o, d):
    t, *n = fn(row, *o, *d, 0.0, math.inf)
    assert not math.isnan(t) and not any(math.isnan(x) for x in n)
    if t == math.inf:
        assert n == [0.0, 0.0, 0.0]
    else:
        assert t > 0.0 and abs(math.sqrt(sum(x * x for x in n)) - 1.0) < 1e-12


def test_parallel_and_in_plane_rays_miss():
    row = pack_plane((0, 0, 0), (0, 2, 0))
    assert hit_plane(row, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, math.inf)[0] == math.inf
    assert hit_plane(row, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, math.inf)[0] == math.inf
    v0 = np.zeros((1, 3))
    e1, e2 = np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]])
    assert hit_triangle(v0, e1, e2, 0, -1.0, 0.2, 0.0, 1.0, 0.0, 0.0, 0.0, math.inf) == math.inf
    # degenerate (zero-area) triangle never hits
    assert hit_triangle(v0, e1, 2 * e1, 0, 0.5, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, math.inf) == math.inf


def test_interval_bounds_are_open():
    row = pack_sphere((0, 0, 5), 1.0)
    assert hit_sphere(row, 0, 0, 0, 0, 0, 1, 0.0, 4.0)[0] == math.inf
    assert hit_sphere(row, 0, 0, 0, 0, 0, 1, 4.0, math.inf)[0] == 6.0
    assert hit_sphere(row, 0, 0, 0, 0, 0, 1, 6.0, math.inf)[0] == math.inf
