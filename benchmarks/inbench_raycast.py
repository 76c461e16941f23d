"""The camera ray cast inside ``vlref bench``'s process: the bench's own sections, in its order, with a probe before
each (BENCHMARKS.md, "The camera ray cast inside the bench's process, and twice as fast").

    python3 benchmarks/inbench_raycast.py LABEL [--sections march,scaling,raycast] [--probe each|raycast]

Runs :func:`vlref.bench.report.run_bench` (full sizes, the sections named) as the ``vlref`` program runs it (its
modules imported with the garbage collector off, the objects then frozen: :func:`vlref.cli.commands.program_command`),
and before each section (``--probe each``) or only before ``raycast`` (``--probe raycast``), and once after the
last, a probe that prints one JSON line:

* ``idle``: over 0.3 s of sleep, each thread of this process that used CPU (name, CPU seconds), this process's
  threads and child processes, the load average, and the whole machine's busy and stolen fractions
  (``/proc/stat``): what else runs while the ray cast would;
* ``ceiling``: :func:`vlref.bench.ceiling.vector_exp` on Numba's threads (median of 5): the machine's speed now,
  touching no memory;
* ``raycast``: :func:`vlref.geometry.raycast` of (b) at 1920x1080 (median of 5 after a warm-up call, as the bench's
  section times it), with the minor page faults and the CPU time of each call; ``kernel``: the ray-cast kernel
  alone on buffers allocated once.

The bench's own figures of the sections run come last (one JSON line).
"""

import argparse
import gc
import json
import os
import resource
import sys
import time

gc.disable()  # as the vlref program imports its command (vlref.cli.commands.program_command)
import numba  # noqa: E402
import numpy as np  # noqa: E402

from vlref.bench.ceiling import ITEMS, vector_exp  # noqa: E402
from vlref.bench.config import FULL, bench_scene  # noqa: E402
from vlref.bench.report import run_bench  # noqa: E402
from vlref.camera import camera_from_settings  # noqa: E402
from vlref.geometry import build_geometry, raycast  # noqa: E402
from vlref.geometry.raycast import _cast_rows, _raycast_kernel, kernel_args  # noqa: E402
from vlref.parallel import COUNTER, work  # noqa: E402

gc.freeze()
gc.enable()

TICK = os.sysconf("SC_CLK_TCK")


def _task_ticks() -> dict:
    out = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            text = open(f"/proc/self/task/{tid}/stat").read()
        except OSError:
            continue
        rest = text[text.rindex(")") + 2:].split()
        out[tid] = (text[text.index("(") + 1:text.rindex(")")], int(rest[11]) + int(rest[12]))
    return out


def _machine_ticks() -> tuple[int, int, int]:
    values = [int(v) for v in open("/proc/stat").readline().split()[1:]]
    idle = values[3] + values[4]
    steal = values[7] if len(values) > 7 else 0
    return sum(values[:8]), idle, steal


def _children() -> list[str]:
    me, found = os.getpid(), []
    for pid in (p for p in os.listdir("/proc") if p.isdigit()):
        try:
            text = open(f"/proc/{pid}/stat").read()
        except OSError:
            continue
        rest = text[text.rindex(")") + 2:].split()
        if int(rest[1]) == me:
            found.append(f"{pid} {text[text.index('(') + 1:text.rindex(')')]} {rest[0]}")
    return found


def idle(seconds: float = 0.3) -> dict:
    t0, m0 = _task_ticks(), _machine_ticks()
    time.sleep(seconds)
    t1, m1 = _task_ticks(), _machine_ticks()
    busy = {f"{name}/{tid}": (ticks - t0[tid][1]) / TICK for tid, (name, ticks) in t1.items()
            if tid in t0 and ticks > t0[tid][1]}
    total = max(1, m1[0] - m0[0])
    return {"threads": len(t1), "busy_threads_cpu_s": busy, "children": _children(), "loadavg": os.getloadavg(),
            "machine_busy": 1 - (m1[1] - m0[1]) / total, "machine_steal": (m1[2] - m0[2]) / total}


def _timed(fn, repeats: int = 5) -> dict:
    fn()
    walls, cpus, faults = [], [], []
    for _ in range(repeats):
        r0, c0 = resource.getrusage(resource.RUSAGE_SELF), time.process_time()
        start = time.perf_counter()
        fn()
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - c0)
        faults.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - r0.ru_minflt)
    return {"seconds": float(np.median(walls)), "walls": walls, "cpu_s": cpus, "minor_faults": faults}


class Probe:
    def __init__(self, label: str):
        self.label = label
        self.scene = bench_scene(1920, 1080, 64, "four", 1024)
        self.camera = camera_from_settings(self.scene.camera, 1920, 1080)
        self.geometry = build_geometry(self.scene)
        self.ceiling_out = np.empty(ITEMS)

    def kernel(self):
        args = kernel_args(self.geometry.arrays, self.camera, raycast(self.scene, self.camera, self.geometry))
        cast = work(_cast_rows, COUNTER, *args)
        return lambda: _raycast_kernel(*args, cast, numba.get_num_threads())

    def __call__(self, where: str) -> None:
        row = {"label": self.label, "before": where, "numba_threads": numba.get_num_threads(), "idle": idle()}
        row["ceiling_s"] = _timed(lambda: vector_exp(self.ceiling_out, FULL.ceiling_steps))["seconds"]
        rc = _timed(lambda: raycast(self.scene, self.camera, self.geometry))
        row["raycast"] = {**rc, "rays_per_s_M": 1920 * 1080 / rc["seconds"] / 1e6}
        k = _timed(self.kernel())
        row["kernel"] = {**k, "rays_per_s_M": 1920 * 1080 / k["seconds"] / 1e6}
        row["idle_after"] = idle()
        print(json.dumps(row), flush=True)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("label")
    p.add_argument("--sections", default="march,scaling,raycast,shadow_maps")
    p.add_argument("--probe", choices=("each", "raycast"), default="each")
    args = p.parse_args()
    probe = Probe(args.label)
    sections = args.sections.split(",")

    def log(message, partial):
        if args.probe == "each" or message.startswith("raycast"):
            probe(message)

    report = run_bench(FULL, ["inbench_raycast"], log, sections)
    probe("end")
    mine = {k: report[k] for k in ("raycast", "shadow_maps") if k in report}
    print(json.dumps({"label": args.label, "bench": mine, "machine": report["machine"],
                      "threading_layer": numba.threading_layer()}), flush=True)


if __name__ == "__main__":
    sys.exit(main())
