"""Bounding-volume hierarchy over triangles (or any boxes): binned-SAH build and njit traversal.

Build (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", IEEE RT 2007):
each node's triangles are binned by centroid into ``BINS`` bins along each of the three axes and
split at the bin boundary minimising the surface-area heuristic
``C = 1 + (A_L N_L + A_R N_R) / A`` (traversal cost 1, one triangle test 1). A node becomes a leaf
when it holds ``<= max_leaf`` triangles, or ``<= 4 * max_leaf`` and no split beats ``N``. When
all centroids coincide, or below depth ``SAH_DEPTH``, the node is split at the median of its
widest centroid axis instead, which bounds the tree depth (< ``SAH_DEPTH + log2 N + 1``) and so
the fixed traversal stack of ``STACK`` entries.

Flattened layout (``Bvh`` arrays):

* ``node_min``, ``node_max`` (N, 3): node bounds, padded outward by ``pad_rel * scale``
  (``scale = max(1, max |coordinate|)``; ``pad_rel = 1e-9`` for triangles) so that a triangle lying
  in a face of its node box is never culled by slab rounding;
* ``node_first`` (N,) int32: first triangle of a leaf, or the left child of an inner node
  (the right child is ``node_first + 1``);
* ``node_count`` (N,) int32: triangles in a leaf, 0 for an inner node;
* ``order`` (T,) int64: input triangle index of each position, so that the triangles of leaf
  ``k`` are ``order[node_first[k] : node_first[k] + node_count[k]]`` and the packed triangle
  arrays are stored in that order.

The build is sequential and deterministic (same tree for the same input).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..jit import njit
from .primitives import hit_triangle

__all__ = ["Bvh", "build_bvh", "build_box_bvh", "traversal_stack", "ray_box", "enter_root", "descend", "pop_nearer",
           "push_children", "next_leaf", "bvh_closest", "bvh_transmittance", "BINS", "SAH_DEPTH", "STACK", "DEDUP"]

BINS = 16
SAH_DEPTH = 48
STACK = 128
DEDUP = 32
INF = np.inf


@dataclass(frozen=True)
class Bvh:
    """Flattened BVH (see the module docstring)."""

    node_min: np.ndarray
    node_max: np.ndarray
    node_first: np.ndarray
    node_count: np.ndarray
    order: np.ndarray

    @property
    def depth(self) -> int:
        return _depth(self.node_first, self.node_count)


@njit(cache=True, fastmath=False)
def _area(ex, ey, ez):
    return ex * ey + ey * ez + ez * ex


@njit(cache=True, fastmath=False)
def _sah_split(tmin, tmax, cent, idx, s, e, cmin, cmax):
    """Best ``(axis, bin, cost)`` over the binned SAH of ``idx[s:e]``; axis -1 when none is possible."""
    best_axis, best_bin, best_cost = -1, -1, INF
    bin_count = np.zeros(BINS, dtype=np.int64)
    bin_lo = np.empty((BINS, 3))
    bin_hi = np.empty((BINS, 3))
    right_area = np.empty(BINS)
    right_count = np.empty(BINS, dtype=np.int64)
    for axis in range(3):
        extent = cmax[axis] - cmin[axis]
        if not extent > 0.0:
            continue
        scale = BINS / extent
        bin_count[:] = 0
        bin_lo[:] = INF
        bin_hi[:] = -INF
        for j in range(s, e):
            k = idx[j]
            b = min(int((cent[k, axis] - cmin[axis]) * scale), BINS - 1)
            bin_count[b] += 1
            for c in range(3):
                bin_lo[b, c] = min(bin_lo[b, c], tmin[k, c])
                bin_hi[b, c] = max(bin_hi[b, c], tmax[k, c])
        lo = np.full(3, INF)
        hi = np.full(3, -INF)
        n = 0
        for b in range(BINS - 1, 0, -1):
            n += bin_count[b]
            for c in range(3):
                lo[c] = min(lo[c], bin_lo[b, c])
                hi[c] = max(hi[c], bin_hi[b, c])
            right_count[b] = n
            right_area[b] = _area(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) if n > 0 else 0.0
        lo[:] = INF
        hi[:] = -INF
        n = 0
        for b in range(1, BINS):
            n += bin_count[b - 1]
            for c in range(3):
                lo[c] = min(lo[c], bin_lo[b - 1, c])
                hi[c] = max(hi[c], bin_hi[b - 1, c])
            if n == 0 or right_count[b] == 0:
                continue
            cost = _area(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) * n + right_area[b] * right_count[b]
            if cost < best_cost:
                best_axis, best_bin, best_cost = axis, b, cost
    return best_axis, best_bin, best_cost


@njit(cache=True, fastmath=False)
def _sort_by_key(idx, s, e, key):
    """Stable in-place sort of ``idx[s:e]`` by ``key[idx]``: a bottom-up merge sort (ties keep their order,
    so the result is ``np.argsort(kind="stable")``'s, which compiles several times slower in Numba)."""
    a = idx[s:e].copy()
    b = np.empty_like(a)
    n = a.shape[0]
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid, hi = min(lo + width, n), min(lo + 2 * width, n)
            i, j = lo, mid
            for k in range(lo, hi):
                if j >= hi or (i < mid and key[a[i]] <= key[a[j]]):
                    b[k] = a[i]
                    i += 1
                else:
                    b[k] = a[j]
                    j += 1
        a, b = b, a
        width *= 2
    for k in range(n):  # not ``idx[s:e] = a``: its shape check compiles Numba's string formatting
        idx[s + k] = a[k]


@njit(cache=True, fastmath=False, entry=True)
def _build(tmin, tmax, cent, max_leaf, pad):
    """Top-down build from per-triangle bounds and centroids (module docstring); returns the
    trimmed node arrays and the triangle order. Nodes are numbered in creation order, siblings adjacent."""
    n = cent.shape[0]
    idx = np.arange(n)
    cap = max(2 * n - 1, 1)
    node_min = np.empty((cap, 3))
    node_max = np.empty((cap, 3))
    node_first = np.zeros(cap, dtype=np.int32)
    node_count = np.zeros(cap, dtype=np.int32)
    work = np.empty((cap, 4), dtype=np.int64)  # node, start, end, depth
    work[0, 0], work[0, 1], work[0, 2], work[0, 3] = 0, 0, n, 0
    top, used = 1, 1
    while top > 0:
        top -= 1
        node, s, e, depth = work[top, 0], work[top, 1], work[top, 2], work[top, 3]
        lo = np.full(3, INF)
        hi = np.full(3, -INF)
        clo = np.full(3, INF)
        chi = np.full(3, -INF)
        for j in range(s, e):
            k = idx[j]
            for c in range(3):
                lo[c] = min(lo[c], tmin[k, c])
                hi[c] = max(hi[c], tmax[k, c])
                clo[c] = min(clo[c], cent[k, c])
                chi[c] = max(chi[c], cent[k, c])
        for c in range(3):  # per element: a row assignment's shape check compiles Numba's string formatting
            node_min[node, c], node_max[node, c] = lo[c] - pad, hi[c] + pad
        count = e - s
        if count <= max_leaf:
            node_first[node], node_count[node] = s, count
            continue
        axis, split_bin, cost = -1, -1, INF
        if depth < SAH_DEPTH:
            axis, split_bin, cost = _sah_split(tmin, tmax, cent, idx, s, e, clo, chi)
            parent_area = _area(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2])
            if count <= 4 * max_leaf and (axis < 0 or 1.0 + cost / max(parent_area, 1e-300) >= count):
                node_first[node], node_count[node] = s, count
                continue
        mid = s
        if axis >= 0:
            scale = BINS / (chi[axis] - clo[axis])
            i, j = s, e - 1
            while i <= j:
                if min(int((cent[idx[i], axis] - clo[axis]) * scale), BINS - 1) < split_bin:
                    i += 1
                else:
                    idx[i], idx[j] = idx[j], idx[i]
                    j -= 1
            mid = i
        if mid == s or mid == e:
            _sort_by_key(idx, s, e, cent[:, np.argmax(chi - clo)])
            mid = (s + e) // 2
        left = used
        used += 2
        node_first[node], node_count[node] = left, 0
        work[top, 0], work[top, 1], work[top, 2], work[top, 3] = left + 1, mid, e, depth + 1
        work[top + 1, 0], work[top + 1, 1], work[top + 1, 2], work[top + 1, 3] = left, s, mid, depth + 1
        top += 2
    return node_min[:used].copy(), node_max[:used].copy(), node_first[:used].copy(), node_count[:used].copy(), idx


