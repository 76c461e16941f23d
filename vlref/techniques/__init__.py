"""The technique registry: every volumetric technique vlref renders, by the name ``render.technique`` gives.

:data:`TECHNIQUES` maps each name to a :class:`Technique`: its render function, its parameter class
(the ``[techniques.NAME]`` table, :mod:`vlref.scene.technique_params`), the golden suite's rule of which
scenes it applies to, its optional notes and its peak memory per pixel. The orchestrator
(:func:`vlref.render.render`), the port path (:mod:`vlref.port`), the notebook helpers,
the golden suite and the memory check dispatch through it; the scene model's accepted names are the
fields of :class:`~vlref.scene.technique_params.TechniqueParams` (the scene layer lies below the
techniques), and ``tests/test_technique_registry.py`` holds the two lists equal.

The stage-buffer contract (:data:`Buffers`): ``render(scene, frame)`` returns a dict of float arrays,
``frame`` a :class:`vlref.render.Frame`, holding the :data:`FRAME_BUFFERS`

=================  ============================================================
``inscatter``      (H,W,3) radiance added to the scene (L)
``transmittance``  (H,W)   view transmittance applied to the scene colour (T; 1 without extinction)
``final``          (H,W,3) the technique's one composite of the scene colour: every technique's
                   composite equals ``scene · T + L`` bit for bit (additive sources have T = 1)
=================  ============================================================

plus its pass buffers under the names of ``docs/TECHNIQUES.md`` (at their own resolution) and, for a
temporal technique, its state for the next frame under ``history`` (not an array).

Adding a technique: write ``vlref/techniques/<name>.py`` with ``render`` (and its applicability rule, named in
the entry, when it does not light every scene), its parameter class with a field in ``TechniqueParams``, one
:class:`Technique` entry below, and its section of ``docs/TECHNIQUES.md``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from types import ModuleType
from typing import Callable, Optional

import numpy as np

from ..scene import bundled_scenes, load_scene
from ..scene.technique_params import (RESOLVED_DEFAULTS, FroxelParams, KillzoneParams, PhysicalParams, RadialParams,
                                      SlightlyMadParams, UrpParams, resolved)

__all__ = ["Technique", "TECHNIQUES", "Buffers", "FRAME_BUFFERS", "RESOLVED_DEFAULTS", "resolved", "every_scene",
           "APPLIES", "suitable_scenes"]

Buffers = dict[str, np.ndarray]
"""What a technique's ``render(scene, frame)`` returns (module docstring)."""

FRAME_BUFFERS = ("final", "inscatter", "transmittance")
"""The buffers every technique returns, whatever its passes."""

def every_scene(scene) -> bool:
    """The applicability rule of a technique that lights any light type: every scene."""
    return True


@dataclass(frozen=True)
class Technique:
    """One registry entry: the technique's module ``vlref.techniques.<name>``, imported on first use (a render
    imports its own technique's passes and kernels only), and what the registry knows without it.

    ``render(scene, frame) -> Buffers`` is the module's ``render``; ``applies(scene) -> bool`` the golden suite's
    rule (:func:`vlref.oracle.golden.suite_entries`): the module's function named ``rule``, :func:`every_scene`
    without one; ``notes(scene, buffers) -> list[str]`` the one-line remarks ``vlref render`` prints: the module's
    ``notes`` where ``has_notes`` (None: none); ``bytes_per_pixel`` the peak memory per frame pixel that
    :func:`vlref.memory.estimate` charges.
    """

    name: str
    params: type
    bytes_per_pixel: int
    rule: str = ""
    has_notes: bool = False

    @property
    def module(self) -> ModuleType:
        return importlib.import_module(f"{__name__}.{self.name}")

    @property
    def render(self) -> Callable[..., Buffers]:
        return self.module.render

    @property
    def applies(self) -> Callable[..., bool]:
        return getattr(self.module, self.rule) if self.rule else every_scene

    @property
    def notes(self) -> Optional[Callable[..., list]]:
        return self.module.notes if self.has_notes else None


TECHNIQUES: dict[str, Technique] = {t.name: t for t in (
    # bytes_per_pixel: measured peaks 228, 352, 294, 333, 292 rounded up; froxel: the largest (not measured)
    Technique("physical", PhysicalParams, 240),
    Technique("killzone", KillzoneParams, 360),
    Technique("slightlymad", SlightlyMadParams, 300, has_notes=True),
    Technique("urp", UrpParams, 340, rule="has_main_light"),
    Technique("radial", RadialParams, 300, rule="light_in_frame", has_notes=True),
    Technique("froxel", FroxelParams, 360, has_notes=True),
)}
"""Every technique by name, in the order the golden suite and the listings use."""

APPLIES = {"physical": "every scene", "killzone": "every scene", "slightlymad": "every scene",
           "urp": "scenes with a directional light (its main light)",
           "radial": "scenes whose radial light projects inside the frame", "froxel": "every scene"}
"""Each technique's ``applies`` rule in words (help texts, README, ``vlref scenes``)."""


def suitable_scenes(technique: str) -> list[str]:
    """The bundled scenes that ``technique``'s ``applies`` rule accepts, by name."""
    rule = TECHNIQUES[technique].applies
    return [name for name, path in bundled_scenes().items() if rule(load_scene(path))]
