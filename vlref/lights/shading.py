"""What a light delivers at a point (unshadowed), and the scene colour of the G-buffer.

:func:`light_incidence` evaluates ``E_l(x)`` of docs/PHYSICS.md "The integral" without visibility or medium:

* point: ``colour·intensity · A(d)`` with ``A`` the light's distance law
  (:mod:`vlref.lights.attenuation`), 0 beyond ``range``;
* spot: the same times the cone law (:mod:`vlref.lights.cone`) and the cookie;
* directional: ``colour·intensity`` (irradiance) times the tiled cookie.

It returns the unit vector ``l`` from ``x`` toward the light (``-direction`` for a directional light)
and the distance to the light (``inf`` for a directional light).

:func:`scene_colour` shades each G-buffer pixel:
``albedo/π · Σ_l E_l · max(0, n·l) · V_l + ambient · albedo + emission`` with
``V_l = 1 − strength·(1 − tr)``, ``tr`` an exact RGB shadow ray (:func:`vlref.geometry.shadow_transmittance`,
compiled into the pixel loop: its ``inline_`` form) from the point pushed ``SURFACE_OFFSET`` along the normal, and
``strength`` the light's ``shadows.strength``
(:func:`vlref.lights.shadow_lookup.apply_strength`: the ``V`` of docs/PHYSICS.md "The integral", which the march
applies in the medium, and a GPU port's lighting pass on its surfaces). A light whose shadows are absent or
disabled casts none, on surfaces as in the medium (the marches' ``SHADOW_NONE``, the reference's unshadowed
lights): ``V_l = 1`` and no shadow ray runs. The medium does not attenuate surface lighting here (the
volumetric pass applies the view transmittance). Pixels that hit nothing get ``render.sky_color``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..geometry import inline_shadow_transmittance, traversal_stack
from ..jit import njit
from ..numeric import cast
from ..parallel import COUNTER, borrowed, take, task_counter, work, workers
from .attenuation import distance_attenuation
from .cone import cone_falloff
from .cookies import directional_cookie_uv, sample_texture, spot_cookie_uv
from .pack import (F_CB, F_CG, F_CK_SIZE, F_COS_INNER, F_COS_OUTER, F_CR, F_DX, F_DY, F_DZ, F_HALF_INNER,
                   F_HALF_OUTER, F_INV_RANGE2, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UNITY_A, F_UNITY_B,
                   F_UX, F_UY, F_UZ, I_ATT, I_CK_FILTER, I_CK_H, I_CK_OFF, I_CK_W, I_CK_WRAP, I_CONE, I_KIND,
                   KIND_DIRECTIONAL, KIND_SPOT, PackedLights)
from .shadow_lookup import apply_strength

__all__ = ["light_incidence", "light_vector", "cookie_rgb", "scene_colour", "SURFACE_OFFSET"]

SURFACE_OFFSET = 1e-4


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def light_vector(px, py, pz, x, y, z):
    """``(lx, ly, lz, dist, d2)``: the unit vector from ``(x, y, z)`` toward a light at ``(px, py, pz)``, the
    distance and its square; ``l = 0`` at the light's own position. Scalars only (no array: called in the
    march's vectorised lane loops)."""
    wx, wy, wz = px - x, py - y, pz - z
    d2 = wx * wx + wy * wy + wz * wz
    dist = math.sqrt(d2)
    inv = cast(x, 1.0) / dist if d2 > cast(x, 0.0) else cast(x, 1.0)
    return wx * inv, wy * inv, wz * inv, dist, d2


