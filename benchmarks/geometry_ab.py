"""A/B of the camera ray cast and the shadow-map casting of two trees on one machine (BENCHMARKS.md, "Whole frame").

    python3 benchmarks/geometry_ab.py TREE_A TREE_B [ROUNDS]

Each tree runs in fresh processes with its own ``NUMBA_CACHE_DIR`` (one warm-up process each, in parallel, which
compiles), then ``ROUNDS`` alternated rounds A, B, A, B, ...: :func:`vlref.bench.stages.bench_geometry` of the bench
scene (b) at 1920x1080 with four shadowed lights at 1024² (medians of 5), the first ``build_geometry`` of the
process (what the ``geometry`` stage of a fresh ``vlref render`` holds), and SHA-256 digests of the G-buffer and
the maps, which must agree between the trees. Prints one JSON line per process and a summary.
"""

import json
import os
import subprocess
import sys

CHILD = """
import dataclasses, hashlib, json, time
import numpy as np
t0 = time.perf_counter()
from vlref.bench.config import FULL, bench_scene
from vlref.geometry import build_geometry
t1 = time.perf_counter()
scene = bench_scene(1920, 1080, 64, "four", 1024)
geometry = build_geometry(scene)
t2 = time.perf_counter()
from vlref.bench.stages import bench_geometry
from vlref.camera import camera_from_settings
from vlref.geometry import raycast
from vlref.lights import pack_lights
from vlref.render import prepare_frame
cfg = dataclasses.replace(FULL, bundled=(), repeats=REPEATS)
rc, sm = bench_geometry(cfg)
camera = camera_from_settings(scene.camera, 1920, 1080)
g = raycast(scene, camera, geometry)
frame = prepare_frame(scene)
maps = frame.shadow_maps()
digest = hashlib.sha256()
for a in (g.depth, g.distance, g.position, g.normal, g.albedo, g.emission, g.object_id, maps.data, maps.tint):
    digest.update(np.ascontiguousarray(a).tobytes())
print(json.dumps({"rays_per_s": rc["bench_four_lights"]["rays_per_s"], "raycast_s": rc["bench_four_lights"]["seconds"],
                  "texels_per_s": sm["bench_four_lights"]["texels_per_s"], "maps_s": sm["bench_four_lights"]["seconds"],
                  "texels": sm["bench_four_lights"]["texels"], "import_s": t1 - t0, "first_build_geometry_s": t2 - t1,
                  "digest": digest.hexdigest()[:16]}))
"""


def child(tree: str, label: str, repeats: int) -> dict:
    env = dict(os.environ, PYTHONPATH=os.path.abspath(tree) + os.pathsep + os.environ.get("PYTHONPATH", ""),
               NUMBA_CACHE_DIR=f"/tmp/nc-geometry-ab-{label}")
    proc = subprocess.run([sys.executable, "-c", CHILD.replace("REPEATS", str(repeats))], env=env,
                          capture_output=True, text=True, cwd=tree)
    if proc.returncode:
        raise SystemExit(f"{label}: {proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(tree_a: str, tree_b: str, rounds: int = 2) -> None:
    trees = {"A": tree_a, "B": tree_b}
    warm = {label: subprocess.Popen(
        [sys.executable, "-c", CHILD.replace("REPEATS", "1")], cwd=tree, stdout=subprocess.DEVNULL,
        env=dict(os.environ, PYTHONPATH=os.path.abspath(tree) + os.pathsep + os.environ.get("PYTHONPATH", ""),
                 NUMBA_CACHE_DIR=f"/tmp/nc-geometry-ab-{label}")) for label, tree in trees.items()}
    for label, proc in warm.items():
        if proc.wait():
            raise SystemExit(f"warm-up of {label} failed")
    results = {"A": [], "B": []}
    for _ in range(rounds):
        for label, tree in trees.items():
            r = child(tree, label, 5)
            results[label].append(r)
            print(label, json.dumps(r), flush=True)
    digests = {label: {r["digest"] for r in rs} for label, rs in results.items()}
    print("same bits:", digests["A"] == digests["B"] and len(digests["A"]) == 1, digests)
    for key in ("rays_per_s", "texels_per_s", "first_build_geometry_s"):
        a = sorted(r[key] for r in results["A"])
        b = sorted(r[key] for r in results["B"])
        print(f"{key}: A {a}  B {b}  B/A (medians) {b[len(b) // 2] / a[len(a) // 2]:.2f}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], *map(int, sys.argv[3:]))
