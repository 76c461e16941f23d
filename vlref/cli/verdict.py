"""``vlref verdict PORT.toml -o DIR``: the whole-frame verdict on a port (:mod:`vlref.oracle.verdict`);
exit 0 pass, 1 fail, 2 bad input."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HELP = "judge a port on its own buffers and against the scene (exit 0 pass, 1 fail, 2 bad input)"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref verdict", description="The whole-frame verdict on a GPU port: its "
                                "pass outputs against vlref march on its own buffers, and its depth, shadow maps, "
                                "scene colour and final frame against the scene (docs/PORTING.md).")
    p.add_argument("manifest", help="port manifest (TOML) with [[passes]] and final")
    p.add_argument("-o", "--output", help="write verdict.json, index.html and one report per comparison here "
                   "(default: write nothing)")
    p.add_argument("--preset", default=None, help="preset of the [[passes]] that name none, when the manifest "
                   "sets no `preset` (default gpu-half)")
    p.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                   help="override a scene field (repeatable; default: none)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing, use the exit code (default: off)")
    return p


def run(args) -> int:
    """0 pass, 1 fail; bad input raises :class:`InputError` (exit 2)."""
    from ..io import check_output_dir
    from ..oracle.verdict import judge

    if args.output:
        check_output_dir(args.output)
    verdict = judge(args.manifest, args.output, args.preset, args.set or ())
    if not args.quiet:
        print(verdict.table())
        if args.output:
            print(f"wrote {Path(args.output) / 'index.html'}", file=sys.stderr)
    return 0 if verdict.passed else 1
