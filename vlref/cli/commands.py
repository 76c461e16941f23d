"""The ``vlref`` command.

Exit codes: 0 success (``compare``: pass), 1 ``compare``/``golden verify`` failed, 2 bad input
(the message names the file, the field and the reason, and nothing is written), 130 / 143 interrupted
by SIGINT (Ctrl-C) / SIGTERM (one line ``vlref: interrupted``, nothing partial left behind).
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import threading
from pathlib import Path

from . import __version__
from .cluster import ItemsFailed, add_scheduler_argument
from .errors import InputError

# Buffers `vlref render` writes without --stages (EXR), besides final.png.
MAIN_BUFFERS = ("final", "depth", "inscatter", "transmittance")


class _Bar:
    """Progress on stderr: a tqdm bar over a command's stages, then over the rows of each banded kernel.

    ``stage(name)`` completes a stage; ``rows(done, total)`` (a :mod:`vlref.progress` listener) counts
    the rows of a long kernel (the march, the quadrature), so the bar moves on long work and its time
    estimate is the kernel's. Each bar shows only once its work has lasted about a second. Quiet: none.
    """

    def __init__(self, quiet: bool, stages: int, desc: str):
        self.quiet, self.stages, self.desc, self.done = quiet, stages, desc, 0
        self.bar = None

    def _show(self, n: int, total: int, unit: str, desc: str) -> None:
        if self.quiet:
            return
        if self.bar is None or self.bar.unit != unit or self.bar.total != total:
            from tqdm import tqdm
            self.close()
            self.bar = tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, delay=1.0, leave=False)
        self.bar.update(n - self.bar.n)

    def stage(self, name: str | None = None) -> None:
        self.done += 1
        self._show(self.done, self.stages, "stage", self.desc)

    def rows(self, done: int, total: int) -> None:
        self._show(done, total, "row", f"{self.desc}, stage {self.done + 1}/{self.stages}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self):
        from .progress import reporting
        self._reporting = reporting(self.rows)
        self._reporting.__enter__()
        self._show(0, self.stages, "stage", self.desc)
        return self

    def __exit__(self, *exc) -> None:
        self._reporting.__exit__(*exc)
        self.close()


def _load(args):
    """The scene of ``args`` with its overrides; the output folder and the memory estimate are checked
    first (before any work), unless ``--ignore-memory-check``."""
    from .io import check_output_dir
    from .memory import check_memory
    from .scene import load_scene

    if getattr(args, "output", None):
        check_output_dir(args.output)
    overrides = list(args.set or [])
    if getattr(args, "technique", None):
        overrides.append(f'render.technique="{args.technique}"')
    scene = load_scene(args.scene, overrides)
    if not args.ignore_memory_check:
        check_memory(scene)
    return scene


def _preview_exposure(scene, image) -> tuple[float, dict[str, str], str]:
    """The PNG preview's exposure ``render.exposure x 1/p``, ``p`` the ``render.auto_exposure`` percentile of
    ``image``'s luminance (``render.exposure`` alone when that is 0); its PNG tEXt and a summary phrase."""
    from .io import luminance, percentile_exposure

    r = scene.render
    if r.auto_exposure <= 0.0:
        rule = f"render.exposure {r.exposure:g}"
        return r.exposure, {"vlref_exposure_rule": rule}, f"preview exposure {r.exposure:.4g}"
    auto, level = percentile_exposure(luminance(image), r.auto_exposure)
    exposure = r.exposure * auto
    rule = (f"render.exposure {r.exposure:g} / luminance {level:.6g} at percentile {r.auto_exposure:g} of the "
            "image (render.auto_exposure; 0 = off)")
    return exposure, {"vlref_exposure_rule": rule}, f"preview exposure {exposure:.4g} = 1/p{r.auto_exposure:g} luminance"


def cmd_render(args) -> int:
    from .io import output_dir, save_render
    from .render import render

    from .warmup import march_ahead

    scene = _load(args)
    if args.frames is not None:
        return _render_frames(args, scene)
    # 4 render stages, then the files; a cold march kernel compiles in a second process meanwhile
    with _Bar(args.quiet, 5, f"render {Path(scene.source).stem}") as bar, march_ahead(scene) as march_ready:
        def stage(name: str) -> None:
            if name == "shading":  # the frame is done: the march comes next
                march_ready()
            bar.stage(name)

        result = render(scene, stages=args.stages, progress=stage)
        exposure, png_meta, phrase = _preview_exposure(scene, result.buffers["final"])
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
    from .io import output_dir
    from .sequence import parse_frames, write_sequence

    frames = parse_frames(args.frames, scene)
    with _Bar(args.quiet, len(frames), f"render {Path(scene.source).stem} frames") as bar, \
            output_dir(args.output) as out:
        write_sequence(out, scene, frames, args.stages, MAIN_BUFFERS, on_frame=lambda f: bar.stage())
    if not args.quiet:
        print(f"wrote {args.output} (frames {frames.start}..{frames.stop - 1}, {scene.render.technique})",
              file=sys.stderr)
    return 0


