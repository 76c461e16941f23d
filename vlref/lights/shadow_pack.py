"""The shadow-map record: what each texel stores, and every map of a frame packed for the njit lookups.

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
  ``min(shadows.distance, camera.far)`` (:func:`vlref.lights.shadow_cast.cascade_splits`). Cascade ``i`` is
  centred on the bounding sphere (centre ``c_i``, radius ``r_i``) of its frustum slice and spans ``[-r_i, r_i]²``
  in the light's right/up axes; rays start on the plane ``c_i - back_i · forward`` (``back_i`` reaches past the
  geometry's bounds) and the map stores the distance from that plane along the light direction. A sample uses
  the first cascade whose sphere contains it (Unity's split spheres); outside every sphere it is lit (no
  shadows beyond the shadow distance).

Bias is applied caster-side, as Unity and GPU rasterisers do: the stored value is
``t + bias + slope_bias · min(tan α, 10)`` with ``α`` the angle between the caster's normal and the
map ray. A lookup is lit when ``d_ref <= stored`` (standard Z), ``d_ref`` the sample's radial
distance (spot, point) or its distance from the cascade's ray plane (directional).

Transparent occluders (``opacity < 1``): when the scene has any, each map gets a second layer per
texel: the biased distance to the first transparent surface in front of the first opaque one
(``inf`` if none) and the RGB transmittance of all transparent crossings in front of that opaque
surface (``shadow_transmittance``). A tap then gives ``lit_opaque · (d_ref > d_transparent ? rgb : 1)``:
stained glass colours the light behind it, a second-order GPU "coloured shadow map".

Where each part lives: :mod:`vlref.lights.shadow_cast` casts the maps of a frame,
:mod:`vlref.lights.shadow_lookup` holds the njit lookups the march calls (filters ``hard``, ``pcf``,
``exact``), :mod:`vlref.lights.shadow_probes` casts rays and looks up points a caller chooses (the verdict).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

__all__ = ["ShadowMaps", "ShadowTable", "LightMaps", "pack_shadow_maps", "CUBE_FACES", "CUBE_AXES", "FILTER_MODES",
           "SHADOW_NONE", "SHADOW_HARD", "SHADOW_PCF", "SHADOW_EXACT", "MAX_CASCADES", "S_MODE", "S_RES", "S_OFFSET",
           "S_CASCADES", "NSI", "S_STRENGTH", "S_CASC", "NSF"]

SHADOW_NONE, SHADOW_HARD, SHADOW_PCF, SHADOW_EXACT = 0, 1, 2, 3
FILTER_MODES = {"hard": SHADOW_HARD, "pcf": SHADOW_PCF, "exact": SHADOW_EXACT}
MAX_CASCADES = 8

CUBE_FACES = (("px", (0, 0, -1), (0, 1, 0), (1, 0, 0)), ("nx", (0, 0, 1), (0, 1, 0), (-1, 0, 0)),
              ("py", (1, 0, 0), (0, 0, -1), (0, 1, 0)), ("ny", (1, 0, 0), (0, 0, 1), (0, -1, 0)),
              ("pz", (1, 0, 0), (0, 1, 0), (0, 0, 1)), ("nz", (-1, 0, 0), (0, 1, 0), (0, 0, -1)))
"""(suffix, right, up, forward) of each cube face, in the D3D/Unity face order."""
CUBE_AXES = np.array([[r, u, f] for _, r, u, f in CUBE_FACES], dtype=np.float64)
"""(6 faces, 3 axes: right, up, forward, 3) the axes of :data:`CUBE_FACES` as one array (njit lookups)."""

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
