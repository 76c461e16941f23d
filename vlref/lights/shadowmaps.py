"""Shadow maps by ray casting from the lights, and their njit lookups.

Storage (every map is square, ``resolution`` texels a side, row 0 at the top, texel centres at
``(c + 0.5, r + 0.5)/res``; float32 as a GPU ``R32F`` map):

* spot: one perspective map, fov = ``spot_angle``, aspect 1, near = ``shadows.near``, far = ``range``,
  in the light frame (right, up, forward) of ``look_rotation(direction)``: texel ``(c, r)`` looks along
  ``forward + x·tan(θ)·right + y·tan(θ)·up`` with ``x = 2(c+0.5)/res - 1``, ``y = 1 - 2(r+0.5)/res``,
  ``θ = spot_angle/2``. Stores the RADIAL distance from the light to the first opaque surface beyond
  the near plane (``inf`` where none lies within ``range``).
* point: a cube map of six faces in the D3D/Unity order ``+X, -X, +Y, -Y, +Z, -Z`` (buffer suffixes
  ``px, nx, py, ny, pz, nz``). Face ``f`` with (right, up, forward) = ``+X: (-z, +y, +x)``,
  ``-X: (+z, +y, -x)``, ``+Y: (+x, -z, +y)``, ``-Y: (+x, +z, -y)``, ``+Z: (+x, +y, +z)``,
  ``-Z: (-x, +y, -z)``: texel ``(c, r)`` looks along ``forward + x·right + y·up`` (x, y as above;
  the D3D cube-map face layout). Stores radial distances like the spot map (near plane per face).
  Lookup picks the face of the major axis of ``x - p`` (ties: x before y before z).
* directional: ``cascades`` orthographic maps covering the view frustum from ``camera.near`` to
  ``min(shadows.distance, camera.far)``, split at ``z_i = λ n (f/n)^{i/N} + (1-λ)(n + (f-n) i/N)``
  (practical split scheme, Zhang et al. 2006; ``λ = split_lambda``). Cascade ``i`` is centred on the
  bounding sphere (centre ``c_i``, radius ``r_i``) of its frustum slice and spans ``[-r_i, r_i]²`` in
  the light's right/up axes; rays start on the plane ``c_i - back_i · forward`` (``back_i`` reaches
  past the geometry's bounds) and the map stores the distance from that plane along the light
  direction. A sample uses the first cascade whose sphere contains it (Unity's split spheres);
  outside every sphere it is lit (no shadows beyond the shadow distance).

Bias is applied caster-side, as Unity and GPU rasterisers do: the stored value is
``t + bias + slope_bias · min(tan α, 10)`` with ``α`` the angle between the caster's normal and the
map ray. A lookup is lit when ``d_ref <= stored`` (standard Z), ``d_ref`` the sample's radial
distance (spot, point) or its distance from the cascade's ray plane (directional).

Filters: ``hard`` = the texel containing the sample (nearest); ``pcf`` = the four texels around
``(u·res - 0.5, v·res - 0.5)``, each compared, blended with bilinear weights (a GPU's 2x2 comparison
sampler), addresses clamped to the face/map; ``exact`` = a shadow ray through the geometry
(:func:`vlref.geometry.shadow_transmittance`, no map). Visibility ``V = 1 - strength · (1 - lit)``
per RGB channel (:func:`apply_strength`).

Transparent occluders (``opacity < 1``): when the scene has any, each map gets a second layer per
texel: the biased distance to the first transparent surface in front of the first opaque one
(``inf`` if none) and the RGB transmittance of all transparent crossings in front of that opaque
surface (``shadow_transmittance``). A tap then gives ``lit_opaque · (d_ref > d_transparent ? rgb : 1)``:
stained glass colours the light behind it, a second-order GPU "coloured shadow map".
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ..camera import Camera
from ..geometry import RAY_CHUNK, closest_hits, shadow_transmittance, traversal_stack
from .pack import (F_DX, F_DY, F_DZ, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UX, F_UY, F_UZ, I_KIND,
                   KIND_DIRECTIONAL, KIND_POINT, KIND_SPOT, PackedLights)

__all__ = ["ShadowMaps", "ShadowTable", "LightMaps", "build_shadow_maps", "pack_shadow_maps", "apply_strength",
           "shadow_visibility", "map_lit", "lit_at_points", "cast_rays", "spot_map_coords", "sample_map",
           "pcf_taps", "pcf_blend", "cube_map_coords", "cascade_map_coords", "cascade_splits", "CUBE_FACES", "SHADOW_NONE", "SHADOW_HARD", "SHADOW_PCF", "SHADOW_EXACT", "MAX_CASCADES"]

SHADOW_NONE, SHADOW_HARD, SHADOW_PCF, SHADOW_EXACT = 0, 1, 2, 3
FILTER_MODES = {"hard": SHADOW_HARD, "pcf": SHADOW_PCF, "exact": SHADOW_EXACT}
MAX_CASCADES = 8
MAX_SLOPE = 10.0

CUBE_FACES = (("px", (0, 0, -1), (0, 1, 0), (1, 0, 0)), ("nx", (0, 0, 1), (0, 1, 0), (-1, 0, 0)),
              ("py", (1, 0, 0), (0, 0, -1), (0, 1, 0)), ("ny", (1, 0, 0), (0, 0, 1), (0, -1, 0)),
              ("pz", (1, 0, 0), (0, 1, 0), (0, 0, 1)), ("nz", (-1, 0, 0), (0, 1, 0), (0, 0, -1)))
"""(suffix, right, up, forward) of each cube face, in the D3D/Unity face order."""
_CUBE = np.array([[r, u, f] for _, r, u, f in CUBE_FACES], dtype=np.float64)  # (6, 3 axes, 3)

S_MODE, S_RES, S_OFFSET, S_CASCADES = range(4)
NSI = 4
S_STRENGTH = 0
S_CASC = 1  # then (cx, cy, cz, radius, back) per cascade
NSF = 1 + 5 * MAX_CASCADES


class ShadowTable(NamedTuple):
    """The shadow record the njit kernels take: the array fields of :class:`ShadowMaps` (same meanings)."""

    ints: np.ndarray
    floats: np.ndarray
    data: np.ndarray
    tint: np.ndarray


@dataclass
class ShadowMaps:
    """All shadow maps of a frame, packed for njit lookups.

    ints : (n_lights, NSI) int64 (mode, resolution, first texel, cascades).
    floats : (n_lights, NSF) float64 (strength, then centre xyz, radius, back per cascade).
    data : (T,) float32 biased distances of every texel of every map.
    tint : (T, 4) float32 transparent layer (biased distance, r, g, b) per texel of ``data``, or
        (0, 4) when the scene has no transparent object.
    names : (buffer name, light, first texel, texel count) for :meth:`buffers`.
    """

    ints: np.ndarray
    floats: np.ndarray
    data: np.ndarray
    tint: np.ndarray
    names: list = field(default_factory=list)

    def with_filter(self, shadow_filter: str) -> "ShadowMaps | None":
        """The same maps looked up with ``shadow_filter`` (``hard``, ``pcf``, ``exact``) by every shadowed
        light, without casting them again; None when a map it needs was never built (an ``exact`` light)."""
        mode = FILTER_MODES[shadow_filter]
        ints = self.ints.copy()
        shadowed = ints[:, S_MODE] != SHADOW_NONE
        if mode != SHADOW_EXACT and np.any(ints[shadowed, S_MODE] == SHADOW_EXACT):
            return None
        ints[shadowed, S_MODE] = mode
        return ShadowMaps(ints, self.floats, self.data, self.tint, self.names)

    @property
    def traces_rays(self) -> bool:
        """Whether a light's shadows are ``exact`` (shadow rays through the geometry) rather than map lookups."""
        return bool(np.any(self.ints[:, S_MODE] == SHADOW_EXACT))

    def mode(self, light: int) -> int:
        """The lookup mode of ``light`` (``SHADOW_NONE``, ``SHADOW_HARD``, ``SHADOW_PCF``, ``SHADOW_EXACT``)."""
        return int(self.ints[light, S_MODE])

    def cascade(self, light: int, k: int) -> tuple[np.ndarray, float, float]:
        """``(centre (3,), radius, back)`` of cascade ``k`` of directional ``light``: its bounding sphere and
        the distance from the map's near plane to the centre (metres)."""
        c = self.floats[light, S_CASC + 5 * k:S_CASC + 5 * k + 5]
        return c[:3], float(c[3]), float(c[4])

    @property
    def table(self) -> ShadowTable:
        """The arrays as the record the njit kernels take."""
        return ShadowTable(self.ints, self.floats, self.data, self.tint)

    def buffers(self) -> dict[str, np.ndarray]:
        """Every map as a named (res, res) float32 buffer, plus ``<name>_transparent_distance`` (res, res)
        and ``<name>_transmittance`` (res, res, 3) for maps with a transparent layer."""
        out = {}
        for name, light, start, count in self.names:
            res = int(self.ints[light, S_RES])
            out[name] = self.data[start:start + count].reshape(res, res)
            if self.tint.shape[0]:
                layer = self.tint[start:start + count].reshape(res, res, 4)
                out[name + "_transparent_distance"] = layer[:, :, 0]
                out[name + "_transmittance"] = layer[:, :, 1:]
        return out


