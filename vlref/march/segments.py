"""The part of a view ray inside a light's volume.

A view ray ``x(t) = o + t d`` (``d`` unit) is given with an interval ``[t0, t1]`` (``t1`` = scene
distance clipped at ``render.max_distance``). Each function returns ``(a, b)`` inside ``[t0, t1]``;
the segment is empty when ``b <= a`` (then ``(t0, t0)`` is returned).

* point light: the ball of radius ``range`` around the light. Roots ``-β ± sqrt(R² - h²)`` with
  ``β = d·(o - p)`` and ``h² = |(o - p) - β d|²`` (the closest-approach distance squared, computed
  directly rather than as ``|o - p|² - β²``, which cancels for distant origins).
* spot light: the cone of half-angle ``spot_angle/2`` around the spot direction ``a`` with its apex at
  the light, intersected with that ball. Both are convex (half-angle < 90°), so the ray meets their
  intersection in one interval. The cone quadratic ``(a·(x-p))² = cos²θ |x-p|²`` gives up to two
  break points inside the ball's interval; each sub-interval is then classified by the exact
  predicate ``a·(x-p) >= cosθ |x-p|`` at its midpoint. This rejects the backward nappe, and stays
  correct for grazing rays (double or lost roots), rays through the apex, rays parallel to the
  cone's surface (``A = 0``) and a camera inside the cone; root round-off only moves the boundary,
  where every cone law is 0 anyway.
* directional light: the whole ``[t0, t1]``.

:func:`light_segment` picks the one of these that a packed light's kind needs; :func:`volume_intervals`
maps the ball or the cone over an image of rays.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..jit import njit
from ..lights.pack import F_COS_OUTER, F_DX, F_DY, F_DZ, F_PX, F_PY, F_PZ, F_RANGE, I_KIND, KIND_DIRECTIONAL, KIND_POINT
from ..numeric import cast

__all__ = ["sphere_segment", "cone_segment", "inside_cone", "light_segment", "volume_intervals"]


@njit(cache=True, fastmath=False)
def sphere_segment(px, py, pz, radius, ox, oy, oz, dx, dy, dz, t0, t1):
    """``[t0, t1] ∩ {t : |o + t d - p| <= radius}`` (module docstring)."""
    vx, vy, vz = ox - px, oy - py, oz - pz
    beta = -(vx * dx + vy * dy + vz * dz)
    hx, hy, hz = vx + beta * dx, vy + beta * dy, vz + beta * dz
    disc = radius * radius - (hx * hx + hy * hy + hz * hz)
    if not disc > cast(ox, 0.0):
        return t0, t0
    s = math.sqrt(disc)
    a = max(t0, beta - s)
    b = min(t1, beta + s)
    if b <= a:
        return t0, t0
    return a, b


@njit(cache=True, fastmath=False)
def inside_cone(px, py, pz, ax, ay, az, cos_half, x, y, z):
    """``a·(x-p) >= cos_half |x-p|``: ``x`` lies in the forward nappe of the cone (apex included)."""
    wx, wy, wz = x - px, y - py, z - pz
    return wx * ax + wy * ay + wz * az >= cos_half * math.sqrt(wx * wx + wy * wy + wz * wz)


@njit(cache=True, fastmath=False)
def _root_in(r, lo, hi):
    return r > lo and r < hi


@njit(cache=True, fastmath=False)
def cone_segment(px, py, pz, ax, ay, az, cos_half, radius, ox, oy, oz, dx, dy, dz, t0, t1):
    """``[t0, t1]`` ∩ ball(p, radius) ∩ forward cone(p, a, acos(cos_half)) (module docstring)."""
    lo, hi = sphere_segment(px, py, pz, radius, ox, oy, oz, dx, dy, dz, t0, t1)
    if hi <= lo:
        return t0, t0
    zero = cast(ox, 0.0)
    half = cast(ox, 0.5)
    vx, vy, vz = ox - px, oy - py, oz - pz
    da = dx * ax + dy * ay + dz * az
    va = vx * ax + vy * ay + vz * az
    dv = dx * vx + dy * vy + dz * vz
    vv = vx * vx + vy * vy + vz * vz
    c2 = cos_half * cos_half
    qa = da * da - c2
    qb = cast(ox, 2.0) * (da * va - c2 * dv)
    qc = va * va - c2 * vv
    # break points: lo, roots strictly inside (lo, hi) in increasing order, hi
    r1, r2 = hi, hi
    disc = qb * qb - cast(ox, 4.0) * qa * qc
    if disc >= zero:
        q = -half * (qb + math.copysign(math.sqrt(disc), qb))
        n_roots = 0
        if qa != zero:
            x = q / qa
            if _root_in(x, lo, hi):
                r1 = x
                n_roots = 1
        if q != zero:
            x = qc / q
            if _root_in(x, lo, hi):
                if n_roots == 0:
                    r1 = x
                else:
                    r2 = max(r1, x)
                    r1 = min(r1, x)
    first, last = hi, lo
    s = lo
    for k in range(3):
        e = r1 if k == 0 else (r2 if k == 1 else hi)
        if e > s:
            m = half * (s + e)
            if inside_cone(px, py, pz, ax, ay, az, cos_half, ox + m * dx, oy + m * dy, oz + m * dz):
                first = min(first, s)
                last = e
            s = e
    if last <= first:
        return t0, t0
    return first, last


@njit(cache=True, fastmath=False)
def light_segment(lights, k, ox, oy, oz, dx, dy, dz, t_end):
    """``(a, b)`` of light ``k`` of ``lights`` (:class:`~vlref.lights.pack.PackedLights`) on ``[0, t_end]``
    (empty when ``b <= a``): :mod:`vlref.march.segments` by the light's kind."""
    lf = lights.floats
    zero = cast(ox, 0.0)
    kind = lights.ints[k, I_KIND]
    if kind == KIND_DIRECTIONAL:
        return zero, t_end
    if kind == KIND_POINT:
        return sphere_segment(lf[k, F_PX], lf[k, F_PY], lf[k, F_PZ], lf[k, F_RANGE], ox, oy, oz, dx, dy, dz,
                              zero, t_end)
    return cone_segment(lf[k, F_PX], lf[k, F_PY], lf[k, F_PZ], lf[k, F_DX], lf[k, F_DY], lf[k, F_DZ],
                        lf[k, F_COS_OUTER], lf[k, F_RANGE], ox, oy, oz, dx, dy, dz, zero, t_end)