@njit(cache=True, fastmath=False, entry=True)
def _depth(node_first, node_count):
    if node_first.shape[0] == 0:
        return 0
    stack = np.empty((node_first.shape[0], 2), dtype=np.int64)
    stack[0, 0], stack[0, 1] = 0, 1
    top, deepest = 1, 0
    while top > 0:
        top -= 1
        node, d = stack[top, 0], stack[top, 1]
        deepest = max(deepest, d)
        if node_count[node] == 0:
            stack[top, 0], stack[top, 1] = node_first[node], d + 1
            stack[top + 1, 0], stack[top + 1, 1] = node_first[node] + 1, d + 1
            top += 2
    return deepest


def build_box_bvh(lo: np.ndarray, hi: np.ndarray, cent: np.ndarray, max_leaf: int, pad_rel: float) -> Bvh:
    """Build the BVH of items with world boxes ``[lo[i], hi[i]]`` binned by ``cent[i]`` (each (n, 3)); n may be 0.

    Node bounds are padded by ``pad_rel * max(1, max |coordinate|)`` (module docstring).
    """
    lo, hi, cent = (np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 3) for a in (lo, hi, cent))
    if lo.shape[0] == 0:
        return Bvh(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.int32), np.zeros(0, np.int32),
                   np.zeros(0, np.int64))
    pad = pad_rel * max(1.0, float(np.max(np.abs(hi))), float(np.max(np.abs(lo))))
    return Bvh(*_build(lo, hi, cent, max_leaf, pad))


