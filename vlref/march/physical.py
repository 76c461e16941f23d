"""The physical single-scattering march (docs/PHYSICS.md "The integral"; Hillaire 2015 step integration).

:func:`vlref.reference.integrand.inscatter` is the same physics, one sample at a time: the quadrature
reference evaluates that integrand exactly where this march sums it step by step.

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
   ``S_int = S · (1 - e^{-σt Δ}) / σt`` (:func:`vlref.medium.step_source_weight`: ``S · Δ`` when
   ``σt = 0``; computed with ``expm1``), ``L += T · S_int``, then ``T *= e^{-σt Δ}`` (Beer–Lambert over
   the step); ``T`` starts at ``exp(-τ(0, a))``.

Every light adds under the same view transmittance ``T(0, t)``. The pixel's transmittance is
``exp(-τ(0, t_end))``. Optical depths ``τ`` are analytic without noise and midpoint sums of ``N``
sub-steps with noise (:func:`vlref.medium.optical_depth`).

Light leg ``T_l`` (``light_extinction``, :func:`vlref.medium.light_leg_attenuates`): ``exp(-τ)`` from the
sample to a point or spot light; for a directional light, to where the ray toward the light leaves the
medium box. **An unbounded medium gives a directional light ``T_l = 1``**: its irradiance ``E`` is taken
as the irradiance arriving at the sample (an infinite homogeneous medium would otherwise extinguish it
completely); bound the medium with ``medium.bounds`` to attenuate sunlight on its way in. With noise the
leg uses ``leg_steps`` midpoint sub-steps. In a noiseless height fog without bounds, the leg of a
point/spot light is :func:`vlref.medium.optical_depth`'s closed form, ``σt`` times the distance times the fog
factor's mean along the leg (:func:`vlref.medium.fog_mean_factor`) of the sample's factor and the light's: the
difference of the two factors over the gap of their exponents, no ``exp`` of its own; in a homogeneous medium
without bounds, ``τ = σt`` times the distance to the light.

The stages of one step, each a function below, in the order they run (:func:`_march_packet`):

=======================  ===============================================================================
:func:`_medium_stage`    the sample ``x = o + t_i d``; density, ``σs``, ``σt``; Beer–Lambert over the step,
                         ``expm1(-σt Δ)``
:func:`_light_stage`     the light: direction ``l`` and distance, distance law × cone (its attenuation and
                         cone), colour and cookie: ``E_l``
:func:`_leg_stage`       the light leg ``T_l``: Beer–Lambert from the sample to the light
:func:`_shadow_stage`    the shadow lookup ``V`` (map or shadow ray, the light's strength applied)
:func:`_accumulate_stage` the phase function ``p(d·l)`` and the accumulation ``L += T S_int``,
                         ``T *= e^{-σt Δ}``
=======================  ===============================================================================

Order of convergence in ``Δ`` (smooth integrand): the per-step source is a rectangle rule at offset
``β``, so the error is ``≈ (1/2 - β) Δ [f(b) - f(a)] + O(Δ²)``: first order for ``β ≠ 1/2``
(``none``, Bayer, hash offsets), second order for ``β = 1/2`` (midpoint); the transmittance update
is exact for a constant ``σt`` per step.

Precision: the kernel is compiled for float64 and float32 inputs; in float32 every quantity of the
march is float32 (``zero, one = zero_one(scratch)``, then constants through :func:`vlref.numeric.cast`,
the HG value included) except texture/shadow-map coordinates and filter weights (float64, as a GPU's
fixed-point sampler would be its own) and exact shadow rays (the geometry is float64).

Determinism: threads take tasks, tiles of pixels (:mod:`vlref.parallel`), each task writes only its own pixels,
no cross-pixel reduction; a lane's arithmetic does not depend on the other lanes of its packet: the same
bits for any thread count and any order in which the tasks are taken.

Performance (how the sum above is evaluated; none of it changes a bit; BENCHMARKS.md "Packets of rays",
"Tiles, Estrin's `exp`, a tighter PCF loop", "Scheduling, borrowed records, a leaner compile"):

* Packets: the rays are marched in packets of up to ``LANES`` (pixel, light) pairs that share a light;
  every pair takes exactly ``N`` steps, so the lanes of a packet stay in lockstep. A task is a tile of
  ``TILE_W x TILE_H`` pixels, two packets of 8 x 8: neighbouring samples read neighbouring shadow-map
  texels.
* Lanes: each stage is a few loops over the lanes that read and write the packet's *scratch*, one row of
  ``LANES`` values per quantity (structure of arrays, rows ``R_*``; :func:`lane` / :func:`set_lane` and
  the three-row :func:`lane3` / :func:`set_lane3` name them; Numba inlines them in its IR, ``inline="always"``,
  so each is the plain ``scratch[R + m]`` to LLVM, with no call or reference count around it). The
  rows of one array at compile-time constant offsets let LLVM see every row apart and vectorise without
  run-time alias checks.
* Vectorisation: a lane loop without table lookups or libm calls is vectorised by LLVM (4 lanes per AVX2
  instruction, 8 with AVX-512: every function of the march asks for the widest vectors,
  :func:`vlref.numeric.prefer_wide_vectors`, which LLVM's tuning for Intel's server cores would otherwise
  cap at 256 bits). The loops that look things up — shadow maps and shadow rays, cookies, a Unity LUT,
  noise, the ``linear`` cone's ``acos`` — run lane by lane with the scalar helpers. ``exp`` and ``expm1``
  are :func:`vlref.numeric.exp` / :func:`vlref.numeric.expm1` (≤ 1 / 2 ulp from libm; a libm call would
  keep the loop scalar). Without fast-math LLVM may not reorder arithmetic, and each lane computes what a
  scalar loop would. The vectorised loops read only scalars and the scratch: a record's array read inside
  a lane loop costs reference-counting calls, which keep the loop scalar.
* A PCF lookup without a transparent layer (:func:`_shadow_stage`; spot, cube and cascaded maps alike) runs as
  three loops: map coordinates, weights and texel offsets (per kind of map, with selects for the cube face and
  the cascade, not table lookups or branches; vectorised, float64 rows ``Q_*`` and the uint64 ``taps``), the
  four depth reads for every lane (no branch: a read skipped for lanes that scatter nothing made the loop
  branch on every lane, and the lit fraction in a row of its own keeps LLVM from moving the reads back
  under the condition; with the arrays declared apart, :func:`_lit_fraction`, hardware gathers on AVX-512),
  then ``V`` (vectorised).
* Height fog: in a noiseless fog the fog exponent is linear in the step index, so the density is
  ``e^{e_0} q^i`` (one multiply per step, rows ``R_FOG``/``R_FOG_STEP``) unless a sample reaches
  ``FOG_MAX_EXPONENT``. ``e^{-σt Δ}`` is ``1 + expm1(-σt Δ)`` from the ``expm1`` the step integral needs.
  These change results by rounding only (≤ 1e-14 relative in float64 and ≤ 3e-6 in float32 against the
  per-step ``exp`` form). The light leg takes the sample's factor from the running product too: the fog factor's
  mean along the leg is the difference of the sample's and the light's factors over the gap of their exponents
  (:func:`vlref.medium.fog_mean_factor`, a series below its cut), where the closed form's ``(1 - e^{-δ})/δ``
  took an ``expm1`` per sample (BENCHMARKS.md "The fog leg without its expm1").
* Outside the steps (a sixth of a 1080p march of one light on the device; BENCHMARKS.md "The march outside its
  steps"): each pixel's view transmittance in a noiseless medium in a loop of its own (:func:`_smooth_transmittance`,
  the closed form without :func:`~vlref.medium.optical_depth`'s noise loop), the fog's running product
  set up per lane without branches (``max`` and ``min`` written out: Numba's builtins stayed calls in that loop),
  and a packet's radiance stored by its pixels' flat index (no division per lane). All of them vectorise.
* Compilation: counts and flags are passed as ``np.int64`` / plain ``bool`` values, never literals (a
  ``Literal[int](0)`` or ``Literal[bool](True)`` argument compiles a function a second time); ``geo`` None
  compiles the march without the ray tracer (:func:`march_physical`).
* Measured, not adopted (BENCHMARKS.md "The march: shadow-map tiles and prefetches, measured, not adopted"): the
  PCF maps copied into tiles of 8 x 8 texels for the march, a prefetch of each lane's next-step texels, every lane
  loop over all ``LANES`` lanes (a constant trip count), the spot map's coordinates and reads in one loop. None was
  faster; what binds the march is the float64 work per sample, which the float32 mode does not narrow (``exp`` and
  ``expm1`` in float64, the map coordinates and texels in float64, the same quotients and roots), and the gathers'
  wait on the memory (about a tenth of the time on Zen 4). Three of a sample's six divisions taken away by exact
  algebra (BENCHMARKS.md "The march: fewer divisions per sample, measured, not adopted": the albedo ``σs/σt`` per
  medium, ``1/d² = (1/d)²``, the phase function's and the fog leg's divisions as one) moved the last bits and
  bought nothing on the device: the divider does not bind the march either.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..jit import njit
from ..lights.attenuation import UNITY, analytic_attenuation, distance_attenuation
from ..lights.cone import CONE_LINEAR, CONE_UNITY, cone_falloff, cone_polynomial
from ..lights.pack import (F_CB, F_CG, F_COS_INNER, F_COS_OUTER, F_CR, F_DX, F_DY, F_DZ, F_HALF_INNER, F_HALF_OUTER,
                           F_INV_RANGE2, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UNITY_A, F_UNITY_B, F_UX, F_UY,
                           F_UZ, I_ATT, I_CK_OFF, I_CONE, I_KIND, KIND_DIRECTIONAL, KIND_SPOT)
from ..lights.shading import cookie_rgb, light_vector
from ..lights.shadow_lookup import (apply_strength, cascade_map_coords, cube_map_coords, exact_visibility, map_lit,
                                    pcf_blend, pcf_taps, spot_map_coords)
from ..lights.shadow_pack import (SHADOW_EXACT, SHADOW_NONE, SHADOW_PCF, S_CASC, S_CASCADES, S_MODE, S_OFFSET, S_RES,
                                  S_STRENGTH)
from ..medium import (FOG_MAX_EXPONENT, M_BOUNDED, M_BX0, M_BX1, M_BY0, M_BY1, M_BZ0, M_BZ1, M_FOG, M_FOG_BASE,
                      M_FOG_K, M_G, M_NOISE, M_SS, M_ST, box_contains, clip_to_bounds, density, fog_mean_factor,
                      fog_exponent, height_exponent, light_leg_attenuates, optical_depth, smooth_optical_depth,
                      step_source_weight)
from ..numeric import arrays_do_not_overlap, cast, exp, expm1, is_float64, prefer_wide_vectors, zero_one
from ..parallel import COUNTER, WORKERS, borrowed, take, work
from ..phase import hg
from .segments import light_segment

__all__ = ["march_physical", "march_tiles", "LANES", "TILE_W", "TILE_H"]

LANES = 64  # (pixel, light) pairs per packet
TILE_W, TILE_H = 8, 16  # a task: a tile of TILE_W x TILE_H pixels, two packets of 8 x 8 (module docstring)

# The packet's scratch (module docstring, "Lanes"): lane m of row R is scratch[R + m]. A row named for a
# vector or a colour is the first of three consecutive rows, (x, y, z) or (r, g, b).
ROWS = 35
R_START = 0 * LANES  # a, the segment's start
R_DELTA = 1 * LANES  # b, the segment's end, until _setup replaces it by the step Δ = (b - a)/N
R_BETA = 2 * LANES  # β, the pixel's sample offset in [0, 1)
R_DIR = 3 * LANES  # (3) d, the unit view direction
R_T_VIEW = 6 * LANES  # T, the view transmittance from the eye to the step's start
R_FOG = 7 * LANES  # the height fog's factor e^{e_i} at the next sample (running product)
R_FOG_STEP = 8 * LANES  # the running product's ratio q per step
R_GEOMETRIC = 9 * LANES  # 1 where the lane takes the running product, else 0
R_POS = 10 * LANES  # (3) x = o + t d, the sample
R_FOG_EXP = 13 * LANES  # the fog exponent at the sample (0 without fog)
R_RHO = 14 * LANES  # ρ, the density factor at the sample
R_SIGMA_T = 15 * LANES  # σt, extinction (1/m)
R_SIGMA_S = 16 * LANES  # σs, scattering (1/m)
R_EM1 = 17 * LANES  # expm1(-σt Δ), Beer–Lambert over the step
R_TO_LIGHT = 18 * LANES  # (3) l, the unit vector toward the light
R_DIST = 21 * LANES  # the distance to the light (inf for a directional light)
R_DIST2 = 22 * LANES  # its square
R_E = 23 * LANES  # distance law × cone
R_E_RGB = 24 * LANES  # (3) E_l: × colour × cookie
R_T_LIGHT = 27 * LANES  # T_l, the light leg's transmittance
R_VIS = 28 * LANES  # (3) V, the shadow visibility per channel
R_L = 31 * LANES  # (3) L, the radiance scattered toward the eye so far
R_COS = 34 * LANES  # cos θ = -l · (the spot's axis), the cone's argument
# float64 rows of a PCF map lookup (as map_lit computes them): the sample's map coordinates (u, v; cascades only)
# and depth, whether the map covers it (in front of a spot light, on a cube face, inside a cascade), the four texel
# weights, the lit fraction; the uint64 rows of ``taps``: the cascade's first texel, then the four texel offsets
QROWS = 9
Q_U, Q_V, Q_DREF, Q_ON_MAP, Q_W00, Q_W10, Q_W01, Q_W11, Q_LIT = range(0, QROWS * LANES, LANES)
T_FACE, T_00, T_10, T_01, T_11 = range(0, 5 * LANES, LANES)


@njit(cache=True, fastmath=False, error_model="numpy", inline="always")
def lane(scratch, row, m):
    """Lane ``m`` of ``row`` (an ``R_*``, ``Q_*`` or ``T_*`` offset) of a packet's scratch."""
    return scratch[row + m]


