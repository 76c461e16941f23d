"""The whole ``vlref render`` of (b) at 1920x1080x64, two trees alternated on one machine, each with its own Numba
cache (BENCHMARKS.md, "One pass for the lights' sum and the composite; the render without the reference"): for trees
whose kernel files differ, where one cache cannot serve both.

    python3 benchmarks/whole_render_ab.py OUT_DIR PAIRS A_TREE B_TREE [CACHE_ROOT]

1. Each tree's cache (``CACHE_ROOT/a``, ``CACHE_ROOT/b``) is filled by a cold render of (b) at 320x180 through
   ``render_to_folder`` (both trees at once), then one 1080p whole render of each is run and dropped.
2. ``PAIRS`` rounds of A, B, B, A: each run is the tree's own ``vlref.bench.renders.bench_whole_render`` with one
   repeat (a fresh process that imports what ``vlref render`` imports, renders (b), writes its default outputs
   and ends as the program ends), started from a parent process of that tree (the parent's own start is not
   timed); the process wall time and its split, with ``rest``: the process wall less the split's parts.
3. The buffers of (b) at 1080p x 64 of each tree (every buffer of the render, the per-light buffers included)
   and the files ``vlref render`` writes, hashed.

Writes ``OUT_DIR/whole_render_ab.json`` after every run.
"""

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ONE = """
import dataclasses, json
from vlref.bench.config import FULL
from vlref.bench.renders import bench_whole_render
print(json.dumps(bench_whole_render(dataclasses.replace(FULL, repeats=1))))
"""

COLD = """
import tempfile
from vlref.bench import bench_scene
from vlref.cli.render import render_to_folder
if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as f:
        render_to_folder(bench_scene(320, 180, 64, "four", 1024), f + "/out")
"""

HASH = """
import hashlib, json, pathlib, tempfile
from vlref.cli.commands import program_command
render_to_folder = program_command("render").render_to_folder
from vlref.bench import bench_scene
if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as d:
        result, _, _, _ = render_to_folder(bench_scene(1920, 1080, 64, "four", 1024), d + "/out", stages=True)
        out = {"buffer " + k: hashlib.sha256(v.tobytes()).hexdigest()[:16] for k, v in sorted(result.buffers.items())}
        out.update({"file " + p.name: hashlib.sha256(p.read_bytes()).hexdigest()[:16]
                    for p in sorted(pathlib.Path(d, "out").iterdir())})
    print(json.dumps(out))
"""


def main(out_dir: str, pairs: int, a: str, b: str, cache_root: str = "/tmp/wrab") -> None:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    trees = {"A": Path(a).resolve(), "B": Path(b).resolve()}

    def env(label: str) -> dict:
        return dict(os.environ, PYTHONPATH=os.pathsep.join([str(trees[label]), os.environ.get("PYTHONPATH", "")]),
                    NUMBA_CACHE_DIR=f"{cache_root}/{label.lower()}")

    def py(label: str, code: str, **kw) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-c", code], env=env(label), cwd=trees[label], capture_output=True,
                              text=True, **kw)

    report = {"trees": {k: str(v) for k, v in trees.items()}, "runs": {"A": [], "B": []}}
    start = time.perf_counter()
    cold = {label: subprocess.Popen([sys.executable, "-c", COLD], env=env(label), cwd=trees[label])
            for label in trees}
    for label, proc in cold.items():
        if proc.wait() != 0:
            raise SystemExit(f"cold render of {label} failed")
    report["cold_both_s"] = time.perf_counter() - start
    print(f"cold renders (both trees at once): {report['cold_both_s']:.1f} s", flush=True)
    for label in trees:
        py(label, ONE, check=True)  # dropped: the first 1080p render of each tree

    def run(label: str) -> None:
        whole = json.loads(py(label, ONE, check=True).stdout.strip().splitlines()[-1])
        # what the process spent outside every part of the split (the bench's scene unpickled, the render's set-up
        # before its first stage and its result after its last, the child's output folder removed)
        whole["split"]["rest"] = whole["seconds"] - sum(whole["split"].values())
        report["runs"][label].append(whole)
        print(label, f"{whole['seconds']:.3f} s;", ", ".join(f"{k} {v:.3f}" for k, v in whole["split"].items()),
              flush=True)
        report["median"] = {k: {"seconds": statistics.median(r["seconds"] for r in runs),
                                **{s: statistics.median(r["split"][s] for r in runs) for s in runs[0]["split"]}}
                            for k, runs in report["runs"].items() if runs}
        (out / "whole_render_ab.json").write_text(json.dumps(report, indent=1))

    for _ in range(pairs):
        for label in ("A", "B", "B", "A"):
            run(label)
    m = report["median"]
    report["ratio_B_over_A"] = m["B"]["seconds"] / m["A"]["seconds"]
    print("medians:", json.dumps(m), "B/A", round(report["ratio_B_over_A"], 4), flush=True)
    hashes = {label: json.loads(py(label, HASH, check=True).stdout.strip().splitlines()[-1]) for label in trees}
    report["hashes"] = hashes
    report["same_bytes"] = hashes["A"] == hashes["B"]
    print("same bytes:", report["same_bytes"], json.dumps(hashes["B"]), flush=True)
    (out / "whole_render_ab.json").write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], *sys.argv[5:])
