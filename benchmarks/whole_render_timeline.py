"""Every part of a fresh-process ``vlref render`` of (b) at 1920x1080x64 on one clock (BENCHMARKS.md, "The whole
render part by part on one clock"): the imports (NumPy, Numba, vlref), each call of the render's steps on the main
thread, each load of the thread of :mod:`vlref.ahead` (Numba's initialisation, then each kernel), the march on its
launch thread, and the writing's parts on their threads (each buffer's float32 channels, each EXR file, the PNG
preview with its luminance, percentile, tone map and encoding), as (thread, part, start, end) in seconds from the
process's first statement.

    PYTHONPATH=TREE NUMBA_CACHE_DIR=... python3 benchmarks/whole_render_timeline.py SCENE.pickle LABEL OUT.jsonl

``SCENE.pickle``: ``pickle.dumps(vlref.bench.bench_scene(1920, 1080, 64, "four", 1024))`` (written by
``whole_render_timeline.py --scene SCENE.pickle``). Appends one JSON line to ``OUT.jsonl`` (the render's stages,
its write time, the parts) and ends as ``vlref render`` ends. Run it twice first to fill the cache (a cold run
compiles in second processes). ``--summary OUT.jsonl`` prints each part's median start and duration over the lines
whose label starts with ``run``.
"""

import time

T0 = time.perf_counter()

import gc  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import pickle  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import threading  # noqa: E402
from pathlib import Path  # noqa: E402

PARTS: list[tuple] = []

TIMED = {  # module -> the names it calls the render's steps by
    "vlref.render": ("scene_at", "camera_from_settings", "build_geometry", "raycast", "pack_lights", "scene_colour",
                     "build_shadow_maps"),
    "vlref.techniques.physical": ("offsets", "pack_medium", "march_physical", "sum_and_composite"),
    "vlref.io.render_files": ("channel_dict", "write_exr"),
    "vlref.cli.render": ("_write_preview",),
    "vlref.cli.options": ("luminance", "percentile_exposure"),
    "vlref.io.png": ("srgb8", "png_bytes"),
}


def part(name: str, start: float) -> None:
    """Record ``name`` on the calling thread from ``start`` until now."""
    PARTS.append((threading.current_thread().name, name, round(start - T0, 4), round(time.perf_counter() - T0, 4)))


def timed(module, name: str) -> None:
    """Replace ``module.name`` by a wrapper that records each call (:func:`part`); an EXR file's part is named
    with the file's name."""
    function = getattr(module, name)

    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            part(f"{name} {Path(args[0]).name}" if name == "write_exr" else name, start)

    setattr(module, name, wrapper)


def timed_loads(ahead):
    """:func:`vlref.ahead._load` with Numba's initialisation and each load recorded."""
    def load(functions):
        start = time.perf_counter()
        ahead.initialise_numba()
        part("load: initialise Numba", start)
        for function, sig in functions:
            start = time.perf_counter()
            function.compile(sig)
            part(f"load: {function.py_func.__name__}", start)
    return load


def summary(path: str) -> None:
    """Each part's median start and duration over the runs of ``path`` (repeated parts numbered in call order)."""
    starts, seconds = {}, {}
    for line in open(path):
        row = json.loads(line)
        if not row["label"].startswith("run"):
            continue
        count = {}
        for _, name, a, b in row["parts"]:
            count[name] = count.get(name, 0) + 1
            key = name if count[name] == 1 else f"{name} #{count[name]}"
            starts.setdefault(key, []).append(a)
            seconds.setdefault(key, []).append(b - a)
    for key in sorted(starts, key=lambda k: statistics.median(starts[k])):
        s = seconds[key]
        print(f"{key:34s} start {statistics.median(starts[key]):6.3f}  {statistics.median(s):7.4f} s "
              f"({min(s):.4f}-{max(s):.4f}, {len(s)} runs)")


def main() -> None:
    start = time.perf_counter()
    import numpy  # noqa: F401
    part("import NumPy", start)
    start = time.perf_counter()
    from vlref.cli import commands
    commands.declare_own_kernels_only()  # Numba imported as the render program imports it (program_command)
    gc.disable()
    with commands._numba_alone():
        import numba  # noqa: F401
    part("import Numba", start)
    start = time.perf_counter()
    render_to_folder = commands.program_command("render").render_to_folder
    gc.enable()
    part("import vlref", start)
    for module, names in TIMED.items():
        for name in names:
            timed(importlib.import_module(module), name)
    ahead = importlib.import_module("vlref.ahead")
    ahead._load = timed_loads(ahead)
    scene_file, label, out = sys.argv[1:4]
    with open(scene_file, "rb") as fh:
        scene = pickle.load(fh)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        result, _, write_s, _ = render_to_folder(scene, folder + "/out")
    part("render_to_folder", start)
    row = {"label": label, "stages": {k: round(v, 4) for k, v in result.timings.items()}, "write": round(write_s, 4),
           "parts": PARTS}
    with open(out, "a") as fh:
        fh.write(json.dumps(row) + "\n")
    commands.exit_at_once(0)


if __name__ == "__main__":
    if sys.argv[1] == "--summary":
        summary(sys.argv[2])
    elif sys.argv[1] == "--scene":
        from vlref.bench import bench_scene
        with open(sys.argv[2], "wb") as fh:
            pickle.dump(bench_scene(1920, 1080, 64, "four", 1024), fh)
    else:
        main()
