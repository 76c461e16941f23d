"""``vlref compare REF TEST``: exit 0 pass, 1 fail, 2 bad input (:mod:`vlref.oracle.compare`)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Sequence

from ..errors import InputError
from ..oracle.compare import compare_files
from ..oracle.junit import report_case, write_junit
from ..oracle.metrics import FLIP_MISSING
from .options import check_report_outputs

HELP = "compare two images (exit 0 pass, 1 fail, 2 bad input)"
CLI = "<command line>"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref compare")
    p.add_argument("ref", help="reference image (.exr, .png, .npy, .npz)")
    p.add_argument("test", help="test image, same size and channel count")
    p.add_argument("--preset", default="float32",
                   help="tolerance preset: exact, float32, gpu-full, gpu-half, gpu-quarter (default float32)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a tolerance knob: abs_tol, rel_tol, max_fail_fraction, max_mean_abs, "
                        "max_flip_mean (none = off), scale (absolute|mean) (repeatable; default: the preset's)")
    p.add_argument("--ignore-sky", metavar="DEPTH|ref",
                   help="skip sky pixels: a depth image (inf or >= --sky-depth = sky) or 'ref' (non-finite "
                        "reference) (default: compare sky too)")
    p.add_argument("--sky-depth", type=float, default=math.inf,
                   help="depth at and beyond which a pixel is sky (default: inf, only infinite depth)")
    p.add_argument("--border", type=int, default=0, help="ignore this many pixels along every edge (default: 0)")
    p.add_argument("--mask", help="mask image: compare where nonzero (default: every pixel)")
    p.add_argument("--key", help="array name inside .npz inputs (default: the file's only array)")
    p.add_argument("-o", "--output", help="write report.json, diff.exr, heatmap.png, report.html and, when HDR-FLIP "
                   "runs (flip-evaluator installed, no --no-flip), flip.png here (default: write nothing)")
    p.add_argument("--exposure", type=float, help="preview exposure in the HTML page (default: automatic, "
                   "1/99th percentile of the reference)")
    p.add_argument("--no-flip", action="store_true", help="skip HDR-FLIP (default: computed when flip-evaluator "
                   "is installed)")
    p.add_argument("--junit", metavar="FILE", help="also write the verdict as JUnit XML, one test case (default: none)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing, use the exit code (default: off)")
    p.add_argument("--allow-8bit", action="store_true", help="accept 8-bit PNG/JPEG inputs, compared as their "
                   "0-1 values (default: refused; a .png of vlref is a tone-mapped preview, not radiance)")
    return p


EIGHT_BIT = (".png", ".jpg", ".jpeg")
"""Image files that hold 8-bit values: tone-mapped previews, refused as inputs without ``--allow-8bit``."""


def _refuse_8bit(args) -> None:
    for key, path in (("ref", args.ref), ("test", args.test)):
        if Path(path).suffix.lower() in EIGHT_BIT and not args.allow_8bit:
            raise InputError(CLI, key, f"{path} is an 8-bit image: vlref's final.png is a preview (auto-exposed, "
                             "sRGB-encoded, clipped to 255), not the linear radiance the tolerances are set for; "
                             "compare the .exr (final.exr), or pass --allow-8bit to compare 8-bit images as they are")


def _parse_set(items: Sequence[str] | None) -> dict[str, str]:
    out = {}
    for item in items or ():
        k, sep, v = item.partition("=")
        if not sep or not k.strip():
            raise InputError(CLI, "--set", f"expected KEY=VALUE, got {item!r}")
        out[k.strip()] = v.strip()
    return out


def run(args) -> int:
    """0 pass, 1 fail; bad input raises :class:`InputError` (exit 2)."""
    check_report_outputs(args.output, args.junit)
    _refuse_8bit(args)
    if args.border < 0:
        raise InputError(CLI, "--border", f"must be an integer >= 0, got {args.border}")
    report = compare_files(args.ref, args.test, args.preset, _parse_set(args.set),
                           ignore_sky=args.ignore_sky, sky_depth=args.sky_depth, border=args.border,
                           mask=args.mask, key=args.key, out_dir=args.output, exposure=args.exposure,
                           flip=not args.no_flip)
    if args.junit:
        html = Path(args.output) / "report.html" if args.output else None
        write_junit(args.junit, "vlref compare", [report_case(f"{Path(args.test).name} vs {Path(args.ref).name}",
                                                              report, html)])
    if not args.quiet and report.flip.note == FLIP_MISSING:
        print(f"vlref compare: note: HDR-FLIP skipped, {FLIP_MISSING}; no flip.png written", file=sys.stderr)
    if not args.quiet:
        print(report.summary())
        if args.output:
            print(f"wrote {Path(args.output) / 'report.html'}")
    return 0 if report.passed else 1
