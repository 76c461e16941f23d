"""The froxel grid: its slices, sample positions and the layout of its exported buffers.

The grid is aligned with the camera frustum (Wronski 2014, AC4 "Volumetric fog"; Hillaire 2015,
Frostbite "Physically based and unified volumetric rendering"): ``gw x gh`` columns, each the
frustum of one screen tile, cut into ``slices`` depth slices along linear eye depth ``z``.

* Column ``(c, r)`` (column, row, row 0 at the top) covers screen uv ``[c/gw, (c+1)/gw] x
  [r/gh, (r+1)/gh]``; its centre ray is :meth:`vlref.camera.Camera.ray_directions` of a ``gw x gh``
  target (pixel centres at +0.5).
* Slice boundaries ``z_0 .. z_D`` (:func:`slice_depths`): the blend of exponential and uniform
  distributions ``z_k = λ n (f/n)^{k/D} + (1 - λ)(n + (f - n) k/D)`` (the practical split scheme,
  the same law as :func:`vlref.lights.shadow_cast.cascade_splits`) with ``n`` the camera's near plane,
  ``f`` the grid's far depth and ``λ = depth_distribution`` (1: exponential, as Wronski and Hillaire;
  0: uniform), and then ``z_0 = 0``: the first slice reaches back to the eye, so the grid covers the
  whole ray ``[0, f]``. Inside a slice depth is linear in the slice coordinate: ``z(k + ξ) = z_k +
  ξ (z_{k+1} - z_k)``, ``ξ ∈ [0, 1]`` (:func:`depth_to_slice` is its inverse).
* A froxel's sample sits at slice coordinate ``(c + ξx, r + ξy, k + ξz)``: the per-frame jitter
  ``ξ`` (:func:`jitter_offsets`) is ``(½, ½, ½)`` without jitter and the Halton (2, 3, 5) point of
  the frame otherwise (Unreal's volumetric fog jitters with a Halton sequence; Hillaire 2015 jitters
  the sample inside the froxel, the sequence is [U]).

Buffer layout (in memory and exported): a grid is an array ``(gh, gw, D, C)`` indexed ``[row,
column, slice, channel]``. :func:`grid_image` turns it into a 2-D image for EXR export and
``vlref compare``: the ``D`` slices stacked top to bottom, slice ``k`` in rows ``k·gh .. (k+1)·gh - 1``
(row 0 of each slice at the top), i.e. an image ``(D·gh, gw, C)``; :func:`grid_from_image` undoes it.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit

__all__ = ["column_rays", "slice_depths", "depth_to_slice", "slice_to_depth", "halton", "jitter_offsets", "grid_image",
           "grid_from_image", "HALTON_BASES"]

HALTON_BASES = (2, 3, 5)


def column_rays(camera, gw: int, gh: int, xi_x: float = 0.5, xi_y: float = 0.5) -> np.ndarray:
    """Unit world rays (gh, gw, 3) through uv ``((c + ξx)/gw, (r + ξy)/gh)`` of every column (row 0 on top);
    ``ξ = (½, ½)`` gives the centre rays, :meth:`vlref.camera.Camera.ray_directions` of a ``gw x gh`` target."""
    x = ((np.arange(gw) + xi_x) / gw * 2.0 - 1.0) * camera.tan_half_fov * camera.aspect
    y = (1.0 - (np.arange(gh) + xi_y) / gh * 2.0) * camera.tan_half_fov
    v = np.stack(np.broadcast_arrays(x[None, :], y[:, None], np.ones((gh, gw))), axis=-1) @ camera.rotation.T
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def slice_depths(near: float, far: float, slices: int, depth_distribution: float) -> np.ndarray:
    """The ``slices + 1`` boundary depths ``z_0 = 0 < z_1 < ... < z_D = far`` (module docstring), float64."""
    if not (0.0 < near < far):
        raise ValueError(f"need 0 < near < far, got near={near}, far={far}")
    i = np.arange(slices + 1) / slices
    z = depth_distribution * near * (far / near) ** i + (1.0 - depth_distribution) * (near + (far - near) * i)
    z[0], z[-1] = 0.0, far
    return z


@njit(cache=True, fastmath=False)
def depth_to_slice(bounds, z):
    """Continuous slice coordinate ``s ∈ [0, D]`` of eye depth ``z`` (clamped to ``[0, z_D]``): the inverse
    of the piecewise-linear :func:`slice_to_depth` (binary search over the boundaries)."""
    d = bounds.shape[0] - 1
    if not z > bounds[0]:
        return 0.0
    if z >= bounds[d]:
        return float(d)
    lo, hi = 0, d
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if bounds[mid] <= z:
            lo = mid
        else:
            hi = mid
    return lo + (z - bounds[lo]) / (bounds[lo + 1] - bounds[lo])


@njit(cache=True, fastmath=False)
def slice_to_depth(bounds, s):
    """Eye depth at continuous slice coordinate ``s ∈ [0, D]`` (linear inside each slice)."""
    d = bounds.shape[0] - 1
    k = min(max(int(np.floor(s)), 0), d - 1)
    return bounds[k] + (s - k) * (bounds[k + 1] - bounds[k])


def halton(index: int, base: int) -> float:
    """The radical inverse of ``index`` in ``base`` (Halton 1964): ``halton(1, 2) = 0.5``, ``halton(2, 2) = 0.25``."""
    f, r, i = 1.0, 0.0, int(index)
    while i > 0:
        f /= base
        r += f * (i % base)
        i //= base
    return r


def jitter_offsets(frame: int, jitter: str, period: int) -> tuple[float, float, float]:
    """The sample offset ``ξ = (ξx, ξy, ξz)`` inside every froxel for frame ``frame``.

    ``none``: ``(½, ½, ½)`` (the froxel centre). ``halton``: the Halton points of bases 2, 3, 5 at index
    ``(frame mod period) + 1`` (index 0 is the degenerate origin): frame 0 samples ``(½, ⅓, ⅕)``.
    """
    if jitter == "none":
        return 0.5, 0.5, 0.5
    n = frame % period + 1
    return tuple(halton(n, b) for b in HALTON_BASES)


def grid_image(grid: np.ndarray) -> np.ndarray:
    """A ``(gh, gw, D, C)`` grid as the ``(D·gh, gw, C)`` image of stacked slices (module docstring)."""
    gh, gw, d, c = grid.shape
    return np.ascontiguousarray(grid.transpose(2, 0, 1, 3).reshape(d * gh, gw, c))


def grid_from_image(image: np.ndarray, slices: int) -> np.ndarray:
    """Inverse of :func:`grid_image`: a ``(D·gh, gw, C)`` image back to ``(gh, gw, D, C)``."""
    rows, gw, c = image.shape
    if rows % slices:
        raise ValueError(f"{rows} rows do not split into {slices} slices")
    return np.ascontiguousarray(image.reshape(slices, rows // slices, gw, c).transpose(1, 2, 0, 3))