@njit(cache=True, fastmath=False, parallel=True)
def volume_intervals(cam, dirs, centre, axis, cos_half, radius, cone, t0, t1):
    """``(enter, leave)`` (h, w) of the rays ``cam + t dirs[r, c]`` on ``[t0, t1]`` through the ball
    (``cone`` false: :func:`sphere_segment`) or the ball ∩ forward cone (:func:`cone_segment`) of apex
    ``centre`` (3,), unit ``axis`` (3,) and ``cos_half``; ``(inf, -inf)`` where the ray misses it.
    prange over pixels."""
    h, w = dirs.shape[0], dirs.shape[1]
    enter, leave = np.full((h, w), np.inf), np.full((h, w), -np.inf)
    for p in prange(h * w):
        r, c = p // w, p % w
        dx, dy, dz = dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2]
        if cone:
            a, b = cone_segment(centre[0], centre[1], centre[2], axis[0], axis[1], axis[2], cos_half, radius,
                                cam[0], cam[1], cam[2], dx, dy, dz, t0, t1)
        else:
            a, b = sphere_segment(centre[0], centre[1], centre[2], radius, cam[0], cam[1], cam[2], dx, dy, dz, t0, t1)
        if b > a:
            enter[r, c], leave[r, c] = a, b
    return enter, leave
