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
"""

from __future__ import annotations

import math

from numba import njit

from ..numeric import cast

__all__ = ["sphere_segment", "cone_segment", "inside_cone"]


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