@dataclass(frozen=True)
class LightMaps:
    """One light's maps given as texels rather than cast (a GPU port's, :mod:`vlref.port.shadows`).

    ``tiles``: ``(buffer name, texels (res * res,) float32)`` in vlref's order (one spot map, the six cube
    faces in ``CUBE_FACES`` order, or the cascades), each texel the biased distance of the module docstring;
    ``cascades``: ``(centre (3,), radius, back)`` per cascade (directional lights only, else empty).
    """

    light: int
    mode: int
    strength: float
    tiles: tuple
    cascades: tuple = ()


def pack_shadow_maps(count: int, maps) -> ShadowMaps:
    """:class:`ShadowMaps` of ``count`` lights from :class:`LightMaps` (lights not listed: unshadowed);
    no transparent layer."""
    ints = np.zeros((count, NSI), dtype=np.int64)
    floats = np.zeros((count, NSF))
    chunks, names, offset = [], [], 0
    for m in maps:
        ints[m.light, S_MODE] = m.mode
        floats[m.light, S_STRENGTH] = m.strength
        for k, (name, texels) in enumerate(m.tiles):
            if k == 0:
                ints[m.light, S_RES], ints[m.light, S_OFFSET] = int(round(math.sqrt(texels.size))), offset
            chunks.append(texels)
            names.append((name, m.light, offset, texels.size))
            offset += texels.size
        for k, (centre, radius, back) in enumerate(m.cascades):
            floats[m.light, S_CASC + 5 * k:S_CASC + 5 * k + 5] = (*centre, radius, back)
        if m.cascades:
            ints[m.light, S_CASCADES] = len(m.cascades)
    data = np.concatenate(chunks) if chunks else np.zeros(0, dtype=np.float32)
    return ShadowMaps(ints, floats, data, np.zeros((0, 4), dtype=np.float32), names)


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
"""A face's ray parameters (:func:`_face_rays`): origin (3), forward, right, up (3 each), scale, near, limit."""


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


