"""The frame of a port's buffers and the march on it (``vlref march PORT.toml -o OUT``).

:func:`port_frame` builds a :class:`vlref.render.Frame` whose G-buffer depth, scene colour and shadow maps
are the port's (normals, albedo and emission are zero: the march reads depth and shadows only);
:func:`march` runs the scene's technique on it, so the result isolates the port's volumetric passes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from ..geometry import build_geometry
from ..geometry.raycast import GBuffer
from ..io.exr import write_exr
from ..io.output_folders import output_dir
from ..lights import pack_lights
from ..render import Frame, scene_hash
from ..techniques import FRAME_BUFFERS, TECHNIQUES
from .manifest import PortBuffers, load_port
from .shadows import shadow_maps_from_port

__all__ = ["port_frame", "march", "march_sequence", "march_port", "save_march"]


def port_frame(port: PortBuffers):
    """A :class:`vlref.render.Frame` whose G-buffer depth, scene colour and shadow maps are the port's."""
    cam = port.camera
    dirs = cam.ray_directions()
    distance = cam.eye_depth_to_distance(port.depth, dirs)
    hit = np.isfinite(port.depth)
    gbuffer = GBuffer(port.depth, distance, np.zeros(port.depth.shape + (3,)), np.where(hit, 0, -1).astype(np.int32),
                      np.asarray(cam.position, dtype=np.float64), dirs, np.zeros((1, 3)), np.zeros((1, 3)))
    maps = shadow_maps_from_port(port.scene, cam, port.shadow_maps, port.source)
    return Frame(port.scene, cam, build_geometry(port.scene), gbuffer, pack_lights(port.scene), port.colour,
                 shadow_cache=maps)


def march(port: PortBuffers) -> dict[str, np.ndarray]:
    """The scene's technique run on the port's buffers: the technique's buffers, plus the port's ``depth``."""
    out = TECHNIQUES[port.scene.render.technique].render(port.scene, port_frame(port))
    out["depth"] = port.depth
    return out


def march_sequence(ports: Sequence[PortBuffers]) -> Iterator[dict[str, np.ndarray]]:
    """:func:`march` on each frame of ``ports`` in order, each given the previous frame's temporal state
    (``froxel`` with ``temporal = true``: the history of :mod:`vlref.froxel.temporal`), as
    :func:`vlref.sequence.render_sequence` chains vlref's own frames; the first frame starts without history.
    The state is the technique's ``history`` buffer, removed from what is yielded."""
    history = None
    for port in ports:
        frame = port_frame(port)
        frame.history = history
        out = TECHNIQUES[port.scene.render.technique].render(port.scene, frame)
        history = out.pop("history", None)
        out["depth"] = port.depth
        yield out


def march_port(path, overrides: Sequence[str] = ()) -> dict[str, np.ndarray]:
    """Load a port manifest (:func:`vlref.port.load_port`) and :func:`march` on its buffers."""
    return march(load_port(path, overrides))


def save_march(out_dir, port: PortBuffers, buffers: dict[str, np.ndarray], stages: bool = False) -> None:
    """Write ``buffers`` of :func:`march` as float32 EXRs into ``out_dir`` (all or nothing): ``FRAME_BUFFERS``
    and ``depth``, or with ``stages`` every image buffer (the first 3 channels of wider ones); each file's
    metadata holds the scene hash, the technique and the manifest's absolute path."""
    meta = {"scene_hash": scene_hash(port.scene), "technique": port.scene.render.technique,
            "port_manifest": str(Path(port.source).resolve())}
    with output_dir(out_dir) as tmp:
        for name, a in buffers.items():
            a = np.asarray(a)
            if name != "depth" and (stages or name in FRAME_BUFFERS) and a.ndim in (2, 3) and a.dtype.kind == "f":
                write_exr(tmp / f"{name}.exr", a if a.ndim == 2 or a.shape[2] <= 4 else a[..., :3], metadata=meta)
        write_exr(tmp / "depth.exr", port.depth, metadata=meta)