@njit(cache=True, fastmath=False, error_model="numpy", inline="always")
def set_lane(scratch, row, m, value):
    """Store ``value`` in lane ``m`` of ``row`` (in the scratch's type)."""
    scratch[row + m] = value


@njit(cache=True, fastmath=False, error_model="numpy", inline="always")
def lane3(scratch, row, m):
    """Lane ``m`` of the three rows from ``row``: a vector ``(x, y, z)`` or a colour ``(r, g, b)``."""
    return scratch[row + m], scratch[row + LANES + m], scratch[row + 2 * LANES + m]


@njit(cache=True, fastmath=False, error_model="numpy", inline="always")
def set_lane3(scratch, row, m, a, b, c):
    """Store ``(a, b, c)`` in lane ``m`` of the three rows from ``row``."""
    scratch[row + m] = a
    scratch[row + LANES + m] = b
    scratch[row + 2 * LANES + m] = c


@njit(cache=True, fastmath=False, error_model="numpy", inline="always")
def scatters_light(ss, er, eg, eb):
    """The sample scatters light of this light: ``σs > 0`` and ``E_l ≠ 0`` (no shadow lookup elsewhere)."""
    zero = cast(ss, 0.0)
    return ss > zero and er + eg + eb > zero


@njit(cache=True, fastmath=False, error_model="numpy", inline="always")
def reuses_distance(s):
    """Whether a map lookup takes the sample's distance to a spot or point light (the map depth ``d_ref``) from the
    light stage's ``R_DIST`` instead of its own square root: in float64 (a constant of the compile,
    :func:`vlref.numeric.is_float64`), where both are ``sqrt(wx² + wy² + wz²)`` of the same float64 ``w = ±(x - p)``
    (a negation is exact), summed in the same order: the same bits. In float32 the light stage computes in float32
    and the map in float64, so each keeps its own."""
    return is_float64(s)


