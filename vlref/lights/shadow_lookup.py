"""Shadow-map lookups, njit: the visibility of a light from a point, by its map or by a shadow ray.

Filters: ``hard`` = the texel containing the sample (nearest); ``pcf`` = the four texels around
``(u·res - 0.5, v·res - 0.5)``, each compared, blended with bilinear weights (a GPU's 2x2 comparison
sampler), addresses clamped to the face/map; ``exact`` = a shadow ray through the geometry
(:func:`vlref.geometry.shadow_transmittance`, no map). Visibility ``V = 1 - strength · (1 - lit)``
per RGB channel (:func:`apply_strength`). A tap is lit when ``d_ref <= stored``; with a transparent layer it
gives ``lit_opaque · (d_ref > d_transparent ? rgb : 1)`` (the record: :mod:`vlref.lights.shadow_pack`).

The march calls :func:`shadow_visibility` per sample, or the parts it vectorises itself (:func:`spot_map_coords`,
:func:`pcf_taps`, :func:`pcf_blend`, :func:`map_lit`).
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import shadow_transmittance
from ..jit import njit
from .pack import (F_DX, F_DY, F_DZ, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UX, F_UY, F_UZ,
                   KIND_DIRECTIONAL, KIND_SPOT)
from .shadow_pack import (S_CASC, S_CASCADES, S_MODE, S_OFFSET, S_RES, S_STRENGTH, SHADOW_EXACT,
                          SHADOW_NONE, SHADOW_PCF)

__all__ = ["shadow_visibility", "map_lit", "exact_visibility", "apply_strength", "spot_map_coords", "cube_map_coords",
           "cascade_map_coords", "sample_map", "pcf_taps", "pcf_blend"]


@njit(cache=True, fastmath=False, forceinline=True)
def _tap(data, tint, base, tbase, k, d_ref):
    lit = 1.0 if d_ref <= data[base + k] else 0.0
    if tbase >= 0 and d_ref > tint[tbase + k, 0]:
        return lit * tint[tbase + k, 1], lit * tint[tbase + k, 2], lit * tint[tbase + k, 3]
    return lit, lit, lit


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def pcf_taps(u, v, res):
    """The 2x2 PCF taps around ``(u, v)`` on a ``res``² face: texel offsets ``row · res + col`` (clamped to the
    edge) ``(k00, k10, k01, k11)`` and bilinear weights ``(w00, w10, w01, w11)``. Scalars only: the march
    computes them in a vectorised lane loop. Columns, rows and offsets are integers held in floating point (exact
    below 2^53), clamped with the bound first (``max(0, NaN)`` is 0: NaN coordinates read texel 0), converted once
    to 32-bit integers (a face has at most 8192² texels, ``ShadowSettings.resolution``): no 64-bit integer compare
    or multiply in the lane loop, no overflow far outside the map, and ``np.floor``'s float where ``math.floor``'s
    int64 went there and back (lane by lane on AVX2; BENCHMARKS.md "The march on AVX2")."""
    su, sv = u * res - 0.5, v * res - 0.5
    fu, fv = np.floor(su), np.floor(sv)
    wu, wv = su - fu, sv - fv
    last, size = float(res - 1), float(res)
    c0, c1 = min(max(0.0, fu), last), min(max(0.0, fu + 1.0), last)
    top, bottom = min(max(0.0, fv), last) * size, min(max(0.0, fv + 1.0), last) * size
    return ((np.int32(top + c0) + 0, np.int32(top + c1) + 0, np.int32(bottom + c0) + 0, np.int32(bottom + c1) + 0),
            ((1 - wu) * (1 - wv), wu * (1 - wv), (1 - wu) * wv, wu * wv))


@njit(cache=True, fastmath=False, forceinline=True)
def pcf_blend(data, base, k00, k10, k01, k11, w00, w10, w01, w11, d_ref):
    """The PCF lit fraction of the taps of :func:`pcf_taps` (no transparent layer): ``Σ w [d_ref <= depth]``
    (selects, not products: the same sum). Unsigned ``base`` and offsets index without the wrap-around of
    negative indices."""
    return ((w00 if d_ref <= data[base + k00] else 0.0) + (w10 if d_ref <= data[base + k10] else 0.0)
            + (w01 if d_ref <= data[base + k01] else 0.0) + (w11 if d_ref <= data[base + k11] else 0.0))


@njit(cache=True, fastmath=False, forceinline=True)
def sample_map(data, tint, base, tbase, res, pcf, u, v, d_ref):
    """Filtered comparison of one face at (u, v) (row 0 at v = 0 = top). Without a transparent layer
    (``tbase < 0``) r = g = b and the PCF blend is evaluated once."""
    if not pcf:
        col = min(max(int(math.floor(u * res)), 0), res - 1)
        row = min(max(int(math.floor(v * res)), 0), res - 1)
        return _tap(data, tint, base, tbase, row * res + col, d_ref)
    (k00, k10, k01, k11), (w00, w10, w01, w11) = pcf_taps(u, v, res)
    if tbase < 0:
        lit = pcf_blend(data, base, k00, k10, k01, k11, w00, w10, w01, w11, d_ref)
        return lit, lit, lit
    a = _tap(data, tint, base, tbase, k00, d_ref)
    b = _tap(data, tint, base, tbase, k10, d_ref)
    c = _tap(data, tint, base, tbase, k01, d_ref)
    d = _tap(data, tint, base, tbase, k11, d_ref)
    return (w00 * a[0] + w10 * b[0] + w01 * c[0] + w11 * d[0], w00 * a[1] + w10 * b[1] + w01 * c[1] + w11 * d[1],
            w00 * a[2] + w10 * b[2] + w01 * c[2] + w11 * d[2])


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def cube_map_coords(wx, wy, wz):
    """``(face, u, v, d_ref, on_face)`` of the point at ``w = x - p`` from a point light (float64): the face of
    ``w``'s major axis (ties: x before y before z; ``CUBE_FACES`` order), the coordinates on it,
    ``u = 1/2 + sc/(2 ma)``, ``v = 1/2 - tc/(2 ma)`` with ``sc``, ``tc``, ``ma`` the components of ``w`` along the
    face's right, up and forward axes (``ma = |w · forward|``), the radial distance the map stores, and whether
    the point has a face (``ma > 0``; else ``u = v = 0.5``).

    The axes are unit vectors of ±x, ±y, ±z, so each component is ``±wx``, ``±wy`` or ``±wz``, chosen here by
    selects (the face table's products with 0 and ±1 give the same values, up to the sign of a zero that
    ``1/2 ± 0`` drops): no table lookup, so the march evaluates it in a vectorised lane loop."""
    ax, ay, az = abs(wx), abs(wy), abs(wz)
    x_major = ax >= ay and ax >= az
    y_major = not x_major and ay >= az
    if x_major:
        face, ma, sc, tc = (0, ax, -wz, wy) if wx >= 0 else (1, ax, wz, wy)
    elif y_major:
        face, ma, sc, tc = (2, ay, wx, -wz) if wy >= 0 else (3, ay, wx, wz)
    else:
        face, ma, sc, tc = (4, az, wx, wy) if wz >= 0 else (5, az, -wx, wy)
    on_face = ma != 0.0
    ma = ma if on_face else 1.0
    u = 0.5 + 0.5 * (sc / ma) if on_face else 0.5
    v = 0.5 - 0.5 * (tc / ma) if on_face else 0.5
    return face, u, v, math.sqrt(wx * wx + wy * wy + wz * wz), on_face


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def cascade_map_coords(cx, cy, cz, radius, back, rx, ry, rz, ux, uy, uz, dx, dy, dz):
    """``(u, v, d_ref, inside)`` of the point at ``c = x - centre`` in a directional light's cascade (float64) of
    bounding-sphere ``radius`` and ray plane ``back`` behind the centre, with the light's right ``r``, up ``u`` and
    forward ``d`` axes: ``u = 1/2 + (c · r)/(2 radius)``, ``v = 1/2 - (c · u)/(2 radius)``, the distance from the
    ray plane ``c · d + back`` the map stores, and whether the sphere contains the point. Scalars only: the march
    evaluates it in a vectorised lane loop, one cascade at a time."""
    inside = cx * cx + cy * cy + cz * cz <= radius * radius
    xl = cx * rx + cy * ry + cz * rz
    yl = cx * ux + cy * uy + cz * uz
    zl = cx * dx + cy * dy + cz * dz
    return 0.5 + 0.5 * xl / radius, 0.5 - 0.5 * yl / radius, zl + back, inside


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def spot_map_coords(wx, wy, wz, rx, ry, rz, ux, uy, uz, dx, dy, dz, tan_half):
    """``(u, v, d_ref, ahead)`` of the point at ``w = x - p`` from a spot light (float64): the map coordinates of
    its projection (right ``r``, up ``u``, forward ``d`` axes; ``tan_half`` of the cone), the distance the map
    stores, and whether the point is in front of the light (else ``u = v = 0.5``). Scalars only: the march
    evaluates it in a vectorised lane loop and looks the map up (:func:`sample_map`) lane by lane."""
    d_ref = math.sqrt(wx * wx + wy * wy + wz * wz)
    xl = wx * rx + wy * ry + wz * rz
    yl = wx * ux + wy * uy + wz * uz
    zl = wx * dx + wy * dy + wz * dz
    ahead = zl > 0.0
    k = 0.5 / (zl * tan_half) if ahead else 0.0
    return 0.5 + xl * k, 0.5 - yl * k, d_ref, ahead


@njit(cache=True, fastmath=False, forceinline=True)
def map_lit(shadows, kind, lf, light, x, y, z):
    """Unfiltered-strength lit fraction (r, g, b) of world point ``x`` from light ``light``'s map (float64).

    ``shadows`` a :class:`ShadowTable`, ``lf`` the light float table of :mod:`vlref.lights.pack`.
    """
    sm_i, sm_f, data, tint = shadows.ints, shadows.floats, shadows.data, shadows.tint
    res = sm_i[light, S_RES]
    base = sm_i[light, S_OFFSET]
    tbase = base if tint.shape[0] > 0 else -1
    pcf = sm_i[light, S_MODE] == SHADOW_PCF
    wx, wy, wz = x - float(lf[light, F_PX]), y - float(lf[light, F_PY]), z - float(lf[light, F_PZ])
    if kind == KIND_DIRECTIONAL:
        for k in range(sm_i[light, S_CASCADES]):
            j = S_CASC + 5 * k
            u, v, d_ref, inside = cascade_map_coords(
                x - sm_f[light, j], y - sm_f[light, j + 1], z - sm_f[light, j + 2], sm_f[light, j + 3],
                sm_f[light, j + 4], float(lf[light, F_RX]), float(lf[light, F_RY]), float(lf[light, F_RZ]),
                float(lf[light, F_UX]), float(lf[light, F_UY]), float(lf[light, F_UZ]), float(lf[light, F_DX]),
                float(lf[light, F_DY]), float(lf[light, F_DZ]))
            if inside:
                o = base + k * res * res
                to = tbase + k * res * res if tbase >= 0 else -1
                return sample_map(data, tint, o, to, res, pcf, u, v, d_ref)
        return 1.0, 1.0, 1.0
    if kind == KIND_SPOT:
        u, v, d_ref, ahead = spot_map_coords(wx, wy, wz, float(lf[light, F_RX]), float(lf[light, F_RY]),
                                             float(lf[light, F_RZ]), float(lf[light, F_UX]), float(lf[light, F_UY]),
                                             float(lf[light, F_UZ]), float(lf[light, F_DX]), float(lf[light, F_DY]),
                                             float(lf[light, F_DZ]), float(lf[light, F_TAN_HALF]))
        if not ahead:
            return 1.0, 1.0, 1.0
        return sample_map(data, tint, base, tbase, res, pcf, u, v, d_ref)
    f, u, v, d_ref, on_face = cube_map_coords(wx, wy, wz)
    if not on_face:
        return 1.0, 1.0, 1.0
    o = base + f * res * res
    to = tbase + f * res * res if tbase >= 0 else -1
    return sample_map(data, tint, o, to, res, pcf, u, v, d_ref)


@njit(cache=True, fastmath=False)
def exact_visibility(geo, kind, lf, light, x, y, z):
    """Unfiltered-strength RGB transmittance of a shadow ray from world point ``x`` toward light ``light``
    (to infinity for directional lights; 1 at the light's own position)."""
    if kind == KIND_DIRECTIONAL:
        return shadow_transmittance(geo, x, y, z, -float(lf[light, F_DX]), -float(lf[light, F_DY]),
                                    -float(lf[light, F_DZ]), np.inf)
    wx, wy, wz = float(lf[light, F_PX]) - x, float(lf[light, F_PY]) - y, float(lf[light, F_PZ]) - z
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    if dist == 0.0:
        return 1.0, 1.0, 1.0
    return shadow_transmittance(geo, x, y, z, wx / dist, wy / dist, wz / dist, dist)


@njit(cache=True, fastmath=False)
def apply_strength(strength, r, g, b):
    """Visibility ``V = 1 - strength · (1 - lit)`` per channel of the lit fraction ``(r, g, b)`` (the
    light's ``shadows.strength``; float64, as every caller evaluates it)."""
    return 1.0 - strength * (1.0 - r), 1.0 - strength * (1.0 - g), 1.0 - strength * (1.0 - b)


@njit(cache=True, fastmath=False)
def shadow_visibility(shadows, geo, kind, lf, light, x, y, z):
    """Visibility (r, g, b) in [0, 1] of light ``light`` from world point ``x`` (float64), strength applied.

    ``shadows`` a :class:`ShadowTable`. Mode ``SHADOW_EXACT`` traces a shadow ray toward the light
    (:func:`exact_visibility`); the map modes are :func:`map_lit`.
    """
    mode = shadows.ints[light, S_MODE]
    if mode == SHADOW_NONE:
        return 1.0, 1.0, 1.0
    if mode == SHADOW_EXACT:
        r, g, b = exact_visibility(geo, kind, lf, light, x, y, z)
    else:
        r, g, b = map_lit(shadows, kind, lf, light, x, y, z)
    return apply_strength(shadows.floats[light, S_STRENGTH], r, g, b)