def cmd_scenes(args) -> int:
    from .scene import bundled_scenes, load_scene
    for name, path in bundled_scenes().items():
        print(f"{name:16s} {load_scene(path).description}")
    return 0


def cmd_reference(args) -> int:
    from .io import output_dir, write_exr, write_png
    from .reference import render_reference
    from .render import scene_hash

    scene = _load(args)
    if args.scheduler:  # the cluster's own bar counts the tiles
        from .reference.tiles import render_reference_tiled
        res = render_reference_tiled(scene, args.rel_tol, scheduler=args.scheduler, rows_per_tile=args.tile_rows)
    else:
        with _Bar(False, 4, f"reference {Path(scene.source).stem}") as bar:  # 3 frame stages, then the quadrature
            res = render_reference(scene, rel_tol=args.rel_tol, progress=bar.stage)
    meta = {"vlref_version": __version__, "scene_hash": scene_hash(scene), "rel_tol": str(args.rel_tol)}
    exposure, png_meta, phrase = _preview_exposure(scene, res.final)
    with output_dir(args.output) as out:
        write_exr(out / "reference.exr", res.final, metadata=meta)
        write_exr(out / "inscatter.exr", res.inscatter, metadata=meta)
        write_exr(out / "error.exr", res.error, metadata=meta)
        write_png(out / "reference.png", res.final, exposure=exposure, text=png_meta)
    print(f"largest error estimate: {res.max_error:.3e} (target relative {args.rel_tol:g}; {phrase})")
    return 0


def cmd_bias(args) -> int:
    from .io import output_dir
    from .reference.bias import technique_bias

    scene = _load(args)
    steps = tuple(int(s) for s in args.steps.split(",")) if args.steps else None
    report = technique_bias(scene, args.technique, steps) if steps else technique_bias(scene, args.technique)
    print(report.summary())
    if args.output:
        with output_dir(args.output) as out:
            report.save(out)
    return 0


def cmd_sweep(args) -> int:
    from .io import check_output_dir
    from .sweep import load_sweep, run_sweep

    check_output_dir(args.output)
    spec = load_sweep(args.spec)
    rows = run_sweep(spec, args.output, scheduler=args.scheduler, quiet=args.quiet)
    if not args.quiet:
        print(f"sweep: {len(rows)} items in {args.output}/summary.csv", file=sys.stderr)
    return 0


def _passthrough(module: str, function: str):
    """A sub-command whose own argument parser lives in ``vlref.<module>`` (imported when used)."""
    def run(argv: list[str]) -> int:
        import importlib
        return int(getattr(importlib.import_module(f"vlref.{module}"), function)(argv))
    return run


