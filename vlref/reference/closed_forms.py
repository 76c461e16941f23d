"""Closed forms of the single-scattering integral for simple configurations.

They check the quadrature reference (:mod:`vlref.reference.quadrature`) and the march. Every
function is vectorised over rays: array arguments broadcast against each other and the result has
the broadcast shape. Units: lengths in metres, coefficients in 1/m, point-light intensity ``I`` in
W/sr (radiant intensity, so the irradiance at distance ``r`` is ``I / r²``), directional
irradiance ``E`` in W/m²; the results are radiances (W/(m² sr)).

Notation (docs/PHYSICS.md "The integral"): a camera ray ``x(t) = o + t·d`` with ``|d| = 1``, integrated over
``t ∈ [t0, t1]``; the view transmittance is measured from the ray origin (``t = 0``), so the
in-scattered radiance is

    L = ∫_{t0}^{t1} e^{-σt·t} σs p(cos θ) T_l(t) E(x(t)) dt.

For a point light at ``P``: ``tc = dot(P - o, d)`` is the ray parameter of the closest approach,
``h = |P - o - tc·d|`` the closest-approach distance, the light distance is
``r(t) = sqrt(h² + (t - tc)²)`` and ``cos θ = dot(d, l) = (tc - t) / r(t)`` (``l`` toward the light).

Functions
---------
* :func:`point_light_no_extinction` (a): σt = 0, isotropic phase, ``E = I / r²``.
* :func:`directional_homogeneous` (b): a directional light in a homogeneous medium, with an
  optional light leg whose length is affine in ``t`` (a box-bounded medium lit from outside).
* :func:`point_light_extinction` (c): point light, extinction on both legs, HG phase — the
  1D integral evaluated by SciPy's adaptive QUADPACK (``quad``), not by a special function.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from ..phase import hg, hg_array

__all__ = ["closest_approach", "point_light_no_extinction", "directional_homogeneous", "point_light_extinction"]

INV_4PI = 1.0 / (4.0 * math.pi)


def closest_approach(origin, direction, light_position):
    """``(tc, h)`` of a point relative to rays: ``tc = dot(P - o, d)``, ``h = |P - o - tc d|``.

    ``origin``, ``direction`` (unit) and ``light_position`` are (..., 3) arrays that broadcast.
    ``h`` is computed from the cross product ``|(P - o) × d|``, which keeps full relative
    accuracy for rays passing close to the light.
    """
    rel = np.asarray(light_position, dtype=np.float64) - np.asarray(origin, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    tc = np.sum(rel * d, axis=-1)
    h = np.linalg.norm(np.cross(rel, d), axis=-1)
    return tc, h


def point_light_no_extinction(sigma_s, intensity, tc, h, t0, t1):
    """(a) In-scattered radiance of an isotropic point light without extinction.

    ``L = σs I / (4π) ∫_{t0}^{t1} dt / (h² + (t - tc)²) = σs I / (4π h) [atan((t1-tc)/h) - atan((t0-tc)/h)]``

    (elementary antiderivative; the airlight of Sun et al. 2005 at zero optical thickness). With
    ``a = t0 - tc`` and ``b = t1 - tc`` the bracket is evaluated as ``atan2(h (b - a), h² + a b)``
    (the difference formula of atan, exact on the branch because ``b ≥ a`` and ``h > 0``), which
    avoids the cancellation of two nearly equal angles for rays far from the light. For
    ``h → 0`` it tends to ``(b - a) / (a b) = 1/a - 1/b`` when the light is outside
    ``[t0, t1]`` (``a b > 0``); a ray through the light (``h = 0``, ``a b ≤ 0``) gives ``inf``.
    """
    sigma_s, intensity, tc, h, t0, t1 = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64)
                                                             for v in (sigma_s, intensity, tc, h, t0, t1)))
    a = t0 - tc
    b = t1 - tc
    ab = a * b
    with np.errstate(divide="ignore", invalid="ignore"):
        general = np.arctan2(h * (b - a), h * h + ab) / h
        limit = np.where(ab > 0.0, (b - a) / ab, np.inf)
    bracket = np.where(h > 0.0, general, limit)
    return sigma_s * intensity * INV_4PI * bracket


def directional_homogeneous(sigma_s, sigma_t, g, cos_theta, irradiance, t0, t1, leg0=0.0, leg_rate=0.0):
    """(b) In-scattered radiance of a directional light in a homogeneous medium.

    The light leg (the path from the sample toward the light inside the medium) has length
    ``ℓ(t) = leg0 + leg_rate · t`` on ``[t0, t1]`` (``0, 0`` = no light-leg extinction, the textbook
    case; a box-bounded medium lit through its top face gives ``leg0 = (y_max - o_y)/l_y``,
    ``leg_rate = -d_y/l_y``). The integrand ``σs p E e^{-σt t} e^{-σt ℓ(t)}`` is one exponential, so

    ``L = σs p(cos θ) E e^{-σt (leg0 + k t0)} (1 - e^{-σt k (t1 - t0)}) / (σt k)``, ``k = 1 + leg_rate``.

    With ``leg0 = leg_rate = t0 = 0`` this is ``σs p E (1 - e^{-σt D}) / σt`` (``D = t1``). The
    limit ``σt k → 0`` is ``σs p E (t1 - t0)``; the factor ``(1 - e^{-x}) / x`` is evaluated with
    ``expm1`` so it is accurate for every ``x ≥ 0``.
    """
    args = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in
                                 (sigma_s, sigma_t, cos_theta, irradiance, t0, t1, leg0, leg_rate)))
    sigma_s, sigma_t, cos_theta, irradiance, t0, t1, leg0, leg_rate = args
    length = t1 - t0
    x = sigma_t * (1.0 + leg_rate) * length
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(x > 0.0, -np.expm1(-x) / x, 1.0)
    start = np.exp(-sigma_t * (leg0 + (1.0 + leg_rate) * t0))
    return sigma_s * hg_array(cos_theta, g) * irradiance * start * ratio * length


def _point_integrand(t, sigma_s, sigma_t, g, intensity, tc, h):
    r2 = h * h + (t - tc) * (t - tc)
    r = math.sqrt(r2)
    return sigma_s * intensity * hg((tc - t) / r, g) * math.exp(-sigma_t * (t + r)) / r2


def point_light_extinction(sigma_s, sigma_t, g, intensity, tc, h, t0, t1, rel_tol=1e-12):
    """(c) In-scattered radiance of a point light with extinction on both legs and HG phase.

    ``L = ∫_{t0}^{t1} σs I p((tc - t)/r) e^{-σt (t + r(t))} / r(t)² dt``, ``r(t) = sqrt(h² + (t - tc)²)``.

    This is the airlight integral of Sun, Ramamoorthi, Narasimhan & Nayar (SIGGRAPH 2005), which
    they reduce to a tabulated special function ``F(u, v)`` for isotropic scattering. Here it is
    evaluated directly, ray by ray, with SciPy's adaptive Gauss–Kronrod (QUADPACK ``qagp``),
    ``epsabs = 0``, ``epsrel = rel_tol`` (1e-12 by default, so the result is good to ~1e-10
    relative even after QUADPACK's error estimate is discounted), ``limit = 500`` subintervals, and
    the interval split at ``tc`` where the integrand peaks (width ``~h``). It is independent of the
    Numba quadrature of the reference (different rule placement, error control and code).
    Requires ``h > 0`` wherever ``tc ∈ [t0, t1]``.
    """
    args = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in
                                 (sigma_s, sigma_t, g, intensity, tc, h, t0, t1)))
    out = np.empty(args[0].shape)
    for idx in np.ndindex(out.shape):
        ss, st, gg, ii, c, hh, a, b = (float(v[idx]) for v in args)
        points = [c] if a < c < b else None
        value, _ = integrate.quad(_point_integrand, a, b, args=(ss, st, gg, ii, c, hh), points=points,
                                  epsabs=0.0, epsrel=rel_tol, limit=500)
        out[idx] = value
    return out
