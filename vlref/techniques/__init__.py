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

Adding a technique: write ``vlref/techniques/<name>.py`` with ``render`` (and its applicability rule
when it does not light every scene), its parameter class with a field in ``TechniqueParams``, one
:class:`Technique` entry below, and its section of ``docs/TECHNIQUES.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from ..scene import bundled_scenes, load_scene
from ..scene.technique_params import (RESOLVED_DEFAULTS, FroxelParams, KillzoneParams, PhysicalParams, RadialParams,
                                      SlightlyMadParams, UrpParams, resolved)
from . import froxel, killzone, physical, radial, slightlymad, urp

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
    """One registry entry.

    ``applies(scene) -> bool`` is the golden suite's rule (:func:`vlref.oracle.golden.suite_entries`);
    ``notes(scene, buffers) -> list[str]`` the one-line remarks ``vlref render`` prints (None: none);
    ``bytes_per_pixel`` the peak memory per frame pixel that :func:`vlref.memory.estimate` charges.
    """

    name: str
    render: Callable[..., Buffers]
    params: type
    applies: Callable[..., bool]
    bytes_per_pixel: int
    notes: Optional[Callable[..., list]] = None


TECHNIQUES: dict[str, Technique] = {t.name: t for t in (
    # bytes_per_pixel: measured peaks 228, 352, 294, 333, 292 rounded up; froxel: the largest (not measured)
    Technique("physical", physical.render, PhysicalParams, every_scene, 240),
    Technique("killzone", killzone.render, KillzoneParams, every_scene, 360),
    Technique("slightlymad", slightlymad.render, SlightlyMadParams, every_scene, 300, slightlymad.notes),
    Technique("urp", urp.render, UrpParams, urp.has_main_light, 340),
    Technique("radial", radial.render, RadialParams, radial.light_in_frame, 300, radial.notes),
    Technique("froxel", froxel.render, FroxelParams, every_scene, 360, froxel.notes),
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