@njit(cache=True, fastmath=False, forceinline=True)
def cookie_rgb(lights, k, x, y, z):
    """The cookie factor ``(r, g, b)`` (float64) of light ``k`` at ``(x, y, z)`` (:mod:`vlref.lights.cookies`);
    the light must have a cookie (``ints[k, I_CK_OFF] >= 0``)."""
    li, lf = lights.ints, lights.floats
    rx, ry, rz = x - lf[k, F_PX], y - lf[k, F_PY], z - lf[k, F_PZ]
    xl = rx * lf[k, F_RX] + ry * lf[k, F_RY] + rz * lf[k, F_RZ]
    yl = rx * lf[k, F_UX] + ry * lf[k, F_UY] + rz * lf[k, F_UZ]
    if li[k, I_KIND] == KIND_SPOT:
        zl = rx * lf[k, F_DX] + ry * lf[k, F_DY] + rz * lf[k, F_DZ]
        u, v = spot_cookie_uv(xl, yl, zl, lf[k, F_TAN_HALF])
    else:
        u, v = directional_cookie_uv(xl, yl, lf[k, F_CK_SIZE])
    return sample_texture(lights.cookies, li[k, I_CK_OFF], li[k, I_CK_W], li[k, I_CK_H], li[k, I_CK_WRAP] == 1,
                          li[k, I_CK_FILTER] == 1, u, v)


@njit(cache=True, fastmath=False, forceinline=True)
def light_incidence(lights, k, x, y, z):
    """``(lx, ly, lz, dist, er, eg, eb)`` of light ``k`` of ``lights`` (:class:`~vlref.lights.pack.PackedLights`)
    at ``(x, y, z)`` (module docstring).

    Works in the float type of ``lights.floats`` and of the point. ``E = 0`` outside the light's volume.
    The parts (:func:`light_vector`, the distance law, the cone, :func:`cookie_rgb`) are what the physical
    march evaluates stage by stage over its packets of rays.
    """
    li, lf = lights.ints, lights.floats
    zero = cast(x, 0.0)
    kind = li[k, I_KIND]
    if kind == KIND_DIRECTIONAL:
        lx, ly, lz = -lf[k, F_DX], -lf[k, F_DY], -lf[k, F_DZ]
        e = cast(x, 1.0)
        dist = cast(x, np.inf)
    else:
        lx, ly, lz, dist, d2 = light_vector(lf[k, F_PX], lf[k, F_PY], lf[k, F_PZ], x, y, z)
        e = distance_attenuation(li[k, I_ATT], d2, lf[k, F_INV_RANGE2], lights.lut)
        if d2 == zero or e == zero:
            return zero, zero, zero, zero, zero, zero, zero
        if kind == KIND_SPOT:
            e *= cone_falloff(li[k, I_CONE], -(lx * lf[k, F_DX] + ly * lf[k, F_DY] + lz * lf[k, F_DZ]),
                              lf[k, F_COS_OUTER], lf[k, F_COS_INNER], lf[k, F_HALF_OUTER], lf[k, F_HALF_INNER],
                              lf[k, F_UNITY_A], lf[k, F_UNITY_B])
            if e == zero:
                return lx, ly, lz, dist, zero, zero, zero
    er, eg, eb = e * lf[k, F_CR], e * lf[k, F_CG], e * lf[k, F_CB]
    if li[k, I_CK_OFF] >= 0:
        cr, cg, cb = cookie_rgb(lights, k, x, y, z)
        er, eg, eb = er * cast(x, cr), eg * cast(x, cg), eb * cast(x, cb)
    return lx, ly, lz, dist, er, eg, eb


