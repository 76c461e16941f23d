"""Check the WebGPU killzone port against vlref: every pass, every variant; prints the README's tables.

    python ports/wgpu/kz_check.py [--size 160x90] [--set K=V ...] [-o DIR]

Steps (the walk-through of docs/PORTING.md, in-process): render the port's faithful variant and export its
buffers (:func:`kz_port.export`), run ``vlref march PORT.toml --stages`` on them, compare each pass's
output with the matching vlref stage under its preset (:data:`PASSES`), then re-run the post passes of
every variant (:mod:`kz_variants`) and compare its ``final`` with vlref's.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import kz_port  # noqa: E402
import kz_scene  # noqa: E402
from kz_variants import VARIANTS  # noqa: E402

SCENE = HERE / "scenes" / "pillars_point.toml"

PASSES = (("depth_lo", "depth_half", "float32"), ("march", "march_half", "gpu-half"),
          ("upsample", "upsample", "gpu-half"), ("blur_h", "blur_h", "gpu-half"), ("blur_v", "blur_v", "gpu-half"),
          ("transmittance", "transmittance", "gpu-half"), ("final", "final", "gpu-half"))
"""(port output, vlref ``--stages`` buffer, preset). The march runs at half resolution and the light
buffers are fp16: ``gpu-half``. The min-depth downsample is exact up to float32 decoding: ``float32``
(sky pixels, ``inf`` in both, are left out with ``--ignore-sky ref``)."""


OWN_BUFFERS = {"max_fail_fraction": 1e-3}
"""``--set`` for a comparison with ``vlref march`` on the port's own buffers at large sizes: no rasteriser
silhouettes are left to absorb, so the failing-fraction allowance of ``gpu-half`` (2 %, sized for edges of
64x36 frames) can shrink to ``float32``'s 0.1 % (docs/PORTING.md)."""


def compare(ref_path: Path, test, preset: str, ignore_sky: bool = False, overrides=None):
    """``vlref compare`` of a vlref EXR with a port array (a report: passed, checks, metrics)."""
    from vlref.io import read_image
    from vlref.oracle.compare import build_mask, compare_arrays
    from vlref.oracle.presets import tolerance

    ref = read_image(ref_path)
    test = np.asarray(test)
    test = test[..., None] if test.ndim == 2 else test
    mask = build_mask(ref, ignore_sky="ref") if ignore_sky else None
    return compare_arrays(ref, test, tolerance(preset, overrides), mask, flip=False)


def margins(report) -> tuple[float, float]:
    """(failing fraction / its bound, mean error / its bound)."""
    frac, mean = report.checks[0], report.checks[1]
    return frac.value / frac.bound, mean.value / mean.bound


def render_and_march(out_dir: Path, overrides=(), dev=None):
    """The faithful port rendered and exported to ``out_dir/port``, vlref marched into ``out_dir/marched``:
    ``(port, passes, marched_dir, seconds of vlref march)``."""
    from vlref.cli import main

    scene = kz_scene.load(str(SCENE), overrides)
    port = kz_port.KillzonePort(scene, dev)
    passes = port.run("faithful")
    manifest = kz_port.export(port, out_dir / "port", str(SCENE), overrides, passes)
    start = time.perf_counter()
    if main(["march", str(manifest), "-o", str(out_dir / "marched"), "--stages", "-q"]) != 0:
        raise RuntimeError("vlref march failed on the port's buffers")
    return port, passes, out_dir / "marched", time.perf_counter() - start


def pass_rows(passes: dict, marched: Path):
    """``[(port pass, vlref buffer, preset, report)]`` for :data:`PASSES`."""
    return [(p, r, preset, compare(marched / f"{r}.exr", passes[p], preset, ignore_sky=(p == "depth_lo")))
            for p, r, preset in PASSES]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="160x90")
    ap.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    ap.add_argument("-o", "--output", default=None, help="keep the port and vlref buffers here")
    args = ap.parse_args(argv)
    w, h = args.size.lower().split("x")
    overrides = [f"render.width={int(w)}", f"render.height={int(h)}", *args.set]
    out = Path(args.output or tempfile.mkdtemp(prefix="kz-check-"))
    port, passes, marched, t_march = render_and_march(out, overrides)
    first = dict(port.timings)
    port.timings.clear()
    port.render_scene()
    port.run("faithful")
    print(f"device: {port.adapter.info['device']}; {w}x{h}; vlref march {t_march:.2f} s; buffers in {out}\n")
    print("| pass | first run (ms) | warm (ms) |\n|---|---|---|")
    for name, t in port.timings.items():
        print(f"| {name} | {1e3 * first[name]:.1f} | {1e3 * t:.1f} |")
    print(f"| total | {1e3 * sum(first.values()):.1f} | {1e3 * sum(port.timings.values()):.1f} |")
    print("\n| port pass | vlref buffer | preset | result | failing pixels | failing fraction | mean error |")
    print("|---|---|---|---|---|---|---|")
    ok = True
    for p, r, preset, rep in pass_rows(passes, marched):
        f, m = margins(rep)
        ok &= rep.passed
        print(f"| {p} | {r} | {preset} | {'PASS' if rep.passed else 'FAIL'} | "
              f"{int(rep.metrics['failing_pixels'])} of {int(rep.metrics['compared_pixels'])} | {f:.3f}x | {m:.3f}x |")
    print("\n| variant | preset | expected | result (final) | failing fraction | mean error "
          "| with `--set max_fail_fraction=1e-3` |\n|---|---|---|---|---|---|---|")
    for name, v in VARIANTS.items():
        final = port.run(name)["final"]
        rep = compare(marched / "final.exr", final, v.preset)
        tight = compare(marched / "final.exr", final, v.preset, overrides=OWN_BUFFERS)
        f, m = margins(rep)
        ok &= rep.passed == (v.expect == "pass")
        print(f"| `{name}`: {v.description} | {v.preset} | {v.expect} | {'PASS' if rep.passed else 'FAIL'} | "
              f"{f:.3g}x | {m:.3g}x | {'PASS' if tight.passed else 'FAIL'} ({margins(tight)[0]:.3g}x) |")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
