"""Ray intersection of the analytic primitives and of one triangle (float64, Numba).

A ray is ``p(t) = o + t d`` (``d`` need not be unit; ``t`` is in units of ``|d|``). Every
``hit_*`` function returns the smallest ``t`` with ``tmin < t < tmax`` (open interval) at which
the ray crosses the surface, or ``inf`` when there is none, together with the surface's
*outward* unit normal there (``(0, 0, 0)`` on a miss). Facing the normal toward the ray origin
is the caller's job (:func:`vlref.geometry.scene_geometry.closest_hit`).

The analytic primitives are stored as one float64 row of ``ROW`` numbers (see :func:`pack_plane`,
:func:`pack_sphere`, :func:`pack_box`, :func:`pack_cylinder`)::

    row[0:3]    centre (plane: a point on it)
    row[3:12]   rotation R, row-major, world-from-local: x_world = R @ x_local + centre
    row[12:15]  plane: unit normal; sphere: radius, -, -; box: half sizes;
                cylinder: radius, half height, -

Rotations are Unity Euler angles (degrees, z then x then y; :func:`vlref.camera.euler_matrix`).

Robustness
----------
* Sphere and cylinder side: the quadratic ``a t² + 2 b t + c = 0`` is solved with the
  discriminant written as ``a (r² - |oc - (b/a) d|²)`` and the roots as ``c / q`` and ``q / a``
  with ``q = -(b + sign(b) sqrt(disc))`` (Haines et al., "Precision Improvements for Ray/Sphere
  Intersection", Ray Tracing Gems ch. 7, 2019), which avoids the cancellation of the textbook form.
* Box and capped cylinder are convex: the ray's parameter interval inside each slab (and inside
  the infinite cylinder) is intersected; the entry is returned when it lies in ``(tmin, tmax)``,
  else the exit -- so a ray starting inside hits the far side. Axes with a zero direction
  component are tested by the origin's coordinate (no ``0 * inf`` NaN).
* A ray lying exactly in a face plane or tangent to a surface yields at most a tangent hit,
  never NaN.

Triangles use Möller & Trumbore, "Fast, minimum storage ray/triangle intersection" (JGT 1997),
with inclusive edge tests (``u >= 0, v >= 0, u + v <= 1``): a ray through a shared edge reports
both triangles (callers dedupe where counting matters). It is not watertight in the strict sense
of Woop et al. (JCGT 2013): the two triangles of an edge evaluate their barycentrics with
different rounding, so a ray within ~1e-16 (relative) of an edge can slip through. Triangles whose
edges are parallel (zero area) and rays parallel to the triangle plane (``det == 0``) never hit.
"""

from __future__ import annotations

import math

import numpy as np

from ..camera import euler_matrix
from ..jit import njit

__all__ = ["PLANE", "SPHERE", "BOX", "CYLINDER", "ROW", "pack_plane", "pack_sphere", "pack_box",
           "pack_cylinder", "hit_plane", "hit_sphere", "hit_box", "hit_cylinder", "hit_primitive",
           "hit_triangle", "triangle_normal"]

PLANE, SPHERE, BOX, CYLINDER = 0, 1, 2, 3
ROW = 16
INF = np.inf


def _row(center, rotation_degrees, params) -> np.ndarray:
    row = np.zeros(ROW)
    row[0:3] = np.asarray(center, dtype=np.float64)
    row[3:12] = euler_matrix(rotation_degrees).ravel()
    row[12:12 + len(params)] = params
    return row


def pack_plane(point, normal) -> np.ndarray:
    """Row of the infinite plane through ``point`` with normal ``normal`` (normalised here)."""
    n = np.asarray(normal, dtype=np.float64)
    return _row(point, (0.0, 0.0, 0.0), n / np.linalg.norm(n))


def pack_sphere(center, radius: float) -> np.ndarray:
    """Row of the sphere ``|x - center| = radius``."""
    return _row(center, (0.0, 0.0, 0.0), [float(radius)])


