"""The parts of the whole ``vlref render`` of (b) at 1920x1080 in fresh processes, two trees on one machine
(BENCHMARKS.md, "SciPy's BLAS threads, kernels loaded ahead"): run after ``whole_render_ab.py`` with the same
``CACHE_ROOT``, whose caches it uses.

    python3 benchmarks/render_parts.py OUT_DIR ROUNDS A_TREE B_TREE [CACHE_ROOT]

Each run is a fresh process of a tree that imports what ``vlref render`` imports, renders (b) at 1080p x 64 with
``render_to_folder`` and ends with ``exit_at_once``; it reports the render's stages, the write, the wall time of
``render_to_folder``, the process's threads at the end, and inside its ray-cast stage the wall time and minor page
faults of each part: the camera's rays, ``tree_spans``, ``work`` (the rows' kernel loaded), the launcher's first
call (its load and the first parallel launch), the same call again on the same buffers (the kernel alone, warm),
and the whole ``raycast`` (the rest: the buffers' allocation, the arguments).

1. ``ROUNDS`` rounds of A, B, F, F, B, A (F: A's tree with Numba initialised in full before the render, as before
   its initialisation was deferred to the first compile);
2. ``ROUNDS`` rounds of L, C, C, L in B's tree: the render with (C) or without (L) the kernels loaded ahead on a
   thread (:func:`vlref.ahead.compile_ahead`);
3. ``ROUNDS`` rounds of U, C, C, U in B's tree: SciPy's BLAS loaded with (C) or without (U) its threads kept to one
   (:mod:`vlref.jit_init`).

Writes ``OUT_DIR/render_parts.json``.
"""

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

CHILD = """
import json, os, pickle, resource, sys, tempfile, time
def now():
    return time.perf_counter(), resource.getrusage(resource.RUSAGE_SELF).ru_minflt
from vlref.cli.commands import exit_at_once, program_command
command = program_command("render")
rc = sys.modules["vlref.geometry.raycast"]  # the package's attribute of that name is the function
from vlref.camera import Camera
parts = {}
def timed(name, fn, again=False):
    def wrapper(*a, **k):
        s = now()
        out = fn(*a, **k)
        e = now()
        if name in parts:  # the first call only (the rays are asked for again, cached, by the march)
            return out
        parts[name] = [e[0] - s[0], e[1] - s[1]]
        if again:
            s = now()
            fn(*a, **k)
            e = now()
            parts[name + " again"] = [e[0] - s[0], e[1] - s[1]]
        return out
    return wrapper
Camera.ray_directions = timed("rays", Camera.ray_directions)
rc.tree_spans = timed("tree_spans", rc.tree_spans)
rc.work = timed("work", rc.work)
rc._raycast_kernel = timed("kernel", rc._raycast_kernel, again=True)
rc.raycast = timed("raycast", rc.raycast)
if sys.argv[2] == "F":  # Numba initialised in full before the render, as before its deferred initialisation
    from vlref.jit_init import initialise_numba
    initialise_numba(compiling=True)
if sys.argv[2] == "L":  # no kernel loaded ahead on a thread
    import vlref.ahead
    vlref.ahead._to_load_ahead = lambda scene, cold: []
if sys.argv[2] == "U":  # SciPy's BLAS loaded as Numba loads it, its threads not kept to one
    import contextlib
    import vlref.jit_init
    vlref.jit_init._blas_on_one_thread = lambda when: contextlib.nullcontext()
import vlref.render
vlref.render.raycast = rc.raycast
with open(sys.argv[1], "rb") as fh:
    scene = pickle.load(fh)
with tempfile.TemporaryDirectory() as folder:
    start = time.perf_counter()
    result, _, write_s, _ = command.render_to_folder(scene, folder + "/out")
    parts["write"] = [write_s, None]
    parts["render_to_folder"] = [time.perf_counter() - start, None]
parts["stages"] = result.timings
parts["threads"] = [len(os.listdir("/proc/self/task")), None]
print(json.dumps(parts), flush=True)
exit_at_once(0)
"""

SCENE = """
import pickle, sys
from vlref.bench import bench_scene
open(sys.argv[1], "wb").write(pickle.dumps(bench_scene(1920, 1080, 64, "four", 1024)))
"""


def main(out_dir: str, rounds: int, a: str, b: str, cache_root: str = "/tmp/wrab") -> None:
    out = Path(out_dir)
    trees = {"A": Path(a).resolve(), "B": Path(b).resolve()}
    scene = Path(cache_root) / "render_parts_scene.pickle"

    def run(label: str, code: str, *args: str) -> dict:
        tree = trees[label]
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tree), os.environ.get("PYTHONPATH", "")]),
                   NUMBA_CACHE_DIR=f"{cache_root}/{label.lower()}")
        proc = subprocess.run([sys.executable, "-c", code, *args], env=env, cwd=tree, capture_output=True, text=True,
                              check=True)
        return json.loads(proc.stdout.strip().splitlines()[-1]) if proc.stdout.strip() else {}

    run("B", SCENE, str(scene))
    report = {"trees": {k: str(v) for k, v in trees.items()}, "raycast": {"A": [], "B": [], "F": []},
              "load": {"L": [], "C": []}, "blas": {"U": [], "C": []}}

    def medians(runs: list) -> dict:
        names = [n for n in runs[0] if n not in ("stages", "write", "render_to_folder", "threads")]
        return {n: round(statistics.median(r[n][0] for r in runs), 4) for n in names} | {
            n + " faults": statistics.median(r[n][1] for r in runs) for n in names}

    for _ in range(rounds):
        for label in ("A", "B", "F", "F", "B", "A"):
            parts = run("A" if label == "F" else label, CHILD, str(scene), label)
            report["raycast"][label].append(parts)
            print("raycast", label, json.dumps({k: v for k, v in parts.items() if k != "stages"}), flush=True)
    report["raycast_medians"] = {k: medians(v) for k, v in report["raycast"].items()}
    print("raycast medians", json.dumps(report["raycast_medians"]), flush=True)
    (out / "render_parts.json").write_text(json.dumps(report, indent=1))
    def in_branch(section: str, modes: tuple) -> None:
        """``rounds`` rounds of ``modes`` in B's tree; per mode the medians of the write, ``render_to_folder`` and
        each stage."""
        for _ in range(rounds):
            for mode in modes:
                parts = run("B", CHILD, str(scene), mode)
                report[section][mode].append(parts)
                print(section, mode, round(parts["write"][0], 4), round(parts["render_to_folder"][0], 4),
                      json.dumps(parts["stages"]), flush=True)
        report[section + "_medians"] = {
            k: {"write": statistics.median(r["write"][0] for r in v), "threads": [r["threads"][0] for r in v],
                "render_to_folder": statistics.median(r["render_to_folder"][0] for r in v),
                **{s: statistics.median(r["stages"][s] for r in v) for s in v[0]["stages"]}}
            for k, v in report[section].items()}
        print(section, "medians", json.dumps(report[section + "_medians"]), flush=True)
        (out / "render_parts.json").write_text(json.dumps(report, indent=1))

    in_branch("load", ("L", "C", "C", "L"))
    in_branch("blas", ("U", "C", "C", "U"))

if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], *sys.argv[5:])
