"""Henyey-Greenstein phase function.

``p(cos θ; g) = (1 - g²) / (4π (1 + g² - 2 g cos θ)^{3/2})``  (Henyey & Greenstein 1941;
docs/CONVENTIONS.md). ``cos θ = dot(d, l)`` with ``d`` the view-ray direction (camera -> scene) and ``l``
the unit vector from the sample *toward* the light, so looking into the light with ``g > 0``
is the forward peak. Mitsuba writes the same law with its direction vectors reversed
(``wi`` points away from the scattering point); the port's ``cos θ`` is then ``-dot``.
"""

from __future__ import annotations

import math

import numpy as np

from .jit import njit
from .numeric import cast

INV_4PI = 1.0 / (4.0 * math.pi)


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def hg(cos_theta, g):
    """Henyey-Greenstein phase value (1/sr) for one cosine, in the precision of ``g``; valid for |g| < 1."""
    one = cast(g, 1.0)
    denom = one + g * g - cast(g, 2.0) * g * cos_theta
    return cast(g, INV_4PI) * (one - g * g) / (denom * math.sqrt(denom))


def hg_array(cos_theta, g):
    """Vectorised NumPy Henyey-Greenstein for plots and tests."""
    c = np.asarray(cos_theta, dtype=np.float64)
    denom = 1.0 + g * g - 2.0 * g * c
    return INV_4PI * (1.0 - g * g) / (denom * np.sqrt(denom))