@njit(cache=True, fastmath=False, parallel=True)
def _cast_face(geo, face, ortho, res, bias, slope_bias, want_tint, out, tint):
    """Per texel of one face (:func:`_face_ray`): biased distance ``start + t`` to the first opaque hit (inf if
    none before ``tmax``), stored as float32; with ``want_tint`` the first transparent surface and its colour."""
    n = res * res
    for chunk in prange((n + RAY_CHUNK - 1) // RAY_CHUNK):
        s, e = chunk * RAY_CHUNK, min(n, (chunk + 1) * RAY_CHUNK)
        m = e - s
        origins, dirs, start, tmax = np.empty((m, 3)), np.empty((m, 3)), np.empty(m), np.empty(m)
        for j in range(m):
            (origins[j, 0], origins[j, 1], origins[j, 2], dirs[j, 0], dirs[j, 1], dirs[j, 2], start[j],
             tmax[j]) = _face_ray(face, ortho, res, s + j)
        stack = traversal_stack()
        t, obj, normal = np.empty(m), np.empty(m, dtype=np.int64), np.empty((m, 3))
        closest_hits(geo, origins, dirs, tmax, True, stack, t, obj, normal)
        _store_hits(t, obj, normal, dirs, start, bias, slope_bias, out[s:e])
        if want_tint:
            end = np.minimum(t, tmax)
            tt, tobj = np.empty(m), np.empty(m, dtype=np.int64)
            closest_hits(geo, origins, dirs, end, False, stack, tt, tobj, normal)
            for j in range(m):
                k = s + j
                if tobj[j] < 0:
                    tint[k, 0], tint[k, 1], tint[k, 2], tint[k, 3] = np.inf, 1.0, 1.0, 1.0
                else:
                    r, g, b = shadow_transmittance(geo, origins[j, 0], origins[j, 1], origins[j, 2], dirs[j, 0],
                                                   dirs[j, 1], dirs[j, 2], end[j] * (1.0 - 1e-9), stack)
                    tint[k, 0], tint[k, 1], tint[k, 2], tint[k, 3] = start[j] + tt[j] + bias, r, g, b


def cast_rays(geometry, origins: np.ndarray, dirs: np.ndarray, start: np.ndarray, tmax: np.ndarray, bias: float,
              slope_bias: float) -> np.ndarray:
    """(N,) the biased distance ``start + t + bias + slope_bias · min(tan α, 10)`` of each ray's first opaque
    hit in ``(0, tmax)`` (``inf`` where none): what a map texel with these rays stores (module docstring),
    for rays a caller chooses (a port's texel rays, :mod:`vlref.oracle.verdict`)."""
    out = np.empty(len(origins))
    _cast_rays(geometry.arrays, np.ascontiguousarray(origins, dtype=np.float64),
               np.ascontiguousarray(dirs, dtype=np.float64), np.ascontiguousarray(start, dtype=np.float64),
               np.ascontiguousarray(tmax, dtype=np.float64), float(bias), float(slope_bias), out)
    return out


@njit(cache=True, fastmath=False)
def _store_hits(t, obj, normal, dirs, start, bias, slope_bias, out):
    """What a texel stores for each ray's first opaque hit (inf for none): the biased distance
    ``start + t + bias + slope_bias · min(tan α, MAX_SLOPE)``, α the angle between the ray and the normal."""
    for j in range(t.shape[0]):
        if obj[j] < 0:
            out[j] = np.inf
        else:
            c = abs(normal[j, 0] * dirs[j, 0] + normal[j, 1] * dirs[j, 1] + normal[j, 2] * dirs[j, 2])
            slope = min(math.sqrt(max(1.0 - c * c, 0.0)) / max(c, 1e-12), MAX_SLOPE)
            out[j] = start[j] + t[j] + bias + slope_bias * slope


@njit(cache=True, fastmath=False, parallel=True)
def _cast_rays(geo, origins, dirs, start, tmax, bias, slope_bias, out):
    """:func:`cast_rays` in chunks of ``RAY_CHUNK`` rays, each chunk on one thread."""
    n = origins.shape[0]
    for chunk in prange((n + RAY_CHUNK - 1) // RAY_CHUNK):
        s, e = chunk * RAY_CHUNK, min(n, (chunk + 1) * RAY_CHUNK)
        m = e - s
        stack = traversal_stack()
        t, obj, normal = np.empty(m), np.empty(m, dtype=np.int64), np.empty((m, 3))
        closest_hits(geo, origins[s:e], dirs[s:e], tmax[s:e], True, stack, t, obj, normal)
        _store_hits(t, obj, normal, dirs[s:e], start[s:e], bias, slope_bias, out[s:e])


def texel_grid(res: int) -> tuple[np.ndarray, np.ndarray]:
    """NDC ``(x, y)`` of the texel centres of a ``res``² map, flattened row-major, row 0 at the top (y = +1)."""
    x = (np.arange(res) + 0.5) / res * 2.0 - 1.0
    return np.broadcast_to(x[None, :], (res, res)).reshape(-1), np.broadcast_to(-x[:, None], (res, res)).reshape(-1)


def _face(origin, fwd, right, up, scale, near, limit) -> np.ndarray:
    """The ``NFACE`` parameters of a face (:func:`_face_ray`)."""
    return np.concatenate([np.asarray(v, dtype=np.float64) for v in (origin, fwd, right, up)]
                          + [np.array([scale, near, limit], dtype=np.float64)])


def build_shadow_maps(scene, camera: Camera, geometry, packed: PackedLights) -> ShadowMaps:
    """Ray-cast the shadow map(s) of every light with shadows (module docstring).

    Lights without ``shadows`` or with ``enabled = false`` get mode ``SHADOW_NONE``; ``exact`` lights
    get no map.
    """
    geo = geometry.arrays
    want_tint = bool(np.any(geo.opacity < 1.0))
    n = packed.count
    ints = np.zeros((n, NSI), dtype=np.int64)
    floats = np.zeros((n, NSF))
    chunks, tints, names = [], [], []
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
                              _face(pos, _CUBE[f, 2], _CUBE[f, 0], _CUBE[f, 1], 1.0, sh.near, light.range), False))
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
            out = np.empty(res * res, dtype=np.float32)
            tint = np.empty((res * res if want_tint else 0, 4), dtype=np.float32)
            _cast_face(geo, face, ortho, res, sh.bias, sh.slope_bias, want_tint, out, tint)
            chunks.append(out)
            tints.append(tint)
            names.append((name, i, offset, res * res))
            offset += res * res
    data = np.concatenate(chunks) if chunks else np.zeros(0, dtype=np.float32)
    tint = np.concatenate(tints) if tints else np.zeros((0, 4), dtype=np.float32)
    return ShadowMaps(ints, floats, data, tint, names)


