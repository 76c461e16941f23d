"""``vlref render``: one frame (EXR buffers and a PNG preview) or, with ``--frames``, a sequence."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..io import output_dir, save_render
from ..render import render
from ..sequence import parse_frames, write_sequence
from ..warmup import march_ahead
from .options import add_scene_arguments, load_scene_checked, preview_exposure, technique_names
from .progress_bar import StageBar

HELP = "render a scene"
MAIN_BUFFERS = ("final", "depth", "inscatter", "transmittance")
"""Buffers ``vlref render`` writes without ``--stages`` (EXR), besides final.png."""


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref render")
    add_scene_arguments(p)
    p.add_argument("-o", "--output", default="out", help="output folder (default: out)")
    p.add_argument("--technique", metavar="NAME",
                   help=f"technique ({technique_names()}); shortcut for --set render.technique=NAME "
                        "(default: the scene's render.technique, physical when unset)")
    p.add_argument("--stages", action="store_true", help="also write every pass's buffer and shadow map (default: off)")
    p.add_argument("--frames", metavar="A:B", help="render frames A..B-1 of the scene's [animation] as numbered "
                   "EXR sequences (<buffer>.NNNN.exr) plus preview.gif (and preview.mp4 with vlref[video]) "
                   "(default: one frame, render.frame)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar, notes or summary (default: off)")
    return p


def run(args) -> int:
    scene = load_scene_checked(args)
    if args.frames is not None:
        return _render_frames(args, scene)
    # 4 render stages, then the files; a cold march kernel compiles in a second process meanwhile
    with StageBar(args.quiet, 5, f"render {Path(scene.source).stem}") as bar, march_ahead(scene) as march_ready:
        def stage(name: str) -> None:
            if name == "shadow maps":  # built (part of the volumetric stage): the march comes next
                march_ready()
            else:
                bar.stage(name)

        result = render(scene, stages=args.stages, progress=stage)
        exposure, png_meta, phrase = preview_exposure(scene, result.buffers["final"])
        with output_dir(args.output) as out:
            save_render(out, result, stages=args.stages, main=MAIN_BUFFERS, exposure=exposure, png_meta=png_meta)
    if not args.quiet:
        for note in result.notes:
            print(f"vlref: note: {note}", file=sys.stderr)
        total = sum(result.timings.values())
        print(f"wrote {args.output} ({scene.render.width}x{scene.render.height}, "
              f"{scene.render.technique}, {total:.2f} s; {phrase})", file=sys.stderr)
    return 0


def _render_frames(args, scene) -> int:
    """``vlref render --frames A:B``: a numbered EXR sequence and previews (:mod:`vlref.sequence`)."""
    frames = parse_frames(args.frames, scene)
    with StageBar(args.quiet, len(frames), f"render {Path(scene.source).stem} frames") as bar, \
            output_dir(args.output) as out:
        write_sequence(out, scene, frames, args.stages, MAIN_BUFFERS, on_frame=lambda f: bar.stage())
    if not args.quiet:
        print(f"wrote {args.output} (frames {frames.start}..{frames.stop - 1}, {scene.render.technique})",
              file=sys.stderr)
    return 0
