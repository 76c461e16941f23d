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

Evaluation (the same integral, rearranged for speed): the rays are marched in **packets** of up to ``LANES``
(pixel, light) pairs that share a light: every pair takes exactly ``N`` steps, so the lanes of a packet stay
in lockstep. Each step runs as a few *stages*, each a loop over the lanes that reads and writes one row per
quantity of a per-thread scratch array (structure of arrays): positions, medium, the light's direction and
distance law, cone, light leg, then phase and accumulation. A stage without table lookups or libm calls is
vectorised by LLVM (4 lanes per AVX2 instruction, 8 with AVX-512: every function of the march asks for the
widest vectors, :func:`vlref.numeric.prefer_wide_vectors`, which LLVM's tuning for Intel's server cores would
otherwise cap at 256 bits); the stages that look things up — shadow maps and shadow rays, cookies, a Unity
LUT, noise, the ``linear`` cone's ``acos`` — run lane by lane with the scalar helpers. ``exp`` and ``expm1``
are :func:`vlref.numeric.exp` / :func:`vlref.numeric.expm1` (≤ 1 / 2 ulp from libm; a libm call would keep the
loop scalar). Vectorisation never changes a bit: without fast-math LLVM may not reorder arithmetic, and each
lane computes what a scalar loop would. BENCHMARKS.md "Packets of rays" has the measurements.

In a noiseless height fog the fog exponent is linear in the step index, so the density is ``e^{e_0} q^i``
(one multiply per step) unless a sample reaches ``FOG_MAX_EXPONENT``; the leg of a point/spot light in an
unbounded noiseless fog is :func:`vlref.medium.optical_depth`'s closed form with the sample's fog factor
reused for the larger end. ``e^{-σt Δ}`` is ``1 + expm1(-σt Δ)`` from the ``expm1`` the step integral
needs. These change results by rounding only (≤ 1e-14 relative in float64 and ≤ 3e-6 in float32 against
the per-step ``exp`` form).

Determinism: threads take tasks, tiles of pixels (:mod:`vlref.parallel`), each task writes only its own pixels,
no cross-pixel reduction; a lane's arithmetic does not depend on the other lanes of its packet: the same
bits for any thread count and any order in which the tasks are taken.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..lights.attenuation import UNITY, analytic_attenuation, distance_attenuation
from ..lights.cone import CONE_LINEAR, cone_falloff, cone_polynomial
from ..lights.pack import (F_CB, F_CG, F_COS_INNER, F_COS_OUTER, F_CR, F_DX, F_DY, F_DZ, F_HALF_INNER, F_HALF_OUTER,
                           F_INV_RANGE2, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UNITY_A, F_UNITY_B, F_UX, F_UY,
                           F_UZ, I_ATT, I_CK_OFF, I_CONE, I_KIND, KIND_DIRECTIONAL, KIND_SPOT)
from ..lights.shading import cookie_rgb, light_vector
from ..lights.shadowmaps import (SHADOW_EXACT, SHADOW_NONE, SHADOW_PCF, S_MODE, S_OFFSET, S_RES, S_STRENGTH,
                                 apply_strength, exact_visibility, map_lit, pcf_blend, pcf_taps, spot_map_coords)
from ..medium import (FOG_MAX_EXPONENT, M_BOUNDED, M_BX0, M_BX1, M_BY0, M_BY1, M_BZ0, M_BZ1, M_FOG, M_FOG_BASE,
                      M_FOG_K, M_G, M_NOISE, M_SS, M_ST, box_contains, clip_to_bounds, density, fog_depth_ratio,
                      fog_exponent, height_exponent, optical_depth, smooth_optical_depth)
from ..numeric import cast, exp, expm1, prefer_wide_vectors
from ..parallel import WORKERS, borrowed, take
from ..phase import hg
from .segments import light_segment

__all__ = ["march_physical", "LANES", "TILE_W", "TILE_H"]