@njit(cache=True, fastmath=False, forceinline=True)
def _tap(data, tint, base, tbase, k, d_ref):
    lit = 1.0 if d_ref <= data[base + k] else 0.0
    if tbase >= 0 and d_ref > tint[tbase + k, 0]:
        return lit * tint[tbase + k, 1], lit * tint[tbase + k, 2], lit * tint[tbase + k, 3]
    return lit, lit, lit


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def pcf_taps(u, v, res):
    """The 2x2 PCF taps around ``(u, v)`` on a ``res``² face: texel offsets ``row · res + col`` (clamped to the
    edge) ``(k00, k10, k01, k11)`` and bilinear weights ``(w00, w10, w01, w11)``. Scalars only: the march
    computes them in a vectorised lane loop. The column is clamped to [-1, res] in floating point before the
    conversion to a 32-bit integer (the same texels; no overflow far outside the map)."""
    su, sv = u * res - 0.5, v * res - 0.5
    fu, fv = math.floor(su), math.floor(sv)
    wu, wv = su - fu, sv - fv
    edge = float(res)
    c0 = np.int32(min(max(fu, -1.0), edge)) + 0  # int32: a packed conversion on AVX2 (int64 has none)
    r0 = np.int32(min(max(fv, -1.0), edge)) + 0
    c0c, c1c = min(max(c0, 0), res - 1), min(max(c0 + 1, 0), res - 1)
    r0c, r1c = min(max(r0, 0), res - 1), min(max(r0 + 1, 0), res - 1)
    top, bottom = r0c * res, r1c * res
    return ((top + c0c, top + c1c, bottom + c0c, bottom + c1c),
            ((1 - wu) * (1 - wv), wu * (1 - wv), (1 - wu) * wv, wu * wv))