@njit(cache=True, fastmath=False, error_model="numpy", inline="always")
def set_texels(q, taps, m, u, v, res, first):
    """Lane ``m``'s four PCF texels around ``(u, v)`` on a ``res``² face whose first texel is ``first``
    (:func:`~vlref.lights.shadow_lookup.pcf_taps`: offsets clamped to the face) and their weights."""
    (k00, k10, k01, k11), (w00, w10, w01, w11) = pcf_taps(u, v, res)
    set_lane(q, Q_W00, m, w00)
    set_lane(q, Q_W10, m, w10)
    set_lane(q, Q_W01, m, w01)
    set_lane(q, Q_W11, m, w11)
    set_lane(taps, T_00, m, first + np.uint64(k00))
    set_lane(taps, T_10, m, first + np.uint64(k10))
    set_lane(taps, T_01, m, first + np.uint64(k01))
    set_lane(taps, T_11, m, first + np.uint64(k11))


@njit(cache=True, fastmath=False, error_model="numpy")
def _setup(s, n, origin, steps, medium):
    """Lanes ``0..n-1`` hold their segment ``a``, ``b``, ``β`` and direction ``d``: ``Δ`` replaces ``b``; the
    view transmittance to ``a``, ``T = exp(-τ(0, a))``, the fog's running product and the sums are set."""
    prefer_wide_vectors()
    mp, lattice = medium.params, medium.noise
    ox, oy, oz = origin[0], origin[1], origin[2]
    zero, one = zero_one(s)
    fsteps = cast(one, steps)
    for m in range(n):  # the step Δ = (b - a)/N
        set_lane(s, R_DELTA, m, (lane(s, R_DELTA, m) - lane(s, R_START, m)) / fsteps)
    if mp[M_NOISE] != zero:  # Beer–Lambert from the eye to a: optical_depth's sub-step loop, or its closed form
        for m in range(n):
            dx, dy, dz = lane3(s, R_DIR, m)
            set_lane(s, R_T_VIEW, m, exp(-optical_depth(mp, lattice, ox, oy, oz, dx, dy, dz, zero, lane(s, R_START, m),
                                                        steps)))
    else:
        for m in range(n):
            dx, dy, dz = lane3(s, R_DIR, m)
            set_lane(s, R_T_VIEW, m, exp(-smooth_optical_depth(mp, ox, oy, oz, dx, dy, dz, zero, lane(s, R_START, m))))
    cap = cast(one, FOG_MAX_EXPONENT)
    smooth_fog = mp[M_FOG] != zero and mp[M_NOISE] == zero
    for m in range(n):  # the height fog's factor at the first sample and its ratio per step
        a, delta, beta = lane(s, R_START, m), lane(s, R_DELTA, m), lane(s, R_BETA, m)
        _, dy, _ = lane3(s, R_DIR, m)
        e_first = fog_exponent(mp, oy + (a + beta * delta) * dy)
        e_last = fog_exponent(mp, oy + (a + (fsteps - one + beta) * delta) * dy)
        # max and min as Numba's builtins compute them (b if b > a else a, b if b < a else a), written out: LLVM left
        # the builtins' calls in this loop, which then ran lane by lane
        top, bottom = e_last if e_last > e_first else e_first, e_last if e_last < e_first else e_first
        geometric = smooth_fog & (top < cap) & (bottom > -cap)  # '&': no branch
        set_lane(s, R_GEOMETRIC, m, one if geometric else zero)
        set_lane(s, R_FOG, m, exp(e_first) if geometric else one)
        set_lane(s, R_FOG_STEP, m, exp(-(dy * delta) * mp[M_FOG_K]) if geometric else one)
        set_lane3(s, R_L, m, zero, zero, zero)