LANES = 64  # (pixel, light) pairs per packet
# a task (the threads take tasks on demand: vlref.parallel.take) is a tile of TILE_W x TILE_H pixels, two
# packets of 8 x 8: neighbouring samples of a packet read neighbouring shadow-map texels (BENCHMARKS.md
# "Tiles, Estrin's `exp`, a tighter PCF loop")
TILE_W, TILE_H = 8, 16

# offsets of the rows of the scratch array: lane m of row R is s[R + m] (compile-time constants, so LLVM
# sees every row apart and vectorises without run-time alias checks)
ROWS = 34
(R_A, R_D, R_B, R_DX, R_DY, R_DZ, R_TRANS, R_FOG, R_FOGQ, R_GEOM, R_X, R_Y, R_Z, R_EA, R_RHO, R_ST, R_SS, R_EM1,
 R_LX, R_LY, R_LZ, R_DIST, R_D2, R_E, R_ER, R_EG, R_EB, R_TL, R_VR, R_VG, R_VB, R_AR, R_AG, R_AB) = range(0, ROWS * LANES,
                                                                                                        LANES)
# float64 rows: a spot light's shadow-map distance and PCF weights, as map_lit computes them (and the
# uint64 scratch ``taps`` holds the four texel offsets)
QROWS = 7
Q_DREF, Q_AHEAD, Q_W00, Q_W10, Q_W01, Q_W11, Q_LIT = range(0, QROWS * LANES, LANES)


@njit(cache=True, fastmath=False, error_model="numpy")
def _setup(s, n, origin, steps, medium):
    """Lanes ``0..n-1``, whose rows ``R_A`` (``a``), ``R_D`` (``b``), ``R_B`` (``β``) and the direction hold
    their segment: ``Δ`` replaces ``b``; the view transmittance to ``a``, the fog's running product and the
    sums are set (module docstring). Lane loops: vectorised without noise."""
    prefer_wide_vectors()
    mp, lattice = medium.params, medium.noise
    ox, oy, oz = origin[0], origin[1], origin[2]
    zero, one = cast(ox, 0.0), cast(ox, 1.0)
    fsteps = cast(ox, steps)
    for m in range(n):
        s[R_D + m] = (s[R_D + m] - s[R_A + m]) / fsteps
    if mp[M_NOISE] != zero:  # optical_depth's sub-step loop; without noise its closed form, a vectorised loop
        for m in range(n):
            s[R_TRANS + m] = exp(-optical_depth(mp, lattice, ox, oy, oz, s[R_DX + m], s[R_DY + m], s[R_DZ + m],
                                                zero, s[R_A + m], steps))
    else:
        for m in range(n):
            s[R_TRANS + m] = exp(-smooth_optical_depth(mp, ox, oy, oz, s[R_DX + m], s[R_DY + m], s[R_DZ + m],
                                                       zero, s[R_A + m]))
    cap = cast(ox, FOG_MAX_EXPONENT)
    smooth_fog = mp[M_FOG] != zero and mp[M_NOISE] == zero
    for m in range(n):
        a, delta, beta, dy = s[R_A + m], s[R_D + m], s[R_B + m], s[R_DY + m]
        e_first = fog_exponent(mp, oy + (a + beta * delta) * dy)
        e_last = fog_exponent(mp, oy + (a + (fsteps - one + beta) * delta) * dy)
        geometric = smooth_fog and max(e_first, e_last) < cap and min(e_first, e_last) > -cap
        s[R_GEOM + m] = one if geometric else zero
        s[R_FOG + m] = exp(e_first) if geometric else one
        s[R_FOGQ + m] = exp(-(dy * delta) * mp[M_FOG_K]) if geometric else one
        s[R_AR + m] = s[R_AG + m] = s[R_AB + m] = zero


