"""Packed scene geometry: analytic primitives + triangle meshes + BVH + materials, and ray queries.

:func:`build_geometry` turns ``scene.objects`` into a :class:`GeoArrays` named tuple of NumPy
arrays (the "geo" tuple) that njit code takes as its first argument:

=================  ===========  ==============================================================
field              shape/dtype  meaning
=================  ===========  ==============================================================
prim_kind          (P,) int64   ``PLANE``, ``SPHERE``, ``BOX``, ``CYLINDER`` (primitives.py)
prim_obj           (P,) int64   object id (index in ``scene.objects``)
prim_row           (P, 16)      packed primitive (see :mod:`vlref.geometry.primitives`)
lin_prims          (L,) int64   primitives tested linearly, ascending: planes and transparent ones
pnode_*            (B...)       BVH over the other (opaque bounded) primitives' world boxes
                                (:mod:`vlref.geometry.prim_bvh`): ``pnode_min/max`` (B, 3),
                                ``pnode_first/count`` (B,) int32, ``pnode_prims`` primitive index
                                of each leaf slot
albedo, emission   (M, 3)       per object (M = ``len(scene.objects)``), linear RGB
opacity            (M,)         1 = opaque; below 1 a transparent occluder
tint               (M, 3)       colour of light passing a transparent object
node_min/max       (N, 3)       BVH bounds (see :mod:`vlref.geometry.bvh`)
node_first/count   (N,) int32   BVH topology
v0, e1, e2         (T, 3)       triangles in BVH order: vertex 0 and edges ``v1 - v0``, ``v2 - v0``
tri_obj            (T,) int64   object id of each triangle
tri_opaque         (T,) bool    ``opacity[tri_obj] == 1``
=================  ===========  ==============================================================

Queries (``t`` in units of ``|d|``; intervals are open):

* :func:`closest_hit` -- nearest surface; the normal faces the ray origin.
* :func:`shadow_transmittance` -- visibility of a light along a shadow ray, coloured by
  transparent occluders (:func:`inline_shadow_transmittance`: the same, compiled into the caller). Every
  surface *crossing* counts: a ray through a closed transparent solid (sphere, box, cylinder, closed mesh) is
  attenuated twice, once entering and once leaving, as a pane of glass per surface.
* :func:`closest_hits` -- a row or chunk of rays in one call (the G-buffer and shadow-map kernels);
  :func:`trace_distances` -- many rays at once, parallel over chunks of rays.

Both queries give the same bits as a linear scan of the primitives in scene order followed by the
triangle BVH (ties between primitives go to the lower index; :mod:`vlref.geometry.prim_bvh`).

Performance (BENCHMARKS.md, "Whole frame"): a field read of the geo tuple and every array passed to a compiled
call take and drop a reference, an atomic add on a counter that all threads share. :func:`closest_hits` reads the
fields once per row or chunk of rays, borrows them (:func:`vlref.parallel.borrowed`: no counters) and has the
whole query (:func:`_closest`, the primitive and triangle traversals) inlined into its ray loop, so that the
compiler sees the borrowed arrays and drops the counting: one thread, 480x270 of the bench scene, 211 → 57 ns
per camera ray (the inlining alone 159 ns, the borrowing alone nothing). The traversal stack is borrowed too: the
inlined traversal passes it on in tuples, and each pass took and dropped a reference (atomic) on every ray, which
was most of a ray's time where the traversal has little to do (dev box, one thread, 1080p of the bench scene: 32 →
6 ns per ray with no geometry at all, 36 → 16 ns on the bench scene; BENCHMARKS.md "The camera ray cast inside the
bench's process, and twice as fast").
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import prange

from ..jit import njit
from ..parallel import borrowed
from ..scene.model import Box, Mesh, Plane, Scene, Sphere
from .bvh import Bvh, build_bvh, bvh_closest, bvh_transmittance, traversal_stack
from .prim_bvh import build_primitive_bvh, prims_closest, prims_occluded
from .obj import load_obj, transform_vertices
from .primitives import (BOX, CYLINDER, PLANE, ROW, SPHERE, hit_primitive, pack_box, pack_cylinder,
                         pack_plane, pack_sphere, triangle_normal)

__all__ = ["GeoArrays", "Geometry", "build_geometry", "builds_trees", "closest_hit", "closest_hits",
           "shadow_transmittance", "inline_shadow_transmittance", "trace_distances", "SHADOW_EPS", "RAY_CHUNK",
           "OPAQUE_ONLY", "EVERY_SURFACE"]

SHADOW_EPS = 1e-6
"""Shadow rays ignore hits closer than this many metres to their origin (self-intersection)."""

INF = np.inf

OPAQUE_ONLY, EVERY_SURFACE = np.bool_(True), np.bool_(False)
"""``opaque_only`` of :func:`closest_hits` for compiled callers: NumPy bools, which Numba types as ``bool``. A Python
``True`` or ``False`` is typed ``Literal[bool](True)`` or ``(False)``, and each literal compiles the query (inlined
traversal and all) once more."""

GeoArrays = namedtuple("GeoArrays", ["prim_kind", "prim_obj", "prim_row", "lin_prims", "pnode_min", "pnode_max",
                                     "pnode_first", "pnode_count", "pnode_prims", "albedo", "emission",
                                     "opacity", "tint", "node_min", "node_max", "node_first", "node_count",
                                     "v0", "e1", "e2", "tri_obj", "tri_opaque"])


@dataclass(frozen=True)
class Geometry:
    """The packed scene geometry.

    Attributes
    ----------
    arrays : the :class:`GeoArrays` "geo" tuple passed to the njit queries.
    bvh : the triangle BVH; ``bvh.order[i]`` is the input index of packed triangle ``i``, input
        triangles being the meshes' faces concatenated in object order.
    bounds_min, bounds_max : (3,) world box of every bounded object (planes excluded);
        both ``nan``-free and equal to ``0`` when the scene has no bounded object.
    prim_bvh : the BVH over the opaque bounded primitives; ``arrays.pnode_prims`` maps its
        ``order`` to primitive indices.
    """

    arrays: GeoArrays
    bvh: Bvh
    bounds_min: np.ndarray
    bounds_max: np.ndarray
    prim_bvh: Bvh

    @property
    def n_objects(self) -> int:
        return self.arrays.opacity.shape[0]

    @property
    def n_triangles(self) -> int:
        return self.arrays.v0.shape[0]


def _mesh_path(mesh: Mesh, scene: Scene) -> Path:
    """The OBJ path: absolute as the scene loader resolves it, else relative to ``scene.source``."""
    path = Path(mesh.path)
    if path.is_absolute() or not scene.source:
        return path
    return Path(scene.source).resolve().parent / path


def _primitive(obj) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """``(kind, row, box_min, box_max)`` of one analytic object (planes get an empty box)."""
    if isinstance(obj, Plane):
        return PLANE, pack_plane(obj.point, obj.normal), np.full(3, np.inf), np.full(3, -np.inf)
    if isinstance(obj, Sphere):
        c = np.asarray(obj.center, dtype=np.float64)
        return SPHERE, pack_sphere(c, obj.radius), c - obj.radius, c + obj.radius
    if isinstance(obj, Box):
        row = pack_box(obj.center, obj.size, obj.rotation)
        ext = np.abs(row[3:12].reshape(3, 3)) @ row[12:15]
        return BOX, row, row[0:3] - ext, row[0:3] + ext
    row = pack_cylinder(obj.center, obj.radius, obj.height, obj.rotation)
    axis = row[3:12].reshape(3, 3)[:, 1]
    ext = np.abs(axis) * row[13] + obj.radius * np.sqrt(np.maximum(0.0, 1.0 - axis * axis))
    return CYLINDER, row, row[0:3] - ext, row[0:3] + ext


def builds_trees(scene: Scene) -> bool:
    """Whether :func:`build_geometry` runs the BVH build's kernel for ``scene``: a mesh (its triangles' tree; a mesh
    has at least one face) or an opaque primitive other than a plane (the primitive tree's members)."""
    return any(isinstance(obj, Mesh) or (not isinstance(obj, Plane) and obj.material.opacity >= 1.0)
               for obj in scene.objects)


def build_geometry(scene: Scene) -> Geometry:
    """Pack ``scene.objects`` (object id = index) into a :class:`Geometry`; meshes are loaded and transformed.

    Raises :class:`vlref.errors.InputError` (from :func:`vlref.geometry.obj.load_obj`) for a bad OBJ file.
    """
    objects = scene.objects
    m = len(objects)
    albedo = np.array([o.material.albedo for o in objects], dtype=np.float64).reshape(m, 3)
    emission = np.array([o.material.emission for o in objects], dtype=np.float64).reshape(m, 3)
    opacity = np.array([o.material.opacity for o in objects], dtype=np.float64).reshape(m)
    tint = np.array([o.material.tint for o in objects], dtype=np.float64).reshape(m, 3)
    kinds, objs, rows, box_lo, box_hi = [], [], [], [], []
    tris, tri_objs = [], []
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for k, obj in enumerate(objects):
        if isinstance(obj, Mesh):
            verts, faces = load_obj(_mesh_path(obj, scene))
            verts = transform_vertices(verts, obj.position, obj.rotation, obj.scale)
            tris.append(verts[faces])
            tri_objs.append(np.full(faces.shape[0], k, dtype=np.int64))
            lo, hi = np.minimum(lo, verts.min(axis=0)), np.maximum(hi, verts.max(axis=0))
            continue
        kind, row, bmin, bmax = _primitive(obj)
        kinds.append(kind)
        objs.append(k)
        rows.append(row)
        box_lo.append(bmin)
        box_hi.append(bmax)
        lo, hi = np.minimum(lo, bmin), np.maximum(hi, bmax)
    tri = np.concatenate(tris) if tris else np.zeros((0, 3, 3))
    tri_obj = np.concatenate(tri_objs) if tri_objs else np.zeros(0, dtype=np.int64)
    bvh = build_bvh(tri[:, 0], tri[:, 1], tri[:, 2])
    tri, tri_obj = tri[bvh.order], tri_obj[bvh.order]
    prim_kind, prim_obj = np.array(kinds, dtype=np.int64), np.array(objs, dtype=np.int64)
    in_tree = (prim_kind != PLANE) & (opacity[prim_obj] >= 1.0)
    tree_idx = np.flatnonzero(in_tree)
    prim_bvh = build_primitive_bvh(np.array(box_lo).reshape(-1, 3)[tree_idx],
                                   np.array(box_hi).reshape(-1, 3)[tree_idx])
    arrays = GeoArrays(
        prim_kind=prim_kind, prim_obj=prim_obj, prim_row=np.array(rows, dtype=np.float64).reshape(len(rows), ROW),
        lin_prims=np.flatnonzero(~in_tree).astype(np.int64), pnode_min=prim_bvh.node_min,
        pnode_max=prim_bvh.node_max, pnode_first=prim_bvh.node_first, pnode_count=prim_bvh.node_count,
        pnode_prims=tree_idx[prim_bvh.order].astype(np.int64),
        albedo=albedo, emission=emission, opacity=opacity, tint=tint,
        node_min=bvh.node_min, node_max=bvh.node_max, node_first=bvh.node_first, node_count=bvh.node_count,
        v0=np.ascontiguousarray(tri[:, 0]), e1=np.ascontiguousarray(tri[:, 1] - tri[:, 0]),
        e2=np.ascontiguousarray(tri[:, 2] - tri[:, 0]), tri_obj=np.ascontiguousarray(tri_obj),
        tri_opaque=np.ascontiguousarray(opacity[tri_obj] >= 1.0))
    if not np.all(np.isfinite(lo)):
        lo, hi = np.zeros(3), np.zeros(3)
    return Geometry(arrays, bvh, lo, hi, prim_bvh)


@njit(cache=True, fastmath=False, forceinline=True)
def _closest(lin, kind, row, prim_obj, opacity, pnode_min, pnode_max, pnode_first, pnode_count, pnode_prims,
             node_min, node_max, node_first, node_count, v0, e1, e2, tri_opaque, tri_obj,
             ox, oy, oz, dx, dy, dz, tmin, tmax, opaque_only, stack):
    """:func:`closest_hit` on the geo tuple's arrays (the fields of the same names)."""
    best, best_k, nx, ny, nz = tmax, np.int64(-1), 0.0, 0.0, 0.0  # int64, not Literal[int](-1): one prims_closest
    for j in range(lin.shape[0]):
        k = lin[j]
        if opaque_only and opacity[prim_obj[k]] < 1.0:
            continue
        t, ax, ay, az = hit_primitive(kind[k], row[k], ox, oy, oz, dx, dy, dz, tmin, best)
        if t < best:
            best, best_k, nx, ny, nz = t, k, ax, ay, az
    ray = (ox, oy, oz, dx, dy, dz)
    best, best_k, nx, ny, nz = prims_closest(pnode_min, pnode_max, pnode_first, pnode_count, pnode_prims, kind, row,
                                             ray, tmin, tmax, best, best_k, nx, ny, nz, stack)
    obj = prim_obj[best_k] if best_k >= 0 else -1
    t, i = bvh_closest(node_min, node_max, node_first, node_count, v0, e1, e2, tri_opaque, opaque_only, ray, tmin,
                       best, stack)
    if i >= 0:
        best, obj = t, tri_obj[i]
        nx, ny, nz = triangle_normal(e1, e2, i)
    if obj < 0:
        return INF, -1, 0.0, 0.0, 0.0
    if nx * dx + ny * dy + nz * dz > 0.0:
        nx, ny, nz = -nx, -ny, -nz
    return best, obj, nx, ny, nz


@njit(cache=True, fastmath=False)
def closest_hit(geo, ox, oy, oz, dx, dy, dz, tmin, tmax, opaque_only, stack=None):
    """Nearest surface in ``(tmin, tmax)``: ``(t, obj, nx, ny, nz)``; ``(inf, -1, 0, 0, 0)`` on a miss.

    ``opaque_only`` skips objects with ``opacity < 1``. The unit normal is flipped to face the
    ray origin (``dot(n, d) <= 0``). ``stack``: the traversals' scratch
    (:func:`~vlref.geometry.bvh.traversal_stack`; allocated here when ``None``). Many rays: :func:`closest_hits`.
    """
    if stack is None:
        stack = traversal_stack()
    return _closest(geo.lin_prims, geo.prim_kind, geo.prim_row, geo.prim_obj, geo.opacity, geo.pnode_min,
                    geo.pnode_max, geo.pnode_first, geo.pnode_count, geo.pnode_prims, geo.node_min, geo.node_max,
                    geo.node_first, geo.node_count, geo.v0, geo.e1, geo.e2, geo.tri_opaque, geo.tri_obj,
                    ox, oy, oz, dx, dy, dz, tmin, tmax, opaque_only, stack)


@njit(cache=True, fastmath=False)
def closest_hits(geo, origins, dirs, tmax, opaque_only, stack, t_out, obj_out, normal_out):
    """:func:`closest_hit` of rays ``i`` (``origins[i]``, ``dirs[i]``, ``t`` in ``(0, tmax[i])``) into ``t_out``,
    ``obj_out`` and ``normal_out`` (N, 3), the same bits ray by ray.

    Kernels call it on a row or chunk of rays with a row or chunk of scratch; the geo arrays and the traversal
    stack are read without reference counts (the caller owns them for the call; module docstring, "Performance").
    """
    geo, stack = borrowed((geo, stack))
    lin, kind, row, prim_obj, opacity = geo.lin_prims, geo.prim_kind, geo.prim_row, geo.prim_obj, geo.opacity
    pnode_min, pnode_max, pnode_first = geo.pnode_min, geo.pnode_max, geo.pnode_first
    pnode_count, pnode_prims = geo.pnode_count, geo.pnode_prims
    node_min, node_max, node_first, node_count = geo.node_min, geo.node_max, geo.node_first, geo.node_count
    v0, e1, e2, tri_opaque, tri_obj = geo.v0, geo.e1, geo.e2, geo.tri_opaque, geo.tri_obj
    for i in range(origins.shape[0]):
        t_out[i], obj_out[i], normal_out[i, 0], normal_out[i, 1], normal_out[i, 2] = _closest(
            lin, kind, row, prim_obj, opacity, pnode_min, pnode_max, pnode_first, pnode_count, pnode_prims,
            node_min, node_max, node_first, node_count, v0, e1, e2, tri_opaque, tri_obj,
            origins[i, 0], origins[i, 1], origins[i, 2], dirs[i, 0], dirs[i, 1], dirs[i, 2], 0.0, tmax[i],
            opaque_only, stack)


@njit(cache=True, fastmath=False)
def shadow_transmittance(geo, ox, oy, oz, dx, dy, dz, tmax, stack=None):
    """RGB transmittance of the segment ``o + t d``, ``t`` in ``(SHADOW_EPS / |d|, tmax)``.

    0 when an opaque surface (``opacity == 1``) lies on it (any-hit early exit), else
    ``prod (1 - opacity_k) * tint_k`` over the transparent surface crossings ``k`` (module docstring).
    ``stack`` as :func:`closest_hit`'s. A kernel that traces a shadow ray per pixel calls
    :func:`inline_shadow_transmittance` instead (the same bits).
    """
    if stack is None:
        stack = traversal_stack()
    return inline_shadow_transmittance(geo, ox, oy, oz, dx, dy, dz, tmax, stack)


@njit(cache=True, fastmath=False, inline="always")
def inline_shadow_transmittance(geo, ox, oy, oz, dx, dy, dz, tmax, stack):
    """:func:`shadow_transmittance` compiled into its caller's loop, with the any-hit traversal of the primitives'
    tree: a call passes the geo tuple's ~25 arrays and returns through memory, which cost the scene colour's
    shadow rays of the bench scene ~8x their time (one thread: 118 → 15 ms at 480x270, four lights; BENCHMARKS.md
    "The scene colour's shadow rays inlined"). Compiled into the caller's Numba IR (:mod:`vlref.parallel`, "Calls
    that carry arrays"). For kernels whose pixel loop traces them (the scene colour, the quadrature reference); the
    other callers keep one compiled copy (:func:`shadow_transmittance`)."""
    norm = math.sqrt(dx * dx + dy * dy + dz * dz)
    if norm == 0.0:
        return 1.0, 1.0, 1.0
    tmin = SHADOW_EPS / norm
    ray = (ox, oy, oz, dx, dy, dz)
    if prims_occluded(geo.pnode_min, geo.pnode_max, geo.pnode_first, geo.pnode_count, geo.pnode_prims,
                      geo.prim_kind, geo.prim_row, ray, tmin, tmax, stack):
        return 0.0, 0.0, 0.0
    lin, kind, row, prim_obj, opacity, tint = (geo.lin_prims, geo.prim_kind, geo.prim_row, geo.prim_obj, geo.opacity,
                                               geo.tint)
    tr, tg, tb = 1.0, 1.0, 1.0
    for j in range(lin.shape[0]):
        k = lin[j]
        o = prim_obj[k]
        t = tmin
        for _ in range(2):  # a plane is crossed at most once, a convex solid at most twice
            t, _nx, _ny, _nz = hit_primitive(kind[k], row[k], ox, oy, oz, dx, dy, dz, t, tmax)
            if t == INF:
                break
            if opacity[o] >= 1.0:
                return 0.0, 0.0, 0.0
            clear = 1.0 - opacity[o]
            tr *= clear * tint[o, 0]
            tg *= clear * tint[o, 1]
            tb *= clear * tint[o, 2]
    if geo.node_min.shape[0] == 0:  # no triangles: no call (ten arrays and their reference counts); tr * 1 is tr
        return tr, tg, tb
    mr, mg, mb = bvh_transmittance(geo.node_min, geo.node_max, geo.node_first, geo.node_count, geo.v0, geo.e1,
                                   geo.e2, geo.tri_obj, geo.opacity, geo.tint, ray, tmin, tmax, stack)
    return tr * mr, tg * mg, tb * mb


RAY_CHUNK = 256
"""Rays per parallel iteration of the many-ray kernels (one traversal stack each)."""


@njit(cache=True, fastmath=False, parallel=True)
def _trace_kernel(geo, origins, dirs, tmax, opaque_only, t_out, obj_out):
    n = origins.shape[0]
    for c in prange((n + RAY_CHUNK - 1) // RAY_CHUNK):
        s, e = c * RAY_CHUNK, min(n, (c + 1) * RAY_CHUNK)
        normal = np.empty((e - s, 3))
        closest_hits(geo, origins[s:e], dirs[s:e], tmax[s:e], opaque_only, traversal_stack(), t_out[s:e],
                     obj_out[s:e], normal)


def trace_distances(geo: GeoArrays, origins, dirs, tmax, opaque_only: bool = True):
    """Closest hits of many rays, parallel over rays: ``(t (N,) float64, obj (N,) int32)``.

    ``origins``, ``dirs`` (N, 3) (or broadcastable); ``tmax`` a scalar or (N,); ``tmin = 0``.
    ``t = inf`` and ``obj = -1`` where nothing is hit. Each ray is independent, so the result is
    the same for any thread count.
    """
    o, d = np.broadcast_arrays(np.asarray(origins, dtype=np.float64), np.asarray(dirs, dtype=np.float64))
    o = np.ascontiguousarray(o.reshape(-1, 3))
    d = np.ascontiguousarray(d.reshape(-1, 3))
    tm = np.ascontiguousarray(np.broadcast_to(np.asarray(tmax, dtype=np.float64), (o.shape[0],)))
    t = np.empty(o.shape[0])
    obj = np.empty(o.shape[0], dtype=np.int32)
    _trace_kernel(geo, o, d, tm, bool(opaque_only), t, obj)
    return t, obj