@njit(cache=True, fastmath=False, forceinline=True)
def pcf_blend(data, base, k00, k10, k01, k11, w00, w10, w01, w11, d_ref):
    """The PCF lit fraction of the taps of :func:`pcf_taps` (no transparent layer): ``Σ w [d_ref <= depth]``
    (selects, not products: the same sum). Unsigned ``base`` and offsets index without the wrap-around of
    negative indices."""
    return ((w00 if d_ref <= data[base + k00] else 0.0) + (w10 if d_ref <= data[base + k10] else 0.0)
            + (w01 if d_ref <= data[base + k01] else 0.0) + (w11 if d_ref <= data[base + k11] else 0.0))


@njit(cache=True, fastmath=False, forceinline=True)
def sample_map(data, tint, base, tbase, res, pcf, u, v, d_ref):
    """Filtered comparison of one face at (u, v) (row 0 at v = 0 = top). Without a transparent layer
    (``tbase < 0``) r = g = b and the PCF blend is evaluated once."""
    if not pcf:
        col = min(max(int(math.floor(u * res)), 0), res - 1)
        row = min(max(int(math.floor(v * res)), 0), res - 1)
        return _tap(data, tint, base, tbase, row * res + col, d_ref)
    (k00, k10, k01, k11), (w00, w10, w01, w11) = pcf_taps(u, v, res)
    if tbase < 0:
        lit = pcf_blend(data, base, k00, k10, k01, k11, w00, w10, w01, w11, d_ref)
        return lit, lit, lit
    a = _tap(data, tint, base, tbase, k00, d_ref)
    b = _tap(data, tint, base, tbase, k10, d_ref)
    c = _tap(data, tint, base, tbase, k01, d_ref)
    d = _tap(data, tint, base, tbase, k11, d_ref)
    return (w00 * a[0] + w10 * b[0] + w01 * c[0] + w11 * d[0], w00 * a[1] + w10 * b[1] + w01 * c[1] + w11 * d[1],
            w00 * a[2] + w10 * b[2] + w01 * c[2] + w11 * d[2])


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def cube_map_coords(wx, wy, wz):
    """``(face, u, v, d_ref, on_face)`` of the point at ``w = x - p`` from a point light (float64): the face of
    ``w``'s major axis (ties: x before y before z; ``CUBE_FACES`` order), the coordinates on it,
    ``u = 1/2 + sc/(2 ma)``, ``v = 1/2 - tc/(2 ma)`` with ``sc``, ``tc``, ``ma`` the components of ``w`` along the
    face's right, up and forward axes (``ma = |w · forward|``), the radial distance the map stores, and whether
    the point has a face (``ma > 0``; else ``u = v = 0.5``).

    The axes are unit vectors of ±x, ±y, ±z, so each component is ``±wx``, ``±wy`` or ``±wz``, chosen here by
    selects (the face table's products with 0 and ±1 give the same values, up to the sign of a zero that
    ``1/2 ± 0`` drops): no table lookup, so the march evaluates it in a vectorised lane loop."""
    ax, ay, az = abs(wx), abs(wy), abs(wz)
    x_major = ax >= ay and ax >= az
    y_major = not x_major and ay >= az
    if x_major:
        face, ma, sc, tc = (0, ax, -wz, wy) if wx >= 0 else (1, ax, wz, wy)
    elif y_major:
        face, ma, sc, tc = (2, ay, wx, -wz) if wy >= 0 else (3, ay, wx, wz)
    else:
        face, ma, sc, tc = (4, az, wx, wy) if wz >= 0 else (5, az, -wx, wy)
    on_face = ma != 0.0
    ma = ma if on_face else 1.0
    u = 0.5 + 0.5 * (sc / ma) if on_face else 0.5
    v = 0.5 - 0.5 * (tc / ma) if on_face else 0.5
    return face, u, v, math.sqrt(wx * wx + wy * wy + wz * wz), on_face


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def cascade_map_coords(cx, cy, cz, radius, back, rx, ry, rz, ux, uy, uz, dx, dy, dz):
    """``(u, v, d_ref, inside)`` of the point at ``c = x - centre`` in a directional light's cascade (float64) of
    bounding-sphere ``radius`` and ray plane ``back`` behind the centre, with the light's right ``r``, up ``u`` and
    forward ``d`` axes: ``u = 1/2 + (c · r)/(2 radius)``, ``v = 1/2 - (c · u)/(2 radius)``, the distance from the
    ray plane ``c · d + back`` the map stores, and whether the sphere contains the point. Scalars only: the march
    evaluates it in a vectorised lane loop, one cascade at a time."""
    inside = cx * cx + cy * cy + cz * cz <= radius * radius
    xl = cx * rx + cy * ry + cz * rz
    yl = cx * ux + cy * uy + cz * uz
    zl = cx * dx + cy * dy + cz * dz
    return 0.5 + 0.5 * xl / radius, 0.5 - 0.5 * yl / radius, zl + back, inside


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def spot_map_coords(wx, wy, wz, rx, ry, rz, ux, uy, uz, dx, dy, dz, tan_half):
    """``(u, v, d_ref, ahead)`` of the point at ``w = x - p`` from a spot light (float64): the map coordinates of
    its projection (right ``r``, up ``u``, forward ``d`` axes; ``tan_half`` of the cone), the distance the map
    stores, and whether the point is in front of the light (else ``u = v = 0.5``). Scalars only: the march
    evaluates it in a vectorised lane loop and looks the map up (:func:`sample_map`) lane by lane."""
    d_ref = math.sqrt(wx * wx + wy * wy + wz * wz)
    xl = wx * rx + wy * ry + wz * rz
    yl = wx * ux + wy * uy + wz * uz
    zl = wx * dx + wy * dy + wz * dz
    ahead = zl > 0.0
    k = 0.5 / (zl * tan_half) if ahead else 0.0
    return 0.5 + xl * k, 0.5 - yl * k, d_ref, ahead


