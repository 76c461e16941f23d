"""SlightlyMad/VolumetricLights: dither texture, density, light term and the ``RayMarch`` loop.

Everything here follows ``docs/SOURCES.md`` §1 (VL = ``VolumetricLight.shader``,
``VolumetricLight.cs``, ``VolumetricLightRenderer.cs`` at HEAD ``d20b6f9``).

Dither (§1.5): the 8x8 texture holds byte ``floor(255 k / 65)`` with ``k`` the **transposed**
standard Bayer index plus 1; the 4x4 variant (``DITHER_4_4``) the standard Bayer index ``k`` with
byte ``floor(255 k / 16)``. Texel ``(x, y)`` is read at the march target's pixel ``(x mod n, y mod n)``
with ``y`` counted from the **bottom** row (Unity's ``SV_Position`` on render textures).

The loop (§1.4), per light and march pixel, ray ``x(t) = o + t d`` with ``o`` the segment start:

    Δ = L / N,  x_i = o + (β + i) Δ d,   i = 0..N-1
    τ = 0 (directional) | ½ σt |c - x_0| (point/spot, quirk 2)
    for each i:  τ += σt Δ ρ_i  (quirk 1: before use);  c_i = A_i σs Δ ρ_i e^{-τ} [· p_HG(μ_i) point/spot]
    V = Σ c_i  [· p_HG(μ) once, directional];  rgb = max(0, V · colour);  α = e^{-τ} (directional)

with ``μ = dot(unit(x - p_L), -d)`` (point/spot) or ``dot(ℓ_forward, -d)`` (directional): the same
cosine as :func:`vlref.phase.hg`'s ``dot(d, l)``, ``l`` toward the light. The density ``ρ`` is
:func:`vlref.medium.density` of a medium built from VL's parameters (``techniques/slightlymad.py``):
noise ``saturate(saturate(n - o) k)`` sampled at ``frac(s x + t s v)``, height fog
``exp(-(y + GroundLevel) HeightScale)``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import prange

from ..jit import njit
from ..lights.attenuation import distance_attenuation
from ..lights.cone import cone_falloff
from ..lights.cookies import sample_texture, spot_cookie_uv
from ..lights.pack import (F_CR, F_COS_INNER, F_COS_OUTER, F_DX, F_DY, F_DZ, F_HALF_INNER, F_HALF_OUTER,
                           F_INV_RANGE2, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UNITY_A, F_UNITY_B, F_UX,
                           F_UY, F_UZ, KIND_DIRECTIONAL, KIND_POINT)
from ..lights.shadow_lookup import shadow_visibility
from ..medium import M_G, density
from ..phase import hg
from .patterns import bayer_matrix

__all__ = ["dither_k", "dither_table", "dither_offsets", "spot_profile_cookie", "SPOT_PROFILE", "CONE_COOKIE_ONLY",
           "VlLight", "VlMarch", "vl_light", "vl_march", "vl_view_tau"]

SPOT_PROFILE = ((0.0, 1.0), (0.5, 1.0), (0.6, 0.977), (0.7, 0.803), (0.8, 0.448), (0.85, 0.273), (0.9, 0.140),
                (0.95, 0.057), (1.0, 0.013), (1.1, 0.0))
"""(r, alpha) of VL's ``spot.png``, r in half-widths from the centre (SOURCES Appendix A, measured)."""

CONE_COOKIE_ONLY = -1
"""``cone_law`` value selecting VL's spot falloff: the cookie alone (§1.6)."""


class VlLight(NamedTuple):
    """One light as VL's ``RayMarch`` sees it (the record :func:`vl_march` takes).

    index : the light's row in the packed tables (shadow lookups).  kind : ``KIND_*`` of
    :mod:`vlref.lights.pack`.  floats : its packed float row with the technique's colour (quirk 14).
    attenuation : distance law code (:mod:`vlref.lights.attenuation`).  cone : cone law code or
    :data:`CONE_COOKIE_ONLY`.  lut : (h, w) Unity LUT (size 0: folk formula).  cookie : (h, w, 3) spot
    cookie.  cube_factor : the point-shadow receiver factor of :func:`vl_shadow`.
    """

    index: int
    kind: int
    floats: np.ndarray
    attenuation: int
    cone: int
    lut: np.ndarray
    cookie: np.ndarray
    cube_factor: float


class VlMarch(NamedTuple):
    """The loop's constants: ``n_steps``; ``sigma_s``, ``sigma_t`` (1/m); ``right_endpoint`` (quirk 1: ``τ``
    updated before use); ``half_tau`` (quirk 2). HG's ``g`` is the medium's (``M_G``)."""

    n_steps: int
    sigma_s: float
    sigma_t: float
    right_endpoint: bool
    half_tau: bool


