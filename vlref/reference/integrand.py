"""The single-scattering integrand of the quadrature reference, evaluated exactly at one point.

``f(t) = T(0, t) Σ_l σs(x) p(cos θ_l) V_l(x) T_l(x) E_l(x)`` at ``x = o + t d`` (docs/PHYSICS.md):

* ``σs``, ``σt`` from :func:`vlref.medium.sigma` (the same density the march samples);
* ``E_l`` from :func:`vlref.lights.shading.light_incidence` (colour × intensity × distance law ×
  cone law × cookie), the function the march calls, so both evaluate the same light;
* ``V_l`` an exact shadow ray (:func:`vlref.geometry.shadow_transmittance`, RGB through tinted
  transparent occluders), with the light's shadow strength: ``V = 1 - strength (1 - tr)``; 1 for a
  light without shadows;
* ``p`` Henyey–Greenstein with ``cos θ = dot(d, l)``, ``l`` toward the light (``-direction`` for a
  directional light);
* ``T(0, t) = e^{-τ}`` and ``T_l`` from the *exact* optical depth ``τ`` (:func:`segment_depth`).
  The light leg of a point/spot light is the segment to the light. A directional light's leg runs
  from ``x`` toward ``-direction`` to the exit of ``medium.bounds``; in an unbounded medium it is
  infinite, so ``T_l`` is taken as 1 (the light's irradiance is defined where it enters the
  volume being rendered) — the same convention as the physical march. ``T_l`` is dropped entirely
  when ``techniques.physical.light_extinction`` is false.

Optical depth of ``x(s) = p + s u`` (``|u| = 1``), ``s ∈ [a, b]``, clipped to the box:

* no noise — closed form. With ``e(s) = min(-(y(s) - base) k, 60)`` the fog exponent
  (:data:`vlref.medium.FOG_MAX_EXPONENT` caps it), ``τ = σt ∫ e^{e(s)} ds``; on a piece where the
  cap is inactive ``e`` is affine, ``∫ = e^{e_max} L φ(|e_a - e_b|)``, ``φ(z) = -expm1(-z)/z``
  (``φ(0) = 1``); the segment is split where ``e`` crosses the cap (constant ``e^{60}`` beyond);
* noise — nested adaptive G7–K15 of :func:`vlref.medium.density`, split at the noise lattice's
  cell faces and, inside a cell, at the kinks of the noise factor's saturate clamps (along the ray the
  trilinear noise is a cubic in ``s``; its crossings of the clamp levels are located by bisection on its
  monotone pieces), so each piece is smooth and its G7–K15 error estimate is reliable; with
  absolute tolerance ``INNER_TOL = 1e-10`` on ``τ`` (a relative error ≤ 1e-10 on ``T``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..geometry import inline_shadow_transmittance, traversal_stack
from ..jit import njit
from ..lights import pack as lp
from ..lights.shading import light_incidence
from ..lights.shadow_lookup import apply_strength
from ..medium import (FOG_MAX_EXPONENT, M_FOG, M_FOG_BASE, M_FOG_K, M_G, M_NINT, M_NOFF, M_NOISE, M_NSCALE,
                      M_NSX, M_NSY, M_NSZ, M_ST, PackedMedium, clip_to_bounds, density, noise_value, pack_medium,
                      sigma)
from ..phase import hg

INNER_TOL = 1e-10
# Gauss-Kronrod 15 nodes (positive half, descending) and weights; entries 1, 3, 5, 7 are the Gauss 7
# nodes (QUADPACK qk15, Piessens et al. 1983). Shared with vlref.reference.quadrature.
XGK = np.array([0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                0.207784955007898467600689403773245, 0.0])
WGK = np.array([0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                0.204432940075298892414161999234649, 0.209482141084727828012999174891714])
WG = np.array([0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
               0.381830050505118944950369775488975, 0.417959183673469387755102040816327])
# Gauss-Kronrod 7 nodes (positive half, descending) and weights; entry 1 and the centre are the Gauss 3 nodes
# (Kronrod's extension of the 3-point Gauss-Legendre rule: Laurie 1997, Math. Comp. 66, 1133; exact for polynomials of
# degree <= 11, G3 for degree <= 5). The coarse rule of vlref.reference.quadrature (``rule = 7``).
XGK7 = np.array([0.960491268708020283423507092629080, 0.774596669241483377035853079956480,
                 0.434243749346802558002071502844628, 0.0])
WGK7 = np.array([0.104656226026467265193823857192073, 0.268488089868333440728569280666710,
                 0.401397414775962222905051818618432, 0.450916538658474142345110087045571])
WG3 = np.array([0.555555555555555555555555555555556, 0.888888888888888888888888888888889])
# Gauss-Kronrod 3 nodes: the Kronrod extension of the 1-point Gauss rule (the midpoint, weight 2) is the 3-point
# Gauss-Legendre rule itself (nodes 0, ±sqrt(3/5), weights 8/9, 5/9: Monegato 1982, SIAM Review 24, 137; exact for
# degree <= 5, G1 for degree <= 1). The coarsest rule of vlref.reference.quadrature (``rule = 3``).
XGK3 = np.array([0.774596669241483377035853079956480, 0.0])
WGK3 = np.array([0.555555555555555555555555555555556, 0.888888888888888888888888888888889])
WG1 = np.array([2.0])

MAX_SPREAD = 1e4
"""The change of variable about a light's closest approach (:func:`peak_substitution`) is used where the pixel's
interval reaches at most this many ``h`` from ``tc``: its edges ``u = atan((t - tc) / h)`` then lie at least ~1e-4
from ``±π/2``, where ``t = tc + h tan u`` keeps ~1e-12 of relative accuracy."""

# per-light reference flags (float64 columns of ReferenceContext.shadows)
R_SHADOWS, R_STRENGTH = 0, 1


class ReferenceContext(NamedTuple):
    """What the reference's njit functions read (everything float64).

    geo : the geometry arrays (exact shadow rays).  lights : :class:`~vlref.lights.pack.PackedLights`.
    shadows : (n_lights, 2) per-light columns ``R_SHADOWS`` (1.0 when the light casts shadows) and
    ``R_STRENGTH``.  medium : :class:`~vlref.medium.PackedMedium`.  light_extinction : the light leg
    ``T_l`` is applied.  bounded : the medium has ``bounds``.  stack : the shadow rays' traversal scratch
    (:func:`vlref.geometry.traversal_stack`), one per thread: a kernel builds each thread's context with its own
    (a shadow ray allocated its 2 KB otherwise, every integrand evaluation).
    """

    geo: tuple
    lights: lp.PackedLights
    shadows: np.ndarray
    medium: PackedMedium
    light_extinction: bool
    bounded: bool
    stack: tuple


def build_context(scene, frame) -> ReferenceContext:
    """The :class:`ReferenceContext` of ``scene``'s ``frame``."""
    med = pack_medium(scene)
    flags = np.zeros((len(scene.lights), 2))
    for i, light in enumerate(scene.lights):
        s = light.shadows
        if s is not None and s.enabled:
            flags[i] = (1.0, s.strength)
    return ReferenceContext(frame.geometry.arrays, frame.lights.astype(np.float64), flags, med.astype(np.float64),
                            bool(scene.techniques.physical.light_extinction), scene.medium.bounds is not None,
                            traversal_stack())


