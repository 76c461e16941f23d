"""Shadow maps by ray casting from the lights: the faces of every light, each texel's ray, what it stores.

A spot light has one perspective face, a point light six cube faces, a directional light ``cascades``
orthographic faces (the storage of each: :mod:`vlref.lights.shadow_pack`). The cascades split the view frustum
from ``camera.near`` to ``min(shadows.distance, camera.far)`` at
``z_i = λ n (f/n)^{i/N} + (1-λ)(n + (f-n) i/N)`` (practical split scheme, Zhang et al. 2006; ``λ = split_lambda``).

Each texel casts one ray through its centre (:func:`_face_ray`) against the opaque geometry
(:func:`vlref.geometry.closest_hits`, chunks of ``RAY_CHUNK`` rays per thread) and stores the biased distance
of its first hit (:func:`biased_distances`); with transparent objects in the scene, a second cast finds the
first transparent surface in front of it and :func:`vlref.geometry.shadow_transmittance` its colour.

Performance (BENCHMARKS.md, "Ray casting: the query inlined, the arrays borrowed, rows on demand"): a face's chunks
are handed out to the threads on demand (:func:`vlref.parallel.take`; texels that see nothing cost little, so
``prange``'s equal blocks would leave threads idle), the workers get every array without reference counts
(:func:`vlref.parallel.borrowed`), and each texel's ray is built in the kernel (no NumPy arrays per face): ~100 M
texels/s on 16 cores for the bench scene's four lights.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numba import prange

from ..camera import Camera
from ..geometry import EVERY_SURFACE, OPAQUE_ONLY, RAY_CHUNK, closest_hits, shadow_transmittance, traversal_stack
from ..jit import njit
from ..parallel import COUNTER, WORKERS, borrowed, take, task_counter, work
from .pack import (F_DX, F_DY, F_DZ, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UX, F_UY, F_UZ, I_KIND,
                   KIND_POINT, KIND_SPOT, PackedLights)
from .shadow_pack import (CUBE_AXES, CUBE_FACES, FILTER_MODES, NSF, NSI, S_CASC, S_CASCADES, S_MODE, S_OFFSET, S_RES,
                          S_STRENGTH, SHADOW_EXACT, ShadowMaps)

__all__ = ["build_shadow_maps", "cascade_splits", "cascade_sphere", "texel_grid", "biased_distances", "MAX_SLOPE"]

MAX_SLOPE = 10.0
"""The slope factor ``tan α`` of the slope bias is clamped to this (:func:`biased_distances`)."""


def cascade_splits(near: float, far: float, count: int, split_lambda: float) -> np.ndarray:
    """The ``count + 1`` split depths of the practical split scheme (module docstring)."""
    i = np.arange(count + 1) / count
    return split_lambda * near * (far / near) ** i + (1.0 - split_lambda) * (near + (far - near) * i)


def cascade_sphere(camera: Camera, z0: float, z1: float) -> tuple[np.ndarray, float]:
    """Bounding sphere ``(centre, radius)`` of the view-frustum slice between eye depths ``z0`` and ``z1``
    (its 8 corners' mean and largest distance): the region a cascade's orthographic map covers."""
    t = camera.tan_half_fov
    corners = np.array([[sx * z * t * camera.aspect, sy * z * t, z] for z in (z0, z1)
                        for sx in (-1, 1) for sy in (-1, 1)])
    world = corners @ camera.rotation.T + camera.position
    centre = world.mean(axis=0)
    return centre, float(np.sqrt(((world - centre) ** 2).sum(axis=1)).max())


FACE_ORIGIN, FACE_FWD, FACE_RIGHT, FACE_UP, FACE_SCALE, FACE_NEAR, FACE_LIMIT = 0, 3, 6, 9, 12, 13, 14
NFACE = 15
"""A face's ray parameters (:func:`_face_ray`): origin (3), forward, right, up (3 each), scale, near, limit."""


@njit(cache=True, fastmath=False, forceinline=True)
def _face_ray(face, ortho, res, k):
    """Ray of texel ``k`` (row-major, row 0 at the top) of a face: ``(ox, oy, oz, dx, dy, dz, start, tmax)``.

    Texel NDC ``x = ((c + 0.5) / res) * 2 - 1``, ``y = -(((r + 0.5) / res) * 2 - 1)`` (:func:`texel_grid`).
    Perspective (spot, cube face; ``scale`` = tan of the half angle or 1): ``v = (fwd + (x s) right) + (y s) up``,
    unit direction ``v / |v|``, origin ``pos + near v`` on the near plane, ``start = near |v|``,
    ``tmax = max(range - start, 0)`` (``limit`` = range). Orthographic (a cascade; ``scale`` = radius,
    ``near`` = back): origin ``((centre + (x r) right) + (y r) up) - back fwd``, direction ``fwd``,
    ``start = 0``, ``tmax = limit`` (= back + radius). The operations and their order are those of the NumPy
    construction this replaces, so the rays have the same bits.
    """
    row, col = k // res, k % res
    x = (col + 0.5) / res * 2.0 - 1.0
    y = -((row + 0.5) / res * 2.0 - 1.0)
    xs, ys = x * face[FACE_SCALE], y * face[FACE_SCALE]
    near = face[FACE_NEAR]
    if ortho:
        ox = (face[0] + xs * face[FACE_RIGHT]) + ys * face[FACE_UP] - near * face[FACE_FWD]
        oy = (face[1] + xs * face[FACE_RIGHT + 1]) + ys * face[FACE_UP + 1] - near * face[FACE_FWD + 1]
        oz = (face[2] + xs * face[FACE_RIGHT + 2]) + ys * face[FACE_UP + 2] - near * face[FACE_FWD + 2]
        return ox, oy, oz, face[FACE_FWD], face[FACE_FWD + 1], face[FACE_FWD + 2], 0.0, face[FACE_LIMIT]
    vx = (face[FACE_FWD] + xs * face[FACE_RIGHT]) + ys * face[FACE_UP]
    vy = (face[FACE_FWD + 1] + xs * face[FACE_RIGHT + 1]) + ys * face[FACE_UP + 1]
    vz = (face[FACE_FWD + 2] + xs * face[FACE_RIGHT + 2]) + ys * face[FACE_UP + 2]
    length = math.sqrt(vx * vx + vy * vy + vz * vz)
    start = near * length
    return (face[0] + near * vx, face[1] + near * vy, face[2] + near * vz, vx / length, vy / length, vz / length,
            start, max(face[FACE_LIMIT] - start, 0.0))


@njit(cache=True, fastmath=False, by_address=True)
def _cast_chunks(taken, geo, face, ortho, res, bias, slope_bias, want_tint, out, tint):
    """Chunks of ``RAY_CHUNK`` texels of one face taken one at a time (:func:`vlref.parallel.take`) until none is
    left: each texel's ray (:func:`_face_ray`), the chunk's first opaque hits (:func:`closest_hits`) stored as
    biased distances; with ``want_tint`` the first transparent surface in front of that hit and the colour of
    every transparent crossing before it (:func:`shadow_transmittance`). The arrays are borrowed
    (:func:`vlref.parallel.borrowed`)."""
    n = res * res
    s = take(taken) * RAY_CHUNK
    if s >= n:  # before any allocation: most of the WORKERS iterations find no chunk left
        return
    geo, face, out, tint = borrowed((geo, face, out, tint))
    origins, dirs, start, tmax = np.empty((RAY_CHUNK, 3)), np.empty((RAY_CHUNK, 3)), np.empty(RAY_CHUNK), np.empty(
        RAY_CHUNK)
    t, obj, normal = np.empty(RAY_CHUNK), np.empty(RAY_CHUNK, dtype=np.int64), np.empty((RAY_CHUNK, 3))
    end, tt, tobj = np.empty(RAY_CHUNK), np.empty(RAY_CHUNK), np.empty(RAY_CHUNK, dtype=np.int64)
    stack = traversal_stack()
    while s < n:
        m = min(n - s, RAY_CHUNK)
        for j in range(m):
            (origins[j, 0], origins[j, 1], origins[j, 2], dirs[j, 0], dirs[j, 1], dirs[j, 2], start[j],
             tmax[j]) = _face_ray(face, ortho, res, s + j)
        closest_hits(geo, origins[:m], dirs[:m], tmax[:m], OPAQUE_ONLY, stack, t[:m], obj[:m], normal[:m])
        biased_distances(t[:m], obj[:m], normal[:m], dirs[:m], start[:m], bias, slope_bias, out[s:s + m])
        if want_tint:
            for j in range(m):
                end[j] = min(t[j], tmax[j])
            closest_hits(geo, origins[:m], dirs[:m], end[:m], EVERY_SURFACE, stack, tt[:m], tobj[:m], normal[:m])
            for j in range(m):
                k = s + j
                if tobj[j] < 0:
                    tint[k, 0], tint[k, 1], tint[k, 2], tint[k, 3] = np.inf, 1.0, 1.0, 1.0
                else:
                    r, g, b = shadow_transmittance(geo, origins[j, 0], origins[j, 1], origins[j, 2], dirs[j, 0],
                                                   dirs[j, 1], dirs[j, 2], end[j] * (1.0 - 1e-9), stack)
                    tint[k, 0], tint[k, 1], tint[k, 2], tint[k, 3] = start[j] + tt[j] + bias, r, g, b
        s = take(taken) * RAY_CHUNK


@njit(cache=True, fastmath=False, parallel=True)
def _cast_face(geo, face, ortho, res, bias, slope_bias, want_tint, out, tint, cast_chunks):
    """Per texel of one face (:func:`_face_ray`): biased distance ``start + t`` to the first opaque hit (inf if
    none before ``tmax``), stored as float32; with ``want_tint`` the first transparent surface and its colour.
    Every worker casts the chunks it takes (``cast_chunks``: :func:`_cast_chunks` by address,
    :func:`vlref.parallel.work`), which borrows the arrays (module docstring, "Performance")."""
    taken = task_counter()
    for _ in prange(WORKERS):
        cast_chunks(taken, geo, face, ortho, res, bias, slope_bias, want_tint, out, tint)


@njit(cache=True, fastmath=False)
def biased_distances(t, obj, normal, dirs, start, bias, slope_bias, out):
    """What a texel stores for each ray's first opaque hit (inf for none): the biased distance
    ``start + t + bias + slope_bias · min(tan α, MAX_SLOPE)``, α the angle between the ray and the normal."""
    for j in range(t.shape[0]):
        if obj[j] < 0:
            out[j] = np.inf
        else:
            c = abs(normal[j, 0] * dirs[j, 0] + normal[j, 1] * dirs[j, 1] + normal[j, 2] * dirs[j, 2])
            slope = min(math.sqrt(max(1.0 - c * c, 0.0)) / max(c, 1e-12), MAX_SLOPE)
            out[j] = start[j] + t[j] + bias + slope_bias * slope



def texel_grid(res: int) -> tuple[np.ndarray, np.ndarray]:
    """NDC ``(x, y)`` of the texel centres of a ``res``² map, flattened row-major, row 0 at the top (y = +1)."""
    x = (np.arange(res) + 0.5) / res * 2.0 - 1.0
    return np.broadcast_to(x[None, :], (res, res)).reshape(-1), np.broadcast_to(-x[:, None], (res, res)).reshape(-1)


def _face(origin, fwd, right, up, scale, near, limit) -> np.ndarray:
    """The ``NFACE`` parameters of a face (:func:`_face_ray`)."""
    return np.concatenate([np.asarray(v, dtype=np.float64) for v in (origin, fwd, right, up)]
                          + [np.array([scale, near, limit], dtype=np.float64)])


def build_shadow_maps(scene, camera: Camera, geometry, packed: PackedLights) -> ShadowMaps:
    """Ray-cast the shadow map(s) of every light with shadows (module docstring; what each texel stores:
    :mod:`vlref.lights.shadow_pack`).

    Lights without ``shadows`` or with ``enabled = false`` get mode ``SHADOW_NONE``; ``exact`` lights
    get no map.
    """
    geo = geometry.arrays
    want_tint = bool(np.any(geo.opacity < 1.0))
    n = packed.count
    ints = np.zeros((n, NSI), dtype=np.int64)
    floats = np.zeros((n, NSF))
    casts, names = [], []  # (face, orthographic, resolution, shadow settings) and the maps' names, in data order
    offset = 0
    for i, light in enumerate(scene.lights):
        sh = light.shadows
        if sh is None or not sh.enabled:
            continue
        mode = FILTER_MODES[sh.filter]
        ints[i, S_MODE] = mode
        floats[i, S_STRENGTH] = sh.strength
        if mode == SHADOW_EXACT:
            continue
        lf = packed.floats[i].astype(np.float64)
        pos = lf[[F_PX, F_PY, F_PZ]]
        fwd, right, up = lf[[F_DX, F_DY, F_DZ]], lf[[F_RX, F_RY, F_RZ]], lf[[F_UX, F_UY, F_UZ]]
        res = sh.resolution
        faces = []  # (name, face parameters, orthographic)
        kind = int(packed.ints[i, I_KIND])
        if kind == KIND_SPOT:
            faces.append((f"shadow_spot_{i}", _face(pos, fwd, right, up, lf[F_TAN_HALF], sh.near, light.range), False))
        elif kind == KIND_POINT:
            for f, (suffix, r, u, w) in enumerate(CUBE_FACES):
                faces.append((f"shadow_point_{i}_face_{suffix}",
                              _face(pos, CUBE_AXES[f, 2], CUBE_AXES[f, 0], CUBE_AXES[f, 1], 1.0, sh.near, light.range),
                              False))
        else:
            far = min(sh.distance, camera.far)
            splits = cascade_splits(camera.near, max(far, camera.near * (1 + 1e-6)), sh.cascades, sh.split_lambda)
            ints[i, S_CASCADES] = sh.cascades
            corners = np.array(list(itertools.product(*zip(geometry.bounds_min, geometry.bounds_max))))
            for k in range(sh.cascades):
                centre, radius = cascade_sphere(camera, splits[k], splits[k + 1])
                back = radius + max(0.0, float(((centre - corners) @ fwd).max())) + 1.0
                floats[i, S_CASC + 5 * k:S_CASC + 5 * k + 5] = (*centre, radius, back)
                faces.append((f"shadow_dir_{i}_cascade_{k}", _face(centre, fwd, right, up, radius, back, back + radius),
                               True))
        ints[i, S_RES], ints[i, S_OFFSET] = res, offset
        for name, face, ortho in faces:
            casts.append((face, ortho, res, sh))
            names.append((name, i, offset, res * res))
            offset += res * res
    # every face cast into its slice of the one table (a table of the faces' own arrays joined was a copy of it)
    data = np.empty(offset, dtype=np.float32)
    tint = np.empty((offset if want_tint else 0, 4), dtype=np.float32)
    for (face, ortho, res, sh), (_, _, start, size) in zip(casts, names):
        args = (geo, face, bool(ortho), int(res), float(sh.bias), float(sh.slope_bias), want_tint,
                data[start:start + size], tint[start:start + size] if want_tint else tint)
        _cast_face(*args, work(_cast_chunks, COUNTER, *args))
    return ShadowMaps(ints, floats, data, tint, names)