@njit(cache=True, fastmath=False, parallel=True)
def lit_at_points(shadows, kind, lf, light, points, out):
    """``out[i]``: the mean over RGB of :func:`map_lit` of light ``light`` at world point ``points[i]`` (N, 3)."""
    for i in prange(points.shape[0]):
        r, g, b = map_lit(shadows, kind, lf, light, points[i, 0], points[i, 1], points[i, 2])
        out[i] = (r + g + b) / 3.0


@njit(cache=True, fastmath=False, forceinline=True)
def map_lit(shadows, kind, lf, light, x, y, z):
    """Unfiltered-strength lit fraction (r, g, b) of world point ``x`` from light ``light``'s map (float64).

    ``shadows`` a :class:`ShadowTable`, ``lf`` the light float table of :mod:`vlref.lights.pack`.
    """
    sm_i, sm_f, data, tint = shadows.ints, shadows.floats, shadows.data, shadows.tint
    res = sm_i[light, S_RES]
    base = sm_i[light, S_OFFSET]
    tbase = base if tint.shape[0] > 0 else -1
    pcf = sm_i[light, S_MODE] == SHADOW_PCF
    wx, wy, wz = x - float(lf[light, F_PX]), y - float(lf[light, F_PY]), z - float(lf[light, F_PZ])
    if kind == KIND_DIRECTIONAL:
        for k in range(sm_i[light, S_CASCADES]):
            j = S_CASC + 5 * k
            u, v, d_ref, inside = cascade_map_coords(
                x - sm_f[light, j], y - sm_f[light, j + 1], z - sm_f[light, j + 2], sm_f[light, j + 3],
                sm_f[light, j + 4], float(lf[light, F_RX]), float(lf[light, F_RY]), float(lf[light, F_RZ]),
                float(lf[light, F_UX]), float(lf[light, F_UY]), float(lf[light, F_UZ]), float(lf[light, F_DX]),
                float(lf[light, F_DY]), float(lf[light, F_DZ]))
            if inside:
                o = base + k * res * res
                to = tbase + k * res * res if tbase >= 0 else -1
                return sample_map(data, tint, o, to, res, pcf, u, v, d_ref)
        return 1.0, 1.0, 1.0
    if kind == KIND_SPOT:
        u, v, d_ref, ahead = spot_map_coords(wx, wy, wz, float(lf[light, F_RX]), float(lf[light, F_RY]),
                                             float(lf[light, F_RZ]), float(lf[light, F_UX]), float(lf[light, F_UY]),
                                             float(lf[light, F_UZ]), float(lf[light, F_DX]), float(lf[light, F_DY]),
                                             float(lf[light, F_DZ]), float(lf[light, F_TAN_HALF]))
        if not ahead:
            return 1.0, 1.0, 1.0
        return sample_map(data, tint, base, tbase, res, pcf, u, v, d_ref)
    f, u, v, d_ref, on_face = cube_map_coords(wx, wy, wz)
    if not on_face:
        return 1.0, 1.0, 1.0
    o = base + f * res * res
    to = tbase + f * res * res if tbase >= 0 else -1
    return sample_map(data, tint, o, to, res, pcf, u, v, d_ref)


