"""March on a port's own buffers: ``vlref march PORT.toml -o OUT``.

A port (a GPU implementation in an engine) exports its camera depth buffer, its shadow maps and the
matrices it used; vlref decodes them, builds a :class:`vlref.render.Frame` whose G-buffer depth and
shadow maps are the port's, and runs the scene's technique (march and post passes) on it. Comparing the
result with the port's own output (``vlref compare``) then isolates the port's volumetric passes from
its rasteriser and shadow renderer. ``docs/PORTING.md`` documents every key with a worked example.

Manifest (TOML; paths relative to it)::

    scene = "scene.toml"            # medium, lights, technique params: a vlref scene file or bundled name
    set = ["render.steps=16"]       # optional --set overrides of the scene (render size = the depth's)
    colour = "colour.exr"           # optional (H, W, 3) lit scene colour; default black
    [camera]                        # optional: default the scene's camera
    view = [[...4 rows...]]         # world -> view, column vectors
    projection = [[...]]            # view -> clip
    forward = "+z"                  # "+z" (vlref, D3D-style LH view) or "-z" (GL / Unity worldToCameraMatrix)
    convention = "d3d"              # depth convention of `projection`: d3d, gl, reversed
    [depth]
    path = "depth.exr"
    encoding = "raw"                # "linear" (eye depth, metres) or "raw" (device depth)
    convention = "reversed"         # raw: d3d ([0,1], 0 at near), gl (NDC [-1,1]), reversed (1 at near)
    near = 0.1                      # raw: the clip planes (default: the camera's)
    far = 1000.0
    uv_origin = "top"               # row 0 of the file is the top ("top") or bottom ("bottom") of the image
    [[shadow_maps]]
    light = 0                       # index of the scene light
    path = "shadow.exr"             # one file holding every tile (atlas), or
    atlas = [1, 1]                  # [columns, rows] of tiles, filled row-major from the file's first row
    encoding = "depth"              # "depth" (per `convention`) or "distance" (from the light / map plane)
    convention = "reversed"         # depth: d3d, gl, reversed (raw device depth) or linear (view depth)
    uv_origin = "top"               # row order inside each tile
    splits = [0.1, 8.0, 30.0]       # directional only: cascade split depths (N + 1 values)
    [[shadow_maps.tiles]]           # one per spot map / cube face / cascade, in atlas order
    face = "px"                     # point only: px, nx, py, ny, pz, nz (any order, each once)
    view = [[...]]
    projection = [[...]]

Decoding (float64):

* camera depth: ``raw`` -> :func:`vlref.camera.raw_to_linear`; the far-plane value (d3d/gl ``1``,
  reversed ``0``) exactly, or a non-finite linear depth, is sky (``inf``).
* shadow texel -> world point ``P``: ``depth`` with a raw convention: NDC ``(x_c, y_c, z)`` of the texel
  centre, ``P = (P·V)^-1 (x_c, y_c, z, 1)`` (so any projection, perspective or orthographic, any
  handedness, decodes through its own matrices; gl stores NDC z in [-1, 1]); ``linear``: the point of the
  texel's ray at view depth ``|z| = value``; ``distance``: the point at that distance along the texel's
  ray from the eye (perspective) or from the view plane ``z = 0`` (orthographic). A texel holding the
  far-plane value (raw) or a non-finite value is empty (``inf``: lit).
* vlref's packing (:mod:`vlref.lights.shadowmaps`): each vlref texel takes the port texel its centre ray
  projects into (nearest); spot/point store ``|P - light|``; cascade ``k`` stores ``(P - c_k)·forward +
  back_k`` with ``(c_k, r_k)`` the bounding sphere of the camera's frustum slice between ``splits[k]``
  and ``splits[k+1]`` (vlref's cascade selection) and ``back_k`` the distance from the tile's near plane
  to ``c_k``. When the port's maps are laid out as vlref's (spot: the light frame of
  ``look_rotation(direction)``, fov = spot_angle; cube faces: the D3D frames; cascades: vlref's spheres)
  every texel maps to itself and the conversion is exact; otherwise it is a nearest resample.
* The filter (hard / pcf) and strength are the scene's (each technique may force its own filter); maps
  carry no transparent layer. Lights without a port map are unshadowed.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from ..camera import DEPTH_CONVENTIONS, Camera, camera_from_settings, raw_to_linear
from ..errors import InputError
from ..lights.shadowmaps import texel_grid

__all__ = ["PortTile", "PortShadowMap", "PortBuffers", "load_port", "decode_depth", "camera_from_matrices",
           "shadow_maps_from_port", "port_frame", "march_port", "main_march", "export_port", "orthographic",
           "FAR_VALUE", "NEAR_VALUE"]

NEAR_VALUE = {"d3d": 0.0, "gl": -1.0, "reversed": 1.0}
"""Device depth (NDC z) of the near plane per convention."""
FAR_VALUE = {"d3d": 1.0, "gl": 1.0, "reversed": 0.0}
"""Device depth (NDC z) of the far plane per convention: the value of a cleared depth buffer."""
CUBE_ORDER = ("px", "nx", "py", "ny", "pz", "nz")
SHADOW_CONVENTIONS = DEPTH_CONVENTIONS + ("linear",)


@dataclass(frozen=True)
class PortTile:
    """One square map of a port: texels (res, res) row 0 = top (v = 0), and its 4x4 matrices."""

    texels: np.ndarray
    view: np.ndarray
    projection: np.ndarray
    face: str = ""


@dataclass(frozen=True)
class PortShadowMap:
    """A light's exported maps: ``encoding`` "depth" with ``convention`` (d3d, gl, reversed, linear) or
    "distance"; ``splits`` (N + 1,) for cascades, else empty."""

    light: int
    tiles: tuple[PortTile, ...]
    encoding: str
    convention: str
    splits: tuple[float, ...] = ()


@dataclass
class PortBuffers:
    """A decoded port manifest: scene, camera, linear eye depth (inf = sky), scene colour, shadow maps."""

    scene: object
    camera: Camera
    depth: np.ndarray
    colour: np.ndarray
    shadow_maps: tuple[PortShadowMap, ...]


# --------------------------------------------------------------------------- decoding helpers

def decode_depth(values, encoding: str, convention: str = "d3d", near: float = 0.1, far: float = 1000.0,
                 uv_origin: str = "top") -> np.ndarray:
    """A port's camera depth (H, W) -> linear eye depth (metres, float64, row 0 = top, ``inf`` = sky).

    ``encoding``: ``linear`` (eye depth; non-finite = sky) or ``raw`` (device depth in ``convention``;
    exactly the far-plane value = sky). ``uv_origin="bottom"``: row 0 of ``values`` is the image bottom.
    """
    a = np.asarray(values, dtype=np.float64)
    if uv_origin == "bottom":
        a = a[::-1]
    if encoding == "linear":
        return np.where(np.isfinite(a), a, np.inf)
    sky = (a == FAR_VALUE[convention]) | ~np.isfinite(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = raw_to_linear(np.where(sky, NEAR_VALUE[convention], a), near, far, convention)
    return np.where(sky, np.inf, z)


def _flip_z(forward: str) -> np.ndarray:
    return np.diag([1.0, 1.0, 1.0 if forward == "+z" else -1.0, 1.0])


def camera_from_matrices(view, projection, width: int, height: int, convention: str = "d3d",
                         forward: str = "+z", file: str = "<port>") -> Camera:
    """The :class:`Camera` of an engine's view and perspective projection matrices.

    ``forward="-z"`` (GL-style view space, Unity's ``worldToCameraMatrix``): the view's z row and the
    projection's z column are negated to reach vlref's view space (x right, y up, z forward). The
    rotation must be orthonormal and proper; fov = ``2 atan(1 / P11)``, the aspect ``P11 / P00`` must
    equal ``width / height``; near/far solve ``ndc_z(z) = NEAR_VALUE / FAR_VALUE`` of ``convention``.
    """
    flip = _flip_z(forward)
    v = flip @ np.asarray(view, dtype=np.float64)
    p = np.asarray(projection, dtype=np.float64) @ flip
    rot = v[:3, :3].T
    if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-6) or np.linalg.det(rot) < 0:
        raise InputError(file, "camera.view", "the rotation part is not a proper orthonormal matrix "
                                              "(scaled view, or the wrong `forward`)")
    if not (p[3, 2] > 0 and p[1, 1] > 0 and p[0, 0] > 0):
        raise InputError(file, "camera.projection", "not a perspective projection looking along `forward`")
    aspect = p[1, 1] / p[0, 0]
    if abs(aspect - width / height) > 1e-6 * aspect:
        raise InputError(file, "camera.projection", f"aspect {aspect:.6g} differs from the depth buffer's "
                                                    f"{width}x{height}")
    a, b = p[2, 2] / p[3, 2], p[2, 3] / p[3, 2]  # ndc_z(z) = a + b / z
    near, far = b / (NEAR_VALUE[convention] - a), b / (FAR_VALUE[convention] - a)
    if not (0 < near < far and math.isfinite(far)):
        raise InputError(file, "camera.convention", f"near {near:.6g} / far {far:.6g} implausible for {convention}")
    return Camera(-rot @ v[:3, 3], rot, math.degrees(2.0 * math.atan(1.0 / p[1, 1])), width, height, near, far)


def _ray_points(tile: PortTile, res: int):
    """View-space texel-centre rays of a tile: origins (n, 3) on the plane z = 0 (orthographic) or at the
    eye (perspective), and unit directions (n, 3) pointing into the map's volume (whose points at NDC
    z = 0.25, inside the clip range of every convention, must lie in front of the view origin)."""
    nx, ny = texel_grid(res)
    inv_p = np.linalg.inv(tile.projection)

    def view_point(z):
        h = np.stack([nx, ny, np.full(nx.shape, z), np.ones(nx.shape)], axis=1) @ inv_p.T
        return h[:, :3] / h[:, 3:4]

    p0, p1 = view_point(0.25), view_point(0.75)  # inside the clip volume of every convention
    d = p1 - p0
    d *= (np.sign(d[:, 2] * p0[:, 2]) / np.linalg.norm(d, axis=1))[:, None]  # away from the eye / view plane
    ortho = np.allclose(tile.projection[3], [0.0, 0.0, 0.0, 1.0])
    origin = p0 - (p0[:, 2] / d[:, 2])[:, None] * d if ortho else np.zeros_like(p0)
    return origin, d


def _tile_points(tile: PortTile, encoding: str, convention: str) -> np.ndarray:
    """World point (res*res, 3) seen by each texel of ``tile`` (NaN rows where the texel is empty)."""
    res = tile.texels.shape[0]
    val = tile.texels.astype(np.float64).ravel()
    inv_v = np.linalg.inv(tile.view)
    if encoding == "depth" and convention != "linear":
        empty = (val == FAR_VALUE[convention]) | ~np.isfinite(val)
        nx, ny = texel_grid(res)
        h = np.stack([nx, ny, np.where(empty, 0.5, val), np.ones(val.shape)], axis=1) @ np.linalg.inv(
            tile.projection @ tile.view).T
        world = h[:, :3] / h[:, 3:4]
    else:
        empty = ~np.isfinite(val)
        origin, d = _ray_points(tile, res)
        v = np.where(empty, 1.0, val)
        if encoding == "depth":  # linear view depth: the ray point with |z| = value
            s = (np.sign(d[:, 2]) * v - origin[:, 2]) / d[:, 2]
        else:
            s = v
        view_pts = origin + s[:, None] * d
        world = view_pts @ inv_v[:3, :3].T + inv_v[:3, 3]
    world[empty] = np.nan
    return world


def _lookup(tile: PortTile, points: np.ndarray) -> np.ndarray:
    """Index of the port texel (nearest, clamped) that each world point projects into."""
    res = tile.texels.shape[0]
    clip = np.concatenate([points, np.ones((len(points), 1))], axis=1) @ (tile.projection @ tile.view).T
    u = (clip[:, 0] / clip[:, 3] + 1.0) * 0.5
    v = (1.0 - clip[:, 1] / clip[:, 3]) * 0.5
    col = np.clip(np.floor(u * res), 0, res - 1).astype(np.int64)
    row = np.clip(np.floor(v * res), 0, res - 1).astype(np.int64)
    return row * res + col


def shadow_maps_from_port(scene, camera: Camera, packed, maps: Sequence[PortShadowMap], file: str = "<port>"):
    """Pack a port's shadow maps into vlref's :class:`~vlref.lights.shadowmaps.ShadowMaps` (module docstring).

    Returns ``{filter: ShadowMaps}`` for ``None`` (the scene's filter), ``"hard"`` and ``"pcf"``, ready
    for :attr:`vlref.render.Frame.shadow_cache`.
    """
    from ..lights.pack import F_DX, F_PX, F_RX, F_TAN_HALF, F_UX, I_KIND
    from ..lights.shadowmaps import (CUBE_FACES, MAX_CASCADES, NSF, NSI, S_CASC, S_CASCADES, S_MODE, S_OFFSET,
                                     S_RES, S_STRENGTH, SHADOW_HARD, SHADOW_PCF, ShadowMaps, cascade_sphere)

    n = packed.count
    ints, floats = np.zeros((n, NSI), dtype=np.int64), np.zeros((n, NSF))
    chunks, names, offset = [], [], 0
    modes = np.zeros(n, dtype=np.int64)
    for m in maps:
        key = f"shadow_maps[light={m.light}]"
        if not 0 <= m.light < n:
            raise InputError(file, key, f"no light {m.light} (the scene has {n})")
        light = scene.lights[m.light]
        sh = light.shadows
        if sh is not None and sh.filter == "exact":
            raise InputError(file, key, "the scene light's shadows.filter is exact (shadow rays): a port's map "
                                        "needs hard or pcf")
        modes[m.light] = SHADOW_PCF if sh is not None and sh.filter == "pcf" else SHADOW_HARD
        floats[m.light, S_STRENGTH] = sh.strength if sh is not None else 1.0
        lf = packed.floats[m.light].astype(np.float64)
        pos, fwd = lf[F_PX:F_PX + 3], lf[F_DX:F_DX + 3]
        right, up = lf[F_RX:F_RX + 3], lf[F_UX:F_UX + 3]
        res = m.tiles[0].texels.shape[0]
        kind = int(packed.ints[m.light, I_KIND])
        expected = {1: 1, 0: 6}.get(kind, len(m.splits) - 1)
        if len(m.tiles) != expected or (kind == 2 and not 1 <= expected <= MAX_CASCADES):
            raise InputError(file, key, f"a {light.type} light needs {expected if kind != 2 else '1..8'} tile(s) "
                                        f"({'len(splits) - 1' if kind == 2 else 'one per face' if kind == 0 else 'one'}),"
                                        f" got {len(m.tiles)}")
        x, y = texel_grid(res)
        ordered = m.tiles
        if kind == 0:
            faces = [t.face for t in m.tiles]
            if sorted(faces) != sorted(CUBE_ORDER):
                raise InputError(file, key + ".tiles", f"cube faces must be {', '.join(CUBE_ORDER)} once each, got {faces}")
            ordered = tuple(m.tiles[faces.index(f)] for f in CUBE_ORDER)
        for k, tile in enumerate(ordered):
            world = _tile_points(tile, m.encoding, m.convention)
            if kind == 1:
                t = lf[F_TAN_HALF]
                probe = pos + fwd + (x * t)[:, None] * right + (y * t)[:, None] * up
                value = np.linalg.norm(world - pos, axis=1)
                name = f"shadow_spot_{m.light}"
            elif kind == 0:
                r_f, u_f, f_f = (np.asarray(a, dtype=np.float64) for a in CUBE_FACES[k][1:])
                probe = pos + f_f + x[:, None] * r_f + y[:, None] * u_f
                value = np.linalg.norm(world - pos, axis=1)
                name = f"shadow_point_{m.light}_face_{CUBE_ORDER[k]}"
            else:
                centre, radius = cascade_sphere(camera, m.splits[k], m.splits[k + 1])
                eye = np.linalg.inv(tile.view)[:3, 3]
                back = float((centre - eye) @ fwd)
                floats[m.light, S_CASC + 5 * k:S_CASC + 5 * k + 5] = (*centre, radius, back)
                probe = centre + (x * radius)[:, None] * right + (y * radius)[:, None] * up
                value = (world - centre) @ fwd + back
                name = f"shadow_dir_{m.light}_cascade_{k}"
            value = value[_lookup(tile, probe)]
            chunks.append(np.where(np.isnan(value), np.inf, value).astype(np.float32))
            names.append((name, m.light, offset, res * res))
            if k == 0:
                ints[m.light, S_RES], ints[m.light, S_OFFSET] = res, offset
            offset += res * res
        if kind == 2:
            ints[m.light, S_CASCADES] = len(m.tiles)
    data = np.concatenate(chunks) if chunks else np.zeros(0, dtype=np.float32)
    out = {}
    for filt, mode in ((None, None), ("hard", SHADOW_HARD), ("pcf", SHADOW_PCF)):
        i = ints.copy()
        i[:, S_MODE] = np.where(modes > 0, modes if mode is None else mode, 0)
        out[filt] = ShadowMaps(i, floats.copy(), data, np.zeros((0, 4), dtype=np.float32), list(names))
    return out


# --------------------------------------------------------------------------- the manifest

def _matrix(value, file: str, key: str) -> np.ndarray:
    try:
        m = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        m = None
    if m is None or m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise InputError(file, key, "must be a 4x4 matrix of finite numbers (4 rows of 4)")
    if abs(np.linalg.det(m)) < 1e-300:
        raise InputError(file, key, "singular matrix")
    return m


def _choice(table: dict, key: str, choices, default, file: str, where: str):
    value = table.get(key, default)
    if value not in choices:
        raise InputError(file, f"{where}.{key}", f"must be one of {', '.join(map(str, choices))}, got {value!r}")
    return value


def _read_single(path: Path, file: str, key: str) -> np.ndarray:
    from ..io import read_image

    if not path.is_file():
        raise InputError(file, key, f"file {path} not found")
    return read_image(path, channels=1)[:, :, 0].astype(np.float64)


def _tiles(table: dict, base: Path, file: str, where: str) -> tuple[PortTile, ...]:
    uv = _choice(table, "uv_origin", ("top", "bottom"), "top", file, where)
    specs = table.get("tiles")
    if not isinstance(specs, list) or not specs:
        raise InputError(file, f"{where}.tiles", "needs one [[...tiles]] table per map / face / cascade")
    atlas = table.get("atlas", [len(specs), 1])
    if not (isinstance(atlas, list) and len(atlas) == 2 and all(isinstance(a, int) and a >= 1 for a in atlas)
            and atlas[0] * atlas[1] >= len(specs)):
        raise InputError(file, f"{where}.atlas", f"must be [columns, rows] with room for {len(specs)} tiles, got {atlas}")
    if "path" not in table:
        raise InputError(file, f"{where}.path", "missing required key")
    image = _read_single(base / str(table["path"]), file, f"{where}.path")
    h, w = image.shape
    if h % atlas[1] or w % atlas[0] or h // atlas[1] != w // atlas[0]:
        raise InputError(file, f"{where}.atlas", f"a {w}x{h} image does not split into {atlas[0]}x{atlas[1]} square tiles")
    res = h // atlas[1]
    out = []
    for k, spec in enumerate(specs):
        r, c = divmod(k, atlas[0])
        texels = image[r * res:(r + 1) * res, c * res:(c + 1) * res]
        out.append(PortTile(texels[::-1] if uv == "bottom" else texels,
                            _matrix(spec.get("view"), file, f"{where}.tiles[{k}].view"),
                            _matrix(spec.get("projection"), file, f"{where}.tiles[{k}].projection"),
                            str(spec.get("face", ""))))
    return tuple(out)


def _bundled_name(text: str) -> bool:
    """A bare bundled-scene name (no suffix, no folder), as :func:`vlref.scene.load_scene` reads it."""
    return not Path(text).suffix and "/" not in text and "\\" not in text


def load_port(path, overrides: Sequence[str] = ()) -> PortBuffers:
    """Read a port manifest (module docstring) and decode its buffers.

    The scene is loaded with the manifest's ``set`` list, then the depth buffer's size, then ``overrides``.
    """
    from ..scene import load_scene
    from ..tomlfile import read_toml

    path = Path(path)
    file = str(path)
    data = read_toml(path, "port manifest")
    base = path.parent
    if "scene" not in data:
        raise InputError(file, "scene", "missing required key")
    depth_table = data.get("depth")
    if not isinstance(depth_table, dict) or "path" not in depth_table:
        raise InputError(file, "depth.path", "missing required key")
    raw_depth = _read_single(base / str(depth_table["path"]), file, "depth.path")
    h, w = raw_depth.shape
    sets = data.get("set", [])
    if not (isinstance(sets, list) and all(isinstance(o, str) for o in sets)):
        raise InputError(file, "set", "must be a list of KEY.PATH=VALUE strings")
    ref = str(data["scene"])
    scene = load_scene(ref if _bundled_name(ref) else base / ref,
                       [*sets, f"render.width={w}", f"render.height={h}", *overrides])

    cam_table = data.get("camera")
    if cam_table is None:
        camera = camera_from_settings(scene.camera, w, h)
    else:
        camera = camera_from_matrices(_matrix(cam_table.get("view"), file, "camera.view"),
                                      _matrix(cam_table.get("projection"), file, "camera.projection"), w, h,
                                      _choice(cam_table, "convention", DEPTH_CONVENTIONS, "d3d", file, "camera"),
                                      _choice(cam_table, "forward", ("+z", "-z"), "+z", file, "camera"), file)
    encoding = _choice(depth_table, "encoding", ("linear", "raw"), "linear", file, "depth")
    convention = _choice(depth_table, "convention", DEPTH_CONVENTIONS, "d3d", file, "depth")
    near, far = float(depth_table.get("near", camera.near)), float(depth_table.get("far", camera.far))
    if encoding == "raw" and not 0 < near < far:
        raise InputError(file, "depth.far", f"needs 0 < near < far, got near {near}, far {far}")
    depth = decode_depth(raw_depth, encoding, convention, near, far,
                         _choice(depth_table, "uv_origin", ("top", "bottom"), "top", file, "depth"))
    if np.any(depth <= 0):
        raise InputError(file, "depth", "decoded eye depths must be > 0 (wrong encoding or convention?)")

    if "colour" in data:
        from ..io import read_image

        colour = read_image(base / str(data["colour"]), channels=3, allow_inf=False).astype(np.float64)
        if colour.shape[:2] != (h, w):
            raise InputError(file, "colour", f"is {colour.shape[1]}x{colour.shape[0]}, the depth {w}x{h}")
    else:
        colour = np.zeros((h, w, 3))

    maps = []
    for k, t in enumerate(data.get("shadow_maps", [])):
        where = f"shadow_maps[{k}]"
        light = t.get("light")
        if not isinstance(light, int) or isinstance(light, bool):
            raise InputError(file, f"{where}.light", "must be the index of a scene light")
        enc = _choice(t, "encoding", ("depth", "distance"), "depth", file, where)
        conv = _choice(t, "convention", SHADOW_CONVENTIONS, "d3d", file, where)
        splits = tuple(float(s) for s in t.get("splits", ()))
        if splits and not all(b > a for a, b in zip(splits, splits[1:])):
            raise InputError(file, f"{where}.splits", f"must increase, got {list(splits)}")
        maps.append(PortShadowMap(light, _tiles(t, base, file, where), enc, conv, splits))
    if len({m.light for m in maps}) != len(maps):
        raise InputError(file, "shadow_maps", "one entry per light")
    return PortBuffers(scene, camera, depth, colour, tuple(maps))


# --------------------------------------------------------------------------- exporting, as a port would

def orthographic(half_width: float, half_height: float, near: float, far: float, convention: str = "d3d") -> np.ndarray:
    """4x4 view -> clip of an orthographic box ``|x| <= half_width``, ``|y| <= half_height``,
    ``near <= z <= far`` (z forward), with NDC depth per ``convention`` (``NEAR_VALUE`` at near,
    ``FAR_VALUE`` at far, linear in z)."""
    p = np.eye(4)
    p[0, 0], p[1, 1] = 1.0 / half_width, 1.0 / half_height
    z0, z1 = NEAR_VALUE[convention], FAR_VALUE[convention]
    p[2, 2] = (z1 - z0) / (far - near)
    p[2, 3] = z0 - near * p[2, 2]
    return p


def _encode(stored: np.ndarray, z: np.ndarray, encoding: str, convention: str, near: float, far: float,
            ortho: bool) -> np.ndarray:
    """vlref's stored distance / view depth ``z`` of each texel -> the port's texel value."""
    from ..camera import linear_to_raw

    if encoding == "distance":
        return stored
    if convention == "linear":
        return z
    empty = ~np.isfinite(z)
    zz = np.where(empty, far, z)
    if ortho:
        raw = orthographic(1.0, 1.0, near, far, convention)
        value = raw[2, 2] * zz + raw[2, 3]
    else:
        value = linear_to_raw(zz, near, far, convention)
    return np.where(empty, FAR_VALUE[convention], value)


def _light_tiles(scene, camera: Camera, maps, light: int, packed, encoding: str, convention: str):
    """vlref's maps of ``light`` as a port would export them: ``(tiles [(texels, view, projection, face)],
    splits)``, texels row 0 = top."""
    from ..lights.pack import F_DX, F_PX, F_RX, F_UX, I_KIND
    from ..lights.shadowmaps import CUBE_FACES, S_CASC, cascade_splits

    sh = scene.lights[light].shadows
    lf = packed.floats[light].astype(np.float64)
    pos, fwd, right, up = lf[F_PX:F_PX + 3], lf[F_DX:F_DX + 3], lf[F_RX:F_RX + 3], lf[F_UX:F_UX + 3]
    kind = int(packed.ints[light, I_KIND])
    bufs = [(name, maps.data[start:start + count]) for name, li, start, count in maps.names if li == light]
    res = int(round(math.sqrt(bufs[0][1].size)))
    x, y = texel_grid(res)
    tiles, splits = [], ()
    for k, (name, stored) in enumerate(bufs):
        stored = stored.astype(np.float64)
        if kind == 2:
            c = maps.floats[light, S_CASC + 5 * k:S_CASC + 5 * k + 5]
            centre, radius, back = c[:3], c[3], c[4]
            rot = np.stack([right, up, fwd], axis=1)
            view = Camera(centre - back * fwd, rot, 90.0, res, res, 1.0, 2.0).view_matrix()
            near, far = 0.0, back + radius
            proj = orthographic(radius, radius, near, far, "d3d" if convention == "linear" else convention)
            z, face, ortho = stored, "", True
        else:
            if kind == 1:
                rot, fov, face = np.stack([right, up, fwd], axis=1), scene.lights[light].spot_angle, ""
                scale = math.tan(math.radians(fov) / 2.0)
            else:
                face, r_f, u_f, f_f = CUBE_FACES[k]
                rot, fov, scale = np.array([r_f, u_f, f_f], dtype=np.float64).T, 90.0, 1.0
            near, far = sh.near, scene.lights[light].range
            cam = Camera(pos, rot, fov, res, res, near, far)
            view, proj = cam.view_matrix(), cam.projection_matrix("d3d" if convention == "linear" else convention)
            z = stored / np.sqrt(1.0 + (x * scale) ** 2 + (y * scale) ** 2)
            ortho = False
        texels = _encode(stored, z, encoding, convention, near, far, ortho).reshape(res, res)
        tiles.append((texels, view, proj, face))
    if kind == 2:
        far = min(sh.distance, camera.far)
        splits = tuple(cascade_splits(camera.near, max(far, camera.near * (1 + 1e-6)), len(bufs), sh.split_lambda))
    return tiles, splits


def _toml_value(v) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(a) for a in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    return '"' + str(v).replace("\\", "\\\\").replace('"', '\\"') + '"'


def export_port(scene_ref, out_dir, overrides: Sequence[str] = (), *, depth_encoding: str = "raw", depth_convention: str = "reversed",
                uv_origin: str = "top", shadow_encoding: str = "depth", shadow_convention: str = "reversed",
                camera_forward: str = "+z", camera_matrices: bool = True) -> Path:
    """Export vlref's own depth buffer, scene colour and shadow maps of a scene (a file or bundled name, with
    ``--set`` ``overrides``) in the given encodings, as a port would, and write ``port.toml`` referring to
    the scene (absolute path or bundled name, with ``set = overrides``); returns the manifest's path.

    Maps go one file per light (cube faces in a 3x2 atlas, cascades in an Nx1 atlas).
    """
    from ..camera import linear_to_raw
    from ..io import output_dir, write_exr, write_text
    from ..lights.shadowmaps import SHADOW_EXACT, SHADOW_NONE, S_MODE
    from ..render import prepare_frame
    from ..scene import load_scene

    scene = load_scene(scene_ref, overrides)
    frame = prepare_frame(scene)
    cam = frame.camera
    maps = frame.shadow_maps()
    flip = (lambda a: a[::-1]) if uv_origin == "bottom" else (lambda a: a)
    depth = frame.gbuffer.depth
    if depth_encoding == "raw":
        sky = ~np.isfinite(depth)
        depth = np.where(sky, FAR_VALUE[depth_convention],
                         linear_to_raw(np.where(sky, cam.far, depth), cam.near, cam.far, depth_convention))
    ref = str(scene_ref) if _bundled_name(str(scene_ref)) else str(Path(scene_ref).resolve())
    lines = [f"scene = {_toml_value(ref)}", f"set = {_toml_value(list(overrides))}", 'colour = "colour.exr"', ""]
    if camera_matrices:
        f = _flip_z(camera_forward)
        lines += ["[camera]", f'forward = "{camera_forward}"', f'convention = "{depth_convention}"',
                  f"view = {_toml_value(f @ cam.view_matrix())}",
                  f"projection = {_toml_value(cam.projection_matrix(depth_convention) @ f)}", ""]
    lines += ["[depth]", 'path = "depth.exr"', f'encoding = "{depth_encoding}"', f'convention = "{depth_convention}"',
              f"near = {cam.near!r}", f"far = {cam.far!r}", f'uv_origin = "{uv_origin}"', ""]
    with output_dir(out_dir) as tmp:
        write_exr(tmp / "depth.exr", flip(depth))
        write_exr(tmp / "colour.exr", frame.scene_colour)
        for light in range(frame.lights.count):
            if maps.ints[light, S_MODE] in (SHADOW_NONE, SHADOW_EXACT):
                continue
            tiles, splits = _light_tiles(scene, cam, maps, light, frame.lights, shadow_encoding, shadow_convention)
            cols = 3 if len(tiles) == 6 else len(tiles)
            rows = len(tiles) // cols
            res = tiles[0][0].shape[0]
            atlas = np.zeros((rows * res, cols * res))
            for k, (texels, _, _, _) in enumerate(tiles):
                r, c = divmod(k, cols)
                atlas[r * res:(r + 1) * res, c * res:(c + 1) * res] = flip(texels)
            write_exr(tmp / f"shadow_{light}.exr", atlas)
            lines += ["[[shadow_maps]]", f"light = {light}", f'path = "shadow_{light}.exr"', f"atlas = [{cols}, {rows}]",
                      f'encoding = "{shadow_encoding}"', f'convention = "{shadow_convention}"', f'uv_origin = "{uv_origin}"']
            if splits:
                lines.append(f"splits = {_toml_value(splits)}")
            lines.append("")
            for texels, view, proj, face in tiles:
                lines += ["[[shadow_maps.tiles]]"] + ([f'face = "{face}"'] if face else [])
                lines += [f"view = {_toml_value(view)}", f"projection = {_toml_value(proj)}", ""]
        write_text(tmp / "port.toml", "\n".join(lines))
    return Path(out_dir) / "port.toml"


# --------------------------------------------------------------------------- the frame and the march

def port_frame(port: PortBuffers, file: str = "<port>"):
    """A :class:`vlref.render.Frame` whose G-buffer depth, scene colour and shadow maps are the port's."""
    from ..geometry import build_geometry
    from ..geometry.raycast import GBuffer
    from ..lights import pack_lights
    from ..render import Frame

    cam = port.camera
    dirs = cam.ray_directions()
    distance = cam.eye_depth_to_distance(port.depth, dirs)
    hit = np.isfinite(port.depth)
    position = np.where(hit[..., None], cam.position + dirs * np.where(hit, distance, 0.0)[..., None], 0.0)
    zeros = np.zeros(port.depth.shape + (3,))
    gbuffer = GBuffer(port.depth, distance, position, zeros, zeros, zeros, np.where(hit, 0, -1).astype(np.int32))
    packed = pack_lights(port.scene)
    maps = shadow_maps_from_port(port.scene, cam, packed, port.shadow_maps, file)
    return Frame(port.scene, cam, build_geometry(port.scene), gbuffer, packed, port.colour, shadow_cache=maps)


