"""The benchmark's NumPy baseline: the physical march of one shadowed spot light, vectorised over pixels.

A straightforward NumPy transcription of :func:`vlref.march.physical.march_physical` for the case
the benchmark times (``vlref bench`` configuration (a)): one spot light with the ``inverse_square``
distance law, the ``smoothstep`` cone, no cookie, a PCF shadow map without a transparent layer,
HG phase, extinction on the view ray and on the light leg, homogeneous medium times height fog
(no noise, no bounds). Per step ``i`` (all pixels at once, Hillaire 2015 as in the kernel):

    t = a + (i + β) Δ,  x = o + t d,  ρ = exp(min(-(y - base) k, 60)),  σs = ss ρ,  σt = st ρ
    S = σs · p_HG(d·l) · V_pcf(x) · exp(-τ(x → light)) · I · cone(cos) / max(r², 1e-4)
    L += T · S · (1 - e^{-σt Δ}) / σt,   T *= e^{-σt Δ}

with ``T`` starting at ``exp(-τ(0, a))`` and ``τ`` the closed-form height-fog optical depth of
:func:`vlref.medium.optical_depth`. The segment ``[a, b]`` of each ray inside the cone comes from
:func:`light_segments` (the njit :func:`vlref.march.segments.light_segment`, per pixel): it is
not per-sample work. The result equals the kernel's to rounding (tests/test_bench.py checks it),
so the samples/s ratio compares the same computation.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..jit import njit
from ..lights.pack import (F_CB, F_CG, F_COS_INNER, F_COS_OUTER, F_CR, F_DX, F_DY, F_DZ, F_INV_RANGE2, F_PX, F_PY,
                           F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UX, F_UY, F_UZ)
from ..lights.shadow_pack import S_OFFSET, S_RES, S_STRENGTH
from ..march.segments import light_segment
from ..medium import FOG_MAX_EXPONENT, M_FOG_BASE, M_FOG_K, M_G, M_SS, M_ST
from ..phase import hg_array

__all__ = ["light_segments", "march_spot_numpy"]


@njit(cache=True, fastmath=False, parallel=True)
def light_segments(lights, origin, dirs, t_end, out):
    """``out[k, y, x] = (a, b)``: the segment of pixel ray ``(y, x)`` inside light ``k`` (empty when ``b <= a``)."""
    h, w = t_end.shape
    for p in prange(h * w):
        i, j = p // w, p % w
        for k in range(lights.ints.shape[0]):
            a, b = light_segment(lights, k, origin[0], origin[1], origin[2], dirs[i, j, 0], dirs[i, j, 1],
                                 dirs[i, j, 2], t_end[i, j])
            out[k, i, j, 0], out[k, i, j, 1] = a, b


def _fog_exponent(mp, y):
    return np.minimum(-(y - mp[M_FOG_BASE]) * mp[M_FOG_K], FOG_MAX_EXPONENT)


def _fog_depth(mp, y0, dy, length):
    """Height-fog optical depth of segments from height ``y0`` along ``dy`` over ``length`` (closed form)."""
    ea = _fog_exponent(mp, y0)
    eb = _fog_exponent(mp, y0 + length * dy)
    delta = np.abs(ea - eb)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(delta < 1e-6, 1.0 - 0.5 * delta, -np.expm1(-delta) / delta)
    return np.where(length > 0.0, mp[M_ST] * length * np.exp(np.maximum(ea, eb)) * ratio, 0.0)


def _pcf(data, base, res, u, v, d_ref):
    """2x2 bilinear comparison (:func:`vlref.lights.shadow_lookup.map_lit` without a transparent layer)."""
    su, sv = u * res - 0.5, v * res - 0.5
    fu, fv = np.floor(su), np.floor(sv)
    wu, wv = su - fu, sv - fv
    c0, r0 = fu.astype(np.int64), fv.astype(np.int64)
    c0c, c1c = np.clip(c0, 0, res - 1), np.clip(c0 + 1, 0, res - 1)
    r0c, r1c = np.clip(r0, 0, res - 1), np.clip(r0 + 1, 0, res - 1)

    def tap(c, r):
        return (d_ref <= data[base + r * res + c]).astype(np.float64)

    return ((1 - wu) * (1 - wv) * tap(c0c, r0c) + wu * (1 - wv) * tap(c1c, r0c) + (1 - wu) * wv * tap(c0c, r1c)
            + wu * wv * tap(c1c, r1c))


def march_spot_numpy(origin, dirs, t_end, beta, steps, mp, lf, sm_ints, sm_floats, sm_data, segments):
    """Inscatter (H, W, 3) of light 0 (a PCF-shadowed spot light) in float64 (module docstring).

    ``segments`` (1, H, W, 2) from :func:`light_segments`; the other arguments as for
    :func:`vlref.march.physical.march_physical` (``lf`` the light floats, ``sm_*`` the shadow maps).
    """
    h, w = t_end.shape
    out = np.zeros((h, w, 3))
    a, b = segments[0, :, :, 0], segments[0, :, :, 1]
    on = b > a
    a, b, bt = a[on], b[on], beta[on]
    d = dirs[on]
    o = np.asarray(origin, dtype=np.float64)
    L = lf[0]
    pos = L[[F_PX, F_PY, F_PZ]]
    fwd, right, up = L[[F_DX, F_DY, F_DZ]], L[[F_RX, F_RY, F_RZ]], L[[F_UX, F_UY, F_UZ]]
    colour = L[[F_CR, F_CG, F_CB]]
    cos_o, cos_i = L[F_COS_OUTER], L[F_COS_INNER]
    res, base, strength = int(sm_ints[0, S_RES]), int(sm_ints[0, S_OFFSET]), sm_floats[0, S_STRENGTH]
    data = sm_data.astype(np.float64)
    delta = (b - a) / steps
    trans = np.exp(-_fog_depth(mp, o[1] + a * 0.0, d[:, 1], a))
    acc = np.zeros((a.shape[0], 3))
    for i in range(steps):
        t = a + (i + bt) * delta
        x = o + t[:, None] * d
        rho = np.exp(_fog_exponent(mp, x[:, 1]))
        st, ss = mp[M_ST] * rho, mp[M_SS] * rho
        wv = pos - x
        d2 = (wv * wv).sum(axis=1)
        att = np.where(d2 * L[F_INV_RANGE2] >= 1.0, 0.0, 1.0 / np.maximum(d2, 1e-4))
        dist = np.sqrt(d2)
        lv = wv / dist[:, None]
        cos_t = -(lv @ fwd)
        s = np.clip((cos_t - cos_o) / (cos_i - cos_o), 0.0, 1.0)
        cone = np.where(cos_t <= cos_o, 0.0, np.where(cos_t >= cos_i, 1.0, s * s * (3.0 - 2.0 * s)))
        e = att * cone
        rel = x - pos
        zl = rel @ fwd
        with np.errstate(divide="ignore", invalid="ignore"):
            k = 0.5 / (zl * L[F_TAN_HALF])
            lit = _pcf(data, base, res, 0.5 + (rel @ right) * k, 0.5 - (rel @ up) * k, dist)
        vis = 1.0 - strength * (1.0 - np.where(zl > 0.0, lit, 1.0))
        leg = np.exp(-_fog_depth(mp, x[:, 1], lv[:, 1], dist))
        phase = hg_array((d * lv).sum(axis=1), mp[M_G])
        with np.errstate(divide="ignore", invalid="ignore"):
            s_int = np.where(st == 0.0, delta, -np.expm1(-st * delta) / st)
        f = np.where((ss > 0.0) & (e > 0.0), trans * ss * phase * leg * s_int * e * vis, 0.0)
        acc += f[:, None] * colour
        trans = trans * np.exp(-st * delta)
    out[on] = acc
    return out