@njit(cache=True, fastmath=False, error_model="numpy")
def _medium_stage(s, n, i, origin, medium, geometric):
    """Sample positions ``x = o + t d``, ``t = a + (i + β) Δ``; density, ``σs``, ``σt``, ``expm1(-σt Δ)``.
    ``geometric``: every lane takes the fog's running product.
    The vectorised loops read only scalars and ``s`` (an array read inside a lane loop costs reference
    counting calls, which keep the loop scalar)."""
    prefer_wide_vectors()
    mp, lattice = medium.params, medium.noise
    ox, oy, oz = origin[0], origin[1], origin[2]
    zero, one = cast(ox, 0.0), cast(ox, 1.0)
    fog, noise, bounded = mp[M_FOG] != zero, mp[M_NOISE] != zero, mp[M_BOUNDED] != zero
    base, falloff = mp[M_FOG_BASE], mp[M_FOG_K]
    x0, y0, z0, x1, y1, z1 = mp[M_BX0], mp[M_BY0], mp[M_BZ0], mp[M_BX1], mp[M_BY1], mp[M_BZ1]
    ss0, st0 = mp[M_SS], mp[M_ST]
    fi = cast(ox, i)
    for m in range(n):
        t = s[R_A + m] + (fi + s[R_B + m]) * s[R_D + m]
        x, y, z = ox + t * s[R_DX + m], oy + t * s[R_DY + m], oz + t * s[R_DZ + m]
        s[R_X + m], s[R_Y + m], s[R_Z + m] = x, y, z
        s[R_EA + m] = height_exponent(base, falloff, y) if fog else zero
    if noise:
        for m in range(n):
            s[R_RHO + m] = density(mp, lattice, s[R_X + m], s[R_Y + m], s[R_Z + m])
    else:  # smooth_density, with the fog's running product where it holds (on every lane: no exp at all)
        for m in range(n):
            inside = not bounded or box_contains(x0, y0, z0, x1, y1, z1, s[R_X + m], s[R_Y + m],
                                                 s[R_Z + m])
            running = s[R_FOG + m]
            if geometric:
                rho = running
            else:
                rho = running if s[R_GEOM + m] != zero else (exp(s[R_EA + m]) if fog else one)
            s[R_RHO + m] = rho if inside else zero
            s[R_FOG + m] = running * s[R_FOGQ + m]
    for m in range(n):
        rho = s[R_RHO + m]
        st = st0 * rho
        s[R_ST + m], s[R_SS + m] = st, ss0 * rho
        s[R_EM1 + m] = expm1(-st * s[R_D + m])


@njit(cache=True, fastmath=False, error_model="numpy")
def _light_stage(s, n, lights, k):
    """Direction ``l`` toward light ``k``, distance and ``E`` without colour: distance law × cone (0 at the
    light's own position), then ``E`` per channel with the colour and the cookie."""
    prefer_wide_vectors()
    li, lf = lights.ints, lights.floats
    kind, law, cone = li[k, I_KIND], li[k, I_ATT], li[k, I_CONE]
    zero, one = cast(lf[0, 0], 0.0), cast(lf[0, 0], 1.0)
    if kind == KIND_DIRECTIONAL:
        for m in range(n):
            s[R_LX + m], s[R_LY + m], s[R_LZ + m] = -lf[k, F_DX], -lf[k, F_DY], -lf[k, F_DZ]
            s[R_DIST + m] = cast(one, np.inf)
            s[R_E + m] = one
    else:
        inv_r2 = lf[k, F_INV_RANGE2]
        px, py, pz = lf[k, F_PX], lf[k, F_PY], lf[k, F_PZ]
        for m in range(n):
            lx, ly, lz, dist, d2 = light_vector(px, py, pz, s[R_X + m], s[R_Y + m], s[R_Z + m])
            s[R_LX + m], s[R_LY + m], s[R_LZ + m], s[R_DIST + m], s[R_D2 + m] = lx, ly, lz, dist, d2
        if law == UNITY and lights.lut.size > 0:
            for m in range(n):
                s[R_E + m] = distance_attenuation(law, s[R_D2 + m], inv_r2, lights.lut)
        else:
            for m in range(n):
                s[R_E + m] = analytic_attenuation(law, s[R_D2 + m], inv_r2)
        for m in range(n):
            s[R_E + m] = s[R_E + m] if s[R_D2 + m] != zero else zero
        if kind == KIND_SPOT:
            ax, ay, az = lf[k, F_DX], lf[k, F_DY], lf[k, F_DZ]
            co, ci, ua, ub = lf[k, F_COS_OUTER], lf[k, F_COS_INNER], lf[k, F_UNITY_A], lf[k, F_UNITY_B]
            if cone == CONE_LINEAR:
                for m in range(n):
                    cos_t = -(s[R_LX + m] * ax + s[R_LY + m] * ay + s[R_LZ + m] * az)
                    s[R_E + m] *= cone_falloff(cone, cos_t, co, ci, lf[k, F_HALF_OUTER], lf[k, F_HALF_INNER],
                                                   ua, ub)
            else:
                for m in range(n):
                    cos_t = -(s[R_LX + m] * ax + s[R_LY + m] * ay + s[R_LZ + m] * az)
                    s[R_E + m] *= cone_polynomial(cone, cos_t, co, ci, ua, ub)
    cr, cg, cb = lf[k, F_CR], lf[k, F_CG], lf[k, F_CB]
    for m in range(n):
        e = s[R_E + m]
        s[R_ER + m], s[R_EG + m], s[R_EB + m] = e * cr, e * cg, e * cb
    if li[k, I_CK_OFF] >= 0:
        for m in range(n):
            if s[R_E + m] != zero:
                r, g, b = cookie_rgb(lights, k, s[R_X + m], s[R_Y + m], s[R_Z + m])
                s[R_ER + m] *= cast(one, r)
                s[R_EG + m] *= cast(one, g)
                s[R_EB + m] *= cast(one, b)


