"""The physical single-scattering march (docs/PHYSICS.md "The integral"; Hillaire 2015 step integration).

For each pixel (view ray ``x(t) = o + t d``, ``t ∈ [0, t_end]``, ``t_end = min(scene distance,
render.max_distance)``) and each light ``l``:

1. the segment ``[a, b]`` of the ray where the integrand can be non-zero: inside the light's volume
   (:mod:`vlref.march.segments`: ball of radius ``range``, cone ∩ ball, or the whole ray for a
   directional light), clipped to ``medium.bounds`` (:func:`vlref.medium.clip_to_bounds`) and to the
   scene depth ``t_end`` (a light of range 1000 m in an 8 m box otherwise spreads its steps over 1000 m
   of empty space: BENCHMARKS.md "Sample placement"). The height fog and the noise are positive wherever
   the medium is, so they clip nothing;
2. ``N`` steps of ``Δ = (b - a)/N`` with samples at ``t_i = a + (i + β) Δ`` (``β`` the pixel's offset);
3. per step, with ``σs, σt`` at the sample (:mod:`vlref.medium`):
   ``S = σs · p(d·l) · V · T_l · E_l`` (``p`` HG with ``l`` toward the light, ``V`` shadow visibility,
   ``T_l`` light-leg transmittance, ``E_l`` :func:`vlref.lights.shading.light_incidence`),
   ``S_int = S · (1 - e^{-σt Δ}) / σt`` (``S · Δ`` when ``σt = 0``; computed with ``expm1``),
   ``L += T · S_int``, then ``T *= e^{-σt Δ}``; ``T`` starts at ``exp(-τ(0, a))``.

Every light adds under the same view transmittance ``T(0, t)``. The pixel's transmittance is
``exp(-τ(0, t_end))``. Optical depths ``τ`` are analytic without noise and midpoint sums of ``N``
sub-steps with noise (:func:`vlref.medium.optical_depth`).

Light leg ``T_l`` (``light_extinction``): ``exp(-τ)`` from the sample to a point or spot light; for a
directional light, to where the ray toward the light leaves the medium box. **An unbounded medium
gives a directional light ``T_l = 1``**: its irradiance ``E`` is taken as the irradiance arriving at
the sample (an infinite homogeneous medium would otherwise extinguish it completely); bound the
medium with ``medium.bounds`` to attenuate sunlight on its way in. With noise the leg uses
``leg_steps`` midpoint sub-steps.

Order of convergence in ``Δ`` (smooth integrand): the per-step source is a rectangle rule at offset
``β``, so the error is ``≈ (1/2 - β) Δ [f(b) - f(a)] + O(Δ²)``: first order for ``β ≠ 1/2``
(``none``, Bayer, hash offsets), second order for ``β = 1/2`` (midpoint); the transmittance update
is exact for a constant ``σt`` per step.

Precision: the kernel is compiled for float64 and float32 inputs; in float32 every quantity of the
march is float32 (constants through :func:`vlref.numeric.cast`, the HG value included) except
texture/shadow-map coordinates and filter weights (float64, as a GPU's fixed-point sampler would be
its own) and exact shadow rays (the geometry is float64).

Evaluation (the same integral, rearranged for speed): per segment ``e^{-σt Δ}`` is taken as
``1 + expm1(-σt Δ)`` from the ``expm1`` the step integral needs (one transcendental, not two) and
reused while ``σt`` does not change (homogeneous or boxed media: once per segment). In a noiseless
height fog the fog exponent is linear in the step index, so the factor is ``e^{e_0} q^i`` (one multiply
per step) unless a sample reaches ``FOG_MAX_EXPONENT``; the leg of a point/spot light in an unbounded
noiseless fog is :func:`vlref.medium.optical_depth`'s closed form with the sample's fog factor reused
for the larger end. These change results by rounding only: at most a few ulp per step (measured
≤ 1e-14 relative in float64 and ≤ 3e-6 in float32 against the per-step ``exp`` form). Shadow-map
lookups are inlined (:func:`vlref.lights.shadowmaps.map_lit`); exact shadow rays stay out of line.

Determinism: ``prange`` over pixels only, no cross-pixel reduction: the same bits for any thread count.
"""

from __future__ import annotations

import math

from numba import njit, prange

from ..numeric import cast
from ..lights.pack import I_KIND, KIND_DIRECTIONAL
from ..lights.shading import light_incidence
from ..lights.shadowmaps import (SHADOW_EXACT, SHADOW_NONE, S_MODE, S_STRENGTH, apply_strength, exact_visibility,
                                 map_lit)
from ..medium import (FOG_MAX_EXPONENT, M_BOUNDED, M_FOG, M_FOG_K, M_G, M_NOISE, M_SS, M_ST, clip_to_bounds,
                      density, fog_depth_ratio, fog_exponent, in_bounds, optical_depth)
from ..phase import hg
from .segments import light_segment

__all__ = ["march_physical"]