@njit(cache=True, fastmath=False)
def exact_visibility(geo, kind, lf, light, x, y, z):
    """Unfiltered-strength RGB transmittance of a shadow ray from world point ``x`` toward light ``light``
    (to infinity for directional lights; 1 at the light's own position)."""
    if kind == KIND_DIRECTIONAL:
        return shadow_transmittance(geo, x, y, z, -float(lf[light, F_DX]), -float(lf[light, F_DY]),
                                    -float(lf[light, F_DZ]), np.inf)
    wx, wy, wz = float(lf[light, F_PX]) - x, float(lf[light, F_PY]) - y, float(lf[light, F_PZ]) - z
    dist = math.sqrt(wx * wx + wy * wy + wz * wz)
    if dist == 0.0:
        return 1.0, 1.0, 1.0
    return shadow_transmittance(geo, x, y, z, wx / dist, wy / dist, wz / dist, dist)


@njit(cache=True, fastmath=False)
def apply_strength(strength, r, g, b):
    """Visibility ``V = 1 - strength · (1 - lit)`` per channel of the lit fraction ``(r, g, b)`` (the
    light's ``shadows.strength``; float64, as every caller evaluates it)."""
    return 1.0 - strength * (1.0 - r), 1.0 - strength * (1.0 - g), 1.0 - strength * (1.0 - b)


@njit(cache=True, fastmath=False)
def shadow_visibility(shadows, geo, kind, lf, light, x, y, z):
    """Visibility (r, g, b) in [0, 1] of light ``light`` from world point ``x`` (float64), strength applied.

    ``shadows`` a :class:`ShadowTable`. Mode ``SHADOW_EXACT`` traces a shadow ray toward the light
    (:func:`exact_visibility`); the map modes are :func:`map_lit`.
    """
    mode = shadows.ints[light, S_MODE]
    if mode == SHADOW_NONE:
        return 1.0, 1.0, 1.0
    if mode == SHADOW_EXACT:
        r, g, b = exact_visibility(geo, kind, lf, light, x, y, z)
    else:
        r, g, b = map_lit(shadows, kind, lf, light, x, y, z)
    return apply_strength(shadows.floats[light, S_STRENGTH], r, g, b)
