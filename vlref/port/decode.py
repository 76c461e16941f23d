"""Decoding a port's buffers: device depth to linear eye depth, engine matrices to a :class:`Camera`,
shadow-map texels to the world points they saw (the rules are in :mod:`vlref.port`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import DEPTH_CONVENTIONS, Camera, raw_to_linear
from ..errors import InputError
from ..lights.shadow_cast import texel_grid

__all__ = ["NEAR_VALUE", "FAR_VALUE", "CUBE_ORDER", "SHADOW_CONVENTIONS", "PortTile", "PortShadowMap",
           "decode_depth", "flip_z", "camera_from_matrices", "tile_rays", "tile_points", "nearest_texel"]

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


def flip_z(forward: str) -> np.ndarray:
    """``diag(1, 1, ±1, 1)``: the view-space flip from a ``forward`` "-z" (GL-style) view to vlref's "+z"."""
    return np.diag([1.0, 1.0, 1.0 if forward == "+z" else -1.0, 1.0])


def camera_from_matrices(view, projection, width: int, height: int, convention: str = "d3d",
                         forward: str = "+z", file: str | None = None) -> Camera:
    """The :class:`Camera` of an engine's view and perspective projection matrices.

    ``forward="-z"`` (GL-style view space, Unity's ``worldToCameraMatrix``): the view's z row and the
    projection's z column are negated to reach vlref's view space (x right, y up, z forward). The
    rotation must be orthonormal and proper; fov = ``2 atan(1 / P11)``, the aspect ``P11 / P00`` must
    equal ``width / height``; near/far solve ``ndc_z(z) = NEAR_VALUE / FAR_VALUE`` of ``convention``.
    Bad matrices raise :class:`InputError` naming ``file`` (the manifest they came from), or
    :class:`ValueError` when ``file`` is None (a Python caller's arguments).
    """
    flip = flip_z(forward)
    v = flip @ np.asarray(view, dtype=np.float64)
    p = np.asarray(projection, dtype=np.float64) @ flip
    rot = v[:3, :3].T
    if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-6) or np.linalg.det(rot) < 0:
        raise _bad(file, "camera.view", "the rotation part is not a proper orthonormal matrix "
                                         "(scaled view, or the wrong `forward`)")
    if not (p[3, 2] > 0 and p[1, 1] > 0 and p[0, 0] > 0):
        raise _bad(file, "camera.projection", "not a perspective projection looking along `forward`")
    aspect = p[1, 1] / p[0, 0]
    if abs(aspect - width / height) > 1e-6 * aspect:
        raise _bad(file, "camera.projection", f"aspect {aspect:.6g} differs from the depth buffer's "
                                               f"{width}x{height}")
    a, b = p[2, 2] / p[3, 2], p[2, 3] / p[3, 2]  # ndc_z(z) = a + b / z
    near, far = b / (NEAR_VALUE[convention] - a), b / (FAR_VALUE[convention] - a)
    if not (0 < near < far and math.isfinite(far)):
        raise _bad(file, "camera.convention", f"near {near:.6g} / far {far:.6g} implausible for {convention}")
    return Camera(-rot @ v[:3, 3], rot, math.degrees(2.0 * math.atan(1.0 / p[1, 1])), width, height, near, far)


def tile_rays(tile: PortTile, res: int):
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


def tile_points(tile: PortTile, encoding: str, convention: str) -> np.ndarray:
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
        origin, d = tile_rays(tile, res)
        v = np.where(empty, 1.0, val)
        if encoding == "depth":  # linear view depth: the ray point with |z| = value
            s = (np.sign(d[:, 2]) * v - origin[:, 2]) / d[:, 2]
        else:
            s = v
        view_pts = origin + s[:, None] * d
        world = view_pts @ inv_v[:3, :3].T + inv_v[:3, 3]
    world[empty] = np.nan
    return world


def nearest_texel(tile: PortTile, points: np.ndarray) -> np.ndarray:
    """Index of the port texel (nearest, clamped) that each world point projects into."""
    res = tile.texels.shape[0]
    clip = np.concatenate([points, np.ones((len(points), 1))], axis=1) @ (tile.projection @ tile.view).T
    u = (clip[:, 0] / clip[:, 3] + 1.0) * 0.5
    v = (1.0 - clip[:, 1] / clip[:, 3]) * 0.5
    col = np.clip(np.floor(u * res), 0, res - 1).astype(np.int64)
    row = np.clip(np.floor(v * res), 0, res - 1).astype(np.int64)
    return row * res + col


def _bad(file: str | None, key: str, reason: str) -> ValueError:
    """:class:`InputError` for a value read from ``file``; a plain :class:`ValueError` for a Python caller's."""
    return InputError(file, key, reason) if file is not None else ValueError(f"{key}: {reason}")