def build_bvh(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray, max_leaf: int = 4) -> Bvh:
    """Build the BVH of triangles ``(v0[i], v1[i], v2[i])`` (each (T, 3) float64); T may be 0."""
    v0, v1, v2 = (np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 3) for a in (v0, v1, v2))
    return build_box_bvh(np.minimum(np.minimum(v0, v1), v2), np.maximum(np.maximum(v0, v1), v2),
                         (v0 + v1 + v2) / 3.0, max_leaf, 1e-9)


@njit(cache=True, fastmath=False)
def traversal_stack():
    """Scratch of one traversal: ``(nodes, entries)``, ``STACK`` node indices (int64) and entry distances.

    The queries take it as their optional last argument (``None``: they allocate their own). Kernels
    allocate one per row or chunk of rays and pass it to every query, where a closest hit used to allocate
    four arrays per ray (on the device that was 6 % of the G-buffer's time; BENCHMARKS.md, "Whole frame").
    """
    return np.empty(STACK, dtype=np.int64), np.empty(STACK)


@njit(cache=True, fastmath=False)
def ray_box(bmin, bmax, k, ox, oy, oz, ix, iy, iz, tmin, tmax):
    """Entry ``t`` of the ray (origin o, inverse direction i) into box ``k`` clipped to ``[tmin, tmax]``; inf if missed.

    Slab test; callers replace zero direction components by ``±1e-300`` before inverting
    (``_inverse``), so ``(b - o) * inv`` is never ``0 * inf``.
    """
    t0 = (bmin[k, 0] - ox) * ix
    t1 = (bmax[k, 0] - ox) * ix
    lo, hi = min(t0, t1), max(t0, t1)
    t0 = (bmin[k, 1] - oy) * iy
    t1 = (bmax[k, 1] - oy) * iy
    lo, hi = max(lo, min(t0, t1)), min(hi, max(t0, t1))
    t0 = (bmin[k, 2] - oz) * iz
    t1 = (bmax[k, 2] - oz) * iz
    lo, hi = max(lo, min(t0, t1), tmin), min(hi, max(t0, t1), tmax)
    return lo if lo <= hi else INF


