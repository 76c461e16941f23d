"""Host-side scene preparation of the WebGPU killzone port: matrices, triangle meshes, uniform blocks.

Written from docs/CONVENTIONS.md and docs/PORTING.md, as an engine's exporter would be. The only vlref
call is :func:`load` (vlref's TOML loader, standing in for the engine's scene import: it parses and
validates the file, nothing else); tessellation, frames and matrices are the port's own (NumPy).

Frames (CONVENTIONS.md): world left-handed, y up; a frame is the 3x3 matrix whose columns are
(right, up, forward); the view matrix has rows ``right, up, forward`` and maps ``p`` to
``R^T (p - eye)`` (view z = linear eye depth). Projections are D3D/WebGPU style (NDC z in [0, 1])
and reversed-Z: ``d = A + B / z`` with ``A = -n/(f-n)``, ``B = f n/(f-n)`` (1 at near, 0 at far).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

SKY_DEPTH = 3.0e38
"""Linear depth the shaders store for sky (a finite stand-in for ``inf``: ``|Δz|`` to it is ~3e38, so a
depth weight ``1/(|Δz| + ε)`` is ~0, and sky-to-sky differences are exactly 0)."""

KIND_POINT, KIND_SPOT, KIND_DIRECTIONAL = 0, 1, 2
ATT_CODES = {"inverse_square": 0, "unity": 1, "windowed": 2}
CONE_CODES = {"unity": 0, "linear": 1, "smoothstep": 2}

CUBE_FACES = (("px", (0, 0, -1), (0, 1, 0), (1, 0, 0)), ("nx", (0, 0, 1), (0, 1, 0), (-1, 0, 0)),
              ("py", (1, 0, 0), (0, 0, -1), (0, 1, 0)), ("ny", (1, 0, 0), (0, 0, 1), (0, -1, 0)),
              ("pz", (1, 0, 0), (0, 1, 0), (0, 0, 1)), ("nz", (-1, 0, 0), (0, 1, 0), (0, 0, -1)))
"""(name, right, up, forward) of the D3D/Unity cube faces, in the order +X, -X, +Y, -Y, +Z, -Z (CONVENTIONS)."""


def load(scene_ref, overrides=()):
    """Parse and validate a vlref scene file or bundled scene name (vlref's loader; the port's only vlref call)."""
    from vlref.scene import load_scene

    return load_scene(scene_ref, list(overrides))


# --------------------------------------------------------------------------- frames and matrices

def euler(degrees) -> np.ndarray:
    """Unity ``Quaternion.Euler(x, y, z)``: ``Ry(y) Rx(x) Rz(z)`` on column vectors (CONVENTIONS)."""
    x, y, z = np.radians(np.asarray(degrees, dtype=np.float64))
    rx = np.array([[1, 0, 0], [0, math.cos(x), -math.sin(x)], [0, math.sin(x), math.cos(x)]])
    ry = np.array([[math.cos(y), 0, math.sin(y)], [0, 1, 0], [-math.sin(y), 0, math.cos(y)]])
    rz = np.array([[math.cos(z), -math.sin(z), 0], [math.sin(z), math.cos(z), 0], [0, 0, 1]])
    return ry @ rx @ rz


def look_frame(forward, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """Columns (right, up, forward): ``right = up × forward``, ``up' = forward × right`` (CONVENTIONS);
    a forward parallel to ``up`` takes world z as the hint (world x when forward is along z) (PORTING)."""
    f = np.asarray(forward, dtype=np.float64)
    f = f / np.linalg.norm(f)
    r = np.cross(np.asarray(up, dtype=np.float64), f)
    if np.linalg.norm(r) < 1e-9:
        r = np.cross([0.0, 0.0, 1.0] if abs(f[2]) < 0.9 else [1.0, 0.0, 0.0], f)
    r /= np.linalg.norm(r)
    return np.stack([r, np.cross(f, r), f], axis=1)


def view_matrix(eye, frame) -> np.ndarray:
    """World -> view (rows right, up, forward; column vectors)."""
    v = np.eye(4)
    v[:3, :3] = frame.T
    v[:3, 3] = -frame.T @ np.asarray(eye, dtype=np.float64)
    return v


def reversed_perspective(fov_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """View -> clip, vertical ``fov_deg``, reversed-Z (module docstring)."""
    t = math.tan(math.radians(fov_deg) / 2.0)
    p = np.zeros((4, 4))
    p[0, 0], p[1, 1] = 1.0 / (aspect * t), 1.0 / t
    p[2, 2], p[2, 3] = -near / (far - near), far * near / (far - near)
    p[3, 2] = 1.0
    return p


@dataclass(frozen=True)
class CameraSetup:
    eye: np.ndarray
    frame: np.ndarray      # columns right, up, forward
    fov: float             # vertical, degrees
    near: float
    far: float
    width: int
    height: int

    @property
    def view(self) -> np.ndarray:
        return view_matrix(self.eye, self.frame)

    @property
    def projection(self) -> np.ndarray:
        return reversed_perspective(self.fov, self.width / self.height, self.near, self.far)


def camera_setup(scene) -> CameraSetup:
    """The scene's ``[camera]`` at the render size: ``look_at`` (with ``up``) or Euler ``rotation``."""
    c = scene.camera
    eye = np.asarray(c.position, dtype=np.float64)
    if c.look_at is not None:
        frame = look_frame(np.asarray(c.look_at) - eye, c.up)
    elif c.rotation is not None:
        frame = euler(c.rotation)
    else:
        frame = np.eye(3)
    return CameraSetup(eye, frame, c.fov, c.near, c.far, scene.render.width, scene.render.height)


