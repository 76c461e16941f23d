"""Scale-out benchmark: a tiled reference and a golden build, in-process and on Dask LocalClusters.

    PYTHONPATH=. python benchmarks/scale.py --schedulers none,local:2 --ref-size 320x180 --golden-size 256x144

For each scheduler (``none`` = in this process with every Numba thread; ``local:N`` = N worker
processes, ``cores // N`` Numba threads each) it times, wall clock as a user sees it (cluster start and
the workers' loading of the cached kernels included, since a ``--scheduler`` run pays them):

* ``reference``: :func:`vlref.reference.tiles.render_reference_tiled` of the bundled ``pillars`` scene
  (``--ref-size``, ``--rel-tol``, ``--tile-rows``) -- in process, the untiled ``render_reference``;
* ``golden``: :func:`vlref.oracle.golden.build` of the whole suite (or ``--only``) at ``--golden-size``
  into a temporary folder (EXR files written, as ``vlref golden build`` does).

Before timing, one small in-process run fills ``NUMBA_CACHE_DIR`` (compile time excluded). Prints one
JSON object per measurement and a table; ``-o FILE`` also writes the JSON list. Also checks that every
scheduler gave the same arrays / manifest as the first (``same`` column).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _size(text: str) -> tuple[int, int]:
    w, h = text.lower().split("x")
    return int(w), int(h)


def _suite(tmp: Path, width: int, height: int) -> Path:
    from vlref.oracle.golden import SUITE_FILE

    text = SUITE_FILE.read_text()
    text = text.replace("width = 64", f"width = {width}").replace("height = 36", f"height = {height}")
    path = tmp / "suite.toml"
    path.write_text(text)
    return path


def _digest(arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def bench_reference(scheduler, size, rel_tol, tile_rows) -> dict:
    from vlref.reference import render_reference
    from vlref.reference.tiles import render_reference_tiled
    from vlref.scene import load_scene

    scene = load_scene("pillars", [f"render.width={size[0]}", f"render.height={size[1]}"])
    start = time.perf_counter()
    if scheduler is None:
        res = render_reference(scene, rel_tol=rel_tol)
    else:
        res = render_reference_tiled(scene, rel_tol, scheduler=scheduler, rows_per_tile=tile_rows, quiet=True)
    seconds = time.perf_counter() - start
    return {"what": "reference", "size": f"{size[0]}x{size[1]}", "rel_tol": rel_tol, "seconds": seconds,
            "pixels_per_s": size[0] * size[1] / seconds,
            "digest": _digest([res.inscatter, res.final, res.error, res.transmittance])}


def bench_golden(scheduler, size, only) -> dict:
    from vlref.oracle.golden import build

    with tempfile.TemporaryDirectory() as tmp:
        suite = _suite(Path(tmp), *size)
        start = time.perf_counter()
        manifest = build(Path(tmp) / "golden", suite, only, log=lambda *a: None, scheduler=scheduler, quiet=True)
        seconds = time.perf_counter() - start
    files = [f["sha256"] for e in manifest["entries"] for f in e["files"].values()]
    return {"what": "golden", "size": f"{size[0]}x{size[1]}", "entries": len(manifest["entries"]),
            "seconds": seconds, "digest": hashlib.sha256("".join(files).encode()).hexdigest()[:16]}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--schedulers", default="none,local:2", help="comma-separated: none, local:N, tcp://...")
    p.add_argument("--what", default="reference,golden", help="reference, golden or both")
    p.add_argument("--ref-size", default="320x180")
    p.add_argument("--rel-tol", type=float, default=1e-4)
    p.add_argument("--tile-rows", type=int, default=16)
    p.add_argument("--golden-size", default="256x144")
    p.add_argument("--only", action="append", help="golden entries (glob), default: the whole suite")
    p.add_argument("-o", "--output", help="write the JSON list here")
    args = p.parse_args(argv)

    import numba

    from vlref.processes import host_cores

    machine = {"cpu": platform.processor() or platform.machine(), "cores": host_cores(),
               "numba_threads": numba.config.NUMBA_NUM_THREADS, "python": platform.python_version(),
               "numpy": np.__version__, "numba": numba.__version__}
    print(json.dumps({"machine": machine}), flush=True)
    what = args.what.split(",")
    # fill the Numba cache (compile excluded from the timings)
    if "reference" in what:
        bench_reference(None, (8, 6), args.rel_tol, args.tile_rows)
    if "golden" in what:
        bench_golden(None, (16, 12), args.only)
    out = []
    for name in args.schedulers.split(","):
        scheduler = None if name == "none" else name
        workers = 1 if scheduler is None else int(name.split(":")[1]) if name.startswith("local:") else None
        threads = host_cores() // workers if workers else None
        for w in what:
            row = (bench_reference(scheduler, _size(args.ref_size), args.rel_tol, args.tile_rows) if w == "reference"
                   else bench_golden(scheduler, _size(args.golden_size), args.only))
            row.update({"scheduler": name, "workers": workers, "numba_threads_per_worker": threads})
            base = next((r for r in out if r["what"] == w), None)
            row["same"] = base is None or base["digest"] == row["digest"]
            out.append(row)
            print(json.dumps(row), flush=True)
    print(f"\n{'what':<10} {'size':<10} {'scheduler':<12} {'workers x threads':<18} {'seconds':>9} {'same':>5}")
    for r in out:
        wt = f"{r['workers']} x {r['numba_threads_per_worker']}" if r["workers"] else "?"
        print(f"{r['what']:<10} {r['size']:<10} {r['scheduler']:<12} {wt:<18} {r['seconds']:>9.2f} {str(r['same']):>5}")
    if args.output:
        Path(args.output).write_text(json.dumps({"machine": machine, "runs": out}, indent=1) + "\n")
    return 0 if all(r["same"] for r in out) else 1


if __name__ == "__main__":
    sys.exit(main())