@njit(cache=True, fastmath=False)
def _inverse(d):
    return 1.0 / (d if d != 0.0 else 1e-300)


@njit(cache=True, fastmath=False, forceinline=True)
def enter_root(node_min, node_max, ray, tmin, tmax, stack):
    """The prologue of every traversal: ``(entered, ix, iy, iz, stack)``, whether ``ray = (ox, oy, oz, dx, dy,
    dz)`` crosses the root box in ``(tmin, tmax)`` (False for an empty tree), its inverse direction (zero
    components replaced by ``1e-300`` first, :func:`ray_box`) and the traversal scratch (``stack``, or a new
    :func:`traversal_stack` when it is None)."""
    ox, oy, oz, dx, dy, dz = ray
    if stack is None:
        stack = traversal_stack()
    if node_min.shape[0] == 0:  # an empty tree: no divisions for an inverse direction never used
        return False, 0.0, 0.0, 0.0, stack
    ix, iy, iz = _inverse(dx), _inverse(dy), _inverse(dz)
    root = np.int64(0)  # not the literal 0, nor the int32 of node_first: ray_box compiles once, for int64
    return ray_box(node_min, node_max, root, ox, oy, oz, ix, iy, iz, tmin, tmax) < INF, ix, iy, iz, stack


@njit(cache=True, fastmath=False, forceinline=True)
def descend(node_min, node_max, left, ox, oy, oz, ix, iy, iz, tmin, best, stack, stack_t, top):
    """Closest-hit traversal step at an interior node whose children are ``left``, ``left + 1``: returns
    ``(node, top)`` — the nearer child hit by the ray (the farther one pushed with its entry distance),
    or ``-1`` when neither child box is hit before ``best``."""
    tl = ray_box(node_min, node_max, left, ox, oy, oz, ix, iy, iz, tmin, best)
    tr = ray_box(node_min, node_max, left + 1, ox, oy, oz, ix, iy, iz, tmin, best)
    if tl == INF and tr == INF:
        return -1, top
    if tr == INF:
        return left, top
    if tl == INF:
        return left + 1, top
    near, far, tfar = (left, left + 1, tr) if tl <= tr else (left + 1, left, tl)
    stack[top], stack_t[top] = far, tfar
    return near, top + 1


@njit(cache=True, fastmath=False, forceinline=True)
def pop_nearer(stack, stack_t, top, node, best):
    """``(node, top)``: ``node`` if set, else the next pushed node whose entry distance is ``<= best``
    (farther ones are skipped: they cannot hold a closer hit); ``-1`` when the stack runs out."""
    while node < 0 and top > 0:
        top -= 1
        if stack_t[top] <= best:
            node = stack[top]
    return node, top


@njit(cache=True, fastmath=False, forceinline=True)
def push_children(node_min, node_max, left, ox, oy, oz, ix, iy, iz, tmin, tmax, stack, top):
    """Any-hit traversal step: push the children ``left``, ``left + 1`` whose boxes the ray crosses in
    ``(tmin, tmax)``; returns the new stack top."""
    for child in range(left, left + 2):
        if ray_box(node_min, node_max, child, ox, oy, oz, ix, iy, iz, tmin, tmax) < INF:
            stack[top] = child
            top += 1
    return top


@njit(cache=True, fastmath=False, forceinline=True)
def next_leaf(node_min, node_max, node_first, node_count, ox, oy, oz, ix, iy, iz, tmin, tmax, stack, top):
    """Any-hit traversal: pop nodes (pushing the crossed children of interior ones) until a leaf;
    returns ``(leaf, top)``, or ``(-1, 0)`` when the stack runs out."""
    while top > 0:
        top -= 1
        node = stack[top]
        if node_count[node] > 0:
            return node, top
        top = push_children(node_min, node_max, node_first[node], ox, oy, oz, ix, iy, iz, tmin, tmax, stack, top)
    return -1, top


