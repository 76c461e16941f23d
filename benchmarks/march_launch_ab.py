"""The march of (b) in one watched launch against main's 17 bands and a plain call on the main thread, in one process
(BENCHMARKS.md, "The march in one launch, watched").

    PYTHONPATH=$PWD python3 benchmarks/march_launch_ab.py OUT.json [WIDTH HEIGHT [STEPS [ROUNDS [THREADS ...]]]]

One process: the modules ``vlref render`` imports, the frame of (b) at WIDTHxHEIGHTxSTEPS (four shadowed lights) and
its shadow maps; then per thread count (default: Numba's), ROUNDS rounds alternated (order reversed every other
round) of

* ``bands``: main's loop, ``march_physical`` once per band of ``vlref.progress.row_bands`` on this thread, the bands
  sized as main sized them (2 M samples per thread per band, whole tiles);
* ``one_call``: one ``march_physical`` call over every row on this thread (no progress, no Ctrl-C until it ends);
* ``watched``: what the technique runs now, the one launch on its own thread (``vlref.progress.watched``) with a
  listener installed (as the ``vlref`` command has),

each with new output arrays (as a render has), every result compared bit for bit with the first ``bands`` one.
The first call of the kernel (its load from the cache) is timed apart, before the rounds.
"""

import json
import statistics
import sys
import time

import numba
import numpy as np

from vlref.cli.commands import program_command

program_command("render")  # the modules `vlref render` imports

from march_bands import SAMPLES_PER_BAND, march_inputs  # noqa: E402 (this folder's; its frame's inputs)
from vlref.bench import bench_scene  # noqa: E402
from vlref.march.physical import TILE_H, march_physical, march_tiles  # noqa: E402
from vlref.progress import bands_for, reporting, row_bands, watched  # noqa: E402
from vlref.render import prepare_frame  # noqa: E402

def main(out_path: str, width: int = 1920, height: int = 1080, steps: int = 64, rounds: int = 3, *threads: int):
    scene = bench_scene(width, height, steps, "four", 1024)
    frame = prepare_frame(scene)
    fixed, h, w, count = march_inputs(scene, frame, steps)
    everything = (np.int64(0), np.int64(h))

    def outputs():
        return np.empty((count, h, w, 3)), np.empty((h, w))

    def bands():
        per, trans = outputs()
        n = bands_for(h * w * steps * count, SAMPLES_PER_BAND * numba.get_num_threads())
        for y0, y1 in row_bands(h, n, TILE_H):
            march_physical(*fixed, per, trans, (np.int64(y0), np.int64(y1)))
        return per, trans

    def one_call():
        per, trans = outputs()
        march_physical(*fixed, per, trans, everything)
        return per, trans

    reports = []

    def watched_launch():
        per, trans = outputs()
        taken = np.zeros(1, dtype=np.int64)
        with reporting(lambda done, total: reports.append(done)):
            watched(lambda: march_physical(*fixed, per, trans, everything, taken), taken, march_tiles(w, h), h)
        return per, trans

    variants = {"bands": bands, "one_call": one_call, "watched": watched_launch}
    t = time.perf_counter()
    ref = bands()
    report = {"first_call_s": time.perf_counter() - t, "threading_layer": numba.threading_layer(), "by_threads": {}}
    print(f"first march (the kernel's load; bands): {report['first_call_s']:.4f} s", flush=True)
    equal = True
    for n in threads or (numba.get_num_threads(),):
        before = numba.get_num_threads()
        numba.set_num_threads(n)
        runs = {k: [] for k in variants}
        try:
            for rnd in range(rounds):
                for name in (list(variants) if rnd % 2 == 0 else list(variants)[::-1]):
                    t = time.perf_counter()
                    per, trans = variants[name]()
                    runs[name].append(time.perf_counter() - t)
                    equal = equal and np.array_equal(per, ref[0]) and np.array_equal(trans, ref[1])
                    del per, trans
                print(f"threads {n} round {rnd}:", {k: round(v[-1], 4) for k, v in runs.items()}, flush=True)
        finally:
            numba.set_num_threads(before)
        report["by_threads"][str(n)] = {k: {"runs": v, "median": statistics.median(v)} for k, v in runs.items()}
        print(f"threads {n} medians:", {k: round(statistics.median(v), 4) for k, v in runs.items()}, flush=True)
    report["all_equal"] = bool(equal)
    report["watched_reports_last_run"] = len(reports)
    print("all equal:", equal, flush=True)
    with open(out_path, "w") as fh:
        json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv[1], *(int(a) for a in sys.argv[2:]))
