"""BVH over the opaque bounded analytic primitives (spheres, boxes, cylinders): closest and any hit.

The tree is the binned-SAH BVH of :mod:`vlref.geometry.bvh` built over the primitives' world
bounding boxes (:func:`build_primitive_bvh`); its leaves hold primitive indices (``order``), and the
primitive rows stay in scene order. Infinite planes and transparent primitives are not in it: they
stay in the short linear list of :mod:`vlref.geometry.scene_geometry`, which keeps the order of
the transparent products of ``shadow_transmittance`` (and so its bits) unchanged.

Same results as a linear scan, bit for bit:

* Every ``hit_*`` of :mod:`vlref.geometry.primitives` returns the first crossing after ``tmin``
  whenever it is below ``tmax``, independently of ``tmax`` (and the same normal). A linear scan
  in index order that narrows ``tmax`` to the best hit so far therefore returns the minimum of
  ``(t, index)`` in lexicographic order: the lowest index wins a tie. :func:`prims_closest` tests
  each leaf primitive against the query's ``tmax`` and keeps that lexicographic minimum, so the
  visiting order does not matter.
* Culling is conservative: node boxes are padded by ``PRIM_PAD * max(1, max |coordinate|)``.
  A computed hit lies within a few ulps (relative to the ray's distance from the primitive) of
  the exact surface, far inside the padding unless the ray origin is ~1e9 scene sizes away.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from .bvh import Bvh, build_box_bvh, descend, enter_root, next_leaf, pop_nearer
from .primitives import hit_primitive

__all__ = ["PRIM_PAD", "PRIM_LEAF", "build_primitive_bvh", "prims_closest", "prims_occluded"]

PRIM_PAD = 1e-7
"""Relative padding of the node boxes (see the module docstring)."""
PRIM_LEAF = 1
"""Leaf size of the build (a primitive test costs several box tests)."""
INF = np.inf


def build_primitive_bvh(box_min: np.ndarray, box_max: np.ndarray) -> Bvh:
    """BVH of primitives with world boxes ``[box_min[i], box_max[i]]`` ((n, 3) each, n may be 0), binned by box centre.

    ``order[j]`` is the index (into the given boxes) of the primitive at leaf slot ``j``.
    """
    lo = np.asarray(box_min, dtype=np.float64).reshape(-1, 3)
    hi = np.asarray(box_max, dtype=np.float64).reshape(-1, 3)
    return build_box_bvh(lo, hi, 0.5 * (lo + hi), PRIM_LEAF, PRIM_PAD)


@njit(cache=True, fastmath=False, forceinline=True)
def prims_closest(node_min, node_max, node_first, node_count, order, kind, row, ray, tmin, tmax, best, best_k,
                  nx, ny, nz, stack=None):
    """Merge the closest primitive hit of ``ray = (ox, oy, oz, dx, dy, dz)`` into ``(best, best_k, nx, ny, nz)``
    and return the updated tuple.

    ``(best, best_k)`` is the best hit so far (``best = tmax``, ``best_k = -1`` when none), ``best_k``
    a primitive index; a hit replaces it when ``(t, k) < (best, best_k)`` lexicographically.
    Front-to-back traversal with a fixed stack (``stack``, see :func:`~vlref.geometry.bvh.traversal_stack`), far
    children skipped when their entry is beyond ``best``.
    The normal is the primitive's outward normal (not yet faced toward the origin).
    """
    entered, ix, iy, iz, stack = enter_root(node_min, node_max, ray, tmin, best, stack)
    if not entered:
        return best, best_k, nx, ny, nz
    ox, oy, oz, dx, dy, dz = ray
    nodes, stack_t = stack
    # int64 from the start: a literal 0 types the first call of descend/pop_nearer with Literal[int](0) before the
    # loop's int64 is known, and Numba compiles the helpers twice (once per type)
    top, node = np.int64(0), np.int64(0)
    while True:
        if node_count[node] > 0:
            first = node_first[node]
            for j in range(first, first + node_count[node]):
                k = order[j]
                t, ax, ay, az = hit_primitive(kind[k], row[k], ox, oy, oz, dx, dy, dz, tmin, tmax)
                if t < best or (t == best and best_k >= 0 and k < best_k):
                    best, best_k, nx, ny, nz = t, k, ax, ay, az
            node = -1
        else:
            node, top = descend(node_min, node_max, np.int64(node_first[node]), ox, oy, oz, ix, iy, iz, tmin, best,
                                nodes, stack_t, top)
        node, top = pop_nearer(nodes, stack_t, top, node, best)
        if node < 0:
            break
    return best, best_k, nx, ny, nz


@njit(cache=True, fastmath=False, inline="always")
def prims_occluded(node_min, node_max, node_first, node_count, order, kind, row, ray, tmin, tmax, stack=None):
    """Whether any primitive of the tree is crossed in ``(tmin, tmax)`` of ``ray = (ox, oy, oz, dx, dy, dz)``
    (any-hit traversal, early exit; ``stack`` as :func:`prims_closest`'s). Compiled into the caller's Numba IR
    (:mod:`vlref.parallel`, "Calls that carry arrays")."""
    entered, ix, iy, iz, stack = enter_root(node_min, node_max, ray, tmin, tmax, stack)
    if not entered:
        return False
    ox, oy, oz, dx, dy, dz = ray
    nodes = stack[0]
    nodes[0] = 0
    top = np.int64(1)
    while True:
        node, top = next_leaf(node_min, node_max, node_first, node_count, ox, oy, oz, ix, iy, iz, tmin, tmax,
                              nodes, top)
        if node < 0:
            break
        first = node_first[node]
        for j in range(first, first + node_count[node]):
            k = order[j]
            if hit_primitive(kind[k], row[k], ox, oy, oz, dx, dy, dz, tmin, tmax)[0] < INF:
                return True
    return False
