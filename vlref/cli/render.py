"""``vlref render``: one frame (EXR buffers and a PNG preview) or, with ``--frames``, a sequence."""

from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import sys
import time
from pathlib import Path

from ..ahead import compile_ahead
from ..errors import InputError
from ..io.files import write_bytes
from ..io.output_folders import output_dir
from ..io.png import png_bytes, write_png
from ..io.render_files import save_render
from ..io.tonemap import srgb8
from ..render import render
from ..sequence import parse_frames, write_sequence
from ..sheet import contact_sheet, inscatter_level, labelled
from ..techniques import TECHNIQUES
from .options import add_scene_arguments, load_scene_checked, preview_exposure, technique_names, technique_rules
from .progress_bar import StageBar

HELP = "render a scene"
MAIN_BUFFERS = ("final", "depth", "inscatter", "transmittance")
"""Buffers ``vlref render`` writes without ``--stages`` (EXR), besides final.png."""
LIGHT_BUFFERS = ("final", "inscatter", "transmittance")
"""The buffers ``--half-float`` stores as half floats (depth and the stage buffers stay float32)."""


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref render")
    add_scene_arguments(p)
    p.add_argument("-o", "--output", default="out", help="output folder (default: out)")
    p.add_argument("--technique", metavar="NAME",
                   help=f"technique ({technique_names()}); {technique_rules()}; shortcut for --set "
                        "render.technique=NAME; 'all': "
                        "every technique that applies to the scene, one exposure for all, DIR/<technique>/ and "
                        "a labelled side-by-side DIR/sheet.png (default: the scene's render.technique, physical "
                        "when unset)")
    p.add_argument("--stages", action="store_true", help="also write every pass's buffer and shadow map (default: off)")
    p.add_argument("--half-float", action="store_true",
                   help=f"store the light buffers ({', '.join(LIGHT_BUFFERS)}) as half-float EXR: half the bytes, "
                        "11 significant bits, values above 65504 become inf (default: off, float32)")
    p.add_argument("--frames", metavar="A:B", help="render frames A..B-1 of the scene's [animation] as numbered "
                   "EXR sequences (<buffer>.NNNN.exr) plus preview.gif (and preview.mp4 with vlref[video]) "
                   "(default: one frame, render.frame)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar, notes or summary (default: off)")
    return p


def render_to_folder(scene, output, stages: bool = False, half_float: bool = False, quiet: bool = True):
    """What ``vlref render`` does with one frame: render ``scene``, write its buffers and preview into ``output``
    (all or nothing). Returns ``(result, phrase, write_seconds, kept)``: the render, the preview-exposure phrase,
    the time from the end of the render to the files in place (exposure, EXR, PNG), and the files of an earlier
    run that ``output`` still holds (this run did not write them)."""
    # 4 render stages, then the files; cold kernels of later stages compile in second processes meanwhile
    with StageBar(quiet, 5, f"render {Path(scene.source).stem}") as bar, compile_ahead(scene) as ready:
        def stage(name: str) -> None:
            if name != "shadow maps":  # built within the volumetric stage: not a stage of the bar
                bar.stage(name)
            ready(name)  # the next stage's kernels, where a second process compiles them

        result = render(scene, stages=stages, progress=stage)
        earlier = _files(output)
        start = time.perf_counter()
        with output_dir(output) as out, concurrent.futures.ThreadPoolExecutor(1) as pool:
            preview = pool.submit(_write_preview, scene, result.buffers["final"], out / "final.png")
            save_render(out, result, stages=stages, main=MAIN_BUFFERS, half=LIGHT_BUFFERS if half_float else (),
                        preview=False)
            phrase = preview.result()
            kept = sorted(earlier - _files(out))
    return result, phrase, time.perf_counter() - start, kept


def _write_preview(scene, final, path) -> str:
    """Write the PNG preview of ``final`` at the scene's preview exposure (:func:`preview_exposure`) to ``path``;
    the exposure's phrase. ``render_to_folder`` runs it on a thread beside the EXR files."""
    exposure, png_meta, phrase = preview_exposure(scene, final)
    write_png(path, final, exposure, png_meta)
    return phrase


