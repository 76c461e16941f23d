"""Procedural triangle meshes: cylinders, boxes and the bundled colonnade.

Every mesh is closed (each edge shared by exactly two triangles, vertices indexed, not
duplicated) and wound so that ``(v1 - v0) x (v2 - v0)`` points outward.

``data/scenes/colonnade.obj`` is ``colonnade()`` written by::

    python -m vlref.geometry.meshgen data/scenes/colonnade.obj
"""

from __future__ import annotations

import sys

import numpy as np

from .obj import write_obj

__all__ = ["cylinder_mesh", "box_mesh", "merge_meshes", "colonnade"]


def cylinder_mesh(center, radius: float, height: float, segments: int, rings: int = 1):
    """Capped cylinder, axis +y, ``segments`` around, ``rings`` bands along the side.

    Triangles: ``2 * segments * rings`` (side) + ``2 * segments`` (cap fans).
    """
    angle = 2.0 * np.pi * np.arange(segments) / segments
    ys = -0.5 * height + height * np.arange(rings + 1) / rings
    ring = np.stack([radius * np.cos(angle), np.zeros(segments), radius * np.sin(angle)], axis=1)
    verts = (ring[None] + np.array([0.0, 1.0, 0.0]) * ys[:, None, None]).reshape(-1, 3)
    verts = np.concatenate([verts, [[0.0, ys[0], 0.0], [0.0, ys[-1], 0.0]]]) + np.asarray(center, dtype=float)
    j, i = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = j * segments + i
    b = j * segments + (i + 1) % segments
    c, d = b + segments, a + segments
    side = np.concatenate([np.stack([a, d, c], -1).reshape(-1, 3), np.stack([a, c, b], -1).reshape(-1, 3)])
    bottom_c, top_c = len(verts) - 2, len(verts) - 1
    i = np.arange(segments)
    nxt = (i + 1) % segments
    top0 = rings * segments
    bottom = np.stack([np.full(segments, bottom_c), i, nxt], axis=1)
    top = np.stack([np.full(segments, top_c), top0 + nxt, top0 + i], axis=1)
    return verts, np.concatenate([side, bottom, top]).astype(np.int64)


def box_mesh(center, size):
    """Axis-aligned box of edge lengths ``size``: 8 corners (index = x_bit + 2 y_bit + 4 z_bit), 12 triangles."""
    half = 0.5 * np.asarray(size, dtype=float)
    bits = np.array([[(k >> a) & 1 for a in range(3)] for k in range(8)])
    verts = np.asarray(center, dtype=float) + (2 * bits - 1) * half
    faces = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, 1):
            quad = []
            for bu, bv in ((0, 0), (1, 0), (1, 1), (0, 1)):  # counter-clockwise about e_u x e_v = e_axis
                corner = np.zeros(3, dtype=int)
                corner[axis], corner[u], corner[v] = side, bu, bv
                quad.append(int(corner[0] + 2 * corner[1] + 4 * corner[2]))
            if side == 0:
                quad.reverse()
            faces += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    return verts, np.array(faces, dtype=np.int64)


def merge_meshes(meshes):
    """Concatenate ``(vertices, faces)`` pairs, offsetting the indices."""
    verts, faces, offset = [], [], 0
    for v, f in meshes:
        verts.append(np.asarray(v, dtype=float))
        faces.append(np.asarray(f, dtype=np.int64) + offset)
        offset += len(v)
    return np.concatenate(verts), np.concatenate(faces)


def colonnade(columns: int = 8, spacing: float = 2.0, radius: float = 0.35, height: float = 5.0,
              segments: int = 24, rings: int = 6):
    """A row of ``columns`` cylinders along x (centred on x = 0, standing on y = 0), each on a plinth,
    under one architrave box. Default: 2796 triangles."""
    xs = spacing * (np.arange(columns) - 0.5 * (columns - 1))
    parts = []
    for x in xs:
        parts.append(cylinder_mesh((x, 0.3 + 0.5 * height, 0.0), radius, height, segments, rings))
        parts.append(box_mesh((x, 0.15, 0.0), (2.6 * radius, 0.3, 2.6 * radius)))
    span = spacing * (columns - 1) + 4.0 * radius
    parts.append(box_mesh((0.0, 0.3 + height + 0.3, 0.0), (span, 0.6, 3.0 * radius)))
    return merge_meshes(parts)


if __name__ == "__main__":
    v, f = colonnade()
    write_obj(sys.argv[1], v, f, f"vlref.geometry.meshgen.colonnade(): {len(f)} triangles")
