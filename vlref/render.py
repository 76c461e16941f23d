"""Render orchestration: scene -> camera -> geometry -> G-buffer -> lights -> technique -> buffers.

``render(scene)`` is what the CLI, the notebooks, the reference and the oracle call. The technique is
the registry's entry :data:`vlref.techniques.TECHNIQUES` ``[render.technique]``; each pass returns named
float buffers (the stage-buffer contract of :mod:`vlref.techniques`); ``RenderResult.buffers`` (a
:class:`RenderBuffers` mapping: ``albedo`` is made on first access) gathers them under stable names:

=================  ============================================================
``final``          (H,W,3) the composited frame
``inscatter``      (H,W,3) in-scattered radiance of the volumetric pass
``transmittance``  (H,W)   view transmittance applied to the scene colour
``scene_colour``   (H,W,3) the lit surfaces before the volumetric pass
``depth``          (H,W)   linear eye depth in metres (inf = sky)
``normal``, ``albedo`` (H,W,3); ``object_id`` (H,W) int32 (-1 = sky)
=================  ============================================================

With ``stages=True`` the technique's intermediate buffers and every shadow map are added.

Temporal techniques (``froxel`` with ``temporal = true``) read the previous frame's state from
``render(..., history=)`` and return theirs as ``RenderResult.history`` (None for the others);
:func:`vlref.sequence.render_sequence` chains them over frames.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from collections.abc import Iterator, MutableMapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from . import __version__
from .camera import Camera, camera_from_settings
from .geometry import build_geometry, raycast
from .geometry.raycast import per_object
from .jit_init import initialise_numba
from .lights import pack_lights
from .lights.shading import scene_colour
from .lights.shadow_cast import build_shadow_maps
from .scene.animation import scene_at
from .scene.model import Scene
from .techniques import APPLIES, FRAME_BUFFERS, TECHNIQUES, suitable_scenes

__all__ = ["Frame", "RenderBuffers", "RenderResult", "render", "prepare_frame", "scene_hash", "scene_settings_json"]


def _portable(node: Any) -> Any:
    """Replace every file path (``path`` keys) by its base name and content hash, recursively."""
    if isinstance(node, dict):
        out = {}
        for key, value in node.items():
            if key == "path" and isinstance(value, str) and value:
                p = Path(value)
                out[key] = {"name": p.name, "sha256": hashlib.sha256(p.read_bytes()).hexdigest()}
            else:
                out[key] = _portable(value)
        return out
    if isinstance(node, (list, tuple)):
        return [_portable(v) for v in node]
    return node


def scene_settings_json(scene: Scene) -> str:
    """The scene as canonical JSON (sorted keys), machine-independent: no source path, files by content."""
    data = dataclasses.asdict(scene)
    data.pop("source", None)
    return json.dumps(_portable(data), sort_keys=True, separators=(",", ":"))


def scene_hash(scene: Scene) -> str:
    """sha256 of :func:`scene_settings_json`: equal scenes hash equal on every machine."""
    return hashlib.sha256(scene_settings_json(scene).encode()).hexdigest()


@dataclass
class Frame:
    """Everything the volumetric passes of one frame read, built once per render.

    ``history`` is the previous frame's temporal state (temporal techniques only). ``shadow_cache`` maps a
    lookup filter (``None`` = each light's own) to its :class:`~vlref.lights.shadow_pack.ShadowMaps`; it
    fills on demand, or a port supplies its own maps (:func:`vlref.port.port_frame`). ``tick(name)``, when
    given, reports the on-demand shadow maps as a render stage (``"shadow maps"``) once they are built.
    """

    scene: Scene
    camera: Camera
    geometry: Any
    gbuffer: Any
    lights: Any
    scene_colour: np.ndarray
    shadow_cache: dict = field(default_factory=dict, repr=False)
    history: Any = field(default=None, repr=False)
    tick: Callable[[str], None] | None = field(default=None, repr=False)

    def shadow_maps(self, shadow_filter: str | None = None):
        """The lights' shadow maps, built on first use (cascades depend on the camera).

        ``shadow_filter`` replaces every shadowed light's lookup filter (``hard``, ``pcf``, ``exact``):
        techniques fix the filter their source uses (Vos and VolumetricLights: one point sample).
        """
        if shadow_filter not in self.shadow_cache:
            maps = None if shadow_filter is None else self.shadow_maps().with_filter(shadow_filter)
            if maps is None:
                scene = self.scene
                if shadow_filter is not None:
                    scene = scene.replace(lights=tuple(
                        dataclasses.replace(l, shadows=dataclasses.replace(l.shadows, filter=shadow_filter))
                        if l.shadows is not None else l for l in scene.lights))
                maps = build_shadow_maps(scene, self.camera, self.geometry, self.lights)
            self.shadow_cache[shadow_filter] = maps
            if shadow_filter is None and self.tick is not None:
                self.tick("shadow maps")
        return self.shadow_cache[shadow_filter]


class _Deferred:
    """A buffer of :class:`RenderBuffers` made on first access: ``make(*args)``."""

    def __init__(self, make: Callable[..., np.ndarray], *args):
        self.make, self.args = make, args


class RenderBuffers(MutableMapping):
    """A render's buffers by name, in the order given, as a dict holds them; an entry given as
    ``RenderBuffers.deferred(make, *args)`` is made by ``make(*args)`` on first access and kept. :func:`render` defers
    the ``albedo`` buffer (a per-pixel copy of the G-buffer's object albedo: 50 MB at 1080p, 0.03-0.27 s on the loaded
    2-core dev box), which ``vlref render`` writes only with ``--stages``. Pickled as a plain dict of every buffer."""

    deferred = _Deferred

    def __init__(self, items=()):
        self._items = dict(items)

    def __getitem__(self, name: str) -> np.ndarray:
        value = self._items[name]
        if isinstance(value, _Deferred):
            value = self._items[name] = value.make(*value.args)
        return value

    def __setitem__(self, name: str, value) -> None:
        self._items[name] = value

    def __delitem__(self, name: str) -> None:
        del self._items[name]

    def __contains__(self, name) -> bool:
        return name in self._items

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"RenderBuffers({list(self._items)})"

    def __reduce__(self):
        return dict, (dict(self),)


@dataclass
class RenderResult:
    buffers: RenderBuffers
    metadata: dict[str, str]
    timings: dict[str, float]
    notes: list[str] = field(default_factory=list)
    """One-line remarks of the technique's ``notes(scene, buffers)`` (source defaults in use, fp16 saturation)."""
    history: Any = None


def prepare_frame(scene: Scene, tick: Callable[[str], None] | None = None) -> Frame:
    """Camera, geometry, G-buffer, packed lights and scene colour of ``scene`` at its ``render.frame``
    (:func:`vlref.scene.animation.scene_at`; ``Frame.scene`` is the evaluated scene). Numba's one-time
    initialisation, where this process has not made it yet, is part of its first stage
    (:func:`vlref.jit_init.initialise_numba`)."""
    tick = tick or (lambda name: None)
    initialise_numba()
    scene = scene_at(scene)
    camera = camera_from_settings(scene.camera, scene.render.width, scene.render.height)
    geometry = build_geometry(scene)
    tick("geometry")
    gbuffer = raycast(scene, camera, geometry)
    tick("raycast")
    lights = pack_lights(scene)
    colour = scene_colour(gbuffer, scene, geometry, lights)
    tick("shading")
    return Frame(scene, camera, geometry, gbuffer, lights, colour, tick=tick)


def render(scene: Scene, stages: bool = False, progress: Callable[[str], None] | None = None,
           history: Any = None) -> RenderResult:
    """Render ``scene`` with its ``render.technique``; see the module docstring for the buffers and ``history``."""
    timings: dict[str, float] = {}
    last = [time.perf_counter()]

    def tick(name: str) -> None:
        now = time.perf_counter()
        timings[name] = now - last[0]
        last[0] = now
        if progress is not None:
            progress(name)

    frame = prepare_frame(scene, tick)
    frame.history = history
    technique = TECHNIQUES[scene.render.technique]
    out = technique.render(frame.scene, frame)
    next_history = out.pop("history", None)
    tick("volumetrics")

    g = frame.gbuffer
    buffers = RenderBuffers({name: out[name] for name in FRAME_BUFFERS})
    albedo = RenderBuffers.deferred(per_object, g.object_albedo, g.object_id)  # g.albedo, when asked for
    buffers.update({"scene_colour": frame.scene_colour, "depth": g.depth, "normal": g.normal, "albedo": albedo,
                    "object_id": g.object_id})
    if stages:
        buffers.update({k: v for k, v in out.items() if k not in buffers})
        if frame.shadow_cache:
            buffers.update(next(iter(frame.shadow_cache.values())).buffers())
    metadata = {"vlref_version": __version__, "scene_hash": scene_hash(scene),
                "technique": scene.render.technique, "settings": scene_settings_json(scene),
                "scene_file": scene.source}
    notes = technique.notes(scene, out) if technique.notes is not None else []
    if not technique.applies(scene):
        notes.insert(0, f"{scene.render.technique} does not suit this scene ({APPLIES[scene.render.technique]}); "
                        f"bundled scenes that suit it: {', '.join(suitable_scenes(scene.render.technique))}")
    return RenderResult(buffers, metadata, timings, notes, next_history)