def dither_k(size: int) -> np.ndarray:
    """The index ``k`` of texel ``[y, x]`` (y from the bottom): 8x8 transposed Bayer + 1, 4x4 standard Bayer."""
    if size == 8:
        return bayer_matrix(8).T + 1
    if size == 4:
        return bayer_matrix(4)
    raise ValueError(f"VL's dither texture is 8x8 or 4x4, got {size}")


def dither_table(size: int = 8) -> np.ndarray:
    """VL's Alpha8 dither bytes ``[y, x]``, row ``y = 0`` the texture's ``v = 0`` (bottom) row (§1.5).

    8x8: ``floor(255 k / 65)``; 4x4: ``floor(255 k / 16)`` (C# float then truncation; exact in integers).
    """
    k = dither_k(size)
    return ((255 * k) // (65 if size == 8 else 16)).astype(np.uint8)


def dither_offsets(width: int, height: int, size: int = 8, as_bytes: bool = True,
                   uv_origin: str = "bottom") -> np.ndarray:
    """Per-pixel offset ``β`` (fraction of a step) of a ``width x height`` march target, row 0 on top.

    ``as_bytes``: ``byte / 255`` as the shader reads it; else the exact ``k / (size² + 1)`` (8x8) or
    ``k / size²`` (4x4) of the same matrix. ``uv_origin="bottom"`` indexes rows from the bottom (Unity).
    """
    k = dither_k(size)
    table = dither_table(size) / 255.0 if as_bytes else k / float(size * size + (1 if size == 8 else 0))
    rows = np.arange(height)
    y = (height - 1 - rows) if uv_origin == "bottom" else rows
    x = np.arange(width)
    return table[(y % size)[:, None], (x % size)[None, :]].astype(np.float64)


def spot_profile_cookie(size: int = 128) -> np.ndarray:
    """A ``size x size`` (h, w, 3) cookie whose radial profile is :data:`SPOT_PROFILE` (linear in r)."""
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    r = np.hypot(c[None, :], c[:, None])
    rs, alphas = zip(*SPOT_PROFILE)
    a = np.interp(r, rs, alphas)
    return np.repeat(a[:, :, None], 3, axis=2)


@njit(cache=True, fastmath=False)
def vl_light(kind, lf, att_law, cone_law, lut, cookie, x, y, z):
    """Unshadowed attenuation ``A(x)`` (§1.6): LUT(d²/R²) x cookie alpha x [z_l > 0] for spots; 1 for
    directional lights (their cookie is ignored: quirk 12). ``lf`` is the light's packed float row
    (``vlref.lights.pack``); ``cone_law = -1`` is VL's cookie-only cone, else a ``cone.py`` law.

    Not :func:`vlref.lights.shading.light_incidence`: VL tests ``z_l > 0`` before the cone, takes the cone
    cosine as ``z_l / d``, ignores directional cookies and has the cookie-only cone."""
    if kind == KIND_DIRECTIONAL:
        return 1.0
    rx, ry, rz = x - lf[F_PX], y - lf[F_PY], z - lf[F_PZ]
    a = distance_attenuation(att_law, rx * rx + ry * ry + rz * rz, lf[F_INV_RANGE2], lut)
    if kind == KIND_POINT or a == 0.0:
        return a
    zl = rx * lf[F_DX] + ry * lf[F_DY] + rz * lf[F_DZ]
    if zl <= 0.0:
        return 0.0
    if cone_law == CONE_COOKIE_ONLY:
        xl = rx * lf[F_RX] + ry * lf[F_RY] + rz * lf[F_RZ]
        yl = rx * lf[F_UX] + ry * lf[F_UY] + rz * lf[F_UZ]
        u, v = spot_cookie_uv(xl, yl, zl, lf[F_TAN_HALF])
        h, w = cookie.shape[0], cookie.shape[1]
        c = sample_texture(cookie.reshape(h * w, 3), 0, w, h, False, False, u, v)
        return a * c[0]
    d = math.sqrt(rx * rx + ry * ry + rz * rz)
    return a * cone_falloff(cone_law, zl / d, lf[F_COS_OUTER], lf[F_COS_INNER], lf[F_HALF_OUTER], lf[F_HALF_INNER],
                            lf[F_UNITY_A], lf[F_UNITY_B])


@njit(cache=True, fastmath=False)
def vl_shadow(shadows, geo, kind, lights_f, light, cube_factor, x, y, z):
    """VL's shadow term ``r + (1 - r) cmp`` (``r = 1 - strength``), grey (mean of the RGB lookup).

    Point lights compare ``cube_factor · |x - p|`` (Unity's 0.97 receiver bias, §1.6): the lookup is
    made at ``p + cube_factor (x - p)``, which has the same cube texel and that reference distance.
    """
    if kind == KIND_POINT:
        px, py, pz = lights_f[light, F_PX], lights_f[light, F_PY], lights_f[light, F_PZ]
        x, y, z = px + cube_factor * (x - px), py + cube_factor * (y - py), pz + cube_factor * (z - pz)
    r, g, b = shadow_visibility(shadows, geo, kind, lights_f, light, x, y, z)
    return (r + g + b) / 3.0


@njit(cache=True, fastmath=False, parallel=True)
def vl_march(cam, dirs, t0, length, covered, beta, march, light, medium, lights, shadows, geo):
    """The ``RayMarch`` loop of one light over a march target (module docstring), prange over pixels.

    cam (3,); dirs (h, w, 3) unit view rays; t0 (h, w) distance from the camera to the segment start
    ``o``; length (h, w) the segment length ``L`` (negative when a surface hides the entry: every
    term is then <= 0 and the max(0, .) clamps to 0, quirk 16); covered (h, w) bool, the light
    volume's raster coverage; beta (h, w) dither offsets; ``march`` a :class:`VlMarch`, ``light`` a
    :class:`VlLight`; ``medium`` the density's :class:`~vlref.medium.PackedMedium`, ``lights`` the frame's
    packed lights and ``shadows`` its :class:`~vlref.lights.shadow_pack.ShadowTable` (shadow lookups).
    Returns ``rgb`` (h, w, 3) and ``tau`` (h, w).
    """
    n_steps, sigma_s, sigma_t, right_endpoint, half_tau = march
    light_index, kind, lf, att_law, cone_law, lut, cookie, cube_factor = light
    mp, lattice = medium.params, medium.noise
    g = mp[M_G]
    lights_f = lights.floats
    h, w = t0.shape
    rgb = np.zeros((h, w, 3))
    tau_out = np.zeros((h, w))
    for p in prange(h * w):
        r, c = p // w, p % w
        if not covered[r, c]:
            continue
        dx, dy, dz = dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2]
        step = length[r, c] / n_steps
        t = t0[r, c] + beta[r, c] * step
        tau = 0.0
        if kind != KIND_DIRECTIONAL:
            tau = (0.5 if half_tau else 1.0) * sigma_t * abs(t)
        acc = 0.0
        for i in range(n_steps):
            x, y, z = cam[0] + t * dx, cam[1] + t * dy, cam[2] + t * dz
            a = vl_light(kind, lf, att_law, cone_law, lut, cookie, x, y, z)
            if a != 0.0:
                a *= vl_shadow(shadows, geo, kind, lights_f, light_index, cube_factor, x, y, z)
            rho = density(mp, lattice, x, y, z)
            d_tau = sigma_t * step * rho
            if right_endpoint:
                tau += d_tau
            term = a * sigma_s * step * rho * math.exp(-tau)
            if not right_endpoint:
                tau += d_tau
            if kind != KIND_DIRECTIONAL:
                lx, ly, lz = x - lf[F_PX], y - lf[F_PY], z - lf[F_PZ]
                ln = math.sqrt(lx * lx + ly * ly + lz * lz)
                mu = -(lx * dx + ly * dy + lz * dz) / ln if ln > 0.0 else 1.0
                term *= hg(mu, g)
            acc += term
            t += step
        if kind == KIND_DIRECTIONAL:
            acc *= hg(-(lf[F_DX] * dx + lf[F_DY] * dy + lf[F_DZ] * dz), g)
        for ch in range(3):
            rgb[r, c, ch] = max(0.0, acc * lf[F_CR + ch])
        tau_out[r, c] = tau
    return rgb, tau_out


@njit(cache=True, fastmath=False, parallel=True)
def vl_view_tau(cam, dirs, length, beta, n_steps, sigma_t, medium):
    """Optical depth of the view rays ``[0, length]`` by VL's step rule (``Σ σt Δ ρ_i``), prange over pixels.

    Used when quirk 3 is neutralised (point/spot lights then attenuate the scene). ``medium`` the density's
    :class:`~vlref.medium.PackedMedium`.
    """
    mp, lattice = medium.params, medium.noise
    h, w = length.shape
    out = np.zeros((h, w))
    for p in prange(h * w):
        r, c = p // w, p % w
        step = length[r, c] / n_steps
        t = beta[r, c] * step
        tau = 0.0
        for i in range(n_steps):
            tau += sigma_t * step * density(mp, lattice, cam[0] + t * dirs[r, c, 0], cam[1] + t * dirs[r, c, 1],
                                            cam[2] + t * dirs[r, c, 2])
            t += step
        out[r, c] = tau
    return out
