"""Error metrics between a reference and a test image, over a mask of compared pixels.

Images are ``(H, W, C)`` arrays (any channel count, equal in both); ``mask`` is ``(H, W)`` bool, true
where a pixel is compared. All sums are taken in float64 over the compared values (every channel of
every compared pixel). With ``d = |t - r|``:

* ``max_abs = max d``, ``mean_abs = mean d``, ``rmse = sqrt(mean d^2)``;
* ``rel_l2 = ||t - r||_2 / ||r||_2`` (0 when both are zero, inf when only the reference is zero);
* ``psnr = 10 log10(peak^2 / mse)`` dB with ``peak = max |r|`` over the compared values (HDR images have
  no fixed white, so the reference's own peak stands in for it); inf when the images are equal;
* per-pixel thresholds: a value is over the absolute threshold when ``d > abs_thr``, over the relative
  one when ``d > rel_tol |r|``, and **fails** when ``d > abs_thr + rel_tol |r|``. A pixel is over / fails
  when any of its channels is; the fractions count pixels out of the compared pixels.
* HDR-FLIP (Andersson et al. 2021, NVIDIA ``flip-evaluator``): see :func:`hdr_flip`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["failing_pixels", "error_metrics", "FlipResult", "hdr_flip"]


def failing_pixels(ref: np.ndarray, test: np.ndarray, abs_thr: float, rel_tol: float) -> np.ndarray:
    """``(..., C)`` -> ``(...)`` bool: true where ``|t_c - r_c| > abs_thr + rel_tol |r_c|`` in any channel ``c``.

    A value exactly at its threshold passes. Non-finite values must have been masked out first.
    """
    r = np.asarray(ref, dtype=np.float64)
    d = np.abs(np.asarray(test, dtype=np.float64) - r)
    return np.any(d > abs_thr + rel_tol * np.abs(r), axis=-1)


def error_metrics(ref: np.ndarray, test: np.ndarray, mask: np.ndarray, abs_thr: float, rel_tol: float) -> dict:
    """The metrics of the module docstring over ``mask`` (which must select at least one pixel)."""
    r = np.asarray(ref, dtype=np.float64)[mask]  # (N, C)
    t = np.asarray(test, dtype=np.float64)[mask]
    d = np.abs(t - r)
    n = r.shape[0]
    mse = float(np.mean(d * d))
    peak = float(np.max(np.abs(r)))
    ref_norm = math.sqrt(float(np.sum(r * r)))
    diff_norm = math.sqrt(float(np.sum(d * d)))
    if ref_norm > 0:
        rel_l2 = diff_norm / ref_norm
    else:
        rel_l2 = 0.0 if diff_norm == 0 else math.inf
    if mse == 0:
        psnr = math.inf
    elif peak == 0:
        psnr = -math.inf
    else:
        psnr = 10.0 * math.log10(peak * peak / mse)
    fail = failing_pixels(r, t, abs_thr, rel_tol)
    return {
        "max_abs": float(np.max(d)),
        "mean_abs": float(np.mean(d)),
        "rmse": math.sqrt(mse),
        "rel_l2": rel_l2,
        "psnr": psnr,
        "peak": peak,
        "ref_mean_abs": float(np.mean(np.abs(r))),
        "frac_over_abs": float(np.count_nonzero(np.any(d > abs_thr, axis=-1))) / n,
        "frac_over_rel": float(np.count_nonzero(np.any(d > rel_tol * np.abs(r), axis=-1))) / n,
        "frac_failing": float(np.count_nonzero(fail)) / n,
        "failing_pixels": int(np.count_nonzero(fail)),
        "compared_pixels": int(n),
    }


@dataclass
class FlipResult:
    """Mean HDR-FLIP over the compared pixels and the ``(H, W)`` error map in [0, 1], or why not."""

    mean: float | None
    error_map: np.ndarray | None
    note: str = ""

    @property
    def available(self) -> bool:
        return self.mean is not None


_FLIP_CLIP = 2.0 ** 20  # values above this (after scaling, reference peak < 1) saturate at every exposure


def _flip_rgb(image: np.ndarray) -> np.ndarray | None:
    """1 channel -> grey RGB, 3 -> as is, 4 -> RGB (alpha ignored); other counts have no colour meaning."""
    c = image.shape[2]
    if c == 1:
        return np.repeat(image, 3, axis=2)
    if c in (3, 4):
        return image[:, :, :3]
    return None


FLIP_MISSING = "flip-evaluator is not installed (a core dependency: pip install flip-evaluator)"


def hdr_flip(ref: np.ndarray, test: np.ndarray, mask: np.ndarray) -> FlipResult:
    """HDR-FLIP of ``test`` against ``ref`` with the ``flip-evaluator`` package (imported lazily).

    FLIP wants linear, non-negative RGB: 1-channel images are shown as grey, RGBA drops alpha, other
    channel counts are reported as unavailable; negative values are clipped to 0 (noted). Pixels
    outside ``mask`` are set to 0 in both images, and the mean is taken over the compared pixels
    only. Both images are scaled by the same power of two so that the reference's largest value lies
    in [0.5, 1), and values above 2^20 are clipped: HDR-FLIP picks its exposure range from the
    reference's luminance, so this leaves the result unchanged while keeping that automatic range
    well defined (the library aborts the process on a nearly black reference). An all-black
    reference has no exposure range: unavailable. Default FLIP parameters (67 pixels per degree,
    ACES tone mapper).
    """
    try:
        import flip_evaluator
    except ImportError:
        return FlipResult(None, None, FLIP_MISSING)
    r = _flip_rgb(np.where(mask[:, :, None], ref, 0.0))
    t = _flip_rgb(np.where(mask[:, :, None], test, 0.0))
    if r is None:
        return FlipResult(None, None, f"FLIP needs 1, 3 or 4 channels, the images have {ref.shape[2]}")
    notes = []
    if (r < 0).any() or (t < 0).any():
        notes.append("negative values clipped to 0")
    r = np.maximum(r, 0.0)
    t = np.maximum(t, 0.0)
    peak = float(r.max())
    if peak <= 0:
        return FlipResult(None, None, "the reference is black where compared (no HDR-FLIP exposure range)")
    scale = 2.0 ** -(math.floor(math.log2(peak)) + 1)
    r = np.ascontiguousarray(np.minimum(r * scale, _FLIP_CLIP), dtype=np.float32)
    t = np.ascontiguousarray(np.minimum(t * scale, _FLIP_CLIP), dtype=np.float32)
    error_map, _, _ = flip_evaluator.evaluate(r, t, "HDR", applyMagma=False, computeMeanError=False)
    error_map = np.asarray(error_map, dtype=np.float32)[:, :, 0]
    return FlipResult(float(np.mean(error_map[mask], dtype=np.float64)), error_map, "; ".join(notes))