@njit(cache=True, fastmath=False, error_model="numpy")
def _medium_stage(s, n, i, origin, medium, geometric):
    """The medium at sample ``i``: ``x = o + t d``, ``t = a + (i + β) Δ``; the density, ``σs``, ``σt``, and
    Beer–Lambert over the step, ``expm1(-σt Δ)``. ``geometric``: every lane takes the fog's running product."""
    prefer_wide_vectors()
    mp, lattice = medium.params, medium.noise
    ox, oy, oz = origin[0], origin[1], origin[2]
    zero, one = zero_one(s)
    fog, noise, bounded = mp[M_FOG] != zero, mp[M_NOISE] != zero, mp[M_BOUNDED] != zero
    base, falloff = mp[M_FOG_BASE], mp[M_FOG_K]
    x0, y0, z0, x1, y1, z1 = mp[M_BX0], mp[M_BY0], mp[M_BZ0], mp[M_BX1], mp[M_BY1], mp[M_BZ1]
    ss0, st0 = mp[M_SS], mp[M_ST]
    fi = cast(one, i)
    for m in range(n):  # the sample
        t = lane(s, R_START, m) + (fi + lane(s, R_BETA, m)) * lane(s, R_DELTA, m)
        dx, dy, dz = lane3(s, R_DIR, m)
        x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
        set_lane3(s, R_POS, m, x, y, z)
        set_lane(s, R_FOG_EXP, m, height_exponent(base, falloff, y) if fog else zero)
    if noise:  # the density
        for m in range(n):
            x, y, z = lane3(s, R_POS, m)
            set_lane(s, R_RHO, m, density(mp, lattice, x, y, z))
    else:  # smooth_density, with the fog's running product where it holds (on every lane: no exp at all)
        for m in range(n):
            x, y, z = lane3(s, R_POS, m)
            inside = not bounded or box_contains(x0, y0, z0, x1, y1, z1, x, y, z)
            running = lane(s, R_FOG, m)
            if geometric:
                rho = running
            else:
                rho = running if lane(s, R_GEOMETRIC, m) != zero else (exp(lane(s, R_FOG_EXP, m)) if fog else one)
            set_lane(s, R_RHO, m, rho if inside else zero)
            set_lane(s, R_FOG, m, running * lane(s, R_FOG_STEP, m))
    for m in range(n):  # σs, σt, and Beer–Lambert over the step
        rho = lane(s, R_RHO, m)
        st = st0 * rho
        set_lane(s, R_SIGMA_T, m, st)
        set_lane(s, R_SIGMA_S, m, ss0 * rho)
        set_lane(s, R_EM1, m, expm1(-st * lane(s, R_DELTA, m)))


@njit(cache=True, fastmath=False, error_model="numpy")
def _light_stage(s, n, lights, k):
    """The light ``k`` at the samples: direction ``l`` and distance, the light's attenuation (distance law)
    and cone (0 at the light's own position), then ``E_l`` per channel with the colour and the cookie
    (:func:`vlref.lights.shading.light_incidence`, lane by lane). The smoothstep cone divides only in packets with a
    lane inside its falloff (elsewhere its value is 0 or 1: BENCHMARKS.md "The march: one square root and a division
    less")."""
    prefer_wide_vectors()
    li, lf = lights.ints, lights.floats
    kind, law, cone = li[k, I_KIND], li[k, I_ATT], li[k, I_CONE]
    zero, one = zero_one(s)
    if kind == KIND_DIRECTIONAL:
        lx, ly, lz = -lf[k, F_DX], -lf[k, F_DY], -lf[k, F_DZ]
        for m in range(n):
            set_lane3(s, R_TO_LIGHT, m, lx, ly, lz)
            set_lane(s, R_DIST, m, cast(one, np.inf))
            set_lane(s, R_E, m, one)
    else:
        inv_r2 = lf[k, F_INV_RANGE2]
        px, py, pz = lf[k, F_PX], lf[k, F_PY], lf[k, F_PZ]
        for m in range(n):  # direction and distance
            x, y, z = lane3(s, R_POS, m)
            lx, ly, lz, dist, d2 = light_vector(px, py, pz, x, y, z)
            set_lane3(s, R_TO_LIGHT, m, lx, ly, lz)
            set_lane(s, R_DIST, m, dist)
            set_lane(s, R_DIST2, m, d2)
        if law == UNITY and lights.lut.size > 0:  # the light's attenuation: its distance law
            for m in range(n):
                set_lane(s, R_E, m, distance_attenuation(law, lane(s, R_DIST2, m), inv_r2, lights.lut))
        else:
            for m in range(n):
                set_lane(s, R_E, m, analytic_attenuation(law, lane(s, R_DIST2, m), inv_r2))
        for m in range(n):
            set_lane(s, R_E, m, lane(s, R_E, m) if lane(s, R_DIST2, m) != zero else zero)
        if kind == KIND_SPOT:  # the cone
            ax, ay, az = lf[k, F_DX], lf[k, F_DY], lf[k, F_DZ]
            co, ci, ua, ub = lf[k, F_COS_OUTER], lf[k, F_COS_INNER], lf[k, F_UNITY_A], lf[k, F_UNITY_B]
            if cone == CONE_LINEAR:
                half_outer, half_inner = lf[k, F_HALF_OUTER], lf[k, F_HALF_INNER]
                for m in range(n):
                    lx, ly, lz = lane3(s, R_TO_LIGHT, m)
                    cos_t = -(lx * ax + ly * ay + lz * az)
                    set_lane(s, R_E, m, lane(s, R_E, m) * cone_falloff(cone, cos_t, co, ci, half_outer, half_inner,
                                                                       ua, ub))
            else:
                falloff = 0  # lanes in the smoothstep's falloff, co < cos θ < ci (or NaN): only they need the division
                for m in range(n):
                    lx, ly, lz = lane3(s, R_TO_LIGHT, m)
                    cos_t = -(lx * ax + ly * ay + lz * az)
                    set_lane(s, R_COS, m, cos_t)
                    falloff += not (cos_t <= co or cos_t >= ci)
                if cone == CONE_UNITY or falloff > 0:
                    for m in range(n):
                        set_lane(s, R_E, m, lane(s, R_E, m) * cone_polynomial(cone, lane(s, R_COS, m), co, ci, ua, ub))
                else:  # cone_polynomial's value without its division, which no lane needs: 0 or 1, the same product
                    for m in range(n):
                        set_lane(s, R_E, m, lane(s, R_E, m) * (zero if lane(s, R_COS, m) <= co else one))
    cr, cg, cb = lf[k, F_CR], lf[k, F_CG], lf[k, F_CB]
    for m in range(n):  # the colour
        e = lane(s, R_E, m)
        set_lane3(s, R_E_RGB, m, e * cr, e * cg, e * cb)
    if li[k, I_CK_OFF] >= 0:  # the cookie
        for m in range(n):
            if lane(s, R_E, m) != zero:
                x, y, z = lane3(s, R_POS, m)
                r, g, b = cookie_rgb(lights, k, x, y, z)
                er, eg, eb = lane3(s, R_E_RGB, m)
                set_lane3(s, R_E_RGB, m, er * cast(one, r), eg * cast(one, g), eb * cast(one, b))


