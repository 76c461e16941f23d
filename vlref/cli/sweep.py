"""``vlref sweep``: a technique x parameter grid against the reference (:mod:`vlref.sweep`)."""

from __future__ import annotations

import argparse
import sys

from ..io.output_folders import check_output_dir
from ..sweep import load_sweep, run_sweep
from .options import add_scheduler_argument

HELP = "a technique x parameter grid against the reference (error, time, FLIP)"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref sweep")
    p.add_argument("spec", help="sweep file (TOML): scene, set, techniques, metrics, [grid] or points")
    p.add_argument("-o", "--output", default="out_sweep", help="output folder (default: out_sweep)")
    add_scheduler_argument(p)
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary (default: off)")
    return p


def run(args) -> int:
    check_output_dir(args.output)
    spec = load_sweep(args.spec)
    rows = run_sweep(spec, args.output, scheduler=args.scheduler, quiet=args.quiet)
    if not args.quiet:
        print(f"sweep: {len(rows)} items in {args.output}/summary.csv", file=sys.stderr)
    return 0