@njit(cache=True, fastmath=False, error_model="numpy")
def _leg_stage(s, n, medium, kind, light_y, light_extinction, leg_steps):
    """Light-leg transmittance ``T_l`` (module docstring): 1, the height-fog closed form (vectorised), or
    :func:`~vlref.medium.optical_depth` lane by lane."""
    prefer_wide_vectors()
    mp, lattice = medium.params, medium.noise
    zero, one = cast(mp[0], 0.0), cast(mp[0], 1.0)
    st0 = mp[M_ST]
    bounded, noise = mp[M_BOUNDED] != zero, mp[M_NOISE] != zero
    if not light_extinction or st0 == zero or (kind == KIND_DIRECTIONAL and not bounded):
        for m in range(n):
            s[R_TL + m] = one
    elif mp[M_FOG] != zero and not noise and not bounded and kind != KIND_DIRECTIONAL:
        el = height_exponent(mp[M_FOG_BASE], mp[M_FOG_K], light_y)  # the leg ends at the light
        fog_l = exp(el)
        for m in range(n):
            dist, ea, rho = s[R_DIST + m], s[R_EA + m], s[R_RHO + m]
            top = rho if ea >= el else fog_l
            s[R_TL + m] = exp(-(st0 * dist * top * fog_depth_ratio(abs(ea - el))))
    else:
        for m in range(n):
            s[R_TL + m] = exp(-optical_depth(mp, lattice, s[R_X + m], s[R_Y + m], s[R_Z + m],
                                                 s[R_LX + m], s[R_LY + m], s[R_LZ + m], zero,
                                                 s[R_DIST + m], leg_steps))


