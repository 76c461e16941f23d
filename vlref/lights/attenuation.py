"""Distance attenuation laws of point and spot lights (the ``attenuation`` of a point or spot light).

``d`` is the distance from the light (metres), ``R`` the light's ``range`` and ``u = d²/R²``.
Every law is 0 for ``d >= R``: the light volume (a ball of radius ``R``) ends there.

``inverse_square``  ``1 / max(d², d_min²)`` with ``d_min = 0.01`` m: the physical law of a point
                    source. The guard is Frostbite's 1 cm light size (Lagarde & de Rousiers 2014,
                    "Moving Frostbite to PBR", §4.1) and keeps a ray through the light finite.
``unity``           Unity built-in pipeline falloff ``LUT(u)`` (``_LightTextureB0`` sampled at
                    ``(u, u)``, SOURCES §1.6). Unity's texture is not published: by default
                    the community reconstruction ``1/(1 + 25u) · saturate(5(1 - sqrt(u)))`` (folk
                    formula ``1/(1+25u)`` faded to 0 at the range; *not Unity's exact texture*),
                    or a user LUT sampled bilinearly with clamp (:func:`unity_lut_lookup`).
                    Dimensionless: ``E = I · LUT(u)``.
``windowed``        ``saturate(1 - (d/R)⁴)² / max(d², d_min²)``: inverse square smoothly windowed to
                    0 at the range (Karis 2013, "Real Shading in Unreal Engine 4"; Frostbite 2014).
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import njit
from ..numeric import cast
from ..scene.model import ATTENUATIONS
from .cookies import filter_taps

__all__ = ["ATTENUATION_CODES", "INVERSE_SQUARE", "UNITY", "WINDOWED", "MIN_DISTANCE",
           "analytic_attenuation", "distance_attenuation", "unity_folk", "unity_lut_lookup"]

ATTENUATION_CODES = {name: code for code, name in enumerate(ATTENUATIONS)}
"""The code of each distance law, its index in the scene model's one list :data:`vlref.scene.model.ATTENUATIONS`
(the ``I_ATT`` column of :class:`~vlref.lights.pack.PackedLights`)."""
INVERSE_SQUARE, UNITY, WINDOWED = (ATTENUATION_CODES[name] for name in ("inverse_square", "unity", "windowed"))
MIN_DISTANCE = 0.01


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def unity_folk(u):
    """Default Unity falloff ``1/(1 + 25u) · saturate(5(1 - sqrt(u)))``, ``u = d²/R²``."""
    fade = min(max(cast(u, 5.0) * (cast(u, 1.0) - math.sqrt(u)), cast(u, 0.0)), cast(u, 1.0))
    return fade / (cast(u, 1.0) + cast(u, 25.0) * u)


@njit(cache=True, fastmath=False)
def unity_lut_lookup(lut, u):
    """Bilinear, clamped sample of ``lut`` (h, w) at texture coordinates ``(u, u)`` (weights in float64).

    Texel ``(row r, column c)`` has its centre at ``((c + 0.5)/w, (r + 0.5)/h)``; row 0 is ``v = 0``
    (Unity ``GetPixels`` order). A (1, w) LUT is a 1D table over ``u ∈ [0, 1]``.
    """
    h, w = lut.shape
    clamp = np.bool_(False)  # not the literal False: filter_taps then compiles once, as for the cookies
    c0, c1, fc = filter_taps(u, w, clamp)
    r0, r1, fr = filter_taps(u, h, clamp)
    top = lut[r0, c0] * (1.0 - fc) + lut[r0, c1] * fc
    bot = lut[r1, c0] * (1.0 - fc) + lut[r1, c1] * fc
    return cast(u, top * (1.0 - fr) + bot * fr)


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def analytic_attenuation(law, d2, inv_range2):
    """:func:`distance_attenuation` for the laws given by a formula (every law but ``unity`` with a LUT): no
    table, no call, so the march's lane loops vectorise over it."""
    u = d2 * inv_range2
    one = cast(d2, 1.0)
    if u >= one:
        return cast(d2, 0.0)
    if law == UNITY:
        return unity_folk(u)
    inv = one / max(d2, cast(d2, MIN_DISTANCE * MIN_DISTANCE))
    if law == WINDOWED:
        w = one - u * u
        return w * w * inv
    return inv


@njit(cache=True, fastmath=False)
def distance_attenuation(law, d2, inv_range2, lut):
    """Attenuation factor at squared distance ``d2`` (m²) for ``law`` (module docstring).

    ``inverse_square`` and ``windowed`` are in 1/m² (``E = I · factor``); ``unity`` is dimensionless.
    ``lut`` of size 0 selects the folk formula for ``unity``.
    """
    if law == UNITY and lut.size > 0:
        u = d2 * inv_range2
        if u >= cast(d2, 1.0):
            return cast(d2, 0.0)
        return unity_lut_lookup(lut, u)
    return analytic_attenuation(law, d2, inv_range2)
