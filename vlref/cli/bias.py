"""``vlref bias``: a technique's error against the reference, and how it falls with the step count."""

from __future__ import annotations

import argparse

from pathlib import Path

from ..io.output_folders import output_dir
from ..reference.bias import DEFAULT_STEPS, technique_bias
from .options import add_scene_arguments, load_scene_checked, technique_names, technique_rules
from .progress_bar import StageBar

HELP = "a technique's error against the reference, and how it falls with steps"


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref bias")
    add_scene_arguments(p, required=True)
    p.add_argument("--technique", required=True, metavar="NAME",
                   help=f"the technique to measure ({technique_names()}; {technique_rules()}); required, no default")
    p.add_argument("--steps", help="comma-separated step counts, e.g. 4,8,16,32 (default: 4,8,16,32,64)")
    p.add_argument("-o", "--output", help="write the error images and report here (default: print only)")
    return p


def run(args) -> int:
    scene = load_scene_checked(args)
    steps = tuple(int(s) for s in args.steps.split(",")) if args.steps else DEFAULT_STEPS
    # the reference's 3 frame stages and its quadrature, then one render per step count
    with StageBar(False, 4 + len(steps), f"bias {Path(scene.source).stem} {args.technique}") as bar:
        report = technique_bias(scene, args.technique, steps, progress=bar.stage)
    print(report.summary())
    if args.output:
        with output_dir(args.output) as out:
            report.save(out)
    return 0