def march_port(path, overrides: Sequence[str] = ()) -> dict[str, np.ndarray]:
    """Load a port manifest and run its scene's technique on the port's buffers: the technique's buffers."""
    port = load_port(path, overrides)
    frame = port_frame(port, str(path))
    technique = importlib.import_module(f"vlref.techniques.{port.scene.render.technique}")
    out = technique.render(port.scene, frame)
    out["depth"] = port.depth
    return out


def export_parser() -> argparse.ArgumentParser:
    """The options of ``vlref march export``."""
    p = argparse.ArgumentParser(prog="vlref march export", description="Export vlref's depth buffer, scene colour "
                                "and shadow maps in a port's encodings, with port.toml (docs/PORTING.md).")
    p.add_argument("scene", help="scene file or bundled scene name")
    p.add_argument("-o", "--output", required=True, help="output folder (required, no default)")
    p.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a scene field (repeatable; default: none)")
    p.add_argument("--depth", default="raw:reversed", choices=["linear", "raw:d3d", "raw:gl", "raw:reversed"],
                   help="camera depth encoding (default raw:reversed)")
    p.add_argument("--shadow", default="depth:reversed",
                   choices=["distance", "depth:linear", "depth:d3d", "depth:gl", "depth:reversed"],
                   help="shadow map encoding (default depth:reversed)")
    p.add_argument("--uv-origin", default="top", choices=["top", "bottom"],
                   help="row 0 of the exported images: top or bottom (default top)")
    p.add_argument("--camera-forward", default="+z", choices=["+z", "-z"],
                   help="view-space axis the camera looks along (default +z)")
    return p


