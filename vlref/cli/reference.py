"""``vlref reference``: the converged single-scattering reference with its per-pixel error estimate."""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import __version__
from ..io.exr import write_exr
from ..io.output_folders import output_dir
from ..io.png import write_png
from ..reference import render_reference
from ..reference.quadrature import RULES
from ..reference.tiles import render_reference_tiled
from ..render import scene_hash
from .options import add_scene_arguments, add_scheduler_argument, load_scene_checked, preview_exposure
from .progress_bar import StageBar

HELP = "converged single-scattering reference with per-pixel error"


def _grid_size(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, not {value}")
    return value


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref reference")
    add_scene_arguments(p, required=True)
    p.add_argument("-o", "--output", default="out_reference",
                   help="output folder for reference.exr/.png, inscatter.exr, error.exr (default: out_reference)")
    p.add_argument("--rel-tol", type=float, default=1e-4,
                   help="target relative error per pixel (default: 1e-4)")
    p.add_argument("--shadow-samples", type=_grid_size, default=512, metavar="N",
                   help="shadow-boundary grid per light and pixel: every lit or shadowed run along a pixel ray longer "
                        "than its light interval / N is split at its exact boundaries (bisected to 1e-12 of the "
                        "distance, 1e-3 --rel-tol^3 above --rel-tol 1e-3, the bracket's width in the error estimate); "
                        "shorter ones are still integrated, but the error estimate may miss them (default: 512)")
    p.add_argument("--rule", type=int, choices=RULES, default=15,
                   help="Gauss-Kronrod rule of the adaptive quadrature by its nodes: 15 (G7-K15), 7 (G3-K7: half the "
                        "evaluations per interval, for a coarse --rel-tol; the error estimate is then the embedded "
                        "G3's) or 3 (G1-K3, the 3-point Gauss rule with the midpoint rule as its estimate: for "
                        "--rel-tol 1e-2 and coarser) (default: 15)")
    add_scheduler_argument(p)
    p.add_argument("--tile-rows", type=int, default=16, metavar="N",
                   help="with --scheduler: image rows per item; the result does not depend on it (default: 16)")
    return p


def run(args) -> int:
    scene = load_scene_checked(args)
    if args.scheduler:  # the cluster's own bar counts the tiles
        res = render_reference_tiled(scene, args.rel_tol, scheduler=args.scheduler, rows_per_tile=args.tile_rows,
                                     shadow_samples=args.shadow_samples, rule=args.rule)
    else:
        with StageBar(False, 4, f"reference {Path(scene.source).stem}") as bar:  # 3 frame stages, then the quadrature
            res = render_reference(scene, rel_tol=args.rel_tol, shadow_samples=args.shadow_samples, rule=args.rule,
                                   progress=bar.stage)
    meta = {"vlref_version": __version__, "scene_hash": scene_hash(scene), "rel_tol": str(args.rel_tol),
            "shadow_samples": str(args.shadow_samples), "rule": str(args.rule)}
    exposure, png_meta, phrase = preview_exposure(scene, res.final)
    with output_dir(args.output) as out:
        write_exr(out / "reference.exr", res.final, metadata=meta)
        write_exr(out / "inscatter.exr", res.inscatter, metadata=meta)
        write_exr(out / "error.exr", res.error, metadata=meta)
        write_png(out / "reference.png", res.final, exposure=exposure, text=png_meta)
    print(f"largest error estimate: {res.max_error:.3e} (target relative {args.rel_tol:g}; {phrase})")
    return 0
