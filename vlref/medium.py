"""The participating medium: density, optical depth along a segment, and the two Beer–Lambert rules the
marches share.

``σs(x) = scattering · ρ(x)``, ``σt(x) = (scattering + absorption) · ρ(x)`` (1/m) with the density factor

    ρ(x) = [x ∈ bounds] · fog(y) · noise(x)

* ``bounds``: the optional axis-aligned box of ``medium.bounds`` (Mitsuba-style bounded medium); ρ = 0
  outside it. Unbounded when absent.
* ``fog(y) = exp(-(y - base) · falloff)`` (height fog; 1 without it). The exponent is capped at
  ``FOG_MAX_EXPONENT = 60`` so that no valid input overflows (ρ ≤ e^60 far below ``base``).
* ``noise(x) = saturate(saturate(n(p) - offset) · intensity)`` with ``p = scale · (x - velocity · time)``
  in lattice cells (the field moves *with* the velocity; VolumetricLights samples ``s·(x + t·v)``,
  i.e. its field moves by ``-v t``). ``n`` is our value noise: i.i.d. uniform [0, 1) values on a
  ``period³`` lattice drawn from ``numpy.random.default_rng(seed)``, interpolated trilinearly and
  periodic (tileable) with period ``period`` cells. Lattice values sit at cell centres, as texels of a
  ``Texture3D`` with repeat wrap: ``n(p)`` blends the 8 values around ``p - 0.5``. Loading
  VolumetricLights' ``NoiseVolume.bytes`` (DDS 128³ L8, voxel ``(w, h, d)`` = byte
  ``128 + w + 128 h + 16384 d`` / 255 on lattice axes x, y, z) replaces the lattice; VL parity then
  needs ``scale = 128 · NoiseScale``.

Optical depth ``τ(t0, t1) = ∫ σt(o + t d) dt`` (:func:`optical_depth`): the segment is first clipped to
the box; without noise it is analytic (homogeneous ``σt · L``; height fog in closed form
``σt · L · e^m · (1 - e^-|Δ|)/|Δ|`` with ``e_a, e_b`` the fog exponents at the ends, ``m = max``,
``Δ = e_a - e_b``: ``σt · L`` times the fog factor's mean along the segment, :func:`fog_mean_factor`); with noise
it is the midpoint rule with ``n_sub`` sub-steps.

The Beer–Lambert rules every march applies (the physical march, :mod:`vlref.march.physical`, and the froxel
passes, :mod:`vlref.froxel.kernels`), each written once:

* :func:`step_source_weight`: over a step of length ``Δ`` where ``σt`` is constant, a constant source ``S``
  adds ``S ∫_0^Δ e^{-σt s} ds = S (1 - e^{-σt Δ})/σt`` (``S Δ`` where ``σt = 0``) under the transmittance
  at the step's start (Hillaire 2015, "energy-conserving" integration);
* :func:`light_leg_attenuates`: the light leg ``T_l`` (sample → light) is ``exp(-τ)`` when
  ``light_extinction`` is on and the medium extinguishes at all, except for a directional light in an
  unbounded medium, where ``T_l = 1`` (its irradiance is the irradiance arriving at the sample: an
  infinite medium would otherwise extinguish it completely; ``medium.bounds`` attenuates sunlight on its
  way in).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .errors import InputError
from .jit import njit
from .numeric import cast, exp, is_float64

__all__ = ["PackedMedium", "pack_medium", "noise_lattice", "load_noise_volume", "density", "smooth_density", "sigma",
           "noise_value", "clip_to_bounds", "optical_depth", "smooth_optical_depth", "fog_exponent", "height_exponent",
           "fog_mean_factor", "FOG_SERIES_BELOW", "in_bounds", "box_contains", "step_source_weight",
           "light_leg_attenuates", "FOG_MAX_EXPONENT"]

FOG_MAX_EXPONENT = 60.0
(M_SS, M_ST, M_G, M_FOG, M_FOG_BASE, M_FOG_K, M_BOUNDED, M_BX0, M_BY0, M_BZ0, M_BX1, M_BY1, M_BZ1, M_NOISE,
 M_NSCALE, M_NINT, M_NOFF, M_NSX, M_NSY, M_NSZ) = range(20)
NM = 20


class PackedMedium(NamedTuple):
    """The medium record the njit kernels take: ``params`` (NM,) float (columns ``M_*``) and the noise
    lattice ``noise`` (P, P, P) float."""

    params: np.ndarray
    noise: np.ndarray

    def astype(self, dtype) -> "PackedMedium":
        return PackedMedium(self.params.astype(dtype), self.noise.astype(dtype))


def noise_lattice(period: int, seed: int) -> np.ndarray:
    """The (period, period, period) value-noise lattice of ``seed`` (uniform [0, 1), float64)."""
    return np.random.default_rng(seed).random((period, period, period))


def load_noise_volume(path: str, file: str = "<noise>", key: str = "medium.noise.path") -> np.ndarray:
    """Read a DDS L8 volume (VolumetricLights' ``NoiseVolume.bytes``) as a lattice ``[x, y, z]`` in [0, 1]."""
    try:
        raw = np.fromfile(path, dtype=np.uint8)
    except OSError as exc:
        raise InputError(file, key, f"cannot read noise volume {path}: {exc.strerror or exc}") from None
    if raw.size < 128 or bytes(raw[:4]) != b"DDS ":
        raise InputError(file, key, f"{path} is not a DDS file")
    head = raw[:128].view("<u4")
    h, w, d = int(head[3]), int(head[4]), int(head[6])
    if w < 1 or h < 1 or d < 1 or raw.size != 128 + w * h * d:
        raise InputError(file, key, f"{path}: expected an 8-bit {w}x{h}x{d} volume ({128 + w * h * d} bytes), "
                                    f"got {raw.size} bytes")
    if not (w == h == d):
        raise InputError(file, key, f"{path}: the noise volume must be cubic, got {w}x{h}x{d}")
    return raw[128:].reshape(d, h, w).transpose(2, 1, 0) / 255.0


def pack_medium(scene, dtype=np.float64) -> PackedMedium:
    """Pack ``scene.medium`` (time and seed from ``scene.render``) for the njit kernels."""
    m = scene.medium
    p = np.zeros(NM)
    p[M_SS], p[M_ST], p[M_G] = m.scattering, m.extinction, m.anisotropy
    if m.height_fog is not None:
        p[M_FOG], p[M_FOG_BASE], p[M_FOG_K] = 1.0, m.height_fog.base, m.height_fog.falloff
    if m.bounds is not None:
        p[M_BOUNDED] = 1.0
        p[M_BX0:M_BZ0 + 1], p[M_BX1:M_BZ1 + 1] = m.bounds.min, m.bounds.max
    lattice = np.zeros((1, 1, 1))
    if m.noise is not None:
        n = m.noise
        p[M_NOISE], p[M_NSCALE], p[M_NINT], p[M_NOFF] = 1.0, n.scale, n.intensity, n.offset
        p[M_NSX:M_NSZ + 1] = np.asarray(n.velocity) * scene.render.time
        if n.path is not None:
            lattice = load_noise_volume(n.path, scene.source or "<scene>")
        else:
            lattice = noise_lattice(n.period, scene.render.seed if n.seed is None else n.seed)
    return PackedMedium(p.astype(dtype), np.ascontiguousarray(lattice, dtype=dtype))


@njit(cache=True, fastmath=False, forceinline=True)
def noise_value(lattice, px, py, pz):
    """Trilinear, periodic sample of ``lattice`` at ``p`` (lattice cells; values at cell centres)."""
    n = lattice.shape[0]
    half = cast(px, 0.5)
    one = cast(px, 1.0)
    cx, cy, cz = px - half, py - half, pz - half
    fx, fy, fz = math.floor(cx), math.floor(cy), math.floor(cz)
    wx, wy, wz = cx - fx, cy - fy, cz - fz
    x0, y0, z0 = int(fx) % n, int(fy) % n, int(fz) % n
    x1, y1, z1 = (x0 + 1) % n, (y0 + 1) % n, (z0 + 1) % n
    c00 = lattice[x0, y0, z0] * (one - wx) + lattice[x1, y0, z0] * wx
    c10 = lattice[x0, y1, z0] * (one - wx) + lattice[x1, y1, z0] * wx
    c01 = lattice[x0, y0, z1] * (one - wx) + lattice[x1, y0, z1] * wx
    c11 = lattice[x0, y1, z1] * (one - wx) + lattice[x1, y1, z1] * wx
    return (c00 * (one - wy) + c10 * wy) * (one - wz) + (c01 * (one - wy) + c11 * wy) * wz


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def height_exponent(base, falloff, y):
    """The height-fog exponent ``min(-(y - base) · falloff, FOG_MAX_EXPONENT)`` (fog factor = its exp)."""
    return min(-(y - base) * falloff, cast(y, FOG_MAX_EXPONENT))


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def fog_exponent(mp, y):
    """:func:`height_exponent` of the packed medium ``mp``."""
    return height_exponent(mp[M_FOG_BASE], mp[M_FOG_K], y)


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def box_contains(x0, y0, z0, x1, y1, z1, x, y, z):
    """The point lies in the closed box ``[x0, x1] × [y0, y1] × [z0, z1]``."""
    return not (x < x0 or x > x1 or y < y0 or y > y1 or z < z0 or z > z1)


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def in_bounds(mp, x, y, z):
    """The point lies in the medium's box (always, for an unbounded medium)."""
    if mp[M_BOUNDED] == cast(x, 0.0):
        return True
    return box_contains(mp[M_BX0], mp[M_BY0], mp[M_BZ0], mp[M_BX1], mp[M_BY1], mp[M_BZ1], x, y, z)


FOG_SERIES_BELOW = (0.1, 1.0)
"""``δ_c`` of :func:`fog_mean_factor` in float64 and float32: below it the series, above it the difference."""
FOG_SERIES = tuple(1.0 / math.factorial(k + 1) for k in range(9))
"""The Taylor coefficients ``1/(k + 1)!``, ``k = 0..8``, of ``(1 - e^{-δ})/δ = Σ_k (-δ)^k / (k + 1)!``."""


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def fog_mean_factor(fa, fb, delta):
    """The mean of the height-fog factor ``e^{e(s)}`` along a straight segment whose ends have factors
    ``fa = e^{e_a}`` and ``fb = e^{e_b}``, ``δ = |e_a - e_b|`` (the optical depth of the segment is ``σt · L``
    times it). The exponent is linear along the segment, so the mean is

        (max(fa, fb) - min(fa, fb)) / δ  =  e^{max} (1 - e^{-δ}) / δ,

    taken as the difference of the two factors from ``δ_c`` up (:data:`FOG_SERIES_BELOW`: 0.1 in float64, 1 in
    float32) and below it as ``max(fa, fb) Σ_{k=0}^{8} (-δ)^k / (k + 1)!`` (the Taylor series of
    ``(1 - e^{-δ})/δ``; its first omitted term ``δ^9/10!`` is below 3e-16 at 0.1 and 3e-7 at 1), where the
    difference would cancel: a relative error ``ε`` of a factor (a running product's rounding, ~1e-14 in
    float64, ~3e-6 in float32) becomes ``≈ ε/δ`` in the difference. No ``exp`` or ``expm1`` of its own: the
    caller has the factors (the march's light leg: the sample's running product and the light's factor)."""
    top, bottom = max(fa, fb), min(fa, fb)
    series = cast(delta, FOG_SERIES[8])
    for k in range(7, -1, -1):  # Horner in -δ
        series = cast(delta, FOG_SERIES[k]) - delta * series
    cut = cast(delta, FOG_SERIES_BELOW[0] if is_float64(delta) else FOG_SERIES_BELOW[1])
    return top * series if delta < cut else (top - bottom) / delta


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def smooth_density(mp, x, y, z):
    """The density factor without the noise: ``[x ∈ bounds] · fog(y)`` (module docstring)."""
    if not in_bounds(mp, x, y, z):
        return cast(x, 0.0)
    if mp[M_FOG] != cast(x, 0.0):
        return exp(fog_exponent(mp, y))
    return cast(x, 1.0)


@njit(cache=True, fastmath=False, forceinline=True)
def density(mp, lattice, x, y, z):
    """Density factor ρ(x) ≥ 0 (module docstring)."""
    zero = cast(x, 0.0)
    one = cast(x, 1.0)
    rho = smooth_density(mp, x, y, z)
    if mp[M_NOISE] != zero and rho != zero:
        s = mp[M_NSCALE]
        n = noise_value(lattice, s * (x - mp[M_NSX]), s * (y - mp[M_NSY]), s * (z - mp[M_NSZ]))
        rho *= min(max(max(n - mp[M_NOFF], zero) * mp[M_NINT], zero), one)
    return rho


@njit(cache=True, fastmath=False)
def sigma(mp, lattice, x, y, z):
    """``(σs, σt)`` at a point (1/m)."""
    rho = density(mp, lattice, x, y, z)
    return mp[M_SS] * rho, mp[M_ST] * rho


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def clip_to_bounds(mp, ox, oy, oz, dx, dy, dz, t0, t1):
    """``[t0, t1]`` clipped to the medium box (slab test); empty when the result has ``a >= b``."""
    if mp[M_BOUNDED] == cast(ox, 0.0):
        return t0, t1
    a, b = t0, t1
    o3 = (ox, oy, oz)
    d3 = (dx, dy, dz)
    for k in range(3):
        lo, hi = mp[M_BX0 + k], mp[M_BX1 + k]
        if d3[k] == cast(ox, 0.0):
            if o3[k] < lo or o3[k] > hi:
                return t0, t0
            continue
        inv = cast(ox, 1.0) / d3[k]
        ta, tb = (lo - o3[k]) * inv, (hi - o3[k]) * inv
        a = max(a, min(ta, tb))
        b = min(b, max(ta, tb))
    if a >= b:
        return t0, t0
    return a, b


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def _smooth_depth(mp, oy, dy, a, b):
    """``τ(a, b)`` of the noiseless medium on an interval inside the box: ``σt L`` or the height-fog closed form."""
    length = b - a
    if mp[M_FOG] == cast(oy, 0.0):
        return mp[M_ST] * length
    ea = fog_exponent(mp, oy + a * dy)
    eb = fog_exponent(mp, oy + b * dy)
    return mp[M_ST] * length * fog_mean_factor(exp(ea), exp(eb), abs(ea - eb))


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def smooth_optical_depth(mp, ox, oy, oz, dx, dy, dz, t0, t1):
    """:func:`optical_depth` of a medium without noise (no loop, no call: the march's lane loops vectorise it)."""
    zero = cast(ox, 0.0)
    a, b = clip_to_bounds(mp, ox, oy, oz, dx, dy, dz, t0, t1)
    if not b - a > zero or mp[M_ST] == zero:
        return zero
    return _smooth_depth(mp, oy, dy, a, b)


@njit(cache=True, fastmath=False, forceinline=True)
def optical_depth(mp, lattice, ox, oy, oz, dx, dy, dz, t0, t1, n_sub):
    """τ = ∫_{t0}^{t1} σt(o + t d) dt for a unit direction ``d`` (module docstring); 0 for ``t1 <= t0``."""
    zero = cast(ox, 0.0)
    if mp[M_NOISE] == zero:
        return smooth_optical_depth(mp, ox, oy, oz, dx, dy, dz, t0, t1)
    a, b = clip_to_bounds(mp, ox, oy, oz, dx, dy, dz, t0, t1)
    length = b - a
    if not length > zero or mp[M_ST] == zero:
        return zero
    h = length / cast(ox, n_sub)
    acc = zero
    for i in range(n_sub):
        t = a + (cast(ox, i) + cast(ox, 0.5)) * h
        acc += density(mp, lattice, ox + t * dx, oy + t * dy, oz + t * dz)
    return mp[M_ST] * acc * h


# ---------------------------------------------------------------------------------------------- Beer–Lambert rules

@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def step_source_weight(st, delta, em1):
    """``∫_0^Δ e^{-σt s} ds = (1 - e^{-σt Δ})/σt`` (``Δ`` where ``σt = 0``), the weight of a source constant
    over a step of length ``delta`` (module docstring). ``em1 = expm1(-σt Δ)``, which the caller computes (it
    also needs ``e^{-σt Δ} = 1 + em1`` for the transmittance update); any float type, kept."""
    return delta if st == 0.0 else -em1 / st


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def light_leg_attenuates(mp, directional, light_extinction):
    """Whether the light leg ``T_l`` of a sample is ``exp(-τ)`` (True) or 1 (module docstring): the medium
    ``mp`` extinguishes, ``light_extinction`` is on, and the light is not ``directional`` in an unbounded
    medium."""
    return light_extinction and mp[M_ST] != 0.0 and not (directional and mp[M_BOUNDED] == 0.0)
