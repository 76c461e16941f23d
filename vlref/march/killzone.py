"""The thesis / Killzone march (thesis §2.2.3, §2.2.4, §2.6, §4.2.2; SOURCES §4): one light.

Per march pixel the view ray ``x(t) = c + t d`` is cut to the light's volume (``[a, b]``, from
:mod:`vlref.march.segments`), divided into ``N`` steps ``Δ = (b - a)/N`` and sampled at
``t_i = a + (β + i) Δ`` (``β`` the Bayer offset, thesis §4.2.5: "offset by the value in the
interleaved sampling texture ... multiplied by the step size"). Each sample is lit "like a white
diffuse surface facing the light" (Vos) by the light's own code:

    L += T_i · σs(x_i) · p_HG(dot(d, l_i); g) · E_l(x_i) · V_l(x_i) · Δ
    T_{i+1} = T_i · exp(-σt(x_i) Δ),     T_0 = exp(-τ(0, t_0))

``E_l`` is :func:`vlref.lights.shading.light_incidence` (attenuation, cone, cookie), ``V_l`` ONE
shadow-map lookup (:func:`vlref.lights.shadow_lookup.shadow_visibility`, filter chosen by the
technique), ``T`` the Beer-Lambert transmittance from the camera (thesis eq. 2.2), exact for a
homogeneous medium (``T_i = exp(-σt t_i)``); ``T ≡ 1`` when the transmittance is off (Vos).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..jit import njit
from ..lights.shading import light_incidence
from ..lights.shadow_lookup import shadow_visibility
from ..lights.pack import I_KIND
from ..medium import M_G, M_SS, M_ST, density, optical_depth
from .segments import light_segment
from ..phase import hg

__all__ = ["kz_march", "kz_segments", "view_transmittance", "KZ_OPTICAL_DEPTH_SUBSTEPS"]

KZ_OPTICAL_DEPTH_SUBSTEPS = 64
"""Midpoint sub-steps of the camera-to-first-sample optical depth when the medium has noise."""


@njit(cache=True, fastmath=False, parallel=True)
def kz_march(cam, dirs, seg_a, seg_b, beta, n_steps, light, lights, medium, shadows, geo, transmittance):
    """In-scattered RGB (h, w, 3) of light ``light`` over a march target (module docstring), prange over pixels.

    cam (3,); dirs (h, w, 3) unit rays; seg_a, seg_b (h, w) the segment (empty when ``b <= a``);
    beta (h, w) offsets in [0, 1); ``lights``, ``medium`` (its anisotropy ``g`` included) and ``shadows``
    the packed records (:mod:`vlref.lights.pack`, :mod:`vlref.medium`, :mod:`vlref.lights.shadow_pack`).
    """
    mp, lattice = medium.params, medium.noise
    lf = lights.floats
    kind = lights.ints[light, I_KIND]
    g = mp[M_G]
    h, w = seg_a.shape
    out = np.zeros((h, w, 3))
    for p in prange(h * w):
        r, c = p // w, p % w
        a, b = seg_a[r, c], seg_b[r, c]
        if not b > a:
            continue
        dx, dy, dz = dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2]
        step = (b - a) / n_steps
        t = a + beta[r, c] * step
        trans = 1.0
        if transmittance:
            trans = math.exp(-optical_depth(mp, lattice, cam[0], cam[1], cam[2], dx, dy, dz, 0.0, t,
                                            KZ_OPTICAL_DEPTH_SUBSTEPS))
        acc_r = acc_g = acc_b = 0.0
        for i in range(n_steps):
            x, y, z = cam[0] + t * dx, cam[1] + t * dy, cam[2] + t * dz
            rho = density(mp, lattice, x, y, z)
            lx, ly, lz, dist, er, eg, eb = light_incidence(lights, light, x, y, z)
            if rho > 0.0 and (er > 0.0 or eg > 0.0 or eb > 0.0):
                vr, vg, vb = shadow_visibility(shadows, geo, kind, lf, light, x, y, z)
                k = trans * mp[M_SS] * rho * hg(dx * lx + dy * ly + dz * lz, g) * step
                acc_r += k * er * vr
                acc_g += k * eg * vg
                acc_b += k * eb * vb
            if transmittance:
                trans *= math.exp(-mp[M_ST] * rho * step)
            t += step
        out[r, c, 0], out[r, c, 1], out[r, c, 2] = acc_r, acc_g, acc_b
    return out


@njit(cache=True, fastmath=False, parallel=True)
def kz_segments(cam, dirs, t_end, lights, light):
    """The part ``[a, b]`` of each ray ``[0, t_end]`` inside light ``light``'s volume, prange over pixels.

    Point: the ball of radius ``range``; spot: that ball cut by the cone of half-angle ``spot_angle/2``;
    directional: the whole ray (the full-screen quad): :func:`~vlref.march.segments.light_segment`.
    """
    h, w = t_end.shape
    a_out, b_out = np.zeros((h, w)), np.zeros((h, w))
    for p in prange(h * w):
        r, c = p // w, p % w
        a, b = light_segment(lights, light, cam[0], cam[1], cam[2], dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2],
                             t_end[r, c])
        a_out[r, c], b_out[r, c] = a, b
    return a_out, b_out


@njit(cache=True, fastmath=False, parallel=True)
def view_transmittance(cam, dirs, t_end, medium):
    """``exp(-τ(0, t_end))`` per pixel (:func:`vlref.medium.optical_depth` of the :class:`~vlref.medium.PackedMedium`
    ``medium``), prange over pixels."""
    mp, lattice = medium.params, medium.noise
    h, w = t_end.shape
    out = np.ones((h, w))
    for p in prange(h * w):
        r, c = p // w, p % w
        out[r, c] = math.exp(-optical_depth(mp, lattice, cam[0], cam[1], cam[2], dirs[r, c, 0], dirs[r, c, 1],
                                            dirs[r, c, 2], 0.0, t_end[r, c], KZ_OPTICAL_DEPTH_SUBSTEPS))
    return out