@njit(cache=True, fastmath=False, error_model="numpy")
def _leg_stage(s, n, medium, kind, light_y, attenuates, leg_steps):
    """The light leg ``T_l``, Beer–Lambert from the sample to the light (module docstring): 1 unless the leg
    ``attenuates`` (:func:`~vlref.medium.light_leg_attenuates`), else the height fog's closed form, a noiseless
    medium's closed form (:func:`~vlref.medium.smooth_optical_depth`, what :func:`~vlref.medium.optical_depth`
    returns there, in a loop without the noise's sub-steps: BENCHMARKS.md "The march's stages on the device, priced
    by taking them away"), or :func:`~vlref.medium.optical_depth`."""
    prefer_wide_vectors()
    mp, lattice = medium.params, medium.noise
    zero, one = zero_one(s)
    st0 = mp[M_ST]
    bounded, noise = mp[M_BOUNDED] != zero, mp[M_NOISE] != zero
    if not attenuates:
        for m in range(n):
            set_lane(s, R_T_LIGHT, m, one)
    elif mp[M_FOG] != zero and not noise and not bounded and kind != KIND_DIRECTIONAL:
        el = height_exponent(mp[M_FOG_BASE], mp[M_FOG_K], light_y)  # the leg ends at the light
        fog_l = exp(el)
        for m in range(n):
            dist, ea, rho = lane(s, R_DIST, m), lane(s, R_FOG_EXP, m), lane(s, R_RHO, m)
            set_lane(s, R_T_LIGHT, m, exp(-(st0 * dist * fog_mean_factor(rho, fog_l, abs(ea - el)))))
    elif mp[M_FOG] == zero and not noise and not bounded:  # homogeneous, unbounded: τ = σt · dist, as optical_depth
        for m in range(n):
            set_lane(s, R_T_LIGHT, m, exp(-(st0 * lane(s, R_DIST, m))))
    elif not noise:  # optical_depth without its noise loop: the same closed form, and the lane loop vectorises
        for m in range(n):
            x, y, z = lane3(s, R_POS, m)
            lx, ly, lz = lane3(s, R_TO_LIGHT, m)
            set_lane(s, R_T_LIGHT, m, exp(-smooth_optical_depth(mp, x, y, z, lx, ly, lz, zero, lane(s, R_DIST, m))))
    else:
        for m in range(n):
            x, y, z = lane3(s, R_POS, m)
            lx, ly, lz = lane3(s, R_TO_LIGHT, m)
            set_lane(s, R_T_LIGHT, m, exp(-optical_depth(mp, lattice, x, y, z, lx, ly, lz, zero, lane(s, R_DIST, m),
                                                         leg_steps)))


@njit(cache=True, fastmath=False, error_model="numpy")
def _spot_texels(s, q, taps, n, lf, k, res):
    """Where the samples fall in spot light ``k``'s map of ``res``² texels: depth, in front of the light
    (:func:`~vlref.lights.shadow_lookup.spot_map_coords`), the texels around ``(u, v)``. The depth is the distance
    to the light: in float64 the light stage's (:func:`reuses_distance`)."""
    prefer_wide_vectors()
    reuse = reuses_distance(s)
    px, py, pz = float(lf[k, F_PX]), float(lf[k, F_PY]), float(lf[k, F_PZ])
    rx, ry, rz = float(lf[k, F_RX]), float(lf[k, F_RY]), float(lf[k, F_RZ])
    ux, uy, uz = float(lf[k, F_UX]), float(lf[k, F_UY]), float(lf[k, F_UZ])
    dx, dy, dz = float(lf[k, F_DX]), float(lf[k, F_DY]), float(lf[k, F_DZ])
    tan_half = float(lf[k, F_TAN_HALF])
    for m in range(n):
        x, y, z = lane3(s, R_POS, m)
        u, v, d_ref, ahead = spot_map_coords(float(x) - px, float(y) - py, float(z) - pz, rx, ry, rz, ux, uy, uz,
                                             dx, dy, dz, tan_half)
        set_lane(q, Q_DREF, m, float(lane(s, R_DIST, m)) if reuse else d_ref)
        set_lane(q, Q_ON_MAP, m, 1.0 if ahead else 0.0)
        set_texels(q, taps, m, u, v, res, np.uint64(0))


