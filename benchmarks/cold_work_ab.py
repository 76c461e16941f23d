"""A/B of two trees (BENCHMARKS.md, "Cold first render on two cores, second round"): the cold first render's CPU per
process, then the warm kernels whose compile changed.

    python3 benchmarks/cold_work_ab.py cold TREE_A TREE_B [ROUNDS] [THREADS]
    python3 benchmarks/cold_work_ab.py warm TREE_A TREE_B [ROUNDS] [THREADS] [WIDTH HEIGHT]
    python3 benchmarks/cold_work_ab.py both TREE_A TREE_B [ROUNDS] [THREADS] [WIDTH HEIGHT]

``cold``: ``ROUNDS`` alternated rounds (B, A, A, B, ...) of ``vlref bench``'s ``first_render`` (scene (a) at 320x180x64,
one spot, in a fresh process with a fresh ``NUMBA_CACHE_DIR``, ``vlref render``'s path with its compile ahead), each
with its wall, its stages and the CPU seconds (user + sys) of the main process and of its compile-ahead children.
``THREADS`` (default: all) caps the cores the render sees (``taskset`` of the first cores): ``2`` reproduces the
2-core box's one compile process on a bigger machine. ``warm``: alternated rounds of one fresh process per tree
(its cache filled by a first call) timing, at ``WIDTH x HEIGHT`` (default 1920x1080), medians of 5: the march
of (a) and (b) in float64 (:func:`~vlref.techniques.physical.march_buffers`), the ray cast, the shadow maps and the
scene colour of (b), with the cache of the tree's last cold run (``both``: the cold rounds, then the warm ones).
Prints one JSON line per measurement.
"""

import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import time

CPU = r'''
import resource
own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"cpu_main_s": own.ru_utime + own.ru_stime, "cpu_children_s": children.ru_utime + children.ru_stime}))
'''
"""Put into ``vlref.bench.renders._WHOLE`` (the first render's child) after its report: the CPU seconds of its
processes (before the child's exit, which may end the process at once)."""


def _with_cpu(child: str) -> str:
    lines = child.split("\n")
    end = max(i for i, line in enumerate(lines) if line.startswith("exit_at_once("))  # after the report, before the exit
    return "\n".join(lines[:end] + CPU.strip("\n").split("\n") + lines[end:])

WARM = r'''
import json, sys
import numpy as np
from vlref.bench.config import bench_scene, median_time
from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry, raycast
from vlref.lights import pack_lights
from vlref.lights.shading import scene_colour
from vlref.lights.shadow_cast import build_shadow_maps
from vlref.render import prepare_frame
from vlref.scene.technique_params import resolved
from vlref.techniques.physical import march_buffers
w, h = int(sys.argv[1]), int(sys.argv[2])
out = {}
for name, lights in (("a", "one"), ("b", "four")):
    scene = bench_scene(w, h, 64, lights, 1024)
    frame = prepare_frame(scene)
    args = (scene, frame.camera, frame.gbuffer.distance, frame.lights, frame.shadow_maps(), frame.geometry.arrays,
            resolved(scene, "steps"), resolved(scene, "sampling"))
    march_buffers(*args)
    out[f"march_{name}_s"] = median_time(lambda: march_buffers(*args), 5)
cam = camera_from_settings(scene.camera, w, h)
geometry = build_geometry(scene)
packed = pack_lights(scene)
gbuffer = raycast(scene, cam, geometry)
out["raycast_s"] = median_time(lambda: raycast(scene, cam, geometry), 5)
out["shadow_maps_s"] = median_time(lambda: build_shadow_maps(scene, cam, geometry, packed), 5)
out["scene_colour_s"] = median_time(lambda: scene_colour(gbuffer, scene, geometry, packed), 5)
print(json.dumps(out))
'''


def _run(tree: str, code: str, args: list, cache: str, threads: int | None, reports: int = 1) -> dict:
    path = os.pathsep.join(p for p in (os.path.abspath(tree), os.environ.get("PYTHONPATH")) if p)
    env = dict(os.environ, PYTHONPATH=path, NUMBA_CACHE_DIR=cache)
    pin = ["taskset", "-c", f"0-{threads - 1}"] if threads else []
    start = time.perf_counter()
    proc = subprocess.run([*pin, sys.executable, "-c", code, *args], env=env, capture_output=True, text=True, cwd="/tmp")
    if proc.returncode:
        raise SystemExit(f"{tree}: {proc.stderr[-3000:]}")
    lines = proc.stdout.strip().splitlines()
    report = {}
    for line in lines[-reports:]:  # the cold child's report, then its CPU
        report.update(json.loads(line))
    report["process_s"] = time.perf_counter() - start
    return report


def _order(rounds: int) -> list:
    return [label for r in range(rounds) for label in (("B", "A") if r % 2 == 0 else ("A", "B"))]


def main(what: str, tree_a: str, tree_b: str, rounds: str = "2", threads: str = "0", width: str = "1920",
         height: str = "1080") -> None:
    sys.path.insert(0, os.path.abspath(tree_a))
    from vlref.bench.config import bench_scene
    from vlref.bench.renders import _WHOLE
    trees, cap = {"A": tree_a, "B": tree_b}, int(threads) or None
    work = tempfile.mkdtemp(prefix="vlref_cold_work_ab_")
    try:
        scene_file = os.path.join(work, "scene.pickle")
        with open(scene_file, "wb") as fh:
            pickle.dump(bench_scene(320, 180, 64, "one", 1024), fh)
        for kind in ("cold", "warm") if what == "both" else (what,):
            for label in _order(int(rounds)):
                cache = os.path.join(work, f"nc-{label}")  # warm: the cache of the tree's last cold run, if any
                if kind == "cold":
                    shutil.rmtree(cache, ignore_errors=True)
                    report = _run(trees[label], _with_cpu(_WHOLE), [scene_file], cache, cap, reports=2)
                else:
                    report = _run(trees[label], WARM, [width, height], cache, cap)
                print(label, kind, json.dumps(report), flush=True)
    finally:
        shutil.rmtree(work)


if __name__ == "__main__":
    main(*sys.argv[1:])