@njit(cache=True, fastmath=False, inline="always")
def with_stack(ctx, stack):
    """``ctx`` with the traversal scratch ``stack`` (:func:`vlref.geometry.traversal_stack`)."""
    return ReferenceContext(ctx.geo, ctx.lights, ctx.shadows, ctx.medium, ctx.light_extinction, ctx.bounded, stack)


def max_split_points(ctx, shadow_samples):
    """Capacity of the split-point buffer of one pixel (volumes, medium box, shadow boundaries)."""
    return 4 + ctx.lights.ints.shape[0] * (8 + shadow_samples)


@njit(cache=True, fastmath=False, inline="always")
def light_count(ctx):
    return ctx.lights.ints.shape[0]


@njit(cache=True, fastmath=False, inline="always")
def casts_shadows(light, ctx):
    return ctx.shadows[light, R_SHADOWS] != 0.0


# ---------------------------------------------------------------------------------------------- optical depth

@njit(cache=True, fastmath=False)
def _phi(z):
    return 1.0 if z == 0.0 else -math.expm1(-z) / z


@njit(cache=True, fastmath=False)
def _fog_integral(mp, py, uy, a, b):
    """``∫_a^b e^{e(s)} ds`` with ``e`` the capped fog exponent along ``y(s) = py + s uy`` (module docstring)."""
    if mp[M_FOG] == 0.0:
        return b - a
    k = mp[M_FOG_K]
    slope = -uy * k
    # e(s) = e0 + slope (s - a) until the cap; split where e(s) = cap
    ea = -(py + a * uy - mp[M_FOG_BASE]) * k
    eb = -(py + b * uy - mp[M_FOG_BASE]) * k
    cap = FOG_MAX_EXPONENT
    if ea >= cap and eb >= cap:
        return math.exp(cap) * (b - a)
    if ea > cap or eb > cap:
        s_cap = a + (cap - ea) / slope
        if ea > cap:
            return math.exp(cap) * (s_cap - a) + _fog_integral(mp, py, uy, s_cap, b)
        return _fog_integral(mp, py, uy, a, s_cap) + math.exp(cap) * (b - s_cap)
    return math.exp(max(ea, eb)) * (b - a) * _phi(abs(ea - eb))