@njit(cache=True, fastmath=False, error_model="numpy")
def _cube_texels(s, q, taps, n, lf, k, res):
    """Where the samples fall in point light ``k``'s cube map of ``res``² faces: the face of the major axis, the
    radial distance (:func:`~vlref.lights.shadow_lookup.cube_map_coords`; in float64 the light stage's,
    :func:`reuses_distance`), the texels around ``(u, v)`` on the face."""
    prefer_wide_vectors()
    reuse = reuses_distance(s)
    px, py, pz = float(lf[k, F_PX]), float(lf[k, F_PY]), float(lf[k, F_PZ])
    face_texels = np.uint64(res * res)
    for m in range(n):
        x, y, z = lane3(s, R_POS, m)
        face, u, v, d_ref, on_face = cube_map_coords(float(x) - px, float(y) - py, float(z) - pz)
        set_lane(q, Q_DREF, m, float(lane(s, R_DIST, m)) if reuse else d_ref)
        set_lane(q, Q_ON_MAP, m, 1.0 if on_face else 0.0)
        set_texels(q, taps, m, u, v, res, np.uint64(face) * face_texels)


@njit(cache=True, fastmath=False, error_model="numpy")
def _cascade_texels(s, q, taps, n, lf, k, sm_i, sm_f):
    """Where the samples fall in directional light ``k``'s cascades: the first cascade whose bounding sphere
    contains the sample, ``(u, v)`` and the depth in it (:func:`~vlref.lights.shadow_lookup.cascade_map_coords`);
    outside every sphere the map covers nothing (lit). The cascades are visited last to first, each a
    vectorised lane loop that overwrites the lanes it contains; then the texels around ``(u, v)``."""
    prefer_wide_vectors()
    rx, ry, rz = float(lf[k, F_RX]), float(lf[k, F_RY]), float(lf[k, F_RZ])
    ux, uy, uz = float(lf[k, F_UX]), float(lf[k, F_UY]), float(lf[k, F_UZ])
    dx, dy, dz = float(lf[k, F_DX]), float(lf[k, F_DY]), float(lf[k, F_DZ])
    res = sm_i[k, S_RES]
    for m in range(n):
        set_lane(q, Q_U, m, 0.5)
        set_lane(q, Q_V, m, 0.5)
        set_lane(q, Q_DREF, m, 0.0)
        set_lane(q, Q_ON_MAP, m, 0.0)
        set_lane(taps, T_FACE, m, np.uint64(0))
    for c in range(sm_i[k, S_CASCADES] - 1, -1, -1):
        j = S_CASC + 5 * c
        cx, cy, cz, radius, back = sm_f[k, j], sm_f[k, j + 1], sm_f[k, j + 2], sm_f[k, j + 3], sm_f[k, j + 4]
        first = np.uint64(c * res * res)
        for m in range(n):
            x, y, z = lane3(s, R_POS, m)
            u, v, d_ref, inside = cascade_map_coords(float(x) - cx, float(y) - cy, float(z) - cz, radius, back,
                                                     rx, ry, rz, ux, uy, uz, dx, dy, dz)
            # the lane's values so far, read before any store (a read under the condition keeps the loop scalar)
            u0, v0, d0, on0, first0 = (lane(q, Q_U, m), lane(q, Q_V, m), lane(q, Q_DREF, m), lane(q, Q_ON_MAP, m),
                                       lane(taps, T_FACE, m))
            set_lane(q, Q_U, m, u if inside else u0)
            set_lane(q, Q_V, m, v if inside else v0)
            set_lane(q, Q_DREF, m, d_ref if inside else d0)
            set_lane(q, Q_ON_MAP, m, 1.0 if inside else on0)
            set_lane(taps, T_FACE, m, first if inside else first0)
    for m in range(n):
        set_texels(q, taps, m, lane(q, Q_U, m), lane(q, Q_V, m), res, lane(taps, T_FACE, m))


@njit(cache=True, fastmath=False, error_model="numpy")
def _lit_fraction(q, taps, n, data, ubase):
    """The PCF lit fraction of every lane (:func:`~vlref.lights.shadow_lookup.pcf_blend` of its taps, always inside
    the map: :func:`~vlref.lights.shadow_lookup.pcf_taps` clamps them) from the maps' ``data`` at ``ubase``. No
    branch, and the arrays are declared apart (:func:`vlref.numeric.arrays_do_not_overlap`): LLVM then reads the
    four depths of eight lanes with one hardware gather each (AVX-512; without the promise a store to ``q`` might
    change a later lane's read, and the loop stayed scalar)."""
    prefer_wide_vectors()
    arrays_do_not_overlap()
    for m in range(n):
        set_lane(q, Q_LIT, m, pcf_blend(data, ubase, lane(taps, T_00, m), lane(taps, T_10, m), lane(taps, T_01, m),
                                        lane(taps, T_11, m), lane(q, Q_W00, m), lane(q, Q_W10, m), lane(q, Q_W01, m),
                                        lane(q, Q_W11, m), lane(q, Q_DREF, m)))


