"""``vlref warmup [--jobs N]``: compile every kernel into Numba's cache with a progress bar (:mod:`vlref.warmup`)."""

from __future__ import annotations

import argparse
import sys
import time

from ..warmup import TASKS, cache_location, warmup

HELP = "compile every kernel once (later first renders start at once)"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref warmup", description="compile every kernel into Numba's cache "
                                "once (a later first render then starts at once); a second run only loads")
    p.add_argument("--jobs", type=int, help="worker processes (default: the available cores)")
    return p


def run(args) -> int:
    from tqdm import tqdm

    start = time.perf_counter()
    with tqdm(total=len(TASKS), desc="vlref warmup", unit="group", file=sys.stderr, leave=False) as bar:
        def done(name):
            bar.set_postfix_str(name, refresh=False)
            bar.update(1)
        warmup(args.jobs, done)
    print(f"vlref warmup: {len(TASKS)} kernel groups compiled or loaded in {time.perf_counter() - start:.1f} s "
          f"(cache: {cache_location()})", file=sys.stderr)
    return 0
