"""A/B of two trees' cold first render and camera ray cast on one machine (BENCHMARKS.md, "The G-buffer's bytes").

    python3 benchmarks/cold_raycast_ab.py TREE_A TREE_B [ROUNDS]

First, one after the other (B, then A), each tree's cold first render as ``vlref bench``'s ``first_render``
measures it (the tree's ``vlref.bench.renders._whole`` with a fresh ``NUMBA_CACHE_DIR``: (a) at 320x180x64, one spot,
in a fresh process, its compile spread over processes as ``vlref render`` does). Then ``ROUNDS`` alternated rounds A,
B, ...: one process of each tree (with the cache its cold render filled) measures ``raycast`` of (b) at 1920x1080 as
``vlref bench``'s ``raycast`` section does (median of 5 after a warm-up call). Prints one JSON line per measurement.
"""

import json
import os
import subprocess
import sys

COLD = """
import json, sys
from vlref.bench.renders import _whole
print(json.dumps(_whole(sys.argv[1], 320, 180, 64, "one", 1024)))
"""

RAYCAST = """
import json
from vlref.bench.config import bench_scene, median_time
from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry, raycast
scene = bench_scene(1920, 1080, 64, "four", 1024)
camera = camera_from_settings(scene.camera, 1920, 1080)
geometry = build_geometry(scene)
seconds = median_time(lambda: raycast(scene, camera, geometry), 5)
print(json.dumps({"raycast_s": seconds, "rays_per_s": 1920 * 1080 / seconds}))
"""


def _run(tree: str, label: str, code: str) -> dict:
    cache = f"/tmp/nc-cold-ab-{label}"
    env = dict(os.environ, PYTHONPATH=os.path.abspath(tree) + os.pathsep + os.environ.get("PYTHONPATH", ""),
               NUMBA_CACHE_DIR=cache)
    proc = subprocess.run([sys.executable, "-c", code, cache], cwd=tree, env=env, capture_output=True, text=True)
    if proc.returncode:
        raise SystemExit(f"{label}: {proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(tree_a: str, tree_b: str, rounds: int = 2) -> None:
    trees = {"A": tree_a, "B": tree_b}
    for label, tree in reversed(trees.items()):  # B first: A's imports then find the OS's file cache warmer
        cold = _run(tree, label, COLD)
        print(label, "cold", json.dumps({"process_s": cold["process_s"], "split": cold["split"]}), flush=True)
    for _ in range(rounds):
        for label, tree in trees.items():
            print(label, "raycast", json.dumps(_run(tree, label, RAYCAST)), flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], *map(int, sys.argv[3:]))