@njit(cache=True, fastmath=False, error_model="numpy")
def _shadow_stage(s, q, taps, n, shadows, geo, lights, k):
    """The shadow lookup: visibility ``V`` per channel (the light's strength applied) where the sample
    scatters light, 1 elsewhere. A PCF map without a transparent layer: where the samples fall in the map, its
    four texels and their weights (:func:`_spot_texels`, :func:`_cube_texels`, :func:`_cascade_texels`), the four
    depth reads, then ``V`` (module docstring, "Performance"); every other lookup is
    :func:`~vlref.lights.shadow_lookup.map_lit` or a shadow ray, lane by lane."""
    prefer_wide_vectors()
    kind = lights.ints[k, I_KIND]
    mode = shadows.ints[k, S_MODE]
    strength = shadows.floats[k, S_STRENGTH]
    zero, one = zero_one(s)
    lf = lights.floats
    sm_i, data = shadows.ints, shadows.data
    if mode == SHADOW_PCF and shadows.tint.shape[0] == 0:
        res, ubase = sm_i[k, S_RES], np.uint64(sm_i[k, S_OFFSET])
        if kind == KIND_SPOT:
            _spot_texels(s, q, taps, n, lf, k, res)
        elif kind == KIND_DIRECTIONAL:
            _cascade_texels(s, q, taps, n, lf, k, sm_i, shadows.floats)
        else:
            _cube_texels(s, q, taps, n, lf, k, res)
        # the lit fraction; lanes that scatter nothing or that the map does not cover keep V = 1 in the loop after
        _lit_fraction(q, taps, n, data, ubase)
        for m in range(n):  # V, the light's strength applied
            lit = lane(q, Q_LIT, m)
            fr, _, _ = apply_strength(strength, lit, lit, lit)
            er, eg, eb = lane3(s, R_E_RGB, m)
            used = lane(q, Q_ON_MAP, m) != 0.0 and scatters_light(lane(s, R_SIGMA_S, m), er, eg, eb)
            v = cast(one, fr) if used else one
            set_lane3(s, R_VIS, m, v, v, v)
        return
    for m in range(n):  # the PCF loop above writes every lane; here V = 1 unless a lookup says otherwise
        set_lane3(s, R_VIS, m, one, one, one)
    if mode == SHADOW_NONE:
        return
    for m in range(n):
        er, eg, eb = lane3(s, R_E_RGB, m)
        if scatters_light(lane(s, R_SIGMA_S, m), er, eg, eb):
            x, y, z = lane3(s, R_POS, m)
            x, y, z = float(x), float(y), float(z)
            if geo is not None and mode == SHADOW_EXACT:  # geo None: Numba prunes the branch (no ray tracer)
                fr, fg, fb = exact_visibility(geo, kind, lf, k, x, y, z)
            else:
                fr, fg, fb = map_lit(shadows, kind, lf, k, x, y, z)
            fr, fg, fb = apply_strength(strength, fr, fg, fb)
            set_lane3(s, R_VIS, m, cast(one, fr), cast(one, fg), cast(one, fb))


@njit(cache=True, fastmath=False, error_model="numpy")
def _accumulate_stage(s, n, g):
    """The phase function and the accumulation: ``L += T σs p(d·l) T_l (1 - e^{-σt Δ})/σt · E V``, then
    Beer–Lambert over the step, ``T *= e^{-σt Δ}`` (module docstring; ``g`` the HG asymmetry)."""
    prefer_wide_vectors()
    zero, one = zero_one(s)
    for m in range(n):
        st, ss, em1, delta = lane(s, R_SIGMA_T, m), lane(s, R_SIGMA_S, m), lane(s, R_EM1, m), lane(s, R_DELTA, m)
        er, eg, eb = lane3(s, R_E_RGB, m)
        dx, dy, dz = lane3(s, R_DIR, m)
        lx, ly, lz = lane3(s, R_TO_LIGHT, m)
        phase = cast(one, hg(dx * lx + dy * ly + dz * lz, g))
        t_view = lane(s, R_T_VIEW, m)
        f = t_view * ss * phase * lane(s, R_T_LIGHT, m) * step_source_weight(st, delta, em1)
        lit = scatters_light(ss, er, eg, eb)
        vr, vg, vb = lane3(s, R_VIS, m)
        lr, lg, lb = lane3(s, R_L, m)
        set_lane3(s, R_L, m, lr + (f * er * vr if lit else zero), lg + (f * eg * vg if lit else zero),
                  lb + (f * eb * vb if lit else zero))
        set_lane(s, R_T_VIEW, m, t_view * (one + em1))


@njit(cache=True, fastmath=False, error_model="numpy")
def _march_packet(s, q, taps, n, pix, w, k, steps, origin, medium, lights, shadows, geo, light_extinction, leg_steps,
                  per_light):
    """March the ``n`` lanes set up in ``s`` (pixels ``pix``, image width ``w``) through light ``k`` and store
    their in-scattered radiance in ``per_light[k]`` (module docstring)."""
    prefer_wide_vectors()
    kind = lights.ints[k, I_KIND]
    light_y = lights.floats[k, F_PY]
    g = medium.params[M_G]
    attenuates = light_leg_attenuates(medium.params, kind == KIND_DIRECTIONAL, light_extinction)
    n_geometric = 0
    for m in range(n):
        n_geometric += lane(s, R_GEOMETRIC, m) != 0.0
    geometric = n_geometric == n  # a bool, never Literal[bool](True): _medium_stage would compile twice
    for i in range(steps):
        _medium_stage(s, n, i, origin, medium, geometric)  # the medium: σs, σt, Beer–Lambert over the step
        _light_stage(s, n, lights, k)  # the light: its direction, attenuation, cone, colour, cookie
        _leg_stage(s, n, medium, kind, light_y, attenuates, leg_steps)  # Beer–Lambert toward the light
        _shadow_stage(s, q, taps, n, shadows, geo, lights, k)  # the shadow lookup
        _accumulate_stage(s, n, g)  # the phase function and the accumulation
    flat, first = per_light.reshape(-1), k * per_light.shape[1] * w  # light k's first pixel (no division per lane)
    for m in range(n):
        at = (first + pix[m]) * 3
        flat[at], flat[at + 1], flat[at + 2] = lane3(s, R_L, m)


@njit(cache=True, fastmath=False, error_model="numpy")
def _smooth_transmittance(mp, ox, oy, oz, dirs, t_end, first, end, out):
    """``out[j] = exp(-τ(0, t_end[j]))`` along ``dirs[j]`` for ``first <= j < end`` (a row of pixels) in a medium
    without noise: :func:`~vlref.medium.smooth_optical_depth`, in a loop that vectorises."""
    prefer_wide_vectors()
    arrays_do_not_overlap()
    zero = cast(oy, 0.0)
    for j in range(first, end):
        out[j] = exp(-smooth_optical_depth(mp, ox, oy, oz, dirs[j, 0], dirs[j, 1], dirs[j, 2], zero, t_end[j]))