def march_parser() -> argparse.ArgumentParser:
    """The options of ``vlref march``."""
    p = argparse.ArgumentParser(prog="vlref march", description="Run a scene's technique on a port's exported "
                                "depth buffer and shadow maps (docs/PORTING.md).")
    p.add_argument("manifest", help="port manifest (TOML)")
    p.add_argument("-o", "--output", default="out_march", help="output folder (default out_march)")
    p.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                   help="override a scene field (repeatable; default: none)")
    p.add_argument("--stages", action="store_true", help="also write every pass's buffer (default: off)")
    p.add_argument("-q", "--quiet", action="store_true", help="no summary line (default: off)")
    return p


def _main_export(argv: Sequence[str]) -> int:
    """``vlref march export SCENE -o DIR``: vlref's own buffers in a port's encodings (:func:`export_port`)."""
    from ..io import check_output_dir

    p = export_parser()
    try:
        args = p.parse_args(list(argv))
    except SystemExit as exc:
        return int(exc.code or 0)
    depth_enc, _, depth_conv = args.depth.partition(":")
    shadow_enc, _, shadow_conv = args.shadow.partition(":")
    try:
        check_output_dir(args.output)
        path = export_port(args.scene, args.output, args.set, depth_encoding=depth_enc,
                           depth_convention=depth_conv or "d3d", uv_origin=args.uv_origin,
                           shadow_encoding=shadow_enc, shadow_convention=shadow_conv or "d3d",
                           camera_forward=args.camera_forward)
    except InputError as exc:
        print(f"vlref march export: error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {path}", file=sys.stderr)
    return 0