@njit(cache=True, fastmath=False)
def _density_gk(mp, lattice, px, py, pz, ux, uy, uz, a, b):
    c = 0.5 * (a + b)
    h = 0.5 * (b - a)
    k = 0.0
    g = 0.0
    for i in range(8):
        if i == 7:
            f = density(mp, lattice, px + c * ux, py + c * uy, pz + c * uz)
            k += WGK[7] * f
            g += WG[3] * f
            continue
        s1 = c - h * XGK[i]
        s2 = c + h * XGK[i]
        f = (density(mp, lattice, px + s1 * ux, py + s1 * uy, pz + s1 * uz)
             + density(mp, lattice, px + s2 * ux, py + s2 * uy, pz + s2 * uz))
        k += WGK[i] * f
        if i % 2 == 1:
            g += WG[i // 2] * f
    return k * h, abs(k - g) * h


@njit(cache=True, fastmath=False)
def _density_adaptive(mp, lattice, px, py, pz, ux, uy, uz, a, b, tol):
    """``∫_a^b ρ ds`` by recursive bisection (fixed stack) to an absolute error ``tol``."""
    stack_a = np.empty(64)
    stack_b = np.empty(64)
    stack_a[0], stack_b[0] = a, b
    n = 1
    total = 0.0
    length = b - a
    while n > 0:
        n -= 1
        lo, hi = stack_a[n], stack_b[n]
        v, e = _density_gk(mp, lattice, px, py, pz, ux, uy, uz, lo, hi)
        mid = 0.5 * (lo + hi)
        if e <= tol * (hi - lo) / length or n >= 62 or not (lo < mid < hi):
            total += v
            continue
        stack_a[n], stack_b[n] = mid, hi
        stack_a[n + 1], stack_b[n + 1] = lo, mid
        n += 2
    return total


@njit(cache=True, fastmath=False)
def _next_face(p, u, s, scale, shift):
    """Smallest ``s' > s`` where ``scale (p + s' u - shift) - 0.5`` is an integer (a lattice cell face)."""
    if u == 0.0:
        return np.inf
    q = scale * (p + s * u - shift) - 0.5
    target = math.floor(q) + 1.0 if u > 0.0 else math.ceil(q) - 1.0
    s_new = s + (target - q) / (scale * u)
    return s_new if s_new > s else np.inf


# Monomial coefficients of the cubic through samples at u = 0, 1/3, 2/3, 1 (inverse Vandermonde).
_CUBIC_FIT = np.linalg.inv(np.vander(np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]), 4, increasing=True))


@njit(cache=True, fastmath=False)
def _cubic_crossings(c, level, out, count):
    """Append to ``out`` the ``u`` in (0, 1) where ``c0 + c1 u + c2 u² + c3 u³ = level``; returns the count.

    The cubic is split at its critical points into monotone pieces, each bisected to machine precision.
    """
    knots = np.empty(4)
    knots[0] = 0.0
    m = 1
    qa, qb, qc = 3.0 * c[3], 2.0 * c[2], c[1]  # derivative qa u² + qb u + qc
    if qa != 0.0:
        disc = qb * qb - 4.0 * qa * qc
        if disc > 0.0:
            r = math.sqrt(disc)
            u1, u2 = (-qb - r) / (2.0 * qa), (-qb + r) / (2.0 * qa)
            for u in (min(u1, u2), max(u1, u2)):
                if 0.0 < u < 1.0:
                    knots[m] = u
                    m += 1
    elif qb != 0.0 and 0.0 < -qc / qb < 1.0:
        knots[m] = -qc / qb
        m += 1
    knots[m] = 1.0
    m += 1
    for j in range(m - 1):
        lo, hi = knots[j], knots[j + 1]
        flo = c[0] + lo * (c[1] + lo * (c[2] + lo * c[3])) - level
        fhi = c[0] + hi * (c[1] + hi * (c[2] + hi * c[3])) - level
        if flo == 0.0 or flo * fhi > 0.0:
            continue
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if not lo < mid < hi:
                break
            fm = c[0] + mid * (c[1] + mid * (c[2] + mid * c[3])) - level
            if (fm < 0.0) == (flo < 0.0):
                lo, flo = mid, fm
            else:
                hi = mid
        if 0.0 < hi < 1.0:
            out[count] = hi
            count += 1
    return count