@njit(cache=True, fastmath=False, by_address=True)
def _shade_rows(taken, geo, lights, strength, origin, dirs, distance, normal, object_id, obj_albedo, obj_emission,
                ambient, sky, out):
    """Rows taken one at a time (:func:`vlref.parallel.take`) until none is left, each pixel's scene colour
    (module docstring) computed from the G-buffer's stored buffers: the surface point ``o + t d`` and the object's
    albedo and emission computed where they are read (the bits of the G-buffer's derived ``position``, ``albedo``
    and ``emission``); one traversal stack for all of a worker's shadow rays. The arrays are borrowed
    (:func:`vlref.parallel.borrowed`: every shadow ray passes the geometry on)."""
    h, w = object_id.shape
    y = take(taken)
    if y >= h:  # before any allocation: a worker may find no row left
        return
    geo, lights, strength, origin, dirs, distance, normal, object_id, obj_albedo, obj_emission, ambient, sky, out = (
        borrowed((geo, lights, strength, origin, dirs, distance, normal, object_id, obj_albedo, obj_emission, ambient,
                  sky, out)))
    inv_pi = 1.0 / math.pi
    ox, oy, oz = origin[0], origin[1], origin[2]
    stack = traversal_stack()
    while y < h:
        for j in range(w):
            obj = object_id[y, j]
            if obj < 0:
                out[y, j, 0], out[y, j, 1], out[y, j, 2] = sky[0], sky[1], sky[2]
                continue
            t = distance[y, j]
            nx, ny, nz = normal[y, j, 0], normal[y, j, 1], normal[y, j, 2]
            x = (ox + t * dirs[y, j, 0]) + SURFACE_OFFSET * nx
            yy = (oy + t * dirs[y, j, 1]) + SURFACE_OFFSET * ny
            z = (oz + t * dirs[y, j, 2]) + SURFACE_OFFSET * nz
            sr, sg, sb = 0.0, 0.0, 0.0
            for k in range(lights.ints.shape[0]):
                lx, ly, lz, dist, er, eg, eb = light_incidence(lights, k, x, yy, z)
                cos_n = nx * lx + ny * ly + nz * lz
                if cos_n <= 0.0 or er + eg + eb == 0.0:
                    continue
                vr, vg, vb = 1.0, 1.0, 1.0
                if strength[k] > 0.0:   # strength 0: no shadow (shadows absent, disabled or of no strength)
                    vr, vg, vb = inline_shadow_transmittance(geo, x, yy, z, lx, ly, lz, dist, stack)
                    if strength[k] < 1.0:   # 1 - 1·(1 - tr) can round off tr: strength 1 keeps tr as it is
                        vr, vg, vb = apply_strength(strength[k], vr, vg, vb)
                sr += er * cos_n * vr
                sg += eg * cos_n * vg
                sb += eb * cos_n * vb
            for c, s in enumerate((sr, sg, sb)):
                out[y, j, c] = obj_albedo[obj, c] * (s * inv_pi + ambient[c]) + obj_emission[obj, c]
        y = take(taken)


@njit(cache=True, fastmath=False, parallel=True)
def _shade(geo, lights, strength, origin, dirs, distance, normal, object_id, obj_albedo, obj_emission, ambient, sky,
           out, shade_rows, workers):
    """The scene colour: each of ``workers`` workers (one per thread, :func:`vlref.parallel.workers`) shades the rows it takes
    (``shade_rows``: :func:`_shade_rows` by address, :func:`vlref.parallel.work`), which borrows the arrays (as the G-buffer's ray cast does,
    :mod:`vlref.geometry.raycast`: sky rows cost next to nothing, and 16 threads counting references to the same
    geometry arrays on every shadow ray contend for their counters)."""
    taken = task_counter()
    for _ in prange(workers):
        shade_rows(taken, geo, lights, strength, origin, dirs, distance, normal, object_id, obj_albedo, obj_emission,
                   ambient, sky, out)


def scene_colour(gbuffer, scene, geometry, packed: PackedLights) -> np.ndarray:
    """(H, W, 3) float64 lit surfaces (module docstring)."""
    lights = packed.astype(np.float64)
    out = np.empty(gbuffer.normal.shape)
    strength = np.array([li.shadows.strength if li.shadows is not None and li.shadows.enabled else 0.0
                         for li in scene.lights], dtype=np.float64)
    args = (geometry.arrays, lights, strength, gbuffer.origin, gbuffer.directions, gbuffer.distance, gbuffer.normal,
            gbuffer.object_id, gbuffer.object_albedo, gbuffer.object_emission,
            np.asarray(scene.render.ambient, dtype=np.float64), np.asarray(scene.render.sky_color, dtype=np.float64), out)
    _shade(*args, work(_shade_rows, COUNTER, *args), workers(out.shape[0]))
    return out
