"""``vlref scenes``: the bundled scenes and their descriptions."""

from __future__ import annotations

import argparse

from ..scene import bundled_scenes, load_scene

HELP = "list the bundled scenes"


def parser() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(prog="vlref scenes")


def run(args) -> int:
    for name, path in bundled_scenes().items():
        print(f"{name:16s} {load_scene(path).description}")
    return 0
