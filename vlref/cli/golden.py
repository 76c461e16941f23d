"""``vlref golden build|verify|list``: 0 success / pass, 1 verify failed, 2 bad input (:mod:`vlref.oracle.golden`)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from tqdm import tqdm

from ..io.output_folders import check_output_dir, check_output_file
from ..oracle.golden import (SUITE_FILE, build, build_dir, find_golden_dir, load_suite, select_entries, suite_entries,
                             verify)
from ..oracle.junit import Case, write_junit
from .options import add_scheduler_argument

HELP = "build or verify the golden suite"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref golden", description="Build or verify the golden suite "
                                "(verify: exit 0 pass, 1 fail, 2 bad input).")
    p.add_argument("action", choices=("build", "verify", "list"),
                   help="build: render and store the goldens; verify: re-render and compare; list: the entries")
    p.add_argument("--dir", help="golden folder (default: $VLREF_GOLDEN, else the checkout's data/golden, else the "
                   "installed <prefix>/share/vlref/golden)")
    p.add_argument("--suite", default=str(SUITE_FILE), help="suite file (default: vlref/data/golden_suite.toml)")
    p.add_argument("--only", action="append", metavar="GLOB",
                   help="entries whose name (scene/technique) matches, e.g. 'pillars/*' (repeatable; default: all)")
    p.add_argument("--preset", help="verify: tolerance preset instead of the manifest's (default: the manifest's)")
    p.add_argument("--junit", metavar="FILE", help="verify: also write JUnit XML, one test case per entry and "
                   "buffer (default: none)")
    p.add_argument("-q", "--quiet", action="store_true", help="print only the summary (default: off)")
    add_scheduler_argument(p)
    return p


def junit_cases(outcomes) -> list[Case]:
    """One :class:`Case` per (entry, buffer) of ``golden verify``'s outcomes: a buffer fails on
    its own problems (``"<buffer>: ..."``) and on its entry's (scene changed ...); an entry never compared
    (missing, tampered, stale suite) is one case holding all its problems."""
    cases = []
    for o in outcomes:
        own = {buf: [p for p in o.problems if p.startswith(f"{buf}:")] for buf in o.margins}
        shared = [p for p in o.problems if not any(p in v for v in own.values())]
        if not o.margins:
            cases.append(Case(o.name, not o.problems, {}, None, "; ".join(o.problems)))
        for buf, (frac, bound, max_abs) in o.margins.items():
            problems = shared + own[buf]
            cases.append(Case(f"{o.name} {buf}", not problems, {"frac_failing": frac, "max_fail_fraction": bound,
                                                               "max_abs": max_abs}, None, "; ".join(problems)))
    return cases


def run(args) -> int:
    log = (lambda *a, **k: None) if args.quiet else tqdm.write  # lines above the items' progress bar
    start = time.perf_counter()
    if args.action == "list":
        for e in select_entries(suite_entries(load_suite(args.suite)), args.only):
            print(f"{e.name:32s} {' '.join(e.overrides)}")
        return 0
    if args.action == "build":
        folder = args.dir or str(build_dir())
        check_output_dir(folder, "--dir")
        manifest = build(folder, args.suite, args.only, log, args.scheduler, args.quiet)
        size = sum(p.stat().st_size for p in Path(folder).rglob("*") if p.is_file())
        print(f"golden build: {len(manifest['entries'])} entries, {size / 1e6:.2f} MB in {folder} "
              f"({time.perf_counter() - start:.1f} s)")
        return 0
    if args.junit:
        check_output_file(args.junit, "--junit")
    outcomes = verify(args.dir or find_golden_dir(), args.suite, args.only, args.preset, log, args.scheduler,
                      args.quiet)
    failed = [o for o in outcomes if o.problems]
    if args.junit:
        write_junit(args.junit, "vlref golden verify", junit_cases(outcomes))
    print(f"golden verify: {len(outcomes) - len(failed)} of {len(outcomes)} passed "
          f"({time.perf_counter() - start:.1f} s)" + (f"; FAILED: {', '.join(o.name for o in failed)}" if failed else ""))
    return 1 if failed else 0
