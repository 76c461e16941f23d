"""Ray casting of the G-buffer: one primary ray per pixel centre against the opaque geometry.

Rays: origin ``camera.position``, unit directions ``camera.ray_directions()`` (pixel centres,
row 0 at the top), ``t`` in ``(0, far / dot(d, forward))`` so every ray ends on the far plane.
Only opaque objects (``opacity == 1``) are seen; transparent occluders write nothing here (they
act on light through :func:`vlref.geometry.shadow_transmittance`).

Per pixel with a hit at distance ``t`` on object ``k``: ``distance = t``, ``depth = t dot(d, f)``
(linear eye depth, the view-space z), ``position = o + t d``, ``normal`` the unit normal facing
the camera, ``albedo``/``emission`` of object ``k``, ``object_id = k``. Sky pixels: ``depth`` and
``distance`` are ``inf``, ``object_id = -1``, every other buffer 0. Pixels are independent (each row's rays cast
together by :func:`~vlref.geometry.scene_geometry.closest_hits`), so the buffers are bit-identical for any thread
count.

Stored and derived buffers: the kernel writes ``depth``, ``distance``, ``normal`` and ``object_id`` (44 bytes a
pixel); ``position``, ``albedo`` and ``emission`` are derived on first use from what is stored (the camera's
origin and ray directions, the objects' materials), with the same operations and so the same bits as if the
kernel had written them. A consumer in a kernel computes them in place (:func:`vlref.lights.shading.scene_colour`
reads ``o + t d`` and the object's albedo and emission: no (H, W, 3) array of them is ever built for shading).

Performance (BENCHMARKS.md, "Ray casting: the query inlined, the arrays borrowed, rows on demand", "The
G-buffer's bytes" and "The camera ray cast inside the bench's process, and twice as fast"): rows are handed out to
the threads on demand (:func:`vlref.parallel.take`; sky rows cost next to nothing, so ``prange``'s equal blocks would
leave threads idle), and the workers get every array without reference counts (:func:`vlref.parallel.borrowed`).
All rays start at the camera, so the rays of a row lie in one plane, those of a column in another: the rays whose
row or column plane passes beside the primitive tree's root box cannot cross any of its primitives and are cast
without the tree (:func:`tree_spans`; the same bits). A fresh G-buffer costs the first touch of its new pages (the OS
zeroes each one), which is why only 44 bytes a pixel are written. They are allocated empty and the kernel writes
every element, the sky's zero normals included: ``np.zeros`` of the 50 MB of normals is free where the memory comes
fresh from the OS, but where glibc serves it from freed heap memory ``calloc`` clears it on the calling thread
first (26-34 ms on the dev box, BENCHMARKS.md "Numba's initialisation deferred to the first compile"); the kernel
writes those zeros on every thread instead.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import prange

from ..camera import Camera, cross
from ..jit import njit
from ..parallel import COUNTER, borrowed, take, task_counter, work, workers
from ..row_blocks import in_row_blocks
from ..scene.model import Scene
from .bvh import traversal_stack
from .scene_geometry import OPAQUE_ONLY, GeoArrays, Geometry, build_geometry, closest_hits

__all__ = ["GBuffer", "raycast", "kernel_args", "per_object", "tree_spans", "without_tree"]


@dataclass(frozen=True)
class GBuffer:
    """Primary-ray buffers (module docstring). Stored: ``depth``, ``distance`` (H, W) float64, ``normal``
    (H, W, 3) float64, ``object_id`` (H, W) int32 (-1: sky); what the derived buffers are computed from:
    ``origin`` (3,) the rays' origin, ``directions`` (H, W, 3) their unit directions (read only, may be the
    camera's own array), ``object_albedo``/``object_emission`` (M, 3) per object. Derived on first use, (H, W, 3)
    float64, 0 on sky: ``position``, ``albedo``, ``emission``."""

    depth: np.ndarray
    distance: np.ndarray
    normal: np.ndarray
    object_id: np.ndarray
    origin: np.ndarray
    directions: np.ndarray
    object_albedo: np.ndarray
    object_emission: np.ndarray

    @property
    def hit(self) -> np.ndarray:
        """(H, W) bool: the pixel sees a surface."""
        return self.object_id >= 0

    @cached_property
    def position(self) -> np.ndarray:
        """(H, W, 3) ``origin + distance · direction`` where a surface is seen, else 0."""
        hit = self.hit[..., None]
        return np.where(hit, self.origin + np.where(hit, self.distance[..., None], 0.0) * self.directions, 0.0)

    @cached_property
    def albedo(self) -> np.ndarray:
        """(H, W, 3) the seen object's albedo, 0 on sky."""
        return per_object(self.object_albedo, self.object_id)

    @cached_property
    def emission(self) -> np.ndarray:
        """(H, W, 3) the seen object's emission, 0 on sky."""
        return per_object(self.object_emission, self.object_id)