@njit(cache=True, fastmath=False, error_model="numpy")
def _shadow_stage(s, q, taps, n, shadows, geo, lights, k):
    """Visibility ``V`` per channel (strength applied) where the sample scatters light; 1 elsewhere. A spot
    light's PCF lookup without a transparent layer has its map coordinates, weights and texel offsets computed
    in one vectorised loop (float64 rows of ``q``, ``taps``), its four depth reads in a second loop that writes
    every lane's lit fraction (no branch: a read skipped for lanes that scatter nothing made the loop branch on
    every lane, and the lit fraction a row of its own keeps LLVM from moving the reads back under the
    condition), and ``V`` in a third, vectorised loop. LLVM keeps the reads scalar on AVX-512 too (its cost
    model for Zen 4 and Sapphire Rapids emits no gathers). Every other lookup is
    :func:`~vlref.lights.shadowmaps.map_lit` or a shadow ray, lane by lane."""
    prefer_wide_vectors()
    kind = lights.ints[k, I_KIND]
    mode = shadows.ints[k, S_MODE]
    strength = shadows.floats[k, S_STRENGTH]
    zero, one = cast(lights.floats[0, 0], 0.0), cast(lights.floats[0, 0], 1.0)
    lf = lights.floats
    sm_i, data = shadows.ints, shadows.data
    if kind == KIND_SPOT and mode == SHADOW_PCF and shadows.tint.shape[0] == 0:
        px, py, pz = float(lf[k, F_PX]), float(lf[k, F_PY]), float(lf[k, F_PZ])
        rx, ry, rz = float(lf[k, F_RX]), float(lf[k, F_RY]), float(lf[k, F_RZ])
        ux, uy, uz = float(lf[k, F_UX]), float(lf[k, F_UY]), float(lf[k, F_UZ])
        dx, dy, dz = float(lf[k, F_DX]), float(lf[k, F_DY]), float(lf[k, F_DZ])
        tan_half = float(lf[k, F_TAN_HALF])
        res, ubase = sm_i[k, S_RES], np.uint64(sm_i[k, S_OFFSET])
        for m in range(n):
            u, v, d_ref, ahead = spot_map_coords(float(s[R_X + m]) - px, float(s[R_Y + m]) - py,
                                                 float(s[R_Z + m]) - pz, rx, ry, rz, ux, uy, uz, dx, dy, dz,
                                                 tan_half)
            (k00, k10, k01, k11), (w00, w10, w01, w11) = pcf_taps(u, v, res)
            q[Q_DREF + m] = d_ref
            q[Q_AHEAD + m] = 1.0 if ahead else 0.0
            q[Q_W00 + m], q[Q_W10 + m], q[Q_W01 + m], q[Q_W11 + m] = w00, w10, w01, w11
            taps[m], taps[1 * LANES + m] = np.uint64(k00), np.uint64(k10)
            taps[2 * LANES + m], taps[3 * LANES + m] = np.uint64(k01), np.uint64(k11)
        # every lane reads its taps (always inside the map: pcf_taps clamps them); lanes that scatter nothing
        # keep V = 1 in the loop after
        for m in range(n):
            q[Q_LIT + m] = pcf_blend(data, ubase, taps[m], taps[1 * LANES + m], taps[2 * LANES + m],
                                     taps[3 * LANES + m], q[Q_W00 + m], q[Q_W10 + m], q[Q_W01 + m], q[Q_W11 + m],
                                     q[Q_DREF + m])
        for m in range(n):
            fr, _, _ = apply_strength(strength, q[Q_LIT + m], q[Q_LIT + m], q[Q_LIT + m])
            used = q[Q_AHEAD + m] != 0.0 and s[R_SS + m] > zero and s[R_ER + m] + s[R_EG + m] + s[R_EB + m] > zero
            v = cast(one, fr) if used else one
            s[R_VR + m], s[R_VG + m], s[R_VB + m] = v, v, v
        return
    for m in range(n):  # the PCF loop above writes every lane; here V = 1 unless a lookup says otherwise
        s[R_VR + m] = s[R_VG + m] = s[R_VB + m] = one
    if mode == SHADOW_NONE:
        return
    for m in range(n):
        if s[R_SS + m] > zero and s[R_ER + m] + s[R_EG + m] + s[R_EB + m] > zero:
            x, y, z = float(s[R_X + m]), float(s[R_Y + m]), float(s[R_Z + m])
            if geo is not None and mode == SHADOW_EXACT:  # geo None: Numba prunes the branch (no ray tracer)
                fr, fg, fb = exact_visibility(geo, kind, lf, k, x, y, z)
            else:
                fr, fg, fb = map_lit(shadows, kind, lf, k, x, y, z)
            fr, fg, fb = apply_strength(strength, fr, fg, fb)
            s[R_VR + m], s[R_VG + m], s[R_VB + m] = cast(one, fr), cast(one, fg), cast(one, fb)