@njit(cache=True, fastmath=False, error_model="numpy", by_address=True)
def _march_tasks(taken, rows, steps, light_extinction, leg_steps, origin, dirs, t_end, offsets, medium, lights, shadows,
                 geo, per_light, transmittance):
    """Take tasks, tiles of ``TILE_W x TILE_H`` pixels of the rows ``rows = (first, end)`` in row-major order of
    tiles (:func:`vlref.parallel.take` on ``taken``), until none is left; per task, its pixels' transmittance,
    then per light its pairs with a non-empty segment in packets of up to ``LANES``, set up by :func:`_setup`
    (module docstring). The arrays are borrowed (:func:`vlref.parallel.borrowed`)."""
    prefer_wide_vectors()
    origin, dirs, t_end, offsets, medium, lights, shadows, geo, per_light, transmittance = borrowed(
        (origin, dirs, t_end, offsets, medium, lights, shadows, geo, per_light, transmittance))
    mp, lattice = medium.params, medium.noise
    ox, oy, oz = origin[0], origin[1], origin[2]
    first, end = rows
    w = t_end.shape[1]
    s = np.empty(ROWS * LANES, dtype=t_end.dtype)
    q = np.empty(QROWS * LANES, dtype=np.float64)
    taps = np.empty(5 * LANES, dtype=np.uint64)
    pix = np.empty(LANES, dtype=np.int64)
    zero, _ = zero_one(s)
    smooth = mp[M_NOISE] == zero  # a medium without noise: the view transmittances' closed form
    tiles_x = (w + TILE_W - 1) // TILE_W
    tiles = tiles_x * ((end - first + TILE_H - 1) // TILE_H)
    while True:
        task = take(taken)
        if task >= tiles:
            return
        i0, j0 = first + (task // tiles_x) * TILE_H, (task % tiles_x) * TILE_W
        i1, j1 = min(end, i0 + TILE_H), min(w, j0 + TILE_W)
        for i in range(i0, i1):  # the pixel's transmittance, Beer–Lambert from the eye to t_end
            if smooth:
                _smooth_transmittance(mp, ox, oy, oz, dirs[i], t_end[i], j0, j1, transmittance[i])
            else:
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
                    set_lane(s, R_START, n, a)
                    set_lane(s, R_DELTA, n, b)
                    set_lane(s, R_BETA, n, offsets[i, j])
                    set_lane3(s, R_DIR, n, dx, dy, dz)
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


def march_physical(origin, dirs, t_end, offsets, steps, medium, lights, shadows, geo, light_extinction, leg_steps,
                   per_light, transmittance, rows, taken=None):
    """Fill the rows ``rows = (first, end)`` (int64, ``first <= end <= H``) of ``per_light`` (n_lights, H, W, 3)
    and ``transmittance`` (H, W) (module docstring); the other rows are left as they are.

    origin (3,), dirs (H, W, 3) unit, t_end (H, W), offsets (H, W) in [0, 1): all in the march's float
    type, like the ``medium`` (:class:`~vlref.medium.PackedMedium`) and the float tables of ``lights``
    (:class:`~vlref.lights.pack.PackedLights`). ``shadows`` a :class:`~vlref.lights.shadow_pack.ShadowTable`;
    ``geo`` the geometry tuple for ``exact`` shadows, or None where no light has them: the kernel is then
    compiled without the ray tracer (its compile takes about a third less; BENCHMARKS.md "Scheduling,
    borrowed records, a leaner compile").

    A caller that marches a frame in bands of rows (:mod:`vlref.progress`) passes the whole arrays and each
    band's ``rows``: the band is written in place, with no buffer of its own to allocate and copy (four lights at
    1080p: 200 MB; BENCHMARKS.md "The march: bands in place, whole tiles, gathered depth reads").

    The pixels are split in tasks, tiles of ``TILE_W x TILE_H`` pixels. The threads of a ``prange`` over
    :data:`~vlref.parallel.WORKERS` take tasks on demand until none is left (:mod:`vlref.parallel`: a
    pixel's cost varies from nothing to hundreds of samples, and ``prange``'s own split is static), each
    marched in packets of up to ``LANES`` (pixel, light) pairs. The workers get the arrays without reference
    counts (:func:`vlref.parallel.borrowed`: the stages take the records on every step). The kernel
    (:func:`_march_kernel`) calls :func:`_march_tasks` by address (:func:`vlref.parallel.work`), which borrows
    them.

    ``taken``: the task counter the workers take tasks from (a 1-element int64 array holding 0; a new one if None),
    :func:`march_tiles` tasks in row-major order of tiles. The kernel releases the GIL: a caller may run it on a
    thread of its own and read the counter meanwhile for progress, or set it past the last task to stop the march
    after the tiles being marched (:func:`vlref.progress.watched`).
    """
    taken = np.zeros(1, dtype=np.int64) if taken is None else taken
    args = (origin, dirs, t_end, offsets, steps, medium, lights, shadows, geo, light_extinction, leg_steps, per_light,
            transmittance, rows, taken)
    _march_kernel(*args, work(_march_tasks, COUNTER, rows, steps, light_extinction, leg_steps, origin, dirs, t_end,
                              offsets, medium, lights, shadows, geo, per_light, transmittance))


def march_tiles(width: int, rows: int) -> int:
    """The tasks of :func:`march_physical` over ``rows`` rows of an image ``width`` pixels wide: its tiles."""
    return -(-int(width) // TILE_W) * -(-int(rows) // TILE_H)


@njit(cache=True, fastmath=False, error_model="numpy", parallel=True, nogil=True)
def _march_kernel(origin, dirs, t_end, offsets, steps, medium, lights, shadows, geo, light_extinction, leg_steps,
                  per_light, transmittance, rows, taken, march_tasks):
    """:func:`march_physical`'s parallel kernel: its checks, then workers that take tasks from ``taken`` and call
    ``march_tasks`` (:func:`_march_tasks` by address). Without the GIL (``nogil``)."""
    if geo is None:
        for k in range(shadows.ints.shape[0]):
            if shadows.ints[k, S_MODE] == SHADOW_EXACT:
                raise ValueError("march_physical: a light has exact shadows, and geo is None")
    if not 0 <= rows[0] <= rows[1] <= t_end.shape[0]:
        raise ValueError("march_physical: rows must satisfy 0 <= first <= end <= the image height")
    if taken.shape[0] != 1:
        raise ValueError("march_physical: taken must hold one counter")
    for _ in prange(WORKERS):
        march_tasks(taken, rows, steps, light_extinction, leg_steps, origin, dirs, t_end, offsets, medium, lights,
                    shadows, geo, per_light, transmittance)
