"""The URP tutorial's march (Valerio Marty; SOURCES §2.3): one directional light.

Per low-res pixel with Blit uv ``(u, v)`` (``v`` up from the bottom, Unity) and view ray ``d`` to
the reconstructed world position ``P`` (at the far plane on sky):

    L = min(|P - c|, MaxDistance),  Δ = L / Steps,  j = rand(u, v) · Δ · Jitter / 100
    x_i = c + (j + i Δ) d,  i = 0 .. Steps - 2          (Steps - 1 samples; the end is not adjusted)
    F = (1 / Steps) Σ_i [S(x_i) > 0] · saturate(p_HG(dot(d, l); g))

``rand(u, v) = frac(sin(41 u + 289 v) · 45758.5453)``, ``l`` the unit vector toward the light and ``g``
in :func:`vlref.phase.hg`'s convention (the tutorial evaluates ``p_HG(dot(d, s); _Scattering)`` with
``s = -l`` the light's forward vector, i.e. ``_Scattering = -g``: the same value bit for bit, as both
negations are exact), ``S`` the main-light shadow attenuation used only as a binary test. The hash depends on the GPU's ``sin`` for arguments up to ~330 rad and is NOT
reproducible across GPUs: :func:`urp_hash` evaluates it in float32 with NumPy's ``sin``; ports
inject their own buffer (``techniques.urp.jitter_path``) or compare statistically.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..jit import njit
from ..lights.pack import KIND_DIRECTIONAL
from ..lights.shadow_lookup import shadow_visibility
from ..phase import hg

__all__ = ["urp_hash", "urp_march", "HASH_A", "HASH_B", "HASH_K"]

HASH_A, HASH_B, HASH_K = 41.0, 289.0, 45758.5453


def urp_hash(width: int, height: int, uv_origin: str = "bottom") -> np.ndarray:
    """``rand(uv)`` of every pixel of a ``width x height`` target, (h, w) float64 in [0, 1), row 0 on top.

    ``u = (x + 0.5)/w``; ``v = (y_b + 0.5)/h`` with ``y_b`` the row counted from the bottom
    (``uv_origin="bottom"``, Unity's Blit uv) or from the top. Evaluated in float32.
    """
    u = ((np.arange(width, dtype=np.float32) + np.float32(0.5)) / np.float32(width))[None, :]
    rows = np.arange(height)
    yb = (height - 1 - rows) if uv_origin == "bottom" else rows
    v = ((yb.astype(np.float32) + np.float32(0.5)) / np.float32(height))[:, None]
    x = np.sin(np.float32(HASH_A) * u + np.float32(HASH_B) * v) * np.float32(HASH_K)
    r = x - np.floor(x)
    return np.where(r >= np.float32(1.0), np.float32(0.0), r).astype(np.float64)


@njit(cache=True, fastmath=False, parallel=True)
def urp_march(cam, dirs, length, rand, n_steps, jitter, g, toward, shadows, geo, lf, light):
    """The fog ``F`` (h, w) of the module docstring, prange over pixels.

    dirs (h, w, 3) unit rays; length (h, w) the clamped ray length ``L``; rand (h, w) the hash;
    toward (3,) the unit vector toward the light (minus its forward vector); ``shadows`` the :class:`~vlref.lights.shadow_pack.ShadowTable`, ``lf``
    the packed light floats, ``light`` the light's index.
    """
    h, w = length.shape
    out = np.zeros((h, w))
    for p in prange(h * w):
        r, c = p // w, p % w
        dx, dy, dz = dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2]
        step = length[r, c] / n_steps
        t = rand[r, c] * step * jitter / 100.0
        phase = min(max(hg(dx * toward[0] + dy * toward[1] + dz * toward[2], g), 0.0), 1.0)
        acc = 0.0
        for i in range(n_steps - 1):
            x, y, z = cam[0] + t * dx, cam[1] + t * dy, cam[2] + t * dz
            vr, vg, vb = shadow_visibility(shadows, geo, KIND_DIRECTIONAL, lf, light, x, y, z)
            if (vr + vg + vb) / 3.0 > 0.0:
                acc += phase
            t += step
        out[r, c] = acc / n_steps
    return out
