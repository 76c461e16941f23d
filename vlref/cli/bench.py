"""``vlref bench [--quick] [--json] [-o FILE]``: the benchmark report (:mod:`vlref.bench`); exit 0 (benchmarks
never fail on a timing), 2 bad input."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from ..bench import FULL, QUICK, format_report, run_bench
from ..io.output_folders import check_output_file

HELP = "benchmarks (--quick, --json)"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref bench", description="benchmarks (see vlref.bench)")
    p.add_argument("--quick", action="store_true", help="tiny sizes, one repeat (CI smoke run; default: full sizes)")
    p.add_argument("--json", action="store_true", help="print the report as JSON (default: a text table)")
    p.add_argument("-o", "--output", help="also write the JSON report to this file (default: print only)")
    p.add_argument("--repeats", type=int, help="timed runs per figure (median); default 3, 1 with --quick")
    return p


def run(args) -> int:
    if args.output:
        check_output_file(args.output)
    cfg = QUICK if args.quick else FULL
    if args.repeats:
        cfg = dataclasses.replace(cfg, repeats=max(1, args.repeats))

    def log(msg, partial):
        print(f"[bench] {msg}", file=sys.stderr, flush=True)
        if args.output:  # what is done so far survives a run cut short
            Path(args.output).write_text(json.dumps(partial, indent=1))

    report = run_bench(cfg, args.argv, log)
    text = json.dumps(report, indent=1)
    if args.output:
        Path(args.output).write_text(text)
    print(text if args.json else format_report(report))
    return 0
