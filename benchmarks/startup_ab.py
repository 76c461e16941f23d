"""The whole ``vlref render`` and its writing, main and a branch alternated on one machine with ONE Numba cache
(BENCHMARKS.md, "Start-up and writing"): for a branch that changes no file holding a kernel, the branch's changed
files are copied over main's checkout and back between runs, so one cold compile serves both.

    cd MAIN_CHECKOUT && NUMBA_CACHE_DIR=... python3 BRANCH/benchmarks/startup_ab.py OUT_DIR SECONDS BRANCH [VARIANT]

1. The branch's changed files under ``vlref/`` (against the checkout in the current folder) are listed; a file that
   holds ``@njit`` code stops the run (a copied kernel file would miss the cache, or fill it for one tree only).
2. With main's files: a cold render of scene (b) at 64x36 through ``render_to_folder`` fills the cache.
3. Rounds main, branch, branch, main, main, branch: each tree's own ``vlref.bench.renders.bench_whole_render``
   (scene (b), 1920x1080x64, four shadowed lights, one fresh process a run; the module reloaded after each swap),
   its wall time and split; ``write`` is the bench's "writing the default outputs" figure.
4. While time is left (``SECONDS`` since the start): the branch once more under cProfile (one fresh process,
   ``render_to_folder`` profiled, the 45 largest cumulative entries to ``OUT_DIR/profile_branch.txt``), then
   ``VARIANT`` (another tree, e.g. the branch with one change more) twice.

Main's files are back in place at the end. Writes ``OUT_DIR/startup_ab.json`` after every run.
"""

import dataclasses
import filecmp
import importlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

PROFILE = """
import cProfile, pickle, pstats, sys, tempfile
from vlref.bench.config import bench_scene
from vlref.cli.render import render_to_folder
scene = bench_scene(1920, 1080, 64, "four", 1024)
with tempfile.TemporaryDirectory() as folder:
    pr = cProfile.Profile()
    pr.enable()
    render_to_folder(scene, folder + "/out")
    pr.disable()
pstats.Stats(pr, stream=sys.stdout).sort_stats("cumulative").print_stats(45)
"""


def changed_files(branch: Path) -> list[str]:
    """Files under vlref/ whose text differs between the branch and the current folder (or exist in one only)."""
    names = set()
    for root in (Path("."), branch):
        names |= {str(p.relative_to(root)) for p in (root / "vlref").rglob("*.py")}
    return sorted(n for n in names if not ((Path(n).is_file() and (branch / n).is_file()
                                            and filecmp.cmp(n, branch / n, shallow=False))))


def main(out_dir: str, seconds: float, branch: str, variant: str | None = None) -> None:
    start = time.perf_counter()
    out = Path(out_dir)
    trees = {"branch": Path(branch).resolve(), **({"variant": Path(variant).resolve()} if variant else {})}
    names = sorted(set().union(*(changed_files(t) for t in trees.values())))
    kernels = [n for n in names if any("njit" in (root / n).read_text() for root in (Path("."), *trees.values())
                                       if (root / n).is_file())]
    if kernels:
        raise SystemExit(f"kernel files differ, one cache cannot serve both trees: {kernels}")
    saved = trees["main"] = Path("/tmp/startup_ab_main_files")
    for n in names:
        if Path(n).is_file():
            (saved / n).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(n, saved / n)
    stamp = [int(time.time()) + 10]

    def use(tree: str) -> None:
        for n in names:
            src = trees[tree] / n
            if src.is_file():
                shutil.copy(src, n)
                stamp[0] += 1  # a new mtime each copy: Python never takes the other tree's .pyc for this one
                os.utime(n, (stamp[0], stamp[0]))
            elif Path(n).is_file():
                os.unlink(n)

    report = {"changed": names, "python": sys.version, "cores": len(os.sched_getaffinity(0)),
              "env": {k: v for k, v in os.environ.items() if k.startswith(("PYTHON", "NUMBA", "OMP"))},
              "runs": {label: [] for label in trees}}
    sys.path.insert(0, os.getcwd())
    from vlref.bench.config import FULL, QUICK  # noqa: E402  (the checkout in the current folder)
    cfg = dataclasses.replace(QUICK if os.environ.get("STARTUP_AB_QUICK") else FULL, repeats=1)  # QUICK: a dry run
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import tempfile\nfrom vlref.bench import bench_scene\n"
                    "from vlref.cli.render import render_to_folder\nwith tempfile.TemporaryDirectory() as f:\n"
                    "    render_to_folder(bench_scene(64, 36, 64, 'four', 1024), f + '/out')"],
                   check=True, env=dict(os.environ, PYTHONPATH=os.pathsep.join([os.getcwd(),
                                                                                 os.environ.get("PYTHONPATH", "")])))
    report["cold_s"] = time.perf_counter() - t
    print(f"cold render (b) 64x36: {report['cold_s']:.1f} s", flush=True)
    try:
        def run(label: str) -> None:
            use(label)
            renders = importlib.reload(importlib.import_module("vlref.bench.renders"))
            whole = renders.bench_whole_render(cfg)
            report["runs"][label].append(whole)
            print(label, f"{whole['seconds']:.3f} s;", ", ".join(f"{k} {v:.3f}" for k, v in whole["split"].items()),
                  flush=True)
            report["median"] = {label: {"seconds": statistics.median(r["seconds"] for r in runs),
                                        "write": statistics.median(r["split"]["write"] for r in runs)}
                                for label, runs in report["runs"].items() if runs}
            (out / "startup_ab.json").write_text(json.dumps(report, indent=1))

        for label in ("main", "branch", "branch", "main", "main", "branch"):
            run(label)
        print("medians:", report["median"], flush=True)
        if time.perf_counter() - start < seconds - 8:
            use("branch")
            env = dict(os.environ, PYTHONPATH=os.pathsep.join([os.getcwd(), os.environ.get("PYTHONPATH", "")]))
            prof = subprocess.run([sys.executable, "-c", PROFILE], env=env, capture_output=True, text=True)
            (out / "profile_branch.txt").write_text(prof.stdout + prof.stderr)
        for _ in range(2):
            if variant and time.perf_counter() - start < seconds - 5:
                run("variant")
    finally:
        use("main")
        shutil.rmtree(saved, ignore_errors=True)


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]), *sys.argv[3:])
