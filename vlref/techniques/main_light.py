"""The URP main light: the first directional light of a scene (the ``urp`` technique lights nothing else).

Apart from :mod:`vlref.techniques.urp` so that the command line checks a scene for it without importing that
technique's passes and kernels.
"""

from __future__ import annotations

from ..errors import InputError
from ..scene import bundled_scenes, load_scene

__all__ = ["main_light", "has_main_light"]


def main_light(scene) -> int:
    """Index of the first directional light; :class:`InputError` when the scene has none."""
    for i, light in enumerate(scene.lights):
        if light.type == "directional":
            return i
    suitable = [name for name, path in bundled_scenes().items() if has_main_light(load_scene(path))]
    raise InputError(scene.source or "<scene>", "render.technique",
                     "\"urp\" needs a directional light (the URP main light); the scene has none (bundled scenes "
                     f"with one: {', '.join(suitable)})")


def has_main_light(scene) -> bool:
    """The golden suite's rule (:mod:`vlref.techniques`): scenes with a directional light, the tutorial's
    main light (the march lights nothing else)."""
    return any(light.type == "directional" for light in scene.lights)
