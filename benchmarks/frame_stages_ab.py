"""A/B of the stages around the kernels of a whole render, for several trees on one machine (BENCHMARKS.md, "The
stages around the kernels").

    python3 benchmarks/frame_stages_ab.py ROUNDS OUT.json LABEL=TREE [LABEL=TREE ...]

Each tree gets its own ``NUMBA_CACHE_DIR``; one cold process per tree (all at once) fills it: ``vlref render``'s
path of (b) at 320x180 and the shadow maps of ``cage`` and ``window``. Then ``ROUNDS`` rounds, each the trees in
order and then in reverse (A, B, C, C, B, A). A tree's label ending in ``-maps`` only measures the shadow maps.
Each process of a tree has the bench's ``whole_render`` run in a fresh process (``vlref render`` of (b) at
1920x1080x64, four shadowed lights, warm cache: wall and stage split), then measures in itself (medians of 5 after
a warm-up call): ``ray_directions`` of a new 1080p camera, ``raycast`` of (b) at 1080p with a new camera (the
directions included, as in a render) and with one camera (the bench's ``raycast`` figure), the shadow maps of (b)
at 1080p and of ``cage`` and ``window`` at 320x180 (medians of 9), and SHA-256 digests of the directions, the
G-buffer and the scene colour (``digest``) and of the shadow maps (``maps_digest``), which must agree between the
trees.
"""

import json
import os
import subprocess
import sys

CHILD = """
import hashlib, json, sys, time
import numpy as np
from vlref.bench.config import bench_scene, median_time as median
from vlref.bench.renders import _whole
from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry, raycast
from vlref.lights import pack_lights
from vlref.lights.shading import scene_colour
from vlref.lights.shadow_cast import build_shadow_maps
from vlref.scene import load_scene
maps_only = sys.argv[1] == "1"
out = {}
if not maps_only:
    whole = _whole(None, 1920, 1080, 64, "four", 1024)
    out.update(whole_s=whole["process_s"], split=whole["split"])
scene = bench_scene(1920, 1080, 64, "four", 1024)
fresh = lambda: camera_from_settings(scene.camera, 1920, 1080)
camera, geometry, packed = fresh(), build_geometry(scene), pack_lights(scene)
digest = hashlib.sha256()
if not maps_only:
    out["directions_s"] = median(lambda: fresh().ray_directions(copy=False), 5)
    out["raycast_new_camera_s"] = median(lambda: raycast(scene, fresh(), geometry), 5)
    out["raycast_s"] = median(lambda: raycast(scene, camera, geometry), 5)
    g = raycast(scene, camera, geometry)
    digest.update(camera.ray_directions(copy=False).tobytes())
    for name in ("depth", "distance", "position", "normal", "albedo", "emission", "object_id"):
        digest.update(np.ascontiguousarray(getattr(g, name)).tobytes())
    digest.update(scene_colour(g, scene, geometry, packed).tobytes())
out["maps_b_s"] = median(lambda: build_shadow_maps(scene, camera, geometry, packed), 5)
maps = build_shadow_maps(scene, camera, geometry, packed)
maps_digest = hashlib.sha256(maps.data.tobytes() + maps.tint.tobytes())
for name in ("cage", "window"):
    s = load_scene(name, ["render.width=320", "render.height=180"])
    c, geo, p = camera_from_settings(s.camera, 320, 180), build_geometry(s), pack_lights(s)
    out[f"maps_{name}_s"] = median(lambda: build_shadow_maps(s, c, geo, p), 9)
    m = build_shadow_maps(s, c, geo, p)
    maps_digest.update(m.data.tobytes() + m.tint.tobytes())
out["digest"], out["maps_digest"] = digest.hexdigest()[:16], maps_digest.hexdigest()[:16]
print(json.dumps(out))
"""

COLD = """
import tempfile
from vlref.bench.config import bench_scene
from vlref.camera import camera_from_settings
from vlref.cli.render import render_to_folder
from vlref.geometry import build_geometry
from vlref.lights import pack_lights
from vlref.lights.shadow_cast import build_shadow_maps
from vlref.scene import load_scene
with tempfile.TemporaryDirectory() as folder:
    render_to_folder(bench_scene(320, 180, 64, "four", 1024), folder + "/out")
for name in ("cage", "window"):
    s = load_scene(name, ["render.width=32", "render.height=18"])
    build_shadow_maps(s, camera_from_settings(s.camera, 32, 18), build_geometry(s), pack_lights(s))
"""


def _env(tree: str, label: str) -> dict:
    return dict(os.environ, PYTHONPATH=os.path.abspath(tree) + os.pathsep + os.environ.get("PYTHONPATH", ""),
                NUMBA_CACHE_DIR=f"/tmp/nc-frame-stages-{label}")


def _median(values):
    values = sorted(values)
    return values[len(values) // 2]


def main(rounds: int, out: str, trees: dict) -> None:
    cold = {label: subprocess.Popen([sys.executable, "-c", COLD], cwd=tree, env=_env(tree, label),
                                    stdout=subprocess.DEVNULL) for label, tree in trees.items()}
    for label, proc in cold.items():
        if proc.wait():
            raise SystemExit(f"cold render of {label} failed")
    results = {label: [] for label in trees}
    order = list(trees) + list(trees)[::-1]
    for _ in range(rounds):
        for label in order:
            proc = subprocess.run([sys.executable, "-c", CHILD, "1" if label.endswith("-maps") else "0"],
                                  cwd=trees[label], env=_env(trees[label], label), capture_output=True, text=True)
            if proc.returncode:
                raise SystemExit(f"{label}: {proc.stderr[-3000:]}")
            results[label].append(json.loads(proc.stdout.strip().splitlines()[-1]))
            print(label, json.dumps(results[label][-1]), flush=True)
            with open(out, "w") as f:
                json.dump(results, f, indent=1)
    for key in ("digest", "maps_digest"):
        print(key, {label: sorted({r[key] for r in rs}) for label, rs in results.items()})
    for key in results[order[0]][0]:
        if key in ("digest", "maps_digest", "split"):
            continue
        print(key, "  ".join(f"{label} {_median(r[key] for r in rs if key in r):.4g}"
                              for label, rs in results.items() if any(key in r for r in rs)))
    for stage in results[order[0]][0].get("split", {}):
        print("split", stage, "  ".join(f"{label} {_median(r['split'][stage] for r in rs):.3f}"
                                        for label, rs in results.items() if "split" in rs[0]))


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2], dict(arg.split("=", 1) for arg in sys.argv[3:]))