def pack_box(center, size, rotation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Row of the oriented box with edge lengths ``size`` along its local axes, rotated by ``rotation``."""
    return _row(center, rotation, 0.5 * np.asarray(size, dtype=np.float64))


def pack_cylinder(center, radius: float, height: float, rotation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Row of the capped cylinder of ``radius``, axis = local y of length ``height`` centred on ``center``."""
    return _row(center, rotation, [float(radius), 0.5 * float(height)])


@njit(cache=True, fastmath=False)
def _to_local(row, ox, oy, oz, dx, dy, dz):
    """Origin and direction in the primitive's frame: ``R^T (o - c)`` and ``R^T d``."""
    px, py, pz = ox - row[0], oy - row[1], oz - row[2]
    lo = (row[3] * px + row[6] * py + row[9] * pz,
          row[4] * px + row[7] * py + row[10] * pz,
          row[5] * px + row[8] * py + row[11] * pz)
    ld = (row[3] * dx + row[6] * dy + row[9] * dz,
          row[4] * dx + row[7] * dy + row[10] * dz,
          row[5] * dx + row[8] * dy + row[11] * dz)
    return lo, ld


@njit(cache=True, fastmath=False)
def _to_world(row, nx, ny, nz):
    """Local normal to world: ``R @ n`` (R orthonormal, so normals need no inverse transpose)."""
    return (row[3] * nx + row[4] * ny + row[5] * nz,
            row[6] * nx + row[7] * ny + row[8] * nz,
            row[9] * nx + row[10] * ny + row[11] * nz)


@njit(cache=True, fastmath=False)
def _quadratic_interval(a, b, c, lx, ly, lz, r):
    """Roots ``t0 <= t1`` of ``a t² + 2 b t + c = 0`` with ``disc = a (r² - |l|²)``; ``(inf, -inf)`` if none."""
    disc = a * (r * r - (lx * lx + ly * ly + lz * lz))
    if disc < 0.0:
        return INF, -INF
    q = -(b + math.copysign(math.sqrt(disc), b))
    if q == 0.0:
        t = -b / a
        return t, t
    t0 = c / q
    t1 = q / a
    if t0 > t1:
        t0, t1 = t1, t0
    return t0, t1


@njit(cache=True, fastmath=False)
def hit_plane(row, ox, oy, oz, dx, dy, dz, tmin, tmax):
    """Infinite plane ``dot(x - p, n) = 0``: ``t = dot(p - o, n) / dot(d, n)``; normal ``n``."""
    nx, ny, nz = row[12], row[13], row[14]
    denom = dx * nx + dy * ny + dz * nz
    if denom == 0.0:
        return INF, 0.0, 0.0, 0.0
    t = ((row[0] - ox) * nx + (row[1] - oy) * ny + (row[2] - oz) * nz) / denom
    if tmin < t < tmax:
        return t, nx, ny, nz
    return INF, 0.0, 0.0, 0.0


@njit(cache=True, fastmath=False)
def hit_sphere(row, ox, oy, oz, dx, dy, dz, tmin, tmax):
    """Sphere ``|o + t d - c| = r``; normal ``(o + t d - c) / r`` (module docstring: robust roots)."""
    r = row[12]
    cx, cy, cz = ox - row[0], oy - row[1], oz - row[2]
    a = dx * dx + dy * dy + dz * dz
    if a == 0.0:
        return INF, 0.0, 0.0, 0.0
    b = cx * dx + cy * dy + cz * dz
    s = b / a
    t0, t1 = _quadratic_interval(a, b, cx * cx + cy * cy + cz * cz - r * r,
                                 cx - s * dx, cy - s * dy, cz - s * dz, r)
    t = t0 if t0 > tmin else t1
    if not (tmin < t < tmax):
        return INF, 0.0, 0.0, 0.0
    nx, ny, nz = cx + t * dx, cy + t * dy, cz + t * dz
    inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    return t, nx * inv, ny * inv, nz * inv


@njit(cache=True, fastmath=False)
def _pick(t_in, t_out, tmin, tmax):
    """0 = the entry ``t_in`` is the hit, 1 = the exit ``t_out``, -1 = neither lies in ``(tmin, tmax)``."""
    if t_in > t_out:
        return -1
    if tmin < t_in < tmax:
        return 0
    if tmin < t_out < tmax:
        return 1
    return -1


@njit(cache=True, fastmath=False)
def hit_box(row, ox, oy, oz, dx, dy, dz, tmin, tmax):
    """Oriented box ``|x_local,i| <= h_i``: slab intervals intersected (Kay & Kajiya 1986)."""
    lo, ld = _to_local(row, ox, oy, oz, dx, dy, dz)
    t_in, t_out = -INF, INF
    ax_in, ax_out = -1, -1
    for i in range(3):
        h = row[12 + i]
        if ld[i] == 0.0:
            if abs(lo[i]) > h:
                return INF, 0.0, 0.0, 0.0
            continue
        t0 = (-h - lo[i]) / ld[i]
        t1 = (h - lo[i]) / ld[i]
        if t0 > t1:
            t0, t1 = t1, t0
        if t0 > t_in:
            t_in, ax_in = t0, i
        if t1 < t_out:
            t_out, ax_out = t1, i
    which = _pick(t_in, t_out, tmin, tmax)
    if which < 0:
        return INF, 0.0, 0.0, 0.0
    ax = ax_in if which == 0 else ax_out
    t = t_in if which == 0 else t_out
    # entering through a face means moving against its outward normal, leaving means along it
    sign = -math.copysign(1.0, ld[ax]) if which == 0 else math.copysign(1.0, ld[ax])
    nx, ny, nz = _to_world(row, sign * (ax == 0), sign * (ax == 1), sign * (ax == 2))
    return t, nx, ny, nz


@njit(cache=True, fastmath=False)
def hit_cylinder(row, ox, oy, oz, dx, dy, dz, tmin, tmax):
    """Capped cylinder ``x² + z² <= r², |y| <= h`` (local): side quadratic interval ∩ cap slab.

    Side normal ``(x, 0, z) / r`` at the local hit point; cap normals ``(0, ±1, 0)``.
    """
    lo, ld = _to_local(row, ox, oy, oz, dx, dy, dz)
    r, h = row[12], row[13]
    a = ld[0] * ld[0] + ld[2] * ld[2]
    if a == 0.0:
        if lo[0] * lo[0] + lo[2] * lo[2] > r * r:
            return INF, 0.0, 0.0, 0.0
        s0, s1 = -INF, INF
    else:
        b = lo[0] * ld[0] + lo[2] * ld[2]
        s = b / a
        s0, s1 = _quadratic_interval(a, b, lo[0] * lo[0] + lo[2] * lo[2] - r * r,
                                     lo[0] - s * ld[0], 0.0, lo[2] - s * ld[2], r)
    if ld[1] == 0.0:
        if abs(lo[1]) > h:
            return INF, 0.0, 0.0, 0.0
        y0, y1 = -INF, INF
    else:
        y0 = (-h - lo[1]) / ld[1]
        y1 = (h - lo[1]) / ld[1]
        if y0 > y1:
            y0, y1 = y1, y0
    cap_in = y0 > s0
    cap_out = y1 < s1
    t_in = y0 if cap_in else s0
    t_out = y1 if cap_out else s1
    which = _pick(t_in, t_out, tmin, tmax)
    if which < 0:
        return INF, 0.0, 0.0, 0.0
    t = t_in if which == 0 else t_out
    if (cap_in if which == 0 else cap_out):
        sy = -math.copysign(1.0, ld[1]) if which == 0 else math.copysign(1.0, ld[1])
        nx, ny, nz = _to_world(row, 0.0, sy, 0.0)
    else:
        px, pz = lo[0] + t * ld[0], lo[2] + t * ld[2]
        inv = 1.0 / math.sqrt(px * px + pz * pz)
        nx, ny, nz = _to_world(row, px * inv, 0.0, pz * inv)
    return t, nx, ny, nz


@njit(cache=True, fastmath=False)
def hit_primitive(kind, row, ox, oy, oz, dx, dy, dz, tmin, tmax):
    """Dispatch on ``kind`` (``PLANE``, ``SPHERE``, ``BOX``, ``CYLINDER``)."""
    if kind == PLANE:
        return hit_plane(row, ox, oy, oz, dx, dy, dz, tmin, tmax)
    if kind == SPHERE:
        return hit_sphere(row, ox, oy, oz, dx, dy, dz, tmin, tmax)
    if kind == BOX:
        return hit_box(row, ox, oy, oz, dx, dy, dz, tmin, tmax)
    return hit_cylinder(row, ox, oy, oz, dx, dy, dz, tmin, tmax)


@njit(cache=True, fastmath=False)
def hit_triangle(v0, e1, e2, i, ox, oy, oz, dx, dy, dz, tmin, tmax):
    """Möller-Trumbore: triangle ``i`` of ``(v0, e1 = v1 - v0, e2 = v2 - v0)`` (each (T, 3)); ``t`` or inf.

    Solves ``o + t d = v0 + u e1 + v e2`` by Cramer's rule with ``p = d x e2``, ``det = e1 . p``,
    ``u = (o - v0) . p / det``, ``q = (o - v0) x e1``, ``v = d . q / det``, ``t = e2 . q / det``.
    The normal is :func:`triangle_normal` (computed only for the closest hit).
    """
    e1x, e1y, e1z = e1[i, 0], e1[i, 1], e1[i, 2]
    e2x, e2y, e2z = e2[i, 0], e2[i, 1], e2[i, 2]
    px = dy * e2z - dz * e2y
    py = dz * e2x - dx * e2z
    pz = dx * e2y - dy * e2x
    det = e1x * px + e1y * py + e1z * pz
    if det == 0.0:
        return INF
    inv = 1.0 / det
    sx, sy, sz = ox - v0[i, 0], oy - v0[i, 1], oz - v0[i, 2]
    u = (sx * px + sy * py + sz * pz) * inv
    if u < 0.0 or u > 1.0:
        return INF
    qx = sy * e1z - sz * e1y
    qy = sz * e1x - sx * e1z
    qz = sx * e1y - sy * e1x
    v = (dx * qx + dy * qy + dz * qz) * inv
    if v < 0.0 or u + v > 1.0:
        return INF
    t = (e2x * qx + e2y * qy + e2z * qz) * inv
    if tmin < t < tmax:
        return t
    return INF


@njit(cache=True, fastmath=False)
def triangle_normal(e1, e2, i):
    """Unit geometric normal ``normalize(e1 x e2)`` of triangle ``i`` (the winding fixes its side)."""
    nx = e1[i, 1] * e2[i, 2] - e1[i, 2] * e2[i, 1]
    ny = e1[i, 2] * e2[i, 0] - e1[i, 0] * e2[i, 2]
    nz = e1[i, 0] * e2[i, 1] - e1[i, 1] * e2[i, 0]
    inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    return nx * inv, ny * inv, nz * inv