def run(args) -> int:
    every = args.technique == "all"
    if every:
        if args.frames is not None:
            raise InputError("<command line>", "--technique all", "renders one frame of each technique: drop --frames")
        args.technique = None
    scene = load_scene_checked(args)
    if every:
        return _render_all(args, scene)
    if args.frames is not None:
        return _render_frames(args, scene)
    result, phrase, _, kept = render_to_folder(scene, args.output, args.stages, args.half_float, args.quiet)
    if not args.quiet:
        _note_kept(args.output, kept)
        for note in result.notes:
            print(f"vlref: note: {note}", file=sys.stderr)
        total = sum(result.timings.values())
        print(f"wrote {args.output} ({scene.render.width}x{scene.render.height}, "
              f"{scene.render.technique}, {total:.2f} s; {phrase})", file=sys.stderr)
    return 0


def _render_frames(args, scene) -> int:
    """``vlref render --frames A:B``: a numbered EXR sequence and previews (:mod:`vlref.sequence`)."""
    frames = parse_frames(args.frames, scene)
    earlier = _files(args.output)
    if scene.animation is None and not args.quiet:
        print(f"vlref: note: {Path(scene.source).name} has no [animation]: every frame shows the same scene "
              "(only render.frame's temporal jitter and froxel's history change); `vlref scenes` marks the "
              "animated ones", file=sys.stderr)
    with StageBar(args.quiet, len(frames), f"render {Path(scene.source).stem}", "frame") as bar, \
            output_dir(args.output) as out:
        write_sequence(out, scene, frames, args.stages, MAIN_BUFFERS, on_frame=lambda f: bar.stage())
        kept = sorted(earlier - _files(out))
    if not args.quiet:
        _note_kept(args.output, kept)
        print(f"wrote {args.output} (frames {frames.start}..{frames.stop - 1}, {scene.render.technique})",
              file=sys.stderr)
    return 0


def _render_all(args, scene) -> int:
    """``vlref render SCENE --technique all``: every technique that applies, one exposure (:mod:`vlref.sheet`)."""
    names = [name for name, t in TECHNIQUES.items() if t.applies(scene)]
    results = {}
    with StageBar(args.quiet, len(names), f"render {Path(scene.source).stem}", "technique") as bar:
        for name in names:
            results[name] = render(scene.replace(render=dataclasses.replace(scene.render, technique=name)),
                                   stages=args.stages)
            bar.stage(name)
    physical = results["physical"].buffers
    exposure, png_meta, phrase = preview_exposure(scene, physical["final"])
    png_meta = {**png_meta, "vlref_exposure_rule": "physical's: " + png_meta["vlref_exposure_rule"]}
    levels = {name: inscatter_level(r.buffers["inscatter"], physical["inscatter"]) for name, r in results.items()}
    earlier = _files(args.output)
    with output_dir(args.output) as out:
        for name, result in results.items():
            (out / name).mkdir()
            save_render(out / name, result, stages=args.stages, main=MAIN_BUFFERS, exposure=exposure,
                        png_meta=png_meta)
        sheet = contact_sheet([labelled(srgb8(r.buffers["final"], exposure), f"{name}  {levels[name]:.3g}x physical")
                               for name, r in results.items()])
        write_bytes(out / "sheet.png", png_bytes(sheet, png_meta))
        kept = sorted(earlier - _files(out))
    if not args.quiet:
        _note_kept(args.output, kept)
        for name, result in results.items():
            for note in result.notes:
                print(f"vlref: note: {name}: {note}", file=sys.stderr)
        print("level against physical (mean inscatter luminance ratio): "
              + ", ".join(f"{name} {level:.3g}x" for name, level in levels.items()), file=sys.stderr)
        print(f"wrote {args.output}/<technique>/ and {args.output}/sheet.png ({scene.render.width}x"
              f"{scene.render.height}, {len(names)} techniques at one exposure; {phrase} of physical)", file=sys.stderr)
    return 0


def _files(folder) -> set[str]:
    """The files under ``folder`` (relative paths; none when it does not exist)."""
    root = Path(folder)
    return {str(p.relative_to(root)) for p in root.rglob("*") if p.is_file()} if root.is_dir() else set()


def _note_kept(folder, kept: list[str]) -> None:
    """Say which files of an earlier run the output folder still holds (a render replaces only its own)."""
    if kept:
        print(f"vlref: note: {folder} keeps {len(kept)} file(s) of an earlier run that this one did not write: "
              f"{', '.join(kept[:4])}{', ...' if len(kept) > 4 else ''}", file=sys.stderr)