@njit(cache=True, fastmath=False, error_model="numpy")
def _accumulate_stage(s, n, g):
    """``L += T σs p(d·l) T_l (1 - e^{-σt Δ})/σt · E V``, then ``T *= e^{-σt Δ}`` (module docstring)."""
    prefer_wide_vectors()
    zero, one = cast(g, 0.0), cast(g, 1.0)
    for m in range(n):
        st, ss, em1, delta = s[R_ST + m], s[R_SS + m], s[R_EM1 + m], s[R_D + m]
        er, eg, eb = s[R_ER + m], s[R_EG + m], s[R_EB + m]
        cos_t = s[R_DX + m] * s[R_LX + m] + s[R_DY + m] * s[R_LY + m] + s[R_DZ + m] * s[R_LZ + m]
        phase = cast(g, hg(cos_t, g))
        s_int = delta if st == zero else -em1 / st
        f = s[R_TRANS + m] * ss * phase * s[R_TL + m] * s_int
        lit = ss > zero and er + eg + eb > zero
        s[R_AR + m] += f * er * s[R_VR + m] if lit else zero
        s[R_AG + m] += f * eg * s[R_VG + m] if lit else zero
        s[R_AB + m] += f * eb * s[R_VB + m] if lit else zero
        s[R_TRANS + m] *= one + em1


@njit(cache=True, fastmath=False, error_model="numpy")
def _march_packet(s, q, taps, n, pix, w, k, steps, origin, medium, lights, shadows, geo, light_extinction, leg_steps,
                  per_light):
    """March the ``n`` lanes set up in ``s`` (pixels ``pix``, image width ``w``) through light ``k`` and store
    their in-scattered radiance in ``per_light[k]`` (module docstring)."""
    prefer_wide_vectors()
    kind = lights.ints[k, I_KIND]
    light_y = lights.floats[k, F_PY]
    g = medium.params[M_G]
    n_geometric = 0
    for m in range(n):
        n_geometric += s[R_GEOM + m] != 0.0
    geometric = n_geometric == n  # a bool, never Literal[bool](True): _medium_stage would compile twice
    for i in range(steps):
        _medium_stage(s, n, i, origin, medium, geometric)
        _light_stage(s, n, lights, k)
        _leg_stage(s, n, medium, kind, light_y, light_extinction, leg_steps)
        _shadow_stage(s, q, taps, n, shadows, geo, lights, k)
        _accumulate_stage(s, n, g)
    for m in range(n):
        i, j = pix[m] // w, pix[m] % w
        per_light[k, i, j, 0], per_light[k, i, j, 1], per_light[k, i, j, 2] = (s[R_AR + m], s[R_AG + m],
                                                                                 s[R_AB + m])