def per_object(table: np.ndarray, object_id: np.ndarray) -> np.ndarray:
    """(H, W, 3): row ``object_id`` of the (M, 3) ``table`` per pixel, 0 where ``object_id`` is -1 (the appended
    zero row, as NumPy's indexing takes index -1); ``np.take`` on blocks of rows on threads
    (:func:`vlref.row_blocks.in_row_blocks`): copies of the table's values, so the bits of ``table[object_id]``."""
    rows = np.concatenate([table, np.zeros((1, 3))])
    out = np.empty(object_id.shape + (3,))
    in_row_blocks(*object_id.shape, lambda y0, y1: np.take(rows, object_id[y0:y1], axis=0, out=out[y0:y1],
                                                            mode="wrap"))
    return out


def tree_spans(geo: GeoArrays, origin: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(H, 2) int64: for each row of the pinhole camera's rays ``dirs`` (H, W, 3) from ``origin``, the columns
    ``[x0, x1)`` outside which no ray can cross the box of the primitive tree's root (``(0, 0)``: none of the row's).

    A pinhole camera's rays of one row lie in one plane through the origin (their local directions
    ``(a, b, 1)`` share ``b``: :func:`vlref.camera.pixel_rays`), those of one column in another (they share
    ``a``); a ray can cross the box only where both its row's and its column's plane do, i.e. where the box's eight
    corners are not all on one side of each. The planes are taken from the rays themselves (the first and last of
    each row and column, whose cross product is the plane's normal), and a corner counts as on a side only when it
    is farther than ``1e-9`` times the box's distance from it: ~10⁶ times more than the rounding of the rays and of
    the slab test (:func:`~vlref.geometry.bvh.ray_box`), so a ray left out would have missed the box there too
    (the same bits). Rows or columns too few (one) or too close in direction to span a plane are not culled. The
    rows' planes and the columns' are tested in one stack (half the NumPy calls: ~20 µs of an 80x45 frame).
    """
    h, w = dirs.shape[0], dirs.shape[1]
    if geo.pnode_min.shape[0] == 0 or h == 0 or w == 0:
        return np.zeros((h, 2), dtype=np.int64)
    lo, hi = geo.pnode_min[0], geo.pnode_max[0]
    corners = np.array(list(itertools.product(*zip(lo.tolist(), hi.tolist())))) - origin
    margin = 1e-9 * (float(np.abs(corners).max()) + 1.0)
    normal = cross(np.concatenate((dirs[:, 0], dirs[0])), np.concatenate((dirs[:, -1], dirs[-1])))
    square = normal * normal
    norm = np.sqrt((square[:, 0] + square[:, 1]) + square[:, 2])  # np.linalg.norm's sum, in its order
    side = corners @ (normal / np.maximum(norm, 1e-300)[:, None]).T
    crosses = ~((side > margin).all(axis=0) | (side < -margin).all(axis=0)) | (norm < 1e-6)
    rows = crosses[:h] if w > 1 else np.ones(h, dtype=bool)
    cols = np.flatnonzero(crosses[h:] if h > 1 else np.ones(w, dtype=bool))
    spans = np.zeros((h, 2), dtype=np.int64)
    if cols.size:
        spans[rows] = (cols[0], cols[-1] + 1)
    return spans


@njit(cache=True, fastmath=False)
def without_tree(geo):
    """``geo`` (:class:`~vlref.geometry.scene_geometry.GeoArrays`) with an empty primitive tree (its five arrays cut
    to length 0: the same types), for rays that cannot cross the tree's root box (:func:`tree_spans`). Made by the
    rows' work from the one geometry the kernel takes: a second tuple of 22 arrays among the kernel's arguments made
    the ray cast's compile 1-2.5 s longer (the CPython wrapper and the ``prange``'s gufunc unbox and pass every
    array; BENCHMARKS.md "The ray cast's launcher takes the geometry once")."""
    return GeoArrays(geo.prim_kind, geo.prim_obj, geo.prim_row, geo.lin_prims, geo.pnode_min[:0], geo.pnode_max[:0],
                     geo.pnode_first[:0], geo.pnode_count[:0], geo.pnode_prims[:0], geo.albedo, geo.emission,
                     geo.opacity, geo.tint, geo.node_min, geo.node_max, geo.node_first, geo.node_count, geo.v0,
                     geo.e1, geo.e2, geo.tri_obj, geo.tri_opaque)


@njit(cache=True, fastmath=False, by_address=True)
def _cast_rows(taken, geo, spans, origin, dirs, forward, far, depth, distance, normal, object_id):
    """Rows taken one at a time (:func:`vlref.parallel.take`) until none is left: each row's rays cast together
    (:func:`closest_hits`; those outside the row's span of :func:`tree_spans` against the geometry without its
    primitive tree, :func:`without_tree`), then its G-buffer pixels written (module docstring). The arrays are
    borrowed (:func:`vlref.parallel.borrowed`)."""
    h, w = depth.shape
    y = take(taken)
    if y >= h:  # before any allocation: a worker may find no row left
        return
    geo, spans, origin, dirs, forward, depth, distance, normal, object_id = borrowed(
        (geo, spans, origin, dirs, forward, depth, distance, normal, object_id))
    outside = without_tree(geo)
    ox, oy, oz = origin[0], origin[1], origin[2]
    origins, cos_f, tmax = np.empty((w, 3)), np.empty(w), np.empty(w)
    t_row, obj_row, n_row = np.empty(w), np.empty(w, dtype=np.int64), np.empty((w, 3))
    stack = traversal_stack()
    for x in range(w):
        origins[x, 0], origins[x, 1], origins[x, 2] = ox, oy, oz
    while y < h:
        for x in range(w):  # the ray's end on the far plane
            cos_f[x] = dirs[y, x, 0] * forward[0] + dirs[y, x, 1] * forward[1] + dirs[y, x, 2] * forward[2]
            tmax[x] = far / cos_f[x]
        x0, x1 = spans[y, 0], spans[y, 1]
        row = dirs[y]
        closest_hits(outside, origins[:x0], row[:x0], tmax[:x0], OPAQUE_ONLY, stack, t_row[:x0], obj_row[:x0],
                     n_row[:x0])
        closest_hits(geo, origins[x0:x1], row[x0:x1], tmax[x0:x1], OPAQUE_ONLY, stack, t_row[x0:x1],
                     obj_row[x0:x1], n_row[x0:x1])
        closest_hits(outside, origins[x1:], row[x1:], tmax[x1:], OPAQUE_ONLY, stack, t_row[x1:], obj_row[x1:],
                     n_row[x1:])
        for x in range(w):  # the surface each ray sees
            t, obj = t_row[x], obj_row[x]
            object_id[y, x] = obj
            if obj < 0:
                depth[y, x] = np.inf
                distance[y, x] = np.inf
                normal[y, x, 0], normal[y, x, 1], normal[y, x, 2] = 0.0, 0.0, 0.0
                continue
            depth[y, x] = t * cos_f[x]
            distance[y, x] = t
            normal[y, x, 0], normal[y, x, 1], normal[y, x, 2] = n_row[x, 0], n_row[x, 1], n_row[x, 2]
        y = take(taken)


@njit(cache=True, fastmath=False, parallel=True)
def _raycast_kernel(geo, spans, origin, dirs, forward, far, depth, distance, normal, object_id, cast_rows, workers):
    """The G-buffer: each of ``workers`` workers (one per thread, :func:`vlref.parallel.workers`) casts the rows it takes
    (``cast_rows``: :func:`_cast_rows` by address, :func:`vlref.parallel.work`), which borrows the arrays (module
    docstring, "Performance")."""
    taken = task_counter()
    for _ in prange(workers):
        cast_rows(taken, geo, spans, origin, dirs, forward, far, depth, distance, normal, object_id)


def raycast(scene: Scene, camera: Camera, geometry: Geometry | None = None,
            width: int | None = None, height: int | None = None) -> GBuffer:
    """The G-buffer of ``scene`` seen by ``camera`` (at ``width x height`` if given, via ``camera.with_size``).

    ``geometry`` defaults to ``build_geometry(scene)``; pass it to reuse a built BVH.
    """
    if width is not None or height is not None:
        camera = camera.with_size(camera.width if width is None else width,
                                  camera.height if height is None else height)
    geo = (build_geometry(scene) if geometry is None else geometry).arrays
    h, w = camera.height, camera.width
    dirs = np.ascontiguousarray(camera.ray_directions(copy=False))  # read only: the camera's own array
    buf = GBuffer(depth=np.empty((h, w)), distance=np.empty((h, w)), normal=np.empty((h, w, 3)),
                  object_id=np.empty((h, w), dtype=np.int32),
                  origin=np.ascontiguousarray(camera.position, dtype=np.float64), directions=dirs,
                  object_albedo=geo.albedo, object_emission=geo.emission)
    args = kernel_args(geo, camera, buf)
    _raycast_kernel(*args, work(_cast_rows, COUNTER, *args), workers(h))
    return buf


def kernel_args(geo: GeoArrays, camera: Camera, buf: GBuffer) -> tuple:
    """The ray-cast kernel's arguments but its work and workers (``_raycast_kernel(*args, work(_cast_rows, COUNTER,
    *args), workers)`` fills ``buf``): the geometry, :func:`tree_spans`, the rays, the far plane, the stored
    buffers."""
    return (geo, tree_spans(geo, buf.origin, buf.directions), buf.origin, buf.directions,
            np.ascontiguousarray(camera.forward, dtype=np.float64), float(camera.far), buf.depth, buf.distance,
            buf.normal, buf.object_id)
