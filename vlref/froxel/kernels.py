"""The froxel passes as Numba kernels: light the grid, integrate it front to back, apply it per pixel.

Grid layout and slices: :mod:`vlref.froxel.grid`. Every kernel runs ``prange`` over grid columns
(or pixels) and never reduces across them, so results do not depend on the thread count.

1. :func:`froxel_scatter` (Wronski 2014 "density estimation" + "in-scattering" passes, merged as
   Hillaire 2015's "light scattering" volume): at the froxel's sample point ``x`` (on the column's ray
   through the jittered uv, at the jittered slice depth) it stores ``(S_r, S_g, S_b, σt)`` with
   ``S = σs(x) Σ_l p(d·l) V_l(x) T_l(x) E_l(x)`` (radiance per metre) exactly as the physical march
   evaluates its source (:mod:`vlref.march.physical`: :func:`vlref.lights.shading.light_incidence`,
   :func:`vlref.lights.shadow_lookup.shadow_visibility` with each light's own filter, HG with ``d`` the
   column's ray, the light leg ``T_l`` of ``light_extinction`` by :func:`vlref.medium.light_leg_attenuates`).
2. :func:`froxel_integrate` (Hillaire 2015, slides 27-28): along each column's *centre* ray, slice
   ``k`` has length ``Δ_k = (z_{k+1} - z_k)/(d·f)`` (``f`` the camera forward); with ``S, σt`` of the
   froxel constant over the step, ``L += T · S (1 - e^{-σt Δ})/σt`` (``S Δ`` when ``σt = 0``;
   :func:`vlref.medium.step_source_weight`, as the physical march), **then**
   ``T *= e^{-σt Δ}``, from ``L = 0, T = 1`` at ``z_0 = 0``. The integrated grid stores ``(L_r, L_g,
   L_b, T)`` at each slice's FAR boundary ``z_{k+1}``.
3. :func:`froxel_apply`: a pixel with uv ``(u, v)`` and eye depth ``z`` (sky and beyond the grid:
   ``z_D``) reads the integrated grid bilinearly over columns at ``(u·gw - ½, v·gh - ½)`` (clamp to
   edge) and linearly over boundaries at ``s = depth_to_slice(z)``, where boundary 0 is ``(0, 0, 0, 1)``
   and boundary ``k ≥ 1`` is slice ``k - 1`` of the integrated grid: in texture terms a trilinear fetch
   at ``w = (s - ½)/D`` of a volume whose texel ``k`` sits at ``z_{k+1}``, with ``(0, 1)`` below the
   first texel. ``final = scene · T + L``.
"""

from __future__ import annotations

import math

from numba import prange

from ..jit import njit
from ..lights.pack import I_KIND, KIND_DIRECTIONAL
from ..lights.shading import light_incidence
from ..lights.shadow_lookup import shadow_visibility
from ..medium import M_G, M_SS, M_ST, density, light_leg_attenuates, optical_depth, step_source_weight
from ..phase import hg
from .grid import depth_to_slice

__all__ = ["froxel_scatter", "froxel_integrate", "froxel_apply", "in_scattering"]


@njit(cache=True, fastmath=False)
def in_scattering(medium, lights, shadows, geo, x, y, z, dx, dy, dz, light_extinction, leg_steps):
    """``(S_r, S_g, S_b, σt)`` at world point ``x`` seen along unit direction ``d`` (module docstring, pass 1).

    ``medium``, ``lights``, ``shadows``: the packed records of :mod:`vlref.medium`, :mod:`vlref.lights.pack`
    and :mod:`vlref.lights.shadow_pack`."""
    mp, lattice = medium.params, medium.noise
    li, lf = lights.ints, lights.floats
    rho = density(mp, lattice, x, y, z)
    ss, st = mp[M_SS] * rho, mp[M_ST] * rho
    sr, sg, sb = 0.0, 0.0, 0.0
    if ss == 0.0:
        return sr, sg, sb, st
    for k in range(li.shape[0]):
        lx, ly, lz, dist, er, eg, eb = light_incidence(lights, k, x, y, z)
        if er + eg + eb == 0.0:
            continue
        kind = li[k, I_KIND]
        vr, vg, vb = shadow_visibility(shadows, geo, kind, lf, k, x, y, z)
        tl = 1.0
        if light_leg_attenuates(mp, kind == KIND_DIRECTIONAL, light_extinction):
            tl = math.exp(-optical_depth(mp, lattice, x, y, z, lx, ly, lz, 0.0, dist, leg_steps))
        f = ss * hg(dx * lx + dy * ly + dz * lz, mp[M_G]) * tl
        sr += f * er * vr
        sg += f * eg * vg
        sb += f * eb * vb
    return sr, sg, sb, st


