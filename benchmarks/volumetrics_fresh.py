"""The volumetric stage of a fresh ``vlref render`` of (b) at 1920x1080x64, piece by piece (BENCHMARKS.md, "The round's
last changes, and its final bench"; "One pass for the lights' sum and the composite; the render without the
reference", where it ran as ``volumetric_pieces.py``): N renders (argument, default 3) in one
fresh process through ``render_to_folder`` as the ``render`` program imports it; per render each stage's time,
minor page faults and the kernel's transparent huge pages (``/proc/vmstat``: ``thp_fault_alloc``,
``thp_fault_fallback``, ``compact_stall``), and the volumetric stage's parts: the march's set-up, its first band
(the kernel's load in the first render), its other bands, the lights' sum and the composite (``sum_lights`` and
``composite_physical``, or ``sum_and_composite``: whichever the tree's technique calls), the rest; and when the thread
of ``vlref.ahead`` began and ended each load (``loads``: name, start, end, s from the render's start) against when
the march's set-up and its first call began (``march_buffers_at``, ``march_at``).

    PYTHONPATH=TREE NUMBA_CACHE_DIR=... python3 benchmarks/volumetrics_fresh.py 3
"""
import json
import resource
import sys
import tempfile
import time

t0 = time.perf_counter()
from vlref.cli.commands import program_command  # noqa: E402 (the import is timed)

render_to_folder = program_command("render").render_to_folder
t1 = time.perf_counter()

import vlref.ahead as ahead  # noqa: E402
import vlref.cli.render as cli_render  # noqa: E402
import vlref.techniques.physical as physical  # noqa: E402
from vlref.bench.config import bench_scene  # noqa: E402

VMSTAT = ("thp_fault_alloc", "thp_fault_fallback", "compact_stall")
parts: dict[str, float] = {}
marks: list[tuple] = []
loads: list[tuple] = []
starts: dict[str, float] = {}


def counters() -> tuple:
    """(time, minor faults, the VMSTAT counters)."""
    with open("/proc/vmstat") as fh:
        vm = dict(line.split() for line in fh)
    return (time.perf_counter(), resource.getrusage(resource.RUSAGE_SELF).ru_minflt,
            *(int(vm.get(k, -1)) for k in VMSTAT))


def timed(name: str) -> None:
    """Replace ``physical.<name>`` (where the tree has it) by a wrapper adding its wall time to ``parts``; the
    march's first band also alone."""
    fn = getattr(physical, name, None)
    if fn is None:
        return

    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        starts.setdefault(name, start)
        result = fn(*args, **kwargs)
        seconds = time.perf_counter() - start
        parts[name] = parts.get(name, 0.0) + seconds
        if name == "march_physical":
            parts.setdefault("first_band", seconds)
        return result

    setattr(physical, name, wrapper)


def timed_loads(functions):
    """``vlref.ahead._load``, each load's start and end recorded."""
    ahead.initialise_numba()
    for function, sig in functions:
        start = time.perf_counter()
        try:
            function.compile(sig)
        except Exception:
            return
        loads.append((function.py_func.__name__, start, time.perf_counter()))


ahead._load = timed_loads

for part in ("march_buffers", "march_physical", "sum_lights", "composite_physical", "sum_and_composite"):
    timed(part)


class Bar(cli_render.StageBar):
    def stage(self, name=None):
        marks.append((name, *counters()))
        return super().stage(name)


cli_render.StageBar = Bar

if __name__ == "__main__":
    THP = "/sys/kernel/mm/transparent_hugepage/"
    with open(THP + "enabled") as a, open(THP + "defrag") as b:
        print("THP", a.read().strip(), "| defrag", b.read().strip())
    print("import", round(t1 - t0, 3), flush=True)
    scene = bench_scene(1920, 1080, 64, "four", 1024)
    with tempfile.TemporaryDirectory() as folder:
        for i in range(int(sys.argv[1]) if len(sys.argv) > 1 else 3):
            parts.clear()
            marks.clear()
            loads.clear()
            starts.clear()
            marks.append(("start", *counters()))
            result, _, write_s, _ = render_to_folder(scene, f"{folder}/o{i}")
            marks.append(("written", *counters()))
            stages = {}
            for prev, cur in zip(marks, marks[1:]):
                stages[cur[0]] = {"s": round(cur[1] - prev[1], 4), "minflt": cur[2] - prev[2],
                                  **{k: cur[3 + j] - prev[3 + j] for j, k in enumerate(VMSTAT)}}
            p = {k: round(v, 4) for k, v in parts.items()}
            p["other_bands"] = round(parts["march_physical"] - parts["first_band"], 4)
            p["setup"] = round(parts["march_buffers"] - parts["march_physical"], 4)
            t_start = marks[0][1]
            p["loads"] = [(n, round(a - t_start, 4), round(b - t_start, 4)) for n, a, b in loads]
            p["march_buffers_at"] = round(starts["march_buffers"] - t_start, 4)
            p["march_at"] = round(starts["march_physical"] - t_start, 4)
            print(i, "write", round(write_s, 3), json.dumps({"timings": {k: round(v, 4) for k, v in
                                                                          result.timings.items()},
                                                              "pieces": p, "marks": stages}), flush=True)
