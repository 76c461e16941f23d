"""``vlref march PORT.toml -o OUT``: a scene's technique on a port's own buffers (:mod:`vlref.port`);
0 written, 2 bad input."""

from __future__ import annotations

import argparse
import sys
import time

from ..io import check_output_dir
from ..port import load_port, march, save_march

HELP = "march and post passes on a port's own buffers"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref march", description="Run a scene's technique on a port's exported "
                                "depth buffer and shadow maps (docs/PORTING.md).")
    p.add_argument("manifest", help="port manifest (TOML)")
    p.add_argument("-o", "--output", default="out_march", help="output folder (default out_march)")
    p.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                   help="override a scene field (repeatable; default: none)")
    p.add_argument("--stages", action="store_true", help="also write every pass's buffer (default: off)")
    p.add_argument("-q", "--quiet", action="store_true", help="no summary line (default: off)")
    return p


def run(args) -> int:
    start = time.perf_counter()
    check_output_dir(args.output)
    port = load_port(args.manifest, args.set or ())
    save_march(args.output, port, march(port), args.stages)
    if not args.quiet:
        print(f"wrote {args.output} ({port.scene.render.technique}, {time.perf_counter() - start:.2f} s)",
              file=sys.stderr)
    return 0