def light_frame(light) -> np.ndarray:
    """A spot light's map frame: ``look_frame(direction)`` (PORTING: fov = spot_angle)."""
    return look_frame(light.direction)


def shadow_tiles(light):
    """``[(face, view, projection)]`` of a light's shadow map: one spot tile or six cube faces (D3D order),
    near = ``shadows.near``, far = ``range``, reversed-Z."""
    pos, sh = np.asarray(light.position, dtype=np.float64), light.shadows
    if light.type == "spot":
        return [("", view_matrix(pos, light_frame(light)),
                 reversed_perspective(light.spot_angle, 1.0, sh.near, light.range))]
    return [(name, view_matrix(pos, np.array([r, u, f], dtype=np.float64).T),
             reversed_perspective(90.0, 1.0, sh.near, light.range)) for name, r, u, f in CUBE_FACES]


# --------------------------------------------------------------------------- cascades of directional lights

def cascade_splits(near: float, far: float, count: int, lam: float) -> np.ndarray:
    """Cascade split depths: the practical split scheme ``λ n (f/n)^{i/N} + (1 − λ)(n + (f − n) i/N)``."""
    i = np.arange(count + 1) / count
    return lam * near * (far / near) ** i + (1.0 - lam) * (near + (far - near) * i)


def frustum_sphere(cam: CameraSetup, z0: float, z1: float) -> tuple[np.ndarray, float]:
    """Bounding sphere of the view-frustum slice between eye depths z0 and z1: its 8 corners' mean, and
    their largest distance from it (the region a cascade covers)."""
    t = math.tan(math.radians(cam.fov) / 2.0)
    aspect = cam.width / cam.height
    corners = np.array([cam.eye + cam.frame @ [sx * z * t * aspect, sy * z * t, z]
                        for z in (z0, z1) for sx in (-1, 1) for sy in (-1, 1)])
    centre = corners.mean(axis=0)
    return centre, float(np.linalg.norm(corners - centre, axis=1).max())


def orthographic_reversed(half: float, far: float) -> np.ndarray:
    """View -> clip of a square orthographic tile of half-size ``half``, depth ``1 − z/far`` (reversed-Z, near 0)."""
    p = np.diag([1.0 / half, 1.0 / half, -1.0 / far, 1.0])
    p[2, 3] = 1.0
    return p


# --------------------------------------------------------------------------- tessellation

def _quad(a, b, c, d):
    return [a, b, c, a, c, d]


def _box(center, size, rot):
    h = np.asarray(size, dtype=np.float64) / 2.0
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    idx = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tri = sum((_quad(*[corners[i] for i in q]) for q in idx), [])
    return np.array(tri) @ rot.T + center


def _cylinder(center, radius, height, rot, segments=48):
    a = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    ring = np.stack([radius * np.cos(a), np.zeros_like(a), radius * np.sin(a)], axis=1)
    ring[-1] = ring[0]   # watertight seam: sin(2 pi) is -2.4e-16, not 0 (a 1-pixel crack otherwise)
    lo, hi = ring - [0, height / 2, 0], ring + [0, height / 2, 0]
    tri = []
    for i in range(segments):
        tri += _quad(lo[i], hi[i], hi[i + 1], lo[i + 1])
        tri += [hi[i], [0, height / 2, 0], hi[i + 1], lo[i], lo[i + 1], [0, -height / 2, 0]]
    return np.array(tri, dtype=np.float64) @ rot.T + center


