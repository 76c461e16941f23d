"""Whole-frame A/B of two trees on one machine (BENCHMARKS.md, "Whole frame"): ray cast, shadow maps, post passes
and ``vlref render`` of scene (b) at 1080p in fresh processes, with the stage split.

Run from a tree's root, once with ``warm`` (compiles into the tree's ``NUMBA_CACHE_DIR`` at the QUICK sizes), then
with ``time`` (FULL sizes, bundled scenes off, medians of 3):

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/whole_frame_ab.py warm LABEL
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/whole_frame_ab.py time LABEL

The whole render is written out step by step (render, preview exposure, ``save_render``) so that a tree without
:func:`vlref.cli.render.render_to_folder` measures the same path; the report goes to ``$OUT/LABEL_PHASE.json``
and a summary to stdout.
"""

import dataclasses
import json
import os
import subprocess
import sys
import time

from vlref.bench.config import FULL, QUICK
from vlref.bench.stages import bench_geometry, bench_post

CHILD = """
import json, tempfile, time
t0 = time.perf_counter()
from vlref.bench import bench_scene
from vlref.cli.options import preview_exposure
from vlref.io.output_folders import output_dir
from vlref.io.render_files import save_render
from vlref.render import render
t1 = time.perf_counter()
scene = bench_scene({w}, {h}, 64, "four", {res})
with tempfile.TemporaryDirectory() as folder:
    result = render(scene)
    t2 = time.perf_counter()
    exposure, png_meta, _ = preview_exposure(scene, result.buffers["final"])
    with output_dir(folder + "/out") as out:
        save_render(out, result, stages=False, main=("final", "depth", "inscatter", "transmittance"),
                    exposure=exposure, png_meta=png_meta)
    t3 = time.perf_counter()
print(json.dumps({{"import_s": t1 - t0, "stages": result.timings, "write_s": t3 - t2, "in_process_s": t3 - t0}}))
"""


def whole_render(cfg, runs: int) -> list[dict]:
    code = CHILD.format(w=cfg.width, h=cfg.height, res=cfg.shadow_resolution)
    out = []
    for _ in range(runs):
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        report = json.loads(proc.stdout.strip().splitlines()[-1])
        report["process_s"] = time.perf_counter() - start
        out.append(report)
    return out


def main(phase: str, label: str) -> None:
    cfg = dataclasses.replace(FULL if phase == "time" else QUICK, bundled=(), repeats=3)
    raycast, shadow_maps = bench_geometry(cfg)
    post = {name: s["seconds"] for name, s in bench_post(cfg).items()}
    runs = whole_render(cfg, 3 if phase == "time" else 1)
    report = {"label": label, "raycast": raycast, "shadow_maps": shadow_maps, "post": post, "whole_render_runs": runs}
    with open(os.path.join(os.environ.get("OUT", "."), f"{label}_{phase}.json"), "w") as fh:
        json.dump(report, fh, indent=1)
    for name, s in raycast.items():
        sm = shadow_maps[name]
        print(f"{label} {name}: ray cast {s['rays_per_s'] / 1e6:.1f} M rays/s; shadow maps {sm['seconds']:.3f} s, "
              f"{sm['texels_per_s'] / 1e6:.1f} M texels/s")
    print(f"{label} post (ms): " + ", ".join(f"{k} {v * 1e3:.1f}" for k, v in post.items()))
    for r in runs:
        split = ", ".join(f"{k} {v:.3f}" for k, v in r["stages"].items())
        print(f"{label} whole render {r['process_s']:.2f} s: import {r['import_s']:.3f}, {split}, "
              f"write {r['write_s']:.3f}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