@njit(cache=True, fastmath=False, parallel=True)
def froxel_scatter(origin, dirs, forward, bounds, xi_z, medium, lights, shadows, geo, light_extinction, leg_steps,
                   out):
    """Fill ``out`` (gh, gw, D, 4) with ``(S, σt)`` per froxel (pass 1).

    ``dirs`` (gh, gw, 3): unit rays through the jittered sample uv of every column; ``bounds`` (D+1,)
    slice boundaries; ``xi_z`` the slice jitter in [0, 1]. Everything float64.
    """
    gh, gw, d = out.shape[0], out.shape[1], out.shape[2]
    for p in prange(gh * gw):
        r, c = p // gw, p % gw
        dx, dy, dz = dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2]
        inv_cos = 1.0 / (dx * forward[0] + dy * forward[1] + dz * forward[2])
        for k in range(d):
            t = (bounds[k] + xi_z * (bounds[k + 1] - bounds[k])) * inv_cos
            s0, s1, s2, st = in_scattering(medium, lights, shadows, geo, origin[0] + t * dx, origin[1] + t * dy,
                                           origin[2] + t * dz, dx, dy, dz, light_extinction, leg_steps)
            out[r, c, k, 0], out[r, c, k, 1], out[r, c, k, 2], out[r, c, k, 3] = s0, s1, s2, st


@njit(cache=True, fastmath=False, parallel=True)
def froxel_integrate(scatter, dirs, forward, bounds, out):
    """Front-to-back integration of ``scatter`` (gh, gw, D, 4) into ``out`` (gh, gw, D, 4) = ``(L, T)`` at
    each slice's far boundary (pass 2); ``dirs`` the columns' centre rays (gh, gw, 3)."""
    gh, gw, d = scatter.shape[0], scatter.shape[1], scatter.shape[2]
    for p in prange(gh * gw):
        r, c = p // gw, p % gw
        cos = dirs[r, c, 0] * forward[0] + dirs[r, c, 1] * forward[1] + dirs[r, c, 2] * forward[2]
        lr, lg, lb, trans = 0.0, 0.0, 0.0, 1.0
        for k in range(d):
            delta = (bounds[k + 1] - bounds[k]) / cos
            st = scatter[r, c, k, 3]
            em1 = math.expm1(-st * delta)
            s_int = step_source_weight(st, delta, em1)
            lr += trans * scatter[r, c, k, 0] * s_int
            lg += trans * scatter[r, c, k, 1] * s_int
            lb += trans * scatter[r, c, k, 2] * s_int
            trans *= 1.0 + em1
            out[r, c, k, 0], out[r, c, k, 1], out[r, c, k, 2], out[r, c, k, 3] = lr, lg, lb, trans


@njit(cache=True, fastmath=False, forceinline=True)
def _boundary(integrated, r, c, b, ch):
    """Channel ``ch`` of the integrated value at boundary ``b`` of column (r, c): boundary 0 = (0, 0, 0, 1)."""
    if b == 0:
        return 1.0 if ch == 3 else 0.0
    return integrated[r, c, b - 1, ch]


@njit(cache=True, fastmath=False, parallel=True)
def froxel_apply(integrated, bounds, depth, inscatter, transmittance):
    """Per pixel of ``depth`` (H, W) eye depth: fill ``inscatter`` (H, W, 3) and ``transmittance`` (H, W)
    by the trilinear lookup of pass 3."""
    h, w = depth.shape
    gh, gw, d = integrated.shape[0], integrated.shape[1], integrated.shape[2]
    for p in prange(h * w):
        i, j = p // w, p % w
        gx = (j + 0.5) / w * gw - 0.5
        gy = (i + 0.5) / h * gh - 0.5
        fx, fy = math.floor(gx), math.floor(gy)
        wx, wy = gx - fx, gy - fy
        c0, r0 = min(max(int(fx), 0), gw - 1), min(max(int(fy), 0), gh - 1)
        c1, r1 = min(max(int(fx) + 1, 0), gw - 1), min(max(int(fy) + 1, 0), gh - 1)
        s = depth_to_slice(bounds, min(depth[i, j], bounds[d]))
        b0 = min(int(math.floor(s)), d)
        b1 = min(b0 + 1, d)
        ws = s - b0
        for ch in range(4):
            v = 0.0
            for rr, cc, wgt in ((r0, c0, (1.0 - wx) * (1.0 - wy)), (r0, c1, wx * (1.0 - wy)),
                                (r1, c0, (1.0 - wx) * wy), (r1, c1, wx * wy)):
                v += wgt * ((1.0 - ws) * _boundary(integrated, rr, cc, b0, ch) + ws * _boundary(integrated, rr, cc,
                                                                                                 b1, ch))
            if ch == 3:
                transmittance[i, j] = v
            else:
                inscatter[i, j, ch] = v