@njit(cache=True, fastmath=False)
def _march_light(origin, dx, dy, dz, a, b, beta, steps, medium, lights, shadows, geo, k, light_extinction,
                 leg_steps):
    mp, lattice = medium.params, medium.noise
    ox, oy, oz = origin[0], origin[1], origin[2]
    zero = cast(ox, 0.0)
    one = cast(ox, 1.0)
    lr, lg, lb = zero, zero, zero
    ss0, st0, g = mp[M_SS], mp[M_ST], mp[M_G]
    if ss0 == zero:  # nothing scatters
        return lr, lg, lb
    lf = lights.floats
    kind = lights.ints[k, I_KIND]
    mode = shadows.ints[k, S_MODE]
    strength = shadows.floats[k, S_STRENGTH]
    fog, noise = mp[M_FOG] != zero, mp[M_NOISE] != zero
    leg = light_extinction and st0 != zero and not (kind == KIND_DIRECTIONAL and mp[M_BOUNDED] == zero)
    # leg of a point/spot light in an unbounded noiseless fog: the closed form of optical_depth with the
    # sample's own fog factor e^{e_a} reused when it is the larger end (same operations, same bits)
    leg_fog = leg and fog and not noise and mp[M_BOUNDED] == zero and kind != KIND_DIRECTIONAL
    trans = math.exp(-optical_depth(mp, lattice, ox, oy, oz, dx, dy, dz, zero, a, steps))
    delta = (b - a) / cast(ox, steps)
    st_prev, em1 = zero, zero  # em1 = expm1(-st_prev * delta), reused while st is unchanged
    # the fog exponent is linear in the step index: e^{e_i} = e^{e_0} q^i while every sample's exponent
    # lies in (-cap, cap) (no cap reached, no underflow of the running product)
    e_first = fog_exponent(mp, oy + (a + beta * delta) * dy)
    e_last = fog_exponent(mp, oy + (a + (cast(ox, steps - 1) + beta) * delta) * dy)
    cap = cast(ox, FOG_MAX_EXPONENT)
    geometric = fog and not noise and max(e_first, e_last) < cap and min(e_first, e_last) > -cap
    fog_i = math.exp(e_first) if geometric else one
    fog_q = math.exp(-(dy * delta) * mp[M_FOG_K]) if geometric else one
    for i in range(steps):
        t = a + (cast(ox, i) + beta) * delta
        x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
        ea = fog_exponent(mp, y) if fog else zero
        if noise:
            rho = density(mp, lattice, x, y, z)
        elif not in_bounds(mp, x, y, z):
            rho = zero
        elif geometric:
            rho = fog_i
        else:
            rho = math.exp(ea) if fog else one
        fog_i *= fog_q
        st = st0 * rho
        ss = ss0 * rho
        if st != st_prev:
            em1 = math.expm1(-st * delta)
            st_prev = st
        if ss > zero:
            lx, ly, lz, dist, er, eg, eb = light_incidence(lights, k, x, y, z)
            if er + eg + eb > zero:
                vr, vg, vb = one, one, one
                if mode == SHADOW_EXACT:
                    fr, fg, fb = exact_visibility(geo, kind, lf, k, float(x), float(y), float(z))
                elif mode != SHADOW_NONE:
                    fr, fg, fb = map_lit(shadows, kind, lf, k, float(x), float(y), float(z))
                if mode != SHADOW_NONE:
                    fr, fg, fb = apply_strength(strength, fr, fg, fb)
                    vr, vg, vb = cast(ox, fr), cast(ox, fg), cast(ox, fb)
                tl = one
                if leg_fog:
                    el = fog_exponent(mp, y + dist * ly)
                    top = rho if ea >= el else math.exp(el)
                    tl = math.exp(-(st0 * dist * top * fog_depth_ratio(abs(ea - el))))
                elif leg:
                    tl = math.exp(-optical_depth(mp, lattice, x, y, z, lx, ly, lz, zero, dist, leg_steps))
                phase = cast(ox, hg(dx * lx + dy * ly + dz * lz, g))
                s_int = delta if st == zero else -em1 / st
                f = trans * ss * phase * tl * s_int
                lr += f * er * vr
                lg += f * eg * vg
                lb += f * eb * vb
        trans *= one + em1
    return lr, lg, lb


@njit(cache=True, fastmath=False, parallel=True)
def march_physical(origin, dirs, t_end, offsets, steps, medium, lights, shadows, geo, light_extinction, leg_steps,
                   per_light, transmittance):
    """Fill ``per_light`` (n_lights, H, W, 3) and ``transmittance`` (H, W) (module docstring).

    origin (3,), dirs (H, W, 3) unit, t_end (H, W), offsets (H, W) in [0, 1): all in the march's float
    type, like the ``medium`` (:class:`~vlref.medium.PackedMedium`) and the float tables of ``lights``
    (:class:`~vlref.lights.pack.PackedLights`). ``shadows`` a :class:`~vlref.lights.shadowmaps.ShadowTable`;
    ``geo`` the geometry tuple (exact shadows).
    """
    mp, lattice = medium.params, medium.noise
    h, w = t_end.shape
    n = lights.ints.shape[0]
    for p in prange(h * w):
        i, j = p // w, p % w
        dx, dy, dz = dirs[i, j, 0], dirs[i, j, 1], dirs[i, j, 2]
        te = t_end[i, j]
        transmittance[i, j] = math.exp(-optical_depth(mp, lattice, origin[0], origin[1], origin[2], dx, dy, dz,
                                                      cast(te, 0.0), te, steps))
        for k in range(n):
            a, b = light_segment(lights, k, origin[0], origin[1], origin[2], dx, dy, dz, te)
            if b > a:
                a, b = clip_to_bounds(mp, origin[0], origin[1], origin[2], dx, dy, dz, a, b)
            if b <= a:
                per_light[k, i, j, 0] = per_light[k, i, j, 1] = per_light[k, i, j, 2] = cast(te, 0.0)
                continue
            r, g, bl = _march_light(origin, dx, dy, dz, a, b, offsets[i, j], steps, medium, lights, shadows, geo, k,
                                    light_extinction, leg_steps)
            per_light[k, i, j, 0], per_light[k, i, j, 1], per_light[k, i, j, 2] = r, g, bl
