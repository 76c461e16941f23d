"""Camera: frames, view/projection matrices, pixel rays, depth encodings.

Conventions (``docs/CONVENTIONS.md``):

* World and view space are Unity's: left-handed, y up. View space has x right, y up and
  z forward, so the view-space z of a point *is* its linear eye depth (metres, > 0 in front).
* Rotations are Unity Euler angles in degrees applied z, then x, then y:
  ``R = Ry(y) @ Rx(x) @ Rz(z)`` acting on column vectors (``Quaternion.Euler``).
* Images: row 0 is the top row. The centre of pixel ``(x, y)`` (column, row) is at
  ``u = (x + 0.5) / W``, ``v = (y + 0.5) / H`` and NDC ``(2u - 1, 1 - 2v)``.
* Projection matrices map view space to clip space with NDC y up; depth encodings:

  ``d3d``       z_raw in [0, 1], 0 at near: ``z_raw = f/(f-n) * (1 - n/z)``
                (equal to OpenGL's *window* depth, what a GL depth texture stores)
  ``gl``        z_ndc in [-1, 1], -1 at near: ``z_ndc = (f+n)/(f-n) - 2fn/((f-n) z)``
  ``reversed``  reversed Z, 1 at near and 0 at far: ``1 - d3d``

  Unity linearises a ``d3d``/``reversed`` raw depth with ``_ZBufferParams``
  (``LinearEyeDepth(z) = 1 / (zp.z * z + zp.w)``); :func:`zbuffer_params` gives them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .row_blocks import in_row_blocks

DEPTH_CONVENTIONS = ("d3d", "gl", "reversed")

__all__ = ["Camera", "cross", "euler_matrix", "look_rotation", "linear_to_raw", "raw_to_linear", "zbuffer_params",
           "unity_linear_eye_depth", "DEPTH_CONVENTIONS", "camera_from_settings", "pixel_rays"]


def _cross(a0, a1, a2, b0, b1, b2) -> tuple:
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


def cross(a, b) -> np.ndarray:
    """``np.cross(a, b)`` of two 3-vectors or two stacks (..., 3) of them, float64, the same bits (NumPy's two
    products and one difference per component) without its axis handling: 1 µs for two 3-vectors where NumPy takes
    ~15 µs (seven calls made ~0.1 ms of an 80x45 frame's set-up)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.ndim == b.ndim == 1:
        return np.array(_cross(*a.tolist(), *b.tolist()))
    return np.stack(_cross(a[..., 0], a[..., 1], a[..., 2], b[..., 0], b[..., 1], b[..., 2]), axis=-1)


def _length(v: np.ndarray) -> float:
    """``np.linalg.norm(v)`` of a 1-D float64 vector, the same bits: NumPy's ``norm`` of a 1-D real array is
    ``sqrt(v.dot(v))``, here without its ~3 µs of argument handling (eight calls per reference frame)."""
    return math.sqrt(v.dot(v))


def euler_matrix(degrees) -> np.ndarray:
    """Unity ``Quaternion.Euler(x, y, z)`` as a 3x3 matrix: ``Ry @ Rx @ Rz``."""
    x, y, z = np.radians(np.asarray(degrees, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(x), np.sin(x), np.cos(y), np.sin(y), np.cos(z), np.sin(z)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return ry @ rx @ rz


def look_rotation(forward, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """Rotation whose columns are (right, up, forward) for a left-handed frame (Unity's ``LookRotation``).

    When ``forward`` is parallel to ``up``, world z (or x) is used as the up hint instead.
    """
    f = np.asarray(forward, dtype=np.float64)
    f = f / _length(f)
    u = np.asarray(up, dtype=np.float64)
    r = cross(u, f)
    if _length(r) < 1e-9 * max(_length(u), 1e-300):
        hint = np.array([0.0, 0.0, 1.0]) if abs(f[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        r = cross(hint, f)
    r = r / _length(r)
    u = cross(f, r)
    return np.stack([r, u, f], axis=1)


@dataclass(frozen=True)
class Camera:
    """A pinhole camera.

    Attributes
    ----------
    position : (3,) world position.
    rotation : (3, 3) columns are the world right, up and forward axes.
    fov : vertical field of view, degrees.
    width, height : image size in pixels (aspect = width / height).
    near, far : clip planes, metres.
    """

    position: np.ndarray
    rotation: np.ndarray
    fov: float
    width: int
    height: int
    near: float
    far: float
    # ray_directions per target size, computed once (the camera is immutable); not pickled, not compared
    _rays: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_rays": {}}

    @property
    def forward(self) -> np.ndarray:
        return self.rotation[:, 2]

    @property
    def aspect(self) -> float:
        return self.width / self.height

    @property
    def tan_half_fov(self) -> float:
        return float(np.tan(np.radians(self.fov) / 2.0))

    def with_size(self, width: int, height: int) -> "Camera":
        """The same camera rendering ``width x height`` pixels (the aspect follows the size)."""
        return Camera(self.position, self.rotation, self.fov, width, height, self.near, self.far)

    def view_matrix(self) -> np.ndarray:
        """4x4 world -> view (x right, y up, z forward = linear eye depth)."""
        m = np.eye(4)
        m[:3, :3] = self.rotation.T
        m[:3, 3] = -self.rotation.T @ self.position
        return m

    def projection_matrix(self, convention: str = "d3d") -> np.ndarray:
        """4x4 view -> clip; ``ndc = clip[:3] / clip[3]`` with NDC y up and depth per ``convention``."""
        n, f = self.near, self.far
        sy = 1.0 / self.tan_half_fov
        sx = sy / self.aspect
        p = np.zeros((4, 4))
        p[0, 0], p[1, 1], p[3, 2] = sx, sy, 1.0
        if convention == "d3d":
            p[2, 2], p[2, 3] = f / (f - n), -n * f / (f - n)
        elif convention == "gl":
            p[2, 2], p[2, 3] = (f + n) / (f - n), -2.0 * n * f / (f - n)
        elif convention == "reversed":
            p[2, 2], p[2, 3] = -n / (f - n), n * f / (f - n)
        else:
            raise ValueError(f"unknown depth convention {convention!r}; use one of {DEPTH_CONVENTIONS}")
        return p

    def view_projection(self, convention: str = "d3d") -> np.ndarray:
        return self.projection_matrix(convention) @ self.view_matrix()

    def pixel_ndc(self, width: int | None = None, height: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """NDC x and y of every pixel centre, each (H, W), row 0 at the top."""
        w = self.width if width is None else width
        h = self.height if height is None else height
        xs = (np.arange(w) + 0.5) / w * 2.0 - 1.0
        ys = 1.0 - (np.arange(h) + 0.5) / h * 2.0
        return np.broadcast_to(xs[None, :], (h, w)), np.broadcast_to(ys[:, None], (h, w))

    def ray_directions(self, width: int | None = None, height: int | None = None, copy: bool = True) -> np.ndarray:
        """Unit world directions through pixel centres, (H, W, 3) float64 (a new array on every call, unless
        ``copy=False``).

        ``width``/``height`` give the rays of a reduced-resolution target covering the same frustum. The
        directions of each size are computed once per camera (:func:`pixel_rays`, in row blocks on Numba's
        thread count) and copied out (a frame re-rendered with other settings, as a notebook's sliders do,
        would otherwise repeat the computation before every march). ``copy=False`` hands
        out the camera's own array, for a caller that only reads it (the physical march: the copy, 4-6 ms at
        1080p on the dev box, ran on one core before every march); writing to it changes every later call's
        rays.
        """
        key = (self.width if width is None else width, self.height if height is None else height)
        rays = self._rays.get(key)
        if rays is None:
            rays = pixel_rays(self, *key)
            self._rays[key] = rays
        return rays.copy() if copy else rays

    def world_to_ndc(self, points: np.ndarray, convention: str = "d3d") -> np.ndarray:
        """World points (..., 3) to NDC (..., 3) (x, y in [-1, 1] on screen, z per convention)."""
        p = np.asarray(points, dtype=np.float64)
        clip = np.concatenate([p, np.ones(p.shape[:-1] + (1,))], axis=-1) @ self.view_projection(convention).T
        return clip[..., :3] / clip[..., 3:4]

    def eye_depth_to_distance(self, depth: np.ndarray, directions: np.ndarray | None = None) -> np.ndarray:
        """Distance along each pixel ray for a linear eye depth: ``t = z / dot(d, forward)``."""
        d = self.ray_directions() if directions is None else directions
        return depth / (d @ self.forward)


def pixel_rays(camera: Camera, width: int, height: int, threads: int | None = None) -> np.ndarray:
    """:meth:`Camera.ray_directions` of a ``width x height`` target, computed anew: (H, W, 3) float64.

    Per pixel ``d = (nx tan·aspect, ny tan, 1) R^T``, ``d / |d|`` (NumPy's ``stack`` and ``matmul``, as written
    here; ``|d| = sqrt((dx² + dy²) + dz²)``, the bits of ``np.linalg.norm(d, axis=-1)``, whose sum runs in this
    order, in a quarter of its time: tests/test_camera.py), on blocks of whole rows written into the result, the blocks spread over
    ``threads`` threads (:func:`vlref.row_blocks.in_row_blocks`; default Numba's thread count). ``matmul`` of a
    (rows, W, 3) stack calls BLAS once per row and the other operations are per pixel, so every block split and
    thread count gives the bits of the whole frame computed at once (tests/test_camera.py); BLAS's kernel may
    still differ between machines.
    """
    nx, ny = camera.pixel_ndc(width, height)
    t, aspect, rotation_t = camera.tan_half_fov, camera.aspect, camera.rotation.T
    rays = np.empty((height, width, 3))

    def block(y0: int, y1: int) -> None:
        x, y = nx[y0:y1], ny[y0:y1]
        d = np.stack([x * t * aspect, y * t, np.ones_like(x)], axis=-1) @ rotation_t
        s = d * d
        np.divide(d, np.sqrt((s[..., 0] + s[..., 1]) + s[..., 2])[..., None], out=rays[y0:y1])

    in_row_blocks(height, width, block, threads)
    return rays


def camera_from_settings(settings, width: int, height: int) -> Camera:
    """Build a :class:`Camera` from the scene's ``[camera]`` table and an image size."""
    pos = np.asarray(settings.position, dtype=np.float64)
    if settings.look_at is not None:
        rot = look_rotation(np.asarray(settings.look_at, dtype=np.float64) - pos, settings.up)
    elif settings.rotation is not None:
        rot = euler_matrix(settings.rotation)
    else:
        rot = np.eye(3)
    return Camera(pos, rot, settings.fov, width, height, settings.near, settings.far)


def linear_to_raw(depth, near: float, far: float, convention: str = "d3d"):
    """Linear eye depth (metres) -> raw device depth in ``convention`` (see the module docstring)."""
    z = np.asarray(depth, dtype=np.float64)
    n, f = near, far
    if convention == "d3d":
        return f / (f - n) * (1.0 - n / z)
    if convention == "gl":
        return (f + n) / (f - n) - 2.0 * f * n / ((f - n) * z)
    if convention == "reversed":
        return 1.0 - f / (f - n) * (1.0 - n / z)
    raise ValueError(f"unknown depth convention {convention!r}; use one of {DEPTH_CONVENTIONS}")


def raw_to_linear(raw, near: float, far: float, convention: str = "d3d"):
    """Raw device depth in ``convention`` -> linear eye depth (metres); inverse of :func:`linear_to_raw`."""
    r = np.asarray(raw, dtype=np.float64)
    n, f = near, far
    if convention == "d3d":
        return n * f / (f - r * (f - n))
    if convention == "gl":
        return 2.0 * f * n / ((f + n) - r * (f - n))
    if convention == "reversed":
        return n * f / (n + r * (f - n))
    raise ValueError(f"unknown depth convention {convention!r}; use one of {DEPTH_CONVENTIONS}")


def zbuffer_params(near: float, far: float, reversed_z: bool = False) -> np.ndarray:
    """Unity's ``_ZBufferParams`` (x, y, z, w) for standard or reversed Z."""
    n, f = near, far
    if reversed_z:
        x, y = f / n - 1.0, 1.0
    else:
        x, y = 1.0 - f / n, f / n
    return np.array([x, y, x / f, y / f])


def unity_linear_eye_depth(raw, zbuffer: np.ndarray):
    """Unity's ``LinearEyeDepth(z) = 1 / (_ZBufferParams.z * z + _ZBufferParams.w)``."""
    return 1.0 / (zbuffer[2] * np.asarray(raw, dtype=np.float64) + zbuffer[3])