@njit(cache=True, fastmath=False)
def _noise_kinks(mp, lattice, px, py, pz, ux, uy, uz, a, b, out):
    """Sorted ``s`` in (a, b) where the noise factor ``saturate(saturate(n - offset) · intensity)`` has a
    kink, for ``[a, b]`` inside one lattice cell: there the trilinear ``n(s)`` is a cubic in ``s``, and the
    kinks are its crossings of ``offset`` and ``offset + 1/intensity``. Returns their count."""
    scale = mp[M_NSCALE]
    f = np.empty(4)
    for i in range(4):
        s = a + (b - a) * i / 3.0
        f[i] = noise_value(lattice, scale * (px + s * ux - mp[M_NSX]), scale * (py + s * uy - mp[M_NSY]),
                           scale * (pz + s * uz - mp[M_NSZ]))
    c = _CUBIC_FIT @ f
    count = _cubic_crossings(c, mp[M_NOFF], out, 0)
    if mp[M_NINT] > 0.0:
        count = _cubic_crossings(c, mp[M_NOFF] + 1.0 / mp[M_NINT], out, count)
    out[:count].sort()
    for i in range(count):
        out[i] = a + (b - a) * out[i]
    return count


@njit(cache=True, fastmath=False)
def segment_depth(mp, lattice, px, py, pz, ux, uy, uz, a, b):
    """Exact optical depth ``τ = ∫_a^b σt(p + s u) ds`` (module docstring); ``|u| = 1``."""
    lo, hi = clip_to_bounds(mp, px, py, pz, ux, uy, uz, a, b)
    if not hi > lo or mp[M_ST] == 0.0:
        return 0.0
    if mp[M_NOISE] == 0.0:
        return mp[M_ST] * _fog_integral(mp, py, uy, lo, hi)
    scale = mp[M_NSCALE]
    total = 0.0
    kinks = np.empty(6)
    s = lo
    while s < hi:
        nxt = min(hi, _next_face(px, ux, s, scale, mp[M_NSX]), _next_face(py, uy, s, scale, mp[M_NSX + 1]),
                  _next_face(pz, uz, s, scale, mp[M_NSX + 2]))
        # inside one cell the integrand is smooth between the noise factor's kinks: integrate piecewise
        count = _noise_kinks(mp, lattice, px, py, pz, ux, uy, uz, s, nxt, kinks)
        start = s
        for i in range(count + 1):
            end = kinks[i] if i < count else nxt
            if end > start:
                total += _density_adaptive(mp, lattice, px, py, pz, ux, uy, uz, start, end,
                                           INNER_TOL / mp[M_ST] * (end - start) / (hi - lo))
                start = end
        s = nxt
    return mp[M_ST] * total


@njit(cache=True, fastmath=False, inline="always")
def view_optical_depth(ray, a, b, ctx):
    """Optical depth of the camera ray between ``t = a`` and ``t = b``."""
    return segment_depth(ctx.medium.params, ctx.medium.noise, ray[0], ray[1], ray[2], ray[3], ray[4], ray[5], a, b)


# ---------------------------------------------------------------------------------------------- lights

@njit(cache=True, fastmath=False, inline="always")
def light_geometry(light, x, y, z, ctx):
    """Unit vector toward the light, distance (inf: directional) and unshadowed ``E_l`` RGB
    (:func:`vlref.lights.shading.light_incidence`, the function the march calls)."""
    return light_incidence(ctx.lights, light, x, y, z)


@njit(cache=True, fastmath=False, inline="always")
def _shadow(light, x, y, z, lx, ly, lz, dist, ctx):
    tr, tg, tb = inline_shadow_transmittance(ctx.geo, x, y, z, lx, ly, lz, dist, ctx.stack)
    return apply_strength(ctx.shadows[light, R_STRENGTH], tr, tg, tb)


