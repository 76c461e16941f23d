"""The quadrature reference in tiles of rows, each an independent item (:mod:`vlref.work_items`).

Every pixel of :func:`vlref.reference.quadrature.render_reference` is solved on its own (its ray, its
split points, its adaptive quadrature), so a tile ``render_reference(scene, rows=(y0, y1))`` equals
those rows of the whole image bit for bit, and the assembled image equals the in-process one whatever
the tiling or the scheduler. Each tile re-prepares the frame (camera, geometry, G-buffer: a small
share of a reference's cost, which is dominated by the per-pixel quadrature).
"""

from __future__ import annotations

import time

import numpy as np

from ..work_items import Item, run_items
from .quadrature import DEFAULT_ABS_TOL, ReferenceResult, render_reference

__all__ = ["tile_rows", "render_reference_tiled"]


def tile_rows(height: int, rows_per_tile: int) -> list[tuple[int, int]]:
    """``[(y0, y1), ...]`` covering ``0 <= y < height`` in bands of ``rows_per_tile`` rows."""
    if rows_per_tile < 1:
        raise ValueError("rows_per_tile must be >= 1")
    return [(y, min(y + rows_per_tile, height)) for y in range(0, height, rows_per_tile)]


def render_reference_tiled(scene, rel_tol: float = 1e-4, abs_tol: float = DEFAULT_ABS_TOL,
                           scheduler: str | None = None, rows_per_tile: int = 16, quiet: bool = False,
                           shadow_samples: int = 512, max_intervals: int = 4000, rule: int = 15) -> ReferenceResult:
    """:func:`render_reference` of ``scene`` solved in bands of ``rows_per_tile`` rows on ``scheduler``
    (:func:`vlref.work_items.run_items`); the arrays equal the untiled result bit for bit. ``stats``:
    ``intervals`` and ``unconverged`` summed over the tiles, ``seconds`` the wall time, ``tiles``."""
    start = time.perf_counter()
    bands = tile_rows(scene.render.height, rows_per_tile)
    items = [Item(f"rows {y0}-{y1}", render_reference, (scene, rel_tol, abs_tol),
                  {"shadow_samples": shadow_samples, "max_intervals": max_intervals, "rows": (y0, y1), "rule": rule})
             for y0, y1 in bands]
    h, w = scene.render.height, scene.render.width
    inscatter, final = np.zeros((h, w, 3)), np.zeros((h, w, 3))
    trans, error = np.zeros((h, w)), np.zeros((h, w))
    edges = np.zeros((h, w), dtype=np.int64)
    counts = {"intervals": 0, "unconverged": 0}

    def place(key, tile: ReferenceResult, seconds):
        y0, y1 = bands[[item.key for item in items].index(key)]
        inscatter[y0:y1], final[y0:y1], trans[y0:y1], error[y0:y1] = (tile.inscatter, tile.final,
                                                                      tile.transmittance, tile.error)
        edges[y0:y1] = tile.stats["shadow_boundaries"]
        for k in counts:
            counts[k] += tile.stats[k]

    run_items(items, scheduler, place, desc="reference tiles", quiet=quiet)
    stats = {**counts, "rel_tol": rel_tol, "abs_tol": abs_tol, "shadow_samples": shadow_samples, "rule": rule,
             "seconds": time.perf_counter() - start, "shadow_boundaries": edges, "tiles": len(bands)}
    return ReferenceResult(inscatter, trans, final, error, float(error.max(initial=0.0)), stats)
