"""Lights packed into arrays for njit kernels.

``pack_lights(scene)`` turns the scene's lights into two tables indexed by light:

* ``ints`` (n, NI) int64: columns ``I_*`` (kind, attenuation law, cone law, cookie layout);
* ``floats`` (n, NF) in the march's float type: columns ``F_*``.

Light frame (all types): ``look_rotation(direction)``, i.e. right ``x_l``, up ``y_l`` and forward
``z_l`` = the direction of light travel (Unity's left-handed light space). ``F_COLOR`` is
``color * intensity`` (linear RGB): radiant intensity (W/sr) for point and spot lights, irradiance
(W/m², measured perpendicular to the light) for directional lights.

Spot constants: ``F_COS_OUTER = cos(spot_angle/2)``, ``F_COS_INNER = cos(inner/2)`` with the inner
angle of :func:`vlref.lights.cone.default_inner_angle` when the scene does not give one.
``F_UNITY_A, F_UNITY_B`` are URP's ``1/max(0.001, cos_inner - cos_outer)`` and ``-cos_outer * A``.

Cookies (see :mod:`vlref.lights.cookies`) are concatenated into one (sum h*w, 3) texel array.
The optional Unity distance LUT (see :mod:`vlref.lights.attenuation`) is a 2D array; size 0
means "use the documented folk formula".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from ..camera import look_rotation
from .attenuation import ATTENUATION_CODES
from .cone import CONE_CODES, default_inner_angle
from .cookies import load_cookie, FILTER_CODES, WRAP_CODES

__all__ = ["PackedLights", "pack_lights", "KIND_CODES", "KIND_POINT", "KIND_SPOT", "KIND_DIRECTIONAL"]

KIND_POINT, KIND_SPOT, KIND_DIRECTIONAL = 0, 1, 2
"""Light kinds, column ``I_KIND`` of the int table."""
KIND_CODES = {"point": KIND_POINT, "spot": KIND_SPOT, "directional": KIND_DIRECTIONAL}

I_KIND, I_ATT, I_CONE, I_CK_OFF, I_CK_W, I_CK_H, I_CK_WRAP, I_CK_FILTER = range(8)
NI = 8

(F_PX, F_PY, F_PZ, F_DX, F_DY, F_DZ, F_RX, F_RY, F_RZ, F_UX, F_UY, F_UZ, F_CR, F_CG, F_CB, F_RANGE, F_INV_RANGE2,
 F_COS_OUTER, F_COS_INNER, F_TAN_HALF, F_HALF_OUTER, F_HALF_INNER, F_UNITY_A, F_UNITY_B, F_CK_SIZE) = range(25)
NF = 25


class PackedLights(NamedTuple):
    """Lights as arrays (see the module docstring for the columns): the light record the njit kernels take.

    ints : (n, NI) int64.  floats : (n, NF) float.  cookies : (m, 3) float texels.
    lut : (h, w) Unity distance LUT, or shape (0, 0) for the folk formula.
    """

    ints: np.ndarray
    floats: np.ndarray
    cookies: np.ndarray
    lut: np.ndarray

    @property
    def count(self) -> int:
        return self.ints.shape[0]

    def astype(self, dtype) -> "PackedLights":
        """The same lights with float arrays in ``dtype`` (the march's precision)."""
        return PackedLights(self.ints, self.floats.astype(dtype), self.cookies.astype(dtype), self.lut.astype(dtype))


def _light_row(light, cookie_offset: int, cookie_shape: tuple[int, int]) -> tuple[list[int], list[float]]:
    rot = look_rotation(light.direction)
    right, up, fwd = rot[:, 0], rot[:, 1], rot[:, 2]
    outer = math.radians(light.spot_angle) / 2.0
    inner_full = light.inner_spot_angle if light.inner_spot_angle is not None else default_inner_angle(
        light.cone, light.spot_angle)
    inner = math.radians(inner_full) / 2.0
    cos_outer, cos_inner = math.cos(outer), math.cos(inner)
    unity_a = 1.0 / max(0.001, cos_inner - cos_outer)
    ck = light.cookie
    ints = [KIND_CODES[light.type], ATTENUATION_CODES[light.attenuation], CONE_CODES[light.cone],
            cookie_offset, cookie_shape[1], cookie_shape[0],
            WRAP_CODES[ck.wrap] if ck else 0, FILTER_CODES[ck.filter] if ck else 0]
    floats = [*light.position, *fwd, *right, *up, *(np.asarray(light.color) * light.intensity),
              light.range, 1.0 / (light.range * light.range), cos_outer, cos_inner, math.tan(outer), outer, inner,
              unity_a, -cos_outer * unity_a, ck.size if ck else 1.0]
    return ints, floats


def pack_lights(scene, unity_lut: np.ndarray | None = None, dtype=np.float64) -> PackedLights:
    """Pack ``scene.lights`` (cookies loaded from disk) for the njit kernels.

    unity_lut : optional Unity distance-falloff LUT, (w,) or (h, w), indexed by ``u = d²/R²``
        (see :func:`vlref.lights.attenuation.unity_lut_lookup`); None = the documented formula.
    """
    ints, floats, texels = [], [], []
    offset = 0
    for i, light in enumerate(scene.lights):
        if light.cookie is not None:
            tex = load_cookie(light.cookie, scene.source or "<scene>", f"lights[{i}].cookie")
            ri, rf = _light_row(light, offset, tex.shape[:2])
            texels.append(tex.reshape(-1, 3))
            offset += tex.shape[0] * tex.shape[1]
        else:
            ri, rf = _light_row(light, -1, (0, 0))
        ints.append(ri)
        floats.append(rf)
    lut = np.zeros((0, 0)) if unity_lut is None else np.atleast_2d(np.asarray(unity_lut, dtype=np.float64))
    cookies = np.concatenate(texels) if texels else np.zeros((0, 3))
    return PackedLights(np.asarray(ints, dtype=np.int64).reshape(-1, NI),
                        np.asarray(floats, dtype=dtype).reshape(-1, NF), cookies.astype(dtype), lut.astype(dtype))