def _sphere(center, radius, segments=64, rings=32):
    th = np.linspace(0.0, math.pi, rings + 1)
    ph = np.linspace(0.0, 2.0 * math.pi, segments + 1)
    p = np.stack([np.sin(th)[:, None] * np.cos(ph)[None], np.cos(th)[:, None] * np.ones_like(ph)[None],
                  np.sin(th)[:, None] * np.sin(ph)[None]], axis=-1) * radius
    p[:, -1] = p[:, 0]   # watertight seam (see _cylinder)
    tri = []
    for i in range(rings):
        for j in range(segments):
            tri += _quad(p[i, j], p[i, j + 1], p[i + 1, j + 1], p[i + 1, j])
    return np.array(tri) + center


def _plane(point, normal, eye, half):
    n = np.asarray(normal, dtype=np.float64)
    n /= np.linalg.norm(n)
    u = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    c = eye - ((eye - point) @ n) * n
    return np.array(_quad(c - half * u - half * v, c + half * u - half * v, c + half * u + half * v,
                          c - half * u + half * v))


def tessellate(scene, eye, plane_half: float) -> np.ndarray:
    """Triangle list ``(n, 9)`` float32: position, flat normal, albedo per vertex (world space).

    Analytic primitives are tessellated (cylinders 48 segments, spheres 64x32; the infinite plane is a
    square of half-size ``plane_half`` centred under the camera); OBJ meshes go as they are (vlref's
    OBJ reader). Faces are wound either way: the port draws without culling.
    """
    parts = []
    for obj in scene.objects:
        if obj.shape == "plane":
            tri = _plane(np.asarray(obj.point, dtype=np.float64), obj.normal, eye, plane_half)
        elif obj.shape == "box":
            tri = _box(np.asarray(obj.center), obj.size, euler(obj.rotation))
        elif obj.shape == "cylinder":
            tri = _cylinder(np.asarray(obj.center), obj.radius, obj.height, euler(obj.rotation))
        elif obj.shape == "sphere":
            tri = _sphere(np.asarray(obj.center), obj.radius)
        else:
            from vlref.geometry.obj import load_obj, transform_vertices
            from pathlib import Path

            verts, faces = load_obj(Path(scene.source).parent / obj.path if scene.source else obj.path)
            verts = transform_vertices(verts, obj.position, obj.rotation, obj.scale)
            tri = verts[np.asarray(faces).reshape(-1)]
        tri = tri.reshape(-1, 3, 3)
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        albedo = np.broadcast_to(np.asarray(obj.material.albedo, dtype=np.float64), tri.shape)
        parts.append(np.concatenate([tri, np.repeat(n[:, None], 3, axis=1), albedo], axis=2).reshape(-1, 9))
    return np.concatenate(parts).astype(np.float32)


