"""``vlref verdict PORT.toml -o DIR``: the whole-frame verdict on a port (:mod:`vlref.oracle.verdict`);
``vlref verdict A.toml B.toml ... -o DIR``: on every frame of a sequence, temporal state carried on both sides
(:func:`vlref.oracle.verdict.judge_sequence`); exit 0 pass, 1 fail, 2 bad input."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..oracle.junit import Case, write_junit
from ..oracle.verdict import judge, judge_sequence
from .options import check_report_outputs

HELP = "judge a port on its own buffers and against the scene (exit 0 pass, 1 fail, 2 bad input)"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref verdict", description="The whole-frame verdict on a GPU port: its "
                                "pass outputs against vlref march on its own buffers, and its depth, shadow maps, "
                                "scene colour and final frame against the scene (docs/PORTING.md).")
    p.add_argument("manifest", nargs="+", help="port manifest (TOML) with [[passes]] and final; several: the "
                   "frames of a sequence, in order, each judged with the previous frames' temporal history on "
                   "both sides (as `vlref march A.toml B.toml ...` carries it)")
    p.add_argument("-o", "--output", help="write verdict.json, index.html and one report per comparison here; "
                   "for a sequence, each frame's under OUT/frame_NNNN and the sequence's verdict.json and "
                   "index.html naming the frame and pass of every failure (default: write nothing)")
    p.add_argument("--preset", default=None, help="preset of the [[passes]] that name none, when the manifest "
                   "sets no `preset` (default gpu-half)")
    p.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                   help="override a scene field (repeatable; default: none)")
    p.add_argument("--junit", metavar="FILE", help="also write JUnit XML, one test case per comparison (default: "
                   "none)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing, use the exit code (default: off)")
    return p


def run(args) -> int:
    """0 pass, 1 fail; bad input raises :class:`InputError` (exit 2)."""
    check_report_outputs(args.output, args.junit)
    if len(args.manifest) == 1:
        verdict = judge(args.manifest[0], args.output, args.preset, args.set or ())
        cases = [Case(f"{p.group}: {p.name}", p.passed, p.metrics, p.report, p.reason) for p in verdict.passes]
    else:
        verdict = judge_sequence(args.manifest, args.output, args.preset, args.set or ())
        cases = [Case(f"frame {i}: {p.group}: {p.name}", p.passed, p.metrics, p.report, p.reason)
                 for i, v in enumerate(verdict.frames) for p in v.passes]
    if args.junit:
        write_junit(args.junit, "vlref verdict", cases)
    if not args.quiet:
        print(verdict.table())
        if args.output:
            print(f"wrote {Path(args.output) / 'index.html'}", file=sys.stderr)
    return 0 if verdict.passed else 1
