"""The frame around the kernels, two trees alternated on one machine (BENCHMARKS.md, "The frame around the
kernels"): the cold first render of ``vlref render``'s path and the whole ``vlref render`` of scene (b) at 1080p in
fresh processes with a warm cache, with the stage split.

Run from any folder, naming the trees (each a checkout's root) by label:

    python3 benchmarks/frame_overhead_ab.py OUT_DIR main=/path/to/main branch=/path/to/branch

1. Cold: for each tree, a fresh ``NUMBA_CACHE_DIR`` and one fresh process that renders (a) at 320x180, 64 steps,
   and writes its outputs through the tree's own :func:`vlref.cli.render.render_to_folder` (the command's path:
   its compile spread over processes as that tree does it). That fills the tree's cache.
2. Warm: three rounds, the trees alternated, each tree's own ``vlref.bench.renders.bench_whole_render`` (scene (b),
   1920x1080x64, four shadowed lights, one fresh process a call): wall time and split.

Writes ``OUT_DIR/frame_overhead_ab.json`` and prints a summary.
"""

import json
import os
import subprocess
import sys
import tempfile
import time

COLD = """
import tempfile
from vlref.bench import bench_scene
from vlref.cli.render import render_to_folder
with tempfile.TemporaryDirectory() as folder:
    render_to_folder(bench_scene(320, 180, 64, "one", 1024), folder + "/out")
"""

WARM = """
import dataclasses, json
from vlref.bench.config import FULL
from vlref.bench.renders import bench_whole_render
print(json.dumps(bench_whole_render(dataclasses.replace(FULL, repeats=1))))
"""


def _run(root: str, cache: str, code: str) -> tuple[float, str]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p),
               NUMBA_CACHE_DIR=cache)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True, check=True)
    return time.perf_counter() - start, proc.stdout


def main(out_dir: str, trees: dict[str, str]) -> None:
    caches = {label: tempfile.mkdtemp(prefix=f"nc-{label}-") for label in trees}
    report = {"cold_s": {}, "warm": {label: [] for label in trees}}
    for label, root in trees.items():
        report["cold_s"][label], _ = _run(root, caches[label], COLD)
        print(f"{label} cold first render (a) 320x180: {report['cold_s'][label]:.1f} s", flush=True)
    for _ in range(3):
        for label, root in trees.items():
            _, out = _run(root, caches[label], WARM)
            whole = json.loads(out.strip().splitlines()[-1])
            report["warm"][label].append(whole)
            split = ", ".join(f"{k} {v:.3f}" for k, v in whole["split"].items())
            print(f"{label} whole render (b) 1080p: {whole['seconds']:.2f} s: {split}", flush=True)
    with open(os.path.join(out_dir, "frame_overhead_ab.json"), "w") as fh:
        json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv[1], dict(arg.split("=", 1) for arg in sys.argv[2:]))
