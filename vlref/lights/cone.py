"""Spot-light cone falloff laws.

``cosθ = dot(a, (x - p)/|x - p|)`` with ``a`` the spot direction (light travel) and ``p`` the light
position. ``spot_angle`` is the FULL cone angle, so the outer half-angle is ``θo = spot_angle/2``;
``θi = inner_spot_angle/2``. Every law is 0 for ``cosθ <= cos θo`` and 1 inside the inner cone.

``unity``       URP ``GetAngleAttenuation``: ``saturate(cosθ·A + B)²`` with
                ``A = 1/max(0.001, cos θi - cos θo)``, ``B = -cos θo · A``
                (UniversalRenderPipeline.GetSpotAngleAttenuation).
``linear``      linear in the angle: ``(θo - θ)/(θo - θi)`` (Mitsuba 3 ``spot`` emitter's falloff curve).
``smoothstep``  ``smoothstep(cos θo, cos θi, cosθ)`` in the cosine (pbrt-v4 ``SpotLight``).

Default inner angles (full angles, used when ``inner_spot_angle`` is not given), each its source's:

``unity``       ``2·atan(tan(spot_angle/2) · 46/64)`` (URP's fallback, "64 - 18 of 64" texels)
``linear``      ``0.75 · spot_angle`` (Mitsuba: beam_width = 3/4 of cutoff_angle)
``smoothstep``  ``max(0, spot_angle - 10°)`` (pbrt-v4: falloff start = cone angle - 5° conedelta)
"""

from __future__ import annotations

import math

from ..jit import njit
from ..numeric import cast
from ..scene.model import CONE_LAWS

__all__ = ["CONE_CODES", "CONE_UNITY", "CONE_LINEAR", "CONE_SMOOTHSTEP", "cone_falloff", "cone_polynomial",
           "default_inner_angle"]

CONE_CODES = {name: code for code, name in enumerate(CONE_LAWS)}
"""The code of each cone law, its index in the scene model's one list :data:`vlref.scene.model.CONE_LAWS` (the
``I_CONE`` column of :class:`~vlref.lights.pack.PackedLights`)."""
CONE_UNITY, CONE_LINEAR, CONE_SMOOTHSTEP = (CONE_CODES[name] for name in ("unity", "linear", "smoothstep"))


def default_inner_angle(law: str, spot_angle: float) -> float:
    """The inner FULL angle (degrees) of ``law`` when the scene gives none (module docstring)."""
    if law == "unity":
        return math.degrees(2.0 * math.atan(math.tan(math.radians(spot_angle) / 2.0) * 46.0 / 64.0))
    if law == "linear":
        return 0.75 * spot_angle
    return max(0.0, spot_angle - 10.0)


@njit(cache=True, fastmath=False)
def cone_falloff(law, cos_t, cos_outer, cos_inner, half_outer, half_inner, unity_a, unity_b):
    """Cone factor in [0, 1] for ``cos_t`` (module docstring); angles in radians."""
    if law != CONE_LINEAR:
        return cone_polynomial(law, cos_t, cos_outer, cos_inner, unity_a, unity_b)
    zero = cast(cos_t, 0.0)
    one = cast(cos_t, 1.0)
    if cos_t <= cos_outer:
        return zero
    if cos_t >= cos_inner:
        return one
    return min(max((half_outer - math.acos(cos_t)) / (half_outer - half_inner), zero), one)


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def cone_polynomial(law, cos_t, cos_outer, cos_inner, unity_a, unity_b):
    """:func:`cone_falloff` for the laws polynomial in ``cos_t`` (``unity``, ``smoothstep``): no call (the
    ``linear`` law's ``acos`` is one), and selects where the value is 0 or 1, not early returns (with them LLVM kept
    the march's lane loop scalar on AVX2), so the march's lane loops vectorise over it."""
    zero = cast(cos_t, 0.0)
    one = cast(cos_t, 1.0)
    if law == CONE_UNITY:
        a = min(max(cos_t * unity_a + unity_b, zero), one)
        inside = a * a
    else:
        x = (cos_t - cos_outer) / (cos_inner - cos_outer)
        inside = one if cos_t >= cos_inner else x * x * (cast(cos_t, 3.0) - cast(cos_t, 2.0) * x)
    return zero if cos_t <= cos_outer else inside
