"""A/B of the G-buffer stages of two trees on one machine (BENCHMARKS.md, "The G-buffer's bytes").

    python3 benchmarks/gbuffer_ab.py TREE_A TREE_B [ROUNDS] [OUT.json]

Each tree gets its own ``NUMBA_CACHE_DIR``; one cold ``vlref render`` path each (both at once, 320x180) fills it.
Then ``ROUNDS`` alternated rounds A, B, A, B, ...; each is one process of the tree which first has the tree's
``vlref.bench.renders._whole`` render (b) at 1920x1080x64 with four shadowed lights in a fresh process (the bench's
``whole_render``: wall and stage split), then measures, as ``vlref bench``'s ``raycast`` section does, ``raycast`` of
(b) at 1920x1080 (median of 5 after a warm-up call), ``scene_colour`` (median of 3), the ray cast's kernel on
buffers allocated once, the same ray cast with NumPy's huge-page advice off, and SHA-256 digests of every G-buffer
buffer (stored or derived), of the scene colour and of the shadow maps, which must agree between the trees. Prints
one JSON line per process and a summary (medians over the rounds).
"""

import json
import os
import subprocess
import sys

CHILD = """
import hashlib, inspect, json
import numba
import numpy as np
from vlref.bench.config import bench_scene, median_time as median
from vlref.bench.renders import _whole
whole = _whole(None, 1920, 1080, 64, "four", 1024)
from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry, raycast
from vlref.lights import pack_lights
from vlref.lights.shading import scene_colour
from vlref.lights.shadow_cast import build_shadow_maps
scene = bench_scene(1920, 1080, 64, "four", 1024)
camera = camera_from_settings(scene.camera, 1920, 1080)
geometry = build_geometry(scene)
packed = pack_lights(scene)

rc = median(lambda: raycast(scene, camera, geometry), 5)
g = raycast(scene, camera, geometry)
sh = median(lambda: scene_colour(g, scene, geometry, packed), 3)
digest = hashlib.sha256()
for name in ("depth", "distance", "position", "normal", "albedo", "emission", "object_id"):
    digest.update(np.ascontiguousarray(getattr(g, name)).tobytes())
digest.update(scene_colour(g, scene, geometry, packed).tobytes())
maps = build_shadow_maps(scene, camera, geometry, packed)
digest.update(maps.data.tobytes())
digest.update(maps.tint.tobytes())
from vlref.geometry.raycast import _raycast_kernel
forward = np.ascontiguousarray(camera.forward, dtype=np.float64)
stored = ((g.depth, g.distance, g.normal, g.object_id) if hasattr(g, "origin") else  # this tree, or the old one
          (g.depth, g.distance, g.position, g.normal, g.albedo, g.emission, g.object_id))
dirs = np.ascontiguousarray(camera.ray_directions(copy=False))
origin = np.ascontiguousarray(camera.position, dtype=np.float64)
kernel_args = (geometry.arrays, origin, dirs, forward, float(camera.far), *stored)
if "spans" in inspect.signature(_raycast_kernel.py_func).parameters:  # rays left out of the primitive tree
    from vlref.geometry.raycast import kernel_args as cast_args
    kernel_args = cast_args(geometry.arrays, camera, g)
if "cast_rows" in inspect.signature(_raycast_kernel.py_func).parameters:  # the kernel takes its work by address
    from vlref.geometry.raycast import _cast_rows
    from vlref.parallel import COUNTER, work
    kernel_args += (work(_cast_rows, COUNTER, *kernel_args),)
if "workers" in inspect.signature(_raycast_kernel.py_func).parameters:  # one prange iteration per thread
    kernel_args += (numba.get_num_threads(),)
kernel = median(lambda: _raycast_kernel(*kernel_args), 5)
from numpy._core.multiarray import _set_madvise_hugepage
_set_madvise_hugepage(False)
rc_small_pages = median(lambda: raycast(scene, camera, geometry), 5)
print(json.dumps({"rays_per_s": 1920 * 1080 / rc, "raycast_s": rc, "shading_warm_s": sh,
                  "rays_per_s_no_hugepage_advice": 1920 * 1080 / rc_small_pages,
                  "rays_per_s_kernel_reused_buffers": 1920 * 1080 / kernel, "whole_s": whole["process_s"],
                  "split": whole["split"], "digest": digest.hexdigest()[:16]}))
"""

COLD = """
import tempfile
from vlref.bench.config import bench_scene
from vlref.cli.render import render_to_folder
with tempfile.TemporaryDirectory() as folder:
    render_to_folder(bench_scene(320, 180, 64, "four", 1024), folder + "/out")
"""


def _env(tree: str, label: str) -> dict:
    return dict(os.environ, PYTHONPATH=os.path.abspath(tree) + os.pathsep + os.environ.get("PYTHONPATH", ""),
                NUMBA_CACHE_DIR=f"/tmp/nc-gbuffer-ab-{label}")


def main(tree_a: str, tree_b: str, rounds: int = 3, out: str | None = None) -> None:
    trees = {"A": tree_a, "B": tree_b}
    cold = {label: subprocess.Popen([sys.executable, "-c", COLD], cwd=tree, env=_env(tree, label),
                                    stdout=subprocess.DEVNULL) for label, tree in trees.items()}
    for label, proc in cold.items():
        if proc.wait():
            raise SystemExit(f"cold render of {label} failed")
    results = {"A": [], "B": []}
    for _ in range(rounds):
        for label, tree in trees.items():
            proc = subprocess.run([sys.executable, "-c", CHILD], cwd=tree, env=_env(tree, label), capture_output=True,
                                  text=True)
            if proc.returncode:
                raise SystemExit(f"{label}: {proc.stderr[-3000:]}")
            results[label].append(json.loads(proc.stdout.strip().splitlines()[-1]))
            print(label, json.dumps(results[label][-1]), flush=True)
            if out:
                with open(out, "w") as f:
                    json.dump(results, f, indent=1)
    digests = {label: sorted({r["digest"] for r in rs}) for label, rs in results.items()}
    print("same bits:", digests["A"] == digests["B"] and len(digests["A"]) == 1, digests)

    def med(values):
        values = sorted(values)
        return values[len(values) // 2]

    for key in ("rays_per_s", "rays_per_s_no_hugepage_advice", "rays_per_s_kernel_reused_buffers", "shading_warm_s",
                "whole_s"):
        a, b = med(r[key] for r in results["A"]), med(r[key] for r in results["B"])
        print(f"{key}: A {a:.4g}  B {b:.4g}  B/A {b / a:.3f}")
    for stage in results["A"][0]["split"]:
        a = med(r["split"][stage] for r in results["A"])
        b = med(r["split"].get(stage, float("nan")) for r in results["B"])
        print(f"split {stage}: A {a:.3f}  B {b:.3f}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], *(int(a) for a in sys.argv[3:4]), *sys.argv[4:5])
