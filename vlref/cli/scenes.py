"""``vlref scenes``: the bundled scenes and their descriptions."""

from __future__ import annotations

import argparse

from ..scene import bundled_scenes, load_scene
from ..techniques import TECHNIQUES

HELP = "list the bundled scenes and the techniques that apply to each"


def parser() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(prog="vlref scenes")


def run(args) -> int:
    for name, path in bundled_scenes().items():
        scene = load_scene(path)
        applies = [t.name for t in TECHNIQUES.values() if t.applies(scene)]
        animated = " [animation: --frames]" if scene.animation is not None else ""
        print(f"{name:16s} {scene.description}{animated}\n{'':16s} techniques: {', '.join(applies)}")
    return 0
