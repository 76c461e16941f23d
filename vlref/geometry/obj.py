"""Wavefront OBJ meshes: loading (vertices and faces only) and the mesh-object transform.

Read: ``v x y z [w]`` (``w`` ignored) and ``f`` lines whose vertex references are ``a``, ``a/b``,
``a//c`` or ``a/b/c`` (only the position index ``a`` is used). Indices are 1-based; a negative
index counts back from the last vertex defined so far (``-1`` = the latest). Polygons with ``n > 3``
vertices are triangulated as fans ``(0, i, i + 1)``. Every other statement (``vn``, ``vt``, ``o``,
``g``, ``s``, ``usemtl``, ``mtllib``, ``l``, ...) and comments are ignored.

Bad input raises :class:`vlref.errors.InputError` naming the file, the line (``"line 12"``) and
the reason.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..camera import euler_matrix
from ..errors import InputError

__all__ = ["load_obj", "transform_vertices", "write_obj"]


def _vertex(parts: list[str], file: str, where: str) -> tuple[float, float, float]:
    if len(parts) < 4:
        raise InputError(file, where, f"a vertex needs 3 coordinates, got {len(parts) - 1}")
    try:
        xyz = (float(parts[1]), float(parts[2]), float(parts[3]))
    except ValueError:
        raise InputError(file, where, f"vertex coordinates must be numbers, got {' '.join(parts[1:4])!r}") from None
    if not all(math.isfinite(c) for c in xyz):
        raise InputError(file, where, "vertex coordinates must be finite")
    return xyz


def _face(parts: list[str], n_vertices: int, file: str, where: str) -> list[int]:
    if len(parts) < 4:
        raise InputError(file, where, f"a face needs at least 3 vertices, got {len(parts) - 1}")
    out = []
    for ref in parts[1:]:
        head = ref.split("/", 1)[0]
        try:
            k = int(head)
        except ValueError:
            raise InputError(file, where, f"bad vertex reference {ref!r}: expected an integer index") from None
        index = k - 1 if k > 0 else n_vertices + k
        if k == 0 or not 0 <= index < n_vertices:
            raise InputError(file, where, f"vertex index {k} out of range (1..{n_vertices} or -1..-{n_vertices} "
                                          "with the vertices defined so far)")
        out.append(index)
    return out


def load_obj(path) -> tuple[np.ndarray, np.ndarray]:
    """Read an OBJ file: ``(vertices (V, 3) float64, faces (F, 3) int64)`` with 0-based indices."""
    file = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputError(file, "", f"cannot read OBJ file ({exc.strerror or exc})") from None
    vertices: list[tuple[float, float, float]] = []
    faces: list[tuple[int, int, int]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        parts = line.split("#", 1)[0].split()
        if not parts:
            continue
        if parts[0] == "v":
            vertices.append(_vertex(parts, file, f"line {number}"))
        elif parts[0] == "f":
            poly = _face(parts, len(vertices), file, f"line {number}")
            faces.extend((poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1))
    if not faces:
        raise InputError(file, "", "the mesh has no faces ('f' lines)")
    return np.array(vertices, dtype=np.float64), np.array(faces, dtype=np.int64)


def transform_vertices(vertices: np.ndarray, position, rotation, scale) -> np.ndarray:
    """Mesh-object transform (Unity's TRS): ``x_world = position + R(rotation) @ (scale * x_local)``.

    ``rotation`` is Unity Euler degrees (z, x, y; :func:`vlref.camera.euler_matrix`), ``scale``
    per-axis. Normals are recomputed from the transformed triangles, so non-uniform scale is exact.
    """
    v = np.asarray(vertices, dtype=np.float64) * np.asarray(scale, dtype=np.float64)
    return v @ euler_matrix(rotation).T + np.asarray(position, dtype=np.float64)


def write_obj(path, vertices: np.ndarray, faces: np.ndarray, comment: str = "") -> None:
    """Write ``v`` and ``f`` lines (1-based, full float64 precision via ``repr``)."""
    lines = [f"# {c}" for c in comment.splitlines()]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=np.float64).tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(faces, dtype=np.int64).tolist()]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