def volume_mesh(light) -> np.ndarray:
    """Triangle list ``(n, 3)`` float32 enclosing a light's volume (Vos: the light-volume geometry).

    Spot: a 24-sided cone, apex at the light, length ``range`` along the axis, its polygon
    circumscribing the circle of radius ``range · tan(θ)``: it contains ball ∩ cone. Point: an
    icosphere (2 subdivisions) scaled so that every face plane lies at least ``range`` from the centre.
    The shader intersects the ray with the exact volume; the mesh only selects the pixels. Both meshes are
    wound alike (clockwise seen from outside, in world coordinates): the march pass culls front faces and
    draws the far side, which a camera inside the volume sees too (data/conformance/inside_volume.toml).
    """
    pos = np.asarray(light.position, dtype=np.float64)
    if light.type == "spot":
        n, frame = 24, light_frame(light)
        rad = light.range * math.tan(math.radians(light.spot_angle) / 2.0) / math.cos(math.pi / n)
        a = np.linspace(0.0, 2.0 * math.pi, n + 1)
        base = np.stack([rad * np.cos(a), rad * np.sin(a), np.full_like(a, light.range)], axis=1)
        tri = []
        for i in range(n):
            tri += [[0, 0, 0], base[i], base[i + 1], [0, 0, light.range], base[i + 1], base[i]]
        return (np.array(tri) @ frame.T + pos).astype(np.float32)
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6],
         [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
         [8, 6, 7], [9, 8, 1]]
    tri = np.array([[v[i] for i in face] for face in f], dtype=np.float64)
    tri /= np.linalg.norm(tri, axis=2, keepdims=True)
    for _ in range(2):
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        ab, bc, ca = [(p + q) / np.linalg.norm(p + q, axis=1, keepdims=True) for p, q in ((a, b), (b, c), (c, a))]
        tri = np.concatenate([np.stack(s, axis=1) for s in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    plane = np.abs(np.einsum("ij,ij->i", n / np.linalg.norm(n, axis=1, keepdims=True), tri[:, 0]))
    tri = tri[:, ::-1]   # wound as the cone: inward-facing in a right-handed sense, so "back faces" are the far side
    return (tri.reshape(-1, 3) * (light.range / plane.min()) + pos).astype(np.float32)


# --------------------------------------------------------------------------- uniform blocks (std140-like, vec4s)

def resolved(scene, name: str):
    """``render.<name>`` or the killzone default (TECHNIQUES.md: render.* override the technique's own)."""
    value = getattr(scene.render, name)
    return value if value is not None else getattr(scene.techniques.killzone, name)


def _inner_full_angle(light) -> float:
    """Inner full angle (degrees): the scene's, else the cone law's default (vlref/lights/cone.py docstring)."""
    if light.inner_spot_angle is not None:
        return light.inner_spot_angle
    if light.cone == "unity":
        return math.degrees(2.0 * math.atan(math.tan(math.radians(light.spot_angle) / 2.0) * 46.0 / 64.0))
    if light.cone == "linear":
        return 0.75 * light.spot_angle
    return max(0.0, light.spot_angle - 10.0)


def light_block(light, layer: int) -> np.ndarray:
    """One ``Light`` struct of the shaders (lights.wgsl): 8 vec4 = 32 float32. ``layer``: the light's first
    layer in the shadow texture (spot, point) or its first cascade (directional), -1 without shadows."""
    colour = np.asarray(light.color, dtype=np.float64) * light.intensity
    sh = light.shadows
    if light.type == "directional":   # unit direction of travel, its frame, cone.x = the number of cascades
        sh = sh if layer >= 0 else None
        frame = look_frame(light.direction)
        rows = [[0.0, 0.0, 0.0, KIND_DIRECTIONAL], [*frame[:, 2], 0.0], [*colour, sh.strength if sh else 0.0],
                [*frame[:, 0], 0.0], [*frame[:, 1], sh.bias if sh else 0.0], [sh.cascades if sh else 0, 0, 0, 0],
                [0, 0, 0, 0], [layer if sh else -1, sh.resolution if sh else 0, 0.0, sh.slope_bias if sh else 0.0]]
        return np.array(rows, dtype=np.float32).reshape(-1)
    kind = KIND_SPOT if light.type == "spot" else KIND_POINT
    pos = np.asarray(light.position, dtype=np.float64)
    frame = light_frame(light) if light.type == "spot" else np.eye(3)
    half_o = math.radians(light.spot_angle) / 2.0
    half_i = math.radians(_inner_full_angle(light)) / 2.0 if light.type == "spot" else 0.0
    cos_o, cos_i = math.cos(half_o), math.cos(half_i)
    unity_a = 1.0 / max(0.001, cos_i - cos_o)
    rows = [[*pos, kind], [*frame[:, 2], light.range], [*colour, sh.strength if sh else 0.0],
            [*frame[:, 0], math.tan(half_o)], [*frame[:, 1], sh.bias if sh else 0.0],
            [cos_o, cos_i, half_o, half_i], [ATT_CODES[light.attenuation], CONE_CODES[light.cone], unity_a, -cos_o * unity_a],
            [layer if sh else -1, sh.resolution if sh else 0, sh.near if sh else 0.0, sh.slope_bias if sh else 0.0]]
    return np.array(rows, dtype=np.float32).reshape(-1)


def globals_block(scene, cam: CameraSetup, low_size, epsilon: float, blur_sigma: float) -> np.ndarray:
    """The ``Globals`` struct (common.wgsl): view-projection, camera frame, medium, sizes."""
    vp = (cam.projection @ cam.view).astype(np.float32)
    m = scene.medium
    rows = [*vp.T.reshape(4, 4).tolist(),                                   # column-major mat4x4f
            [*cam.eye, 0.0], [*cam.frame[:, 0], 0.0], [*cam.frame[:, 1], 0.0], [*cam.frame[:, 2], 0.0],
            [math.tan(math.radians(cam.fov) / 2.0), cam.width / cam.height, cam.near, cam.far],
            [scene.render.max_distance, m.scattering, m.extinction, m.anisotropy],
            [cam.width, cam.height, low_size[0], low_size[1]],
            [resolved(scene, "steps"), len(scene.lights), epsilon, blur_sigma],
            [*scene.render.ambient, 0.0], [*scene.render.sky_color, 0.0]]
    return np.array(rows, dtype=np.float32).reshape(-1)
