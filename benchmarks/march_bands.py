"""Why the volumetric stage of a fresh ``vlref render`` of (b) is slower than the bench's warm march, and what the
march's band count costs (BENCHMARKS.md, "The march in fewer bands").

    PYTHONPATH=$PWD python3 benchmarks/march_bands.py OUT.json [STEPS [WIDTH HEIGHT]]

One fresh process: the modules ``vlref render`` imports, the frame of (b) at 1920x1080xSTEPS (four shadowed lights)
and its shadow maps, then

1. ``fresh``: the march as ``march_buffers`` runs it (its bands, new output arrays), each band timed: the first band
   holds the kernel's load from the Numba cache;
2. ``bands``: the same march, warm, with 64, 32, 16, 8, 4 and 1 bands of whole tiles, three rounds alternated, new
   output arrays each call (as a render does), and with output arrays already touched (``touched``: the first touch
   of the ~215 MB of output pages measured apart); every result equal to the first, bit for bit;
3. ``dispatch``: 64 calls of the kernel on empty row ranges (the call and the parallel launch without work);
4. ``bench``: ``physical.render`` as the bench's march section times it (median of 3 after one call).
"""

import json
import math
import statistics
import sys
import time

import numba
import numpy as np

from vlref.cli.commands import program_command

program_command("render")  # the modules `vlref render` imports

from vlref.bench import bench_scene  # noqa: E402
from vlref.march.patterns import offsets  # noqa: E402
from vlref.march.physical import TILE_H, march_physical  # noqa: E402
from vlref.medium import pack_medium  # noqa: E402
from vlref.progress import bands_for, row_bands  # noqa: E402
from vlref.render import prepare_frame  # noqa: E402
from vlref.scene.technique_params import resolved  # noqa: E402
from vlref.techniques import physical  # noqa: E402


SAMPLES_PER_BAND = 2_000_000  # the march's band size before it ran in one launch (per thread per band)


def march_inputs(scene, frame, steps: int) -> tuple:
    """``(fixed, h, w, count)``: the arguments of ``march_physical`` before its outputs (float64) for ``frame`` of
    ``scene``, the frame's size and the light count."""
    sm = frame.shadow_maps()
    h, w = frame.gbuffer.distance.shape
    dirs = frame.camera.ray_directions(w, h, copy=False)
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    beta = offsets(resolved(scene, "sampling"), w, h, scene.render.seed)
    packed = frame.lights.astype(np.float64)
    geo = frame.geometry.arrays if sm.traces_rays else None
    fixed = (np.asarray(frame.camera.position, dtype=np.float64), dirs, t_end, beta, steps,
             pack_medium(scene, np.float64), packed, sm.table, geo, bool(scene.techniques.physical.light_extinction),
             int(math.ceil(math.sqrt(steps))))
    return fixed, h, w, packed.count


def main(out_path: str, steps: int = 64, width: int = 1920, height: int = 1080) -> None:
    report = {"threads": numba.get_num_threads(), "threading_layer": None}
    scene = bench_scene(width, height, steps, "four", 1024)
    frame = prepare_frame(scene)
    report["threading_layer"] = numba.threading_layer()
    fixed, h, w, count = march_inputs(scene, frame, steps)
    default = bands_for(h * w * steps * count, SAMPLES_PER_BAND * numba.get_num_threads())
    report["default_bands"] = default

    def march(bands, out=None, per_band=None):
        per_light, trans = out if out is not None else (np.empty((count, h, w, 3)), np.empty((h, w)))
        start = time.perf_counter()
        for y0, y1 in row_bands(h, bands, TILE_H):
            t = time.perf_counter()
            march_physical(*fixed, per_light, trans, (np.int64(y0), np.int64(y1)))
            if per_band is not None:
                per_band.append(time.perf_counter() - t)
        return time.perf_counter() - start, per_light, trans

    first = []
    seconds, ref_l, ref_t = march(default, per_band=first)
    report["fresh"] = {"bands": default, "seconds": seconds, "first_band": first[0],
                       "other_bands_median": statistics.median(first[1:]) if len(first) > 1 else None,
                       "per_band": first}
    print(f"fresh march, {default} bands: {seconds:.4f} s (first band {first[0]:.4f})", flush=True)

    counts = (64, 32, 16, 8, 4, 1)
    runs = {str(n): [] for n in counts}
    touched = {str(n): [] for n in (64, 8)}
    equal = True
    kept = (np.empty_like(ref_l), np.empty_like(ref_t))
    kept[0].fill(0.0)
    kept[1].fill(0.0)
    for rnd in range(3):
        for n in (counts if rnd % 2 == 0 else counts[::-1]):
            s, l, t = march(n)
            runs[str(n)].append(s)
            equal = equal and np.array_equal(l, ref_l) and np.array_equal(t, ref_t)
            del l, t
        for n in (64, 8):
            s, l, t = march(n, kept)
            touched[str(n)].append(s)
            equal = equal and np.array_equal(l, ref_l) and np.array_equal(t, ref_t)
        print(f"round {rnd}:", {k: round(v[-1], 4) for k, v in runs.items()},
              "touched", {k: round(v[-1], 4) for k, v in touched.items()}, flush=True)
    report["bands"] = {k: {"runs": v, "median": statistics.median(v)} for k, v in runs.items()}
    report["touched"] = {k: {"runs": v, "median": statistics.median(v)} for k, v in touched.items()}
    report["all_equal"] = bool(equal)

    calls = []
    for _ in range(3):
        t = time.perf_counter()
        for _ in range(64):
            march_physical(*fixed, kept[0], kept[1], (np.int64(0), np.int64(0)))
        calls.append((time.perf_counter() - t) / 64)
    report["dispatch_per_call"] = calls
    print("empty call:", [round(c * 1e6, 1) for c in calls], "us", flush=True)

    fn = lambda: physical.render(scene, frame)  # noqa: E731
    fn()
    times = []
    for _ in range(3):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    report["bench"] = {"runs": times, "median": statistics.median(times)}
    print("bench's march (physical.render):", [round(x, 4) for x in times], "equal", equal, flush=True)
    with open(out_path, "w") as fh:
        json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv[1], *(int(a) for a in sys.argv[2:]))
