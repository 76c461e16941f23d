"""The volumetric stage of ``vlref render`` in a fresh process against the same render repeated in that process
(BENCHMARKS.md, "The round's last changes, and its final bench"): scene (b) at 1920x1080x64 rendered N times (argument,
default 3) through ``render_to_folder`` as the ``render`` program imports it; per render the stage timings, the
volumetric stage's parts (offsets, the march's bands with the first band alone, the sum over lights, the composite)
and the minor page faults.

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=... python3 benchmarks/volumetrics_fresh.py 3
"""
import resource
import sys
import tempfile
import time

t0 = time.perf_counter()
from vlref.cli.commands import program_command  # noqa: E402 (the import is timed)

render_to_folder = program_command("render").render_to_folder
t1 = time.perf_counter()

import vlref.techniques.physical as physical  # noqa: E402
from vlref.bench.config import bench_scene  # noqa: E402

parts: dict[str, float] = {}


def timed(name: str) -> None:
    """Replace ``physical.<name>`` by a wrapper that adds its wall time to ``parts[name]`` (the march's first band
    also alone: it loads the kernel)."""
    fn = getattr(physical, name)

    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        result = fn(*args, **kwargs)
        seconds = time.perf_counter() - start
        parts[name] = parts.get(name, 0.0) + seconds
        if name == "march_physical":
            parts.setdefault("first_band", seconds)
        return result

    setattr(physical, name, wrapper)


for part in ("march_buffers", "march_physical", "sum_lights", "composite_physical", "offsets"):
    timed(part)
scene = bench_scene(1920, 1080, 64, "four", 1024)
print("import", round(t1 - t0, 3), flush=True)
with tempfile.TemporaryDirectory() as folder:
    for i in range(int(sys.argv[1]) if len(sys.argv) > 1 else 3):
        parts.clear()
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        start = time.perf_counter()
        result, _, write_s, _ = render_to_folder(scene, f"{folder}/o{i}")
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
        print(i, "total", round(time.perf_counter() - start, 3), "write", round(write_s, 3),
              {k: round(v, 3) for k, v in result.timings.items()}, {k: round(v, 4) for k, v in parts.items()},
              "minflt", faults, flush=True)
