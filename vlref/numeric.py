"""Numeric helpers shared by the kernels."""

from __future__ import annotations

import numpy as np
from numba import types
from numba.extending import overload


def cast(like, value):
    """``value`` in the float type of ``like``; inside njit code float32 stays float32.

    Python float literals are float64 in Numba and would promote float32 arithmetic, so a
    kernel compiled for float32 writes ``cast(x, 2.0)`` where it means "2 in x's precision".
    """
    return type(like)(value)


@overload(cast)
def _cast_impl(like, value):
    if like == types.float32:
        return lambda like, value: np.float32(value)
    return lambda like, value: np.float64(value)