@njit(cache=True, fastmath=False, inline="always")
def visibility(light, t, ray, ctx):
    """RGB visibility ``V`` of ``light`` from ``x(t)`` (1 for lights without shadows)."""
    x, y, z = ray[0] + t * ray[3], ray[1] + t * ray[4], ray[2] + t * ray[5]
    lx, ly, lz, dist, er, eg, eb = light_geometry(light, x, y, z, ctx)
    if ctx.shadows[light, R_SHADOWS] == 0.0 or (lx == 0.0 and ly == 0.0 and lz == 0.0):
        return 1.0, 1.0, 1.0
    return _shadow(light, x, y, z, lx, ly, lz, dist, ctx)


@njit(cache=True, fastmath=False, inline="always")
def light_leg_depth(x, y, z, lx, ly, lz, dist, ctx):
    """Optical depth from ``x`` toward the light (module docstring for directional lights)."""
    if not ctx.light_extinction:
        return 0.0
    if dist == np.inf and not ctx.bounded:
        return 0.0
    far = dist if dist < np.inf else 1e300
    return segment_depth(ctx.medium.params, ctx.medium.noise, x, y, z, lx, ly, lz, 0.0, far)


@njit(cache=True, fastmath=False, inline="always")
def inscatter(t, ray, ctx):
    """The integrand ``f(t)`` (RGB radiance per metre) of the module docstring.

    Numba compiles it, and every helper here that takes the context (~30 arrays), into its caller's IR
    (:mod:`vlref.parallel`, "Calls that carry arrays"); its callers keep one call site each
    (:func:`vlref.reference.quadrature.gk`, the shadow search)."""
    mp, lattice = ctx.medium.params, ctx.medium.noise
    x, y, z = ray[0] + t * ray[3], ray[1] + t * ray[4], ray[2] + t * ray[5]
    s_s, _ = sigma(mp, lattice, x, y, z)
    if s_s == 0.0:
        return 0.0, 0.0, 0.0
    r, g, b = 0.0, 0.0, 0.0
    for light in range(ctx.lights.ints.shape[0]):
        lx, ly, lz, dist, er, eg, eb = light_geometry(light, x, y, z, ctx)
        if er == 0.0 and eg == 0.0 and eb == 0.0:
            continue
        vr, vg, vb = 1.0, 1.0, 1.0
        if ctx.shadows[light, R_SHADOWS] != 0.0:
            vr, vg, vb = _shadow(light, x, y, z, lx, ly, lz, dist, ctx)
        w = hg(ray[3] * lx + ray[4] * ly + ray[5] * lz, mp[M_G]) * math.exp(
            -light_leg_depth(x, y, z, lx, ly, lz, dist, ctx))
        r += w * vr * er
        g += w * vg * eg
        b += w * vb * eb
    tv = s_s * math.exp(-view_optical_depth(ray, 0.0, t, ctx))
    return r * tv, g * tv, b * tv


# ---------------------------------------------------------------------------------------------- split points

@njit(cache=True, fastmath=False)
def _cone_roots(ray, px, py, pz, ax, ay, az, c, out, n):
    """Append the ray parameters where the ray crosses the forward nappe of the cone (apex p, axis a, cos c)."""
    wx, wy, wz = ray[0] - px, ray[1] - py, ray[2] - pz
    da = ray[3] * ax + ray[4] * ay + ray[5] * az
    wa = wx * ax + wy * ay + wz * az
    dw = ray[3] * wx + ray[4] * wy + ray[5] * wz
    ww = wx * wx + wy * wy + wz * wz
    qa = da * da - c * c
    qb = 2.0 * (da * wa - c * c * dw)
    qc = wa * wa - c * c * ww
    roots = np.empty(2)
    m = 0
    if abs(qa) < 1e-14:
        if qb != 0.0:
            roots[0] = -qc / qb
            m = 1
    else:
        disc = qb * qb - 4.0 * qa * qc
        if disc >= 0.0:
            sq = math.sqrt(disc)
            q = -0.5 * (qb + math.copysign(sq, qb))
            if q != 0.0:
                roots[0] = q / qa
                roots[1] = qc / q
                m = 2
    for i in range(m):
        if wa + roots[i] * da >= 0.0 and n < out.size:
            out[n] = roots[i]
            n += 1
    return n


