"""``vlref march PORT.toml -o OUT``: a scene's technique on a port's own buffers (:mod:`vlref.port`);
0 written, 2 bad input."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..io.output_folders import check_output_dir
from ..port import load_port, march_sequence, save_march
from .progress_bar import StageBar

HELP = "march and post passes on a port's own buffers"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref march", description="Run a scene's technique on a port's exported "
                                "depth buffer and shadow maps (docs/PORTING.md).")
    p.add_argument("manifest", nargs="+", help="port manifest (TOML); several: the frames of a sequence, in order, "
                   "each given the previous one's temporal history, written to OUT/frame_NNNN (NNNN its index)")
    p.add_argument("-o", "--output", default="out_march", help="output folder (default out_march)")
    p.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                   help="override a scene field (repeatable; default: none)")
    p.add_argument("--stages", action="store_true", help="also write every pass's buffer (default: off)")
    p.add_argument("-q", "--quiet", action="store_true", help="no summary line (default: off)")
    return p


def run(args) -> int:
    start = time.perf_counter()
    check_output_dir(args.output)
    ports = [load_port(m, args.set or ()) for m in args.manifest]
    with StageBar(args.quiet, len(ports), f"march {Path(args.manifest[0]).stem}", unit="frame") as bar:
        for i, (port, out) in enumerate(zip(ports, march_sequence(ports))):  # the bar moves with the march's rows
            save_march(args.output if len(ports) == 1 else Path(args.output) / f"frame_{i:04d}", port, out,
                       args.stages)
            bar.stage()
    port = ports[0]
    if not args.quiet:
        print(f"wrote {args.output} ({port.scene.render.technique}, {time.perf_counter() - start:.2f} s)",
              file=sys.stderr)
    return 0