# Sub-commands that parse their own arguments: ``vlref NAME ...`` hands everything after NAME over.
PASSTHROUGH = {
    "golden": (_passthrough("oracle.golden", "main_golden"), "build or verify the golden suite"),
    "march": (_passthrough("oracle.port_buffers", "main_march"), "march and post passes on a port's own buffers"),
    "bench": (_passthrough("bench", "main_bench"), "benchmarks (--quick, --json)"),
    "warmup": (_passthrough("warmup", "main_warmup"), "compile every kernel once (later first renders start at once)"),
}


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref", description="vlref: a CPU reference renderer for real-time "
                                "volumetric lighting (god rays). Exit codes: 0 ok, 1 compare/verify failed, 2 bad input, "
                                "130/143 interrupted (Ctrl-C / SIGTERM).")
    p.add_argument("--version", action="version", version=f"vlref {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    from .scene.model import TECHNIQUES
    techniques = ", ".join(TECHNIQUES)

    def scene_args(sp, required=False):
        if required:
            sp.add_argument("scene", help="scene file (TOML/JSON) or bundled scene name (see `vlref scenes`)")
        else:
            sp.add_argument("scene", nargs="?", default=None,
                            help="scene file (TOML/JSON) or bundled scene name (default: the bundled default)")
        sp.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                        help="override any scene field, e.g. render.width=320 or lights.0.intensity=20 "
                             "(repeatable; default: none)")
        sp.add_argument("--ignore-memory-check", action="store_true",
                        help="render even when the estimated peak memory exceeds the available memory "
                             "(default: refuse, exit 2)")

    r = sub.add_parser("render", help="render a scene")
    scene_args(r)
    r.add_argument("-o", "--output", default="out", help="output folder (default: out)")
    r.add_argument("--technique", metavar="NAME",
                   help=f"technique ({techniques}); shortcut for --set render.technique=NAME "
                        "(default: the scene's render.technique, physical when unset)")
    r.add_argument("--stages", action="store_true", help="also write every pass's buffer and shadow map (default: off)")
    r.add_argument("--frames", metavar="A:B", help="render frames A..B-1 of the scene's [animation] as numbered "
                   "EXR sequences (<buffer>.NNNN.exr) plus preview.gif (and preview.mp4 with vlref[video]) "
                   "(default: one frame, render.frame)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar, notes or summary (default: off)")
    r.set_defaults(func=cmd_render)

    s = sub.add_parser("scenes", help="list the bundled scenes")
    s.set_defaults(func=cmd_scenes)

    ref = sub.add_parser("reference", help="converged single-scattering reference with per-pixel error")
    scene_args(ref, required=True)
    ref.add_argument("-o", "--output", default="out_reference",
                     help="output folder for reference.exr/.png, inscatter.exr, error.exr (default: out_reference)")
    ref.add_argument("--rel-tol", type=float, default=1e-4,
                     help="target relative error per pixel (default: 1e-4)")
    add_scheduler_argument(ref)
    ref.add_argument("--tile-rows", type=int, default=16, metavar="N",
                     help="with --scheduler: image rows per item; the result does not depend on it (default: 16)")
    ref.set_defaults(func=cmd_reference)

    b = sub.add_parser("bias", help="a technique's error against the reference, and how it falls with steps")
    scene_args(b, required=True)
    b.add_argument("--technique", required=True, metavar="NAME",
                   help=f"the technique to measure ({techniques}); required, no default")
    b.add_argument("--steps", help="comma-separated step counts, e.g. 4,8,16,32 (default: 4,8,16,32,64)")
    b.add_argument("-o", "--output", help="write the error images and report here (default: print only)")
    b.set_defaults(func=cmd_bias)

    sw = sub.add_parser("sweep", help="a technique x parameter grid against the reference (error, time, FLIP)")
    sw.add_argument("spec", help="sweep file (TOML): scene, set, techniques, metrics, [grid] or points")
    sw.add_argument("-o", "--output", default="out_sweep", help="output folder (default: out_sweep)")
    add_scheduler_argument(sw)
    sw.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary (default: off)")
    sw.set_defaults(func=cmd_sweep)

    from .oracle.compare import add_arguments, run_compare
    c = sub.add_parser("compare", help="compare two images (exit 0 pass, 1 fail, 2 bad input)")
    add_arguments(c)
    c.set_defaults(func=run_compare)

    for name, (_, text) in PASSTHROUGH.items():
        sub.add_parser(name, help=text, add_help=False)  # listed in --help; run by main() directly
    return p


class Interrupted(KeyboardInterrupt):
    """Raised in the main thread by SIGINT (Ctrl-C) or SIGTERM while a ``vlref`` command runs."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _raise_interrupted(signum, frame):
    # Further signals are ignored from here on, so the clean-up the exception unwinds through (temporary
    # files and folders of vlref.io) runs to its end.
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    raise Interrupted(signum)


@contextlib.contextmanager
def _interruptible():
    """SIGINT and SIGTERM raise :class:`Interrupted` inside the block (main thread only); handlers restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.signal(sig, _raise_interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def main(argv: list[str] | None = None) -> int:
    """Run a command. Ctrl-C or SIGTERM: one line ``vlref: interrupted``, exit 130 / 143 (128 + signal),
    no partial output (files are written atomically, folders all or nothing: :mod:`vlref.io`)."""
    with _interruptible():
        try:
            return _run(list(sys.argv[1:] if argv is None else argv))
        except KeyboardInterrupt as exc:
            print("vlref: interrupted", file=sys.stderr)
            return 128 + int(getattr(exc, "signum", signal.SIGINT))


def _run(argv: list[str]) -> int:
    try:
        if argv and argv[0] in PASSTHROUGH:
            return PASSTHROUGH[argv[0]][0](argv[1:])
    except InputError as exc:
        print(f"vlref: error: {exc}", file=sys.stderr)
        return 2
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: 2 on bad usage, 0 on --help/--version
        return int(exc.code or 0)
    try:
        return int(args.func(args))
    except InputError as exc:
        print(f"vlref: error: {exc}", file=sys.stderr)
        return 2
    except ItemsFailed as exc:
        print(f"vlref: {exc}", file=sys.stderr)
        return exc.exit_code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