@njit(cache=True, fastmath=False)
def light_interval(light, ray, t0, t1, lights):
    """The part of ``[t0, t1]`` where ``light`` of ``lights`` (the context's) can be non-zero (its range sphere; all
    of it if directional). The per-pixel helpers take the records they read, not the whole context: passing the
    context (its ~30 arrays) costs a call far more than its work."""
    ints, fl = lights.ints, lights.floats
    if ints[light, lp.I_KIND] == lp.KIND_DIRECTIONAL:
        return t0, t1
    wx, wy, wz = ray[0] - fl[light, lp.F_PX], ray[1] - fl[light, lp.F_PY], ray[2] - fl[light, lp.F_PZ]
    b = wx * ray[3] + wy * ray[4] + wz * ray[5]
    h2 = (wx * wx + wy * wy + wz * wz) - b * b
    r = fl[light, lp.F_RANGE]
    if h2 >= r * r:
        return t0, t0
    half = math.sqrt(r * r - h2)
    return max(t0, -b - half), min(t1, -b + half)


@njit(cache=True, fastmath=False)
def peak_substitution(ray, a, b, lights):
    """``(light, tc, h)`` of the change of variable ``t = tc + h tan u`` about the closest approach of the scene's
    only point or spot light of ``lights`` (the context's) to the ray (``tc = dot(P - o, d)``, ``h = |(P - o) × d|``) for the integral over
    ``[a, b]``; ``(-1, 0.0, 0.0)`` where there is none: no light or more than one of those kinds, an empty
    ``[a, b]``, or ``max(|a - tc|, |b - tc|) > MAX_SPREAD h`` (a ray through or very near the light).

    ``f`` carries the light's ``1/r²`` with ``r² = h² + (t - tc)² = h² sec² u``, and ``dt = h sec² u du``, so
    ``f dt/du`` is smooth across the peak (the inverse square cancels): one piece of a few nodes integrates it, where
    ``t`` needs the peak as a split point (vlref.reference.quadrature, step 3)."""
    ints, fl = lights.ints, lights.floats
    light = -1
    for i in range(ints.shape[0]):
        if ints[i, lp.I_KIND] != lp.KIND_DIRECTIONAL:
            if light >= 0:
                return -1, 0.0, 0.0
            light = i
    if light < 0 or not b > a:
        return -1, 0.0, 0.0
    wx, wy, wz = fl[light, lp.F_PX] - ray[0], fl[light, lp.F_PY] - ray[1], fl[light, lp.F_PZ] - ray[2]
    tc = wx * ray[3] + wy * ray[4] + wz * ray[5]
    cx, cy, cz = wy * ray[5] - wz * ray[4], wz * ray[3] - wx * ray[5], wx * ray[4] - wy * ray[3]
    h = math.sqrt(cx * cx + cy * cy + cz * cz)
    if not h * MAX_SPREAD >= max(abs(a - tc), abs(b - tc)):
        return -1, 0.0, 0.0
    return light, tc, h


@njit(cache=True, fastmath=False)
def split_points(ray, t0, t1, lights, mp, out, substituted):
    """Write the known discontinuities of ``f`` (or of its derivatives) in ``[t0, t1]`` into ``out`` (``lights`` and
    the medium's parameters ``mp``, the context's): light
    range spheres, spot cones (outer and inner), each point/spot light's closest approach but that of light
    ``substituted`` (integrated in the variable of :func:`peak_substitution`; -1: none), the medium box;
    returns the count. (Shadow boundaries are found separately by the visibility search.)"""
    ints, fl = lights.ints, lights.floats
    n = 0
    a, b = clip_to_bounds(mp, ray[0], ray[1], ray[2], ray[3], ray[4], ray[5], t0, t1)
    out[0], out[1] = a, b
    n = 2
    for light in range(ints.shape[0]):
        kind = ints[light, lp.I_KIND]
        if kind == lp.KIND_DIRECTIONAL:
            continue
        lo, hi = light_interval(light, ray, t0, t1, lights)
        if hi > lo:
            out[n], out[n + 1] = lo, hi
            n += 2
        px, py, pz = fl[light, lp.F_PX], fl[light, lp.F_PY], fl[light, lp.F_PZ]
        if light != substituted:
            out[n] = (px - ray[0]) * ray[3] + (py - ray[1]) * ray[4] + (pz - ray[2]) * ray[5]
            n += 1
        if kind == lp.KIND_SPOT:
            ax, ay, az = fl[light, lp.F_DX], fl[light, lp.F_DY], fl[light, lp.F_DZ]
            n = _cone_roots(ray, px, py, pz, ax, ay, az, fl[light, lp.F_COS_OUTER], out, n)
            n = _cone_roots(ray, px, py, pz, ax, ay, az, fl[light, lp.F_COS_INNER], out, n)
    return n
