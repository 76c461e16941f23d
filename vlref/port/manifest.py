"""Reading a port manifest (``port.toml``, the keys in :mod:`vlref.port`): every key checked, every
buffer decoded (:mod:`vlref.port.decode`); errors are :class:`InputError` naming the manifest and the key.

The manifest's tables are the dataclasses below, checked by the schema engine the scene files use
(:func:`vlref.scene.schema.build`: types, choices, bounds, files that must exist, unknown keys with a
suggestion, each class's ``check``); what depends on the images (sizes, atlas split, decoded depths) is
checked here after reading them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from ..camera import DEPTH_CONVENTIONS, Camera, camera_from_settings
from ..errors import InputError
from ..io.images import read_image
from ..scene import load_scene
from ..scene.animation import scene_at
from ..scene.fields import F
from ..scene.schema import build
from ..tomlfile import read_toml
from .decode import SHADOW_CONVENTIONS, PortShadowMap, PortTile, camera_from_matrices, decode_depth

__all__ = ["PortManifest", "PortBuffers", "PortPass", "load_port", "bundled_name"]

Matrix4 = tuple[tuple[float, float, float, float], ...]
UV_ORIGINS = ("top", "bottom")


def _matrix_problem(key: str, rows: tuple) -> tuple[str, str] | None:
    """``(key, reason)`` unless ``rows`` is 4 rows of a non-singular 4x4 matrix."""
    if len(rows) != 4:
        return key, f"must be a 4x4 matrix (4 rows of 4), got {len(rows)} rows"
    if abs(np.linalg.det(np.asarray(rows, dtype=np.float64))) < 1e-300:
        return key, "singular matrix"
    return None


@dataclass(frozen=True)
class CameraTable:
    """``[camera]``: the port's camera matrices (default: the scene's camera)."""

    view: Matrix4 = F(doc="world -> view, 4 rows (column vectors: p_view = V p_world)")
    projection: Matrix4 = F(doc="view -> clip, 4 rows")
    forward: str = F("+z", "view-space axis the camera looks along (+z: vlref / D3D; -z: GL, Unity)",
                     choices=("+z", "-z"))
    convention: str = F("d3d", "depth convention of `projection` (gives near and far)", choices=DEPTH_CONVENTIONS)

    def check(self):
        return _matrix_problem("view", self.view) or _matrix_problem("projection", self.projection)


@dataclass(frozen=True)
class DepthTable:
    """``[depth]``: the port's camera depth buffer."""

    path: str = F(doc="one-channel image (EXR, NPY, NPZ), relative to the manifest", file=True)
    encoding: str = F("linear", "linear (eye depth, metres) or raw (device depth)", choices=("linear", "raw"))
    convention: str = F("d3d", "raw: d3d, gl or reversed", choices=DEPTH_CONVENTIONS)
    near: Optional[float] = F(None, "raw: near clip plane (default: the camera's)")
    far: Optional[float] = F(None, "raw: far clip plane (default: the camera's)")
    uv_origin: str = F("top", "row 0 of the file is the top or the bottom of the image", choices=UV_ORIGINS)


@dataclass(frozen=True)
class TileTable:
    """``[[shadow_maps.tiles]]``: one spot map, cube face or cascade, in atlas order."""

    view: Matrix4 = F(doc="the light's world -> view for this tile")
    projection: Matrix4 = F(doc="perspective (spot, cube faces) or orthographic (cascades)")
    face: str = F("", "point lights: the cube face", choices=("",) + ("px", "nx", "py", "ny", "pz", "nz"))

    def check(self):
        return _matrix_problem("view", self.view) or _matrix_problem("projection", self.projection)


@dataclass(frozen=True)
class ShadowMapTable:
    """``[[shadow_maps]]``: one shadowed light's maps in one image."""

    light: int = F(doc="index of the scene light")
    path: str = F(doc="one image holding every tile, relative to the manifest", file=True)
    tiles: tuple[TileTable, ...] = F(doc="one table per map / face / cascade")
    atlas: tuple[int, ...] = F((), "[columns, rows] of square tiles, filled row-major (default: one row)")
    encoding: str = F("depth", "depth (per `convention`) or distance", choices=("depth", "distance"))
    convention: str = F("d3d", "depth: d3d, gl, reversed (device depth) or linear (view depth)",
                        choices=SHADOW_CONVENTIONS)
    uv_origin: str = F("top", "row order inside each tile", choices=UV_ORIGINS)
    splits: tuple[float, ...] = F((), "directional lights: cascade split depths (cascades + 1 values)")

    def check(self):
        if not self.tiles:
            return "tiles", "needs one [[...tiles]] table per map / face / cascade"
        columns, rows = self.columns_rows
        if len(self.atlas) not in (0, 2) or min(columns, rows) < 1 or columns * rows < len(self.tiles):
            return "atlas", f"must be [columns, rows] with room for {len(self.tiles)} tiles, got {list(self.atlas)}"
        if not all(b > a for a, b in zip(self.splits, self.splits[1:])):
            return "splits", f"must increase, got {list(self.splits)}"
        return None

    @property
    def columns_rows(self) -> tuple[int, int]:
        return (self.atlas[0], self.atlas[1]) if len(self.atlas) == 2 else (len(self.tiles), 1)