@njit(cache=True, fastmath=False, forceinline=True)
def bvh_closest(node_min, node_max, node_first, node_count, v0, e1, e2, opaque, opaque_only, ray, tmin, tmax,
                stack=None):
    """Closest triangle hit in ``(tmin, tmax)`` of ``ray = (ox, oy, oz, dx, dy, dz)``: ``(t, i)`` (``i`` in
    packed order) or ``(inf, -1)``.

    With ``opaque_only`` the triangles whose ``opaque[i]`` is false are skipped.

    Front-to-back traversal: the nearer child first, the farther pushed on a fixed stack of
    ``STACK`` (node, entry t) pairs (``stack``, see :func:`traversal_stack`) and skipped on pop when its
    entry is beyond the best hit.
    """
    entered, ix, iy, iz, stack = enter_root(node_min, node_max, ray, tmin, tmax, stack)
    if not entered:
        return INF, -1
    ox, oy, oz, dx, dy, dz = ray
    best, found = tmax, -1
    nodes, stack_t = stack
    top, node = np.int64(0), np.int64(0)  # typed int64 from the start: see prims_closest
    while True:
        if node_count[node] > 0:
            first = node_first[node]
            for i in range(first, first + node_count[node]):
                if opaque[i] or not opaque_only:
                    t = hit_triangle(v0, e1, e2, i, ox, oy, oz, dx, dy, dz, tmin, best)
                    if t < best:
                        best, found = t, i
            node = -1
        else:
            node, top = descend(node_min, node_max, np.int64(node_first[node]), ox, oy, oz, ix, iy, iz, tmin, best,
                                nodes, stack_t, top)
        node, top = pop_nearer(nodes, stack_t, top, node, best)
        if node < 0:
            break
    if found < 0:
        return INF, -1
    return best, found


@njit(cache=True, fastmath=False)
def _seen(hit_obj, hit_t, n, obj, t):
    """Whether a crossing of ``obj`` at (relatively) the same ``t`` was already counted (shared edges)."""
    for j in range(n):
        if hit_obj[j] == obj and abs(hit_t[j] - t) <= 1e-9 * max(abs(t), 1e-300):
            return True
    return False


@njit(cache=True, fastmath=False)
def bvh_transmittance(node_min, node_max, node_first, node_count, v0, e1, e2, tri_obj, opacity, tint, ray, tmin,
                      tmax, stack=None):
    """Product of ``(1 - opacity) * tint`` over triangles crossed in ``(tmin, tmax)`` of ``ray = (ox, oy, oz, dx,
    dy, dz)``; 0 at the first opaque one.

    All-hit traversal (any order) with an early exit on an opaque triangle (``opacity == 1``).
    A ray through an edge shared by two triangles of one object reports both; a crossing of
    the same object at the same ``t`` (relative 1e-9) is counted once. The last ``DEDUP`` counted
    crossings are remembered for that check.
    """
    tr, tg, tb = 1.0, 1.0, 1.0
    entered, ix, iy, iz, stack = enter_root(node_min, node_max, ray, tmin, tmax, stack)
    if not entered:
        return tr, tg, tb
    ox, oy, oz, dx, dy, dz = ray
    nodes = stack[0]
    hit_obj = np.empty(DEDUP, dtype=np.int64)
    hit_t = np.empty(DEDUP)
    n_hits = 0
    nodes[0] = 0
    top = np.int64(1)
    while True:
        node, top = next_leaf(node_min, node_max, node_first, node_count, ox, oy, oz, ix, iy, iz, tmin, tmax,
                              nodes, top)
        if node < 0:
            break
        first = node_first[node]
        for i in range(first, first + node_count[node]):
            t = hit_triangle(v0, e1, e2, i, ox, oy, oz, dx, dy, dz, tmin, tmax)
            if t == INF:
                continue
            obj = tri_obj[i]
            if opacity[obj] >= 1.0:
                return 0.0, 0.0, 0.0
            if _seen(hit_obj, hit_t, min(n_hits, DEDUP), obj, t):
                continue
            hit_obj[n_hits % DEDUP], hit_t[n_hits % DEDUP] = obj, t
            n_hits += 1
            clear = 1.0 - opacity[obj]
            tr *= clear * tint[obj, 0]
            tg *= clear * tint[obj, 1]
            tb *= clear * tint[obj, 2]
    return tr, tg, tb