@njit(cache=True, fastmath=False, error_model="numpy")
def _march_tasks(taken, steps, light_extinction, leg_steps, origin, dirs, t_end, offsets, medium, lights, shadows, geo,
                 per_light, transmittance):
    """Take tasks, tiles of ``TILE_W x TILE_H`` pixels in row-major order of tiles (:func:`vlref.parallel.take`
    on ``taken``), until none is left; per task, its pixels' transmittance, then per light its pairs with a
    non-empty segment in packets of up to ``LANES``, set up by :func:`_setup` (module docstring)."""
    prefer_wide_vectors()
    mp, lattice = medium.params, medium.noise
    ox, oy, oz = origin[0], origin[1], origin[2]
    h, w = t_end.shape
    zero = cast(ox, 0.0)
    s = np.empty(ROWS * LANES, dtype=t_end.dtype)
    q = np.empty(QROWS * LANES, dtype=np.float64)
    taps = np.empty(4 * LANES, dtype=np.uint64)
    pix = np.empty(LANES, dtype=np.int64)
    tiles_x = (w + TILE_W - 1) // TILE_W
    tiles = tiles_x * ((h + TILE_H - 1) // TILE_H)
    while True:
        task = take(taken)
        if task >= tiles:
            return
        i0, j0 = (task // tiles_x) * TILE_H, (task % tiles_x) * TILE_W
        i1, j1 = min(h, i0 + TILE_H), min(w, j0 + TILE_W)
        for i in range(i0, i1):
            for j in range(j0, j1):
                transmittance[i, j] = exp(-optical_depth(mp, lattice, ox, oy, oz, dirs[i, j, 0], dirs[i, j, 1],
                                                         dirs[i, j, 2], zero, t_end[i, j], steps))
        for k in range(lights.ints.shape[0]):
            n = np.int64(0)  # not the literal 0: _march_packet would compile a second time for Literal[int](0)
            for i in range(i0, i1):
                for j in range(j0, j1):
                    dx, dy, dz = dirs[i, j, 0], dirs[i, j, 1], dirs[i, j, 2]
                    a, b = light_segment(lights, k, ox, oy, oz, dx, dy, dz, t_end[i, j])
                    if b > a:
                        a, b = clip_to_bounds(mp, ox, oy, oz, dx, dy, dz, a, b)
                    if b <= a:
                        per_light[k, i, j, 0] = per_light[k, i, j, 1] = per_light[k, i, j, 2] = zero
                        continue
                    s[R_A + n], s[R_D + n], s[R_B + n] = a, b, offsets[i, j]
                    s[R_DX + n], s[R_DY + n], s[R_DZ + n] = dx, dy, dz
                    pix[n] = i * w + j
                    n += 1
                    if n == LANES:
                        _setup(s, n, origin, steps, medium)
                        _march_packet(s, q, taps, n, pix, w, k, steps, origin, medium, lights, shadows, geo,
                                      light_extinction, leg_steps, per_light)
                        n = np.int64(0)
            if n > 0:
                _setup(s, n, origin, steps, medium)
                _march_packet(s, q, taps, n, pix, w, k, steps, origin, medium, lights, shadows, geo, light_extinction,
                              leg_steps, per_light)


@njit(cache=True, fastmath=False, error_model="numpy", parallel=True)
def march_physical(origin, dirs, t_end, offsets, steps, medium, lights, shadows, geo, light_extinction, leg_steps,
                   per_light, transmittance):
    """Fill ``per_light`` (n_lights, H, W, 3) and ``transmittance`` (H, W) (module docstring).

    origin (3,), dirs (H, W, 3) unit, t_end (H, W), offsets (H, W) in [0, 1): all in the march's float
    type, like the ``medium`` (:class:`~vlref.medium.PackedMedium`) and the float tables of ``lights``
    (:class:`~vlref.lights.pack.PackedLights`). ``shadows`` a :class:`~vlref.lights.shadowmaps.ShadowTable`;
    ``geo`` the geometry tuple for ``exact`` shadows, or None where no light has them: the kernel is then
    compiled without the ray tracer (its compile takes about a third less; BENCHMARKS.md "Scheduling,
    borrowed records, a leaner compile").

    The pixels are split in tasks, tiles of ``TILE_W x TILE_H`` pixels. The threads of a ``prange`` over
    :data:`~vlref.parallel.WORKERS` take tasks on demand until none is left (:mod:`vlref.parallel`: a
    pixel's cost varies from nothing to hundreds of samples, and ``prange``'s own split is static), each
    marched in packets of up to ``LANES`` (pixel, light) pairs. The workers get the arrays without reference
    counts (:func:`vlref.parallel.borrowed`: the stages take the records on every step).
    """
    if geo is None:
        for k in range(shadows.ints.shape[0]):
            if shadows.ints[k, S_MODE] == SHADOW_EXACT:
                raise ValueError("march_physical: a light has exact shadows, and geo is None")
    taken = np.zeros(1, dtype=np.int64)
    for _ in prange(WORKERS):
        o, d, te, off, med, lts, shd, gg, out, tr = borrowed((origin, dirs, t_end, offsets, medium, lights, shadows,
                                                              geo, per_light, transmittance))
        _march_tasks(taken, steps, light_extinction, leg_steps, o, d, te, off, med, lts, shd, gg, out, tr)