@dataclass(frozen=True)
class PassTable:
    """``[[passes]]``: one pass output of the port, judged against ``vlref march --stages`` on its own buffers."""

    name: str = F(doc="the port's name for the pass (reports, JUnit)")
    buffer: str = F(doc="the vlref --stages buffer it reproduces (march_half, upsample, final, ...)")
    path: str = F(doc="(h, w) or (h, w, C) image, row 0 on top, relative to the manifest", file=True)
    preset: Optional[str] = F(None, "tolerance preset (default: the manifest's `preset`, else the verdict's)")
    ignore_sky: bool = F(False, "compare only where the vlref buffer is finite (e.g. a min-depth buffer)")


@dataclass(frozen=True)
class PortManifest:
    """A port manifest (``port.toml``)."""

    scene: str = F(doc="vlref scene file (relative to the manifest) or bundled scene name")
    depth: DepthTable = F(doc="the camera depth buffer")
    set: tuple[str, ...] = F((), "--set overrides of the scene (KEY.PATH=VALUE); the render size is the depth's")
    colour: Optional[str] = F(None, "(H, W, 3) lit scene colour, relative to the manifest (default: black)",
                              file=True)
    camera: Optional[CameraTable] = F(None, "the port's camera matrices (default: the scene's camera)")
    shadow_maps: tuple[ShadowMapTable, ...] = F((), "one per shadowed light")
    shadows: bool = F(True, "false: the port renders no shadows (shadowed scene lights are judged unshadowed); "
                            "true: every light with hard/pcf shadows needs a [[shadow_maps]] entry")
    final: Optional[str] = F(None, "(H, W, 3) the port's final frame, relative to the manifest", file=True)
    preset: Optional[str] = F(None, "default tolerance preset of the [[passes]] comparisons")
    passes: tuple[PassTable, ...] = F((), "the port's pass outputs (vlref verdict)")

    def check(self):
        lights = [m.light for m in self.shadow_maps]
        if len(set(lights)) != len(lights):
            return "shadow_maps", "one entry per light"
        if not self.shadows and self.shadow_maps:
            return "shadows", "is false (no shadows) but [[shadow_maps]] are exported"
        names = [p.name for p in self.passes]
        if len(set(names)) != len(names):
            return "passes", f"pass names must be unique, got {names}"
        return None


@dataclass(frozen=True)
class PortPass:
    """A port's pass output (``[[passes]]``): its name, the vlref buffer it reproduces, the image (float64,
    (h, w, C)), the preset it asks for (None: the default) and whether sky texels are left out."""

    name: str
    buffer: str
    image: np.ndarray
    preset: str | None
    ignore_sky: bool
    path: str


@dataclass
class PortBuffers:
    """A decoded port manifest: scene, camera, linear eye depth (inf = sky), scene colour, shadow maps, and
    ``source``, the manifest's path (error messages name it); for the verdict (:mod:`vlref.oracle.verdict`)
    the port's ``final`` frame (or None), its ``passes``, the default ``preset`` and whether it has shadows."""

    scene: object
    camera: Camera
    depth: np.ndarray
    colour: np.ndarray
    shadow_maps: tuple[PortShadowMap, ...]
    source: str
    final: np.ndarray | None = None
    passes: tuple[PortPass, ...] = ()
    preset: str | None = None
    has_shadows: bool = True


def _read_single(path) -> np.ndarray:
    """The one-channel image at ``path`` as float64 (H, W)."""
    return read_image(path, channels=1)[:, :, 0].astype(np.float64)