def main_march(argv: Sequence[str]) -> int:
    """``vlref march PORT.toml -o OUT [--stages] [--set K=V]`` (0 written, 2 bad input), or
    ``vlref march export SCENE -o DIR`` (:func:`_main_export`)."""
    if argv and argv[0] == "export":
        return _main_export(argv[1:])
    from ..io import check_output_dir, output_dir, write_exr
    from ..render import scene_hash

    p = march_parser()
    try:
        args = p.parse_args(list(argv))
    except SystemExit as exc:
        return int(exc.code or 0)
    start = time.perf_counter()
    try:
        check_output_dir(args.output)
        port = load_port(args.manifest, args.set or ())
        frame = port_frame(port, args.manifest)
        technique = importlib.import_module(f"vlref.techniques.{port.scene.render.technique}")
        out = technique.render(port.scene, frame)
        names = [k for k in out if args.stages or k in ("final", "inscatter", "transmittance")]
        meta = {"scene_hash": scene_hash(port.scene), "technique": port.scene.render.technique,
                "port_manifest": str(Path(args.manifest).resolve())}
        with output_dir(args.output) as tmp:
            for name in names:
                a = np.asarray(out[name])
                if a.ndim in (2, 3) and a.dtype.kind == "f":
                    write_exr(tmp / f"{name}.exr", a if a.ndim == 2 or a.shape[2] <= 4 else a[..., :3], metadata=meta)
            write_exr(tmp / "depth.exr", port.depth, metadata=meta)
    except InputError as exc:
        print(f"vlref march: error: {exc}", file=sys.stderr)
        return 2
    if not args.quiet:
        print(f"wrote {args.output} ({port.scene.render.technique}, {time.perf_counter() - start:.2f} s)",
              file=sys.stderr)
    return 0
