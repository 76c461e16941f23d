"""Page faults and the exit of the whole ``vlref render`` of (b) at 1920x1080x64, two trees alternated on one machine
(BENCHMARKS.md, "Numba's initialisation deferred to the first compile"): run after ``whole_render_ab.py`` with the same
``CACHE_ROOT``, whose caches it uses.

    python3 benchmarks/whole_render_faults.py OUT_DIR ROUNDS A_TREE B_TREE [CACHE_ROOT]

``ROUNDS`` rounds of A, B, B, A: a fresh process of the tree imports what ``vlref render`` imports
(``program_command``), renders (b) with ``render_to_folder`` and ends with ``exit_at_once``; per render stage its
wall time and minor page faults (``getrusage``), the machine's transparent huge pages faulted in meanwhile
(``thp_fault_alloc`` of ``/proc/vmstat``), and the exit's tear-down: from the child's last timestamp to the parent
seeing it gone. Writes ``OUT_DIR/whole_render_faults.json``.
"""

import json
import os
import pickle
import statistics
import subprocess
import sys
import time
from pathlib import Path

CHILD = """
import json, pickle, resource, sys, tempfile, time
def faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt
t0, f0 = time.perf_counter(), faults()
from vlref.cli.commands import exit_at_once, program_command
command = program_command("render")
marks = [("import", time.perf_counter(), faults())]
render = command.render
def marked(scene, stages=False, progress=None, history=None):
    def tick(name):
        marks.append((name, time.perf_counter(), faults()))
        progress(name)
    return render(scene, stages, tick, history)
command.render = marked
with open(sys.argv[1], "rb") as fh:
    scene = pickle.load(fh)
with tempfile.TemporaryDirectory() as folder:
    command.render_to_folder(scene, folder + "/out")
    marks.append(("write", time.perf_counter(), faults()))
split, last = {}, (t0, f0)
for name, t, f in marks:
    split[name] = [t - last[0], f - last[1]]
    last = (t, f)
print(json.dumps({"split": split, "faults": faults(), "exit_at": time.time()}), flush=True)
exit_at_once(0)
"""


def thp_faults() -> int:
    for line in Path("/proc/vmstat").read_text().splitlines():
        if line.startswith("thp_fault_alloc "):
            return int(line.split()[1])
    return -1


def main(out_dir: str, rounds: int, a: str, b: str, cache_root: str = "/tmp/wrab") -> None:
    trees = {"A": Path(a).resolve(), "B": Path(b).resolve()}
    sys.path.insert(0, str(trees["B"]))
    from vlref.bench import bench_scene

    scene_file = Path(out_dir) / "scene_b_1080.pickle"
    scene_file.write_bytes(pickle.dumps(bench_scene(1920, 1080, 64, "four", 1024)))
    report = {"trees": {k: str(v) for k, v in trees.items()}, "runs": {"A": [], "B": []}}
    for _ in range(rounds):
        for label in ("A", "B", "B", "A"):
            env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(trees[label]), os.environ.get("PYTHONPATH", "")]),
                       NUMBA_CACHE_DIR=f"{cache_root}/{label.lower()}")
            thp = thp_faults()
            start = time.perf_counter()
            proc = subprocess.Popen([sys.executable, "-c", CHILD, str(scene_file)], env=env, cwd=trees[label],
                                    stdout=subprocess.PIPE, text=True)
            out = proc.stdout.read()
            proc.wait()
            end, wall = time.time(), time.perf_counter() - start
            run = json.loads(out.strip().splitlines()[-1])
            run.update(wall=wall, teardown=end - run.pop("exit_at"), thp_faults=thp_faults() - thp)
            report["runs"][label].append(run)
            print(label, f"{wall:.3f} s, teardown {run['teardown'] * 1000:.1f} ms, thp {run['thp_faults']},",
                  ", ".join(f"{k} {v[0]:.3f} s {v[1]} flt" for k, v in run["split"].items()), flush=True)
    report["median"] = {label: {"wall": statistics.median(r["wall"] for r in runs),
                                "teardown": statistics.median(r["teardown"] for r in runs),
                                "faults": statistics.median(r["faults"] for r in runs),
                                **{k: [statistics.median(r["split"][k][0] for r in runs),
                                       statistics.median(r["split"][k][1] for r in runs)] for k in runs[0]["split"]}}
                        for label, runs in report["runs"].items()}
    print("medians:", json.dumps(report["median"]), flush=True)
    (Path(out_dir) / "whole_render_faults.json").write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], *sys.argv[5:])
