"""Rec. 709 luminance of linear RGB, and the exposure that maps a percentile of it to 1 for previews."""

from __future__ import annotations

import numpy as np

__all__ = ["LUMINANCE", "luminance", "percentile_exposure"]

LUMINANCE = (0.2126, 0.7152, 0.0722)
"""Rec. 709 / sRGB luminance weights of linear RGB."""


def luminance(image: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance ``0.2126 R + 0.7152 G + 0.0722 B`` of ``(H, W, 3)``; ``(H, W)``/(H, W, 1) pass through."""
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 3 and a.shape[2] == 1:
        return a[:, :, 0]
    return a @ np.asarray(LUMINANCE) if a.ndim == 3 else a


def percentile_exposure(values: np.ndarray, percentile: float = 99.0) -> tuple[float, float]:
    """``(1 / level, level)``, ``level`` the ``percentile`` of the finite ``values``: the exposure that maps that
    level to 1 before the tone map (where the ACES fit gives 0.80, sRGB code 231). ``(1, level)`` when the
    level is not positive (a black image)."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]  # a copy of our own: partitioned in place
    level = float(np.percentile(v, percentile, overwrite_input=True)) if v.size else 0.0
    return (1.0 / level if level > 0.0 else 1.0), level