def _tiles(table: ShadowMapTable, file: str, where: str) -> tuple[PortTile, ...]:
    """The tiles of ``table``'s image, each with its matrices; row 0 = top."""
    columns, rows = table.columns_rows
    image = _read_single(table.path)
    h, w = image.shape
    if h % rows or w % columns or h // rows != w // columns:
        raise InputError(file, f"{where}.atlas", f"a {w}x{h} image does not split into {columns}x{rows} square tiles")
    res = h // rows
    out = []
    for k, spec in enumerate(table.tiles):
        r, c = divmod(k, columns)
        texels = image[r * res:(r + 1) * res, c * res:(c + 1) * res]
        out.append(PortTile(texels[::-1] if table.uv_origin == "bottom" else texels,
                            np.asarray(spec.view, dtype=np.float64), np.asarray(spec.projection, dtype=np.float64),
                            spec.face))
    return tuple(out)


def bundled_name(text: str) -> bool:
    """A bare bundled-scene name (no suffix, no folder), as :func:`vlref.scene.load_scene` reads it."""
    return not Path(text).suffix and "/" not in text and "\\" not in text


def load_port(path, overrides: Sequence[str] = ()) -> PortBuffers:
    """Read a port manifest (:class:`PortManifest`) and decode its buffers.

    The scene is loaded with the manifest's ``set`` list, then the depth buffer's size, then ``overrides``,
    and its ``[animation]`` is evaluated at ``render.frame`` (:func:`vlref.scene.animation.scene_at`: the
    lights and medium of that frame; the camera is the manifest's when it has one).
    """
    path = Path(path)
    file = str(path)
    base = path.parent
    m = build(PortManifest, read_toml(path, "port manifest"), file, base)
    raw_depth = _read_single(m.depth.path)
    h, w = raw_depth.shape
    scene = scene_at(load_scene(m.scene if bundled_name(m.scene) else base / m.scene,
                                [*m.set, f"render.width={w}", f"render.height={h}", *overrides]))

    if m.camera is None:
        camera = camera_from_settings(scene.camera, w, h)
    else:
        camera = camera_from_matrices(np.asarray(m.camera.view, dtype=np.float64),
                                      np.asarray(m.camera.projection, dtype=np.float64), w, h,
                                      m.camera.convention, m.camera.forward, file)
    d = m.depth
    near = d.near if d.near is not None else camera.near
    far = d.far if d.far is not None else camera.far
    if d.encoding == "raw" and not 0 < near < far:
        raise InputError(file, "depth.far", f"needs 0 < near < far, got near {near}, far {far}")
    depth = decode_depth(raw_depth, d.encoding, d.convention, near, far, d.uv_origin)
    if np.any(depth <= 0):
        raise InputError(file, "depth", "decoded eye depths must be > 0 (wrong encoding or convention?)")

    if m.colour is not None:
        colour = read_image(m.colour, channels=3, allow_inf=False).astype(np.float64)
        if colour.shape[:2] != (h, w):
            raise InputError(file, "colour", f"is {colour.shape[1]}x{colour.shape[0]}, the depth {w}x{h}")
    else:
        colour = np.zeros((h, w, 3))

    maps = tuple(PortShadowMap(t.light, _tiles(t, file, f"shadow_maps[{k}]"), t.encoding, t.convention, t.splits)
                 for k, t in enumerate(m.shadow_maps))
    if m.shadows:
        _check_maps(scene, {t.light for t in m.shadow_maps}, file)
    final = None
    if m.final is not None:
        final = read_image(m.final, channels=3, allow_inf=False).astype(np.float64)
        if final.shape[:2] != (h, w):
            raise InputError(file, "final", f"is {final.shape[1]}x{final.shape[0]}, the depth {w}x{h}")
    passes = tuple(PortPass(p.name, p.buffer, read_image(p.path).astype(np.float64), p.preset, p.ignore_sky, p.path)
                   for p in m.passes)
    return PortBuffers(scene, camera, depth, colour, maps, file, final, passes, m.preset, m.shadows)


def _check_maps(scene, exported: set, file: str) -> None:
    """:class:`InputError` naming an exported light the scene lacks, or the first light whose scene shadows
    are hard or pcf but has no exported map."""
    n = len(scene.lights)
    for i in sorted(exported):
        if not 0 <= i < n:
            raise InputError(file, f"shadow_maps[light={i}]", f"no light {i} (the scene has {n})")
    for i, light in enumerate(scene.lights):
        sh = light.shadows
        if sh is not None and sh.enabled and sh.filter != "exact" and i not in exported:
            raise InputError(file, "shadow_maps", f"light {i} ({light.type}) has {sh.filter} shadows in the scene but "
                                                  "no exported map: export its map, or set `shadows = false` if the "
                                                  "port renders no shadows")
