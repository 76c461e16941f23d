"""A port's shadow maps resampled into vlref's :class:`~vlref.lights.shadow_pack.ShadowMaps`.

Each vlref texel takes the port texel its centre ray projects into (nearest); spot and point maps store
``|P - light|``, cascade ``k`` stores ``(P - c_k)·forward + back_k`` (the rules in :mod:`vlref.port`).
Packing goes through :func:`vlref.lights.shadow_pack.pack_shadow_maps`; the light frames are the scene's
(``look_rotation(direction)``, as :mod:`vlref.lights.pack` builds them).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..camera import Camera, look_rotation
from ..errors import InputError
from ..lights.shadow_cast import cascade_sphere, texel_grid
from ..lights.shadow_pack import CUBE_FACES, MAX_CASCADES, SHADOW_HARD, SHADOW_PCF, LightMaps, pack_shadow_maps
from .decode import CUBE_ORDER, PortShadowMap, nearest_texel, tile_points

__all__ = ["shadow_maps_from_port"]


def _tile_count(light, m: PortShadowMap) -> tuple[int, str]:
    """The number of tiles a ``light`` needs and how it is counted."""
    if light.type == "spot":
        return 1, "one"
    if light.type == "point":
        return 6, "one per face"
    return len(m.splits) - 1, "len(splits) - 1"


def shadow_maps_from_port(scene, camera: Camera, maps: Sequence[PortShadowMap], file: str) -> dict:
    """Pack a port's shadow maps (read from the manifest ``file``) into vlref's shadow maps.

    Returns ``{filter: ShadowMaps}`` for ``None`` (the scene's filter), ``"hard"`` and ``"pcf"``, ready
    for :attr:`vlref.render.Frame.shadow_cache`.
    """
    n = len(scene.lights)
    packed = []
    for m in maps:
        key = f"shadow_maps[light={m.light}]"
        if not 0 <= m.light < n:
            raise InputError(file, key, f"no light {m.light} (the scene has {n})")
        light = scene.lights[m.light]
        sh = light.shadows
        if sh is not None and sh.filter == "exact":
            raise InputError(file, key, "the scene light's shadows.filter is exact (shadow rays): a port's map "
                                        "needs hard or pcf")
        rot = look_rotation(light.direction)
        pos = np.asarray(light.position, dtype=np.float64)
        right, up, fwd = rot[:, 0], rot[:, 1], rot[:, 2]
        res = m.tiles[0].texels.shape[0]
        expected, rule = _tile_count(light, m)
        directional = light.type == "directional"
        if len(m.tiles) != expected or (directional and not 1 <= expected <= MAX_CASCADES):
            raise InputError(file, key, f"a {light.type} light needs {'1..8' if directional else expected} tile(s) "
                                        f"({rule}), got {len(m.tiles)}")
        x, y = texel_grid(res)
        ordered = m.tiles
        if light.type == "point":
            faces = [t.face for t in m.tiles]
            if sorted(faces) != sorted(CUBE_ORDER):
                raise InputError(file, key + ".tiles", f"cube faces must be {', '.join(CUBE_ORDER)} once each, got {faces}")
            ordered = tuple(m.tiles[faces.index(f)] for f in CUBE_ORDER)
        tiles, cascades = [], []
        for k, tile in enumerate(ordered):
            world = tile_points(tile, m.encoding, m.convention)
            if light.type == "spot":
                t = math.tan(math.radians(light.spot_angle) / 2.0)
                probe = pos + fwd + (x * t)[:, None] * right + (y * t)[:, None] * up
                value = np.linalg.norm(world - pos, axis=1)
                name = f"shadow_spot_{m.light}"
            elif light.type == "point":
                r_f, u_f, f_f = (np.asarray(a, dtype=np.float64) for a in CUBE_FACES[k][1:])
                probe = pos + f_f + x[:, None] * r_f + y[:, None] * u_f
                value = np.linalg.norm(world - pos, axis=1)
                name = f"shadow_point_{m.light}_face_{CUBE_ORDER[k]}"
            else:
                centre, radius = cascade_sphere(camera, m.splits[k], m.splits[k + 1])
                eye = np.linalg.inv(tile.view)[:3, 3]
                back = float((centre - eye) @ fwd)
                cascades.append((centre, radius, back))
                probe = centre + (x * radius)[:, None] * right + (y * radius)[:, None] * up
                value = (world - centre) @ fwd + back
                name = f"shadow_dir_{m.light}_cascade_{k}"
            value = value[nearest_texel(tile, probe)]
            tiles.append((name, np.where(np.isnan(value), np.inf, value).astype(np.float32)))
        mode = SHADOW_PCF if sh is not None and sh.filter == "pcf" else SHADOW_HARD
        packed.append(LightMaps(m.light, mode, sh.strength if sh is not None else 1.0, tuple(tiles), tuple(cascades)))
    maps = pack_shadow_maps(n, packed)
    return {None: maps, "hard": maps.with_filter("hard"), "pcf": maps.with_filter("pcf")}
