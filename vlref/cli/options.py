"""Options shared by several commands, and the scene they name (checked before any work)."""

from __future__ import annotations

import argparse

from ..io.exposure import luminance, percentile_exposure
from ..io.output_folders import check_output_dir, check_output_file
from ..memory import check_memory
from ..scene import load_scene
from ..scene.model import TECHNIQUES
from ..techniques import APPLIES
from ..techniques.main_light import main_light

__all__ = ["add_scene_arguments", "add_scheduler_argument", "technique_names", "load_scene_checked",
           "preview_exposure"]


def technique_names() -> str:
    """The techniques, comma-separated, for help texts."""
    return ", ".join(TECHNIQUES)


def technique_rules() -> str:
    """Which scenes the techniques apply to, for help texts: each rule that is not 'every scene'."""
    return "; ".join(f"{n} applies to {rule}" for n, rule in APPLIES.items() if rule != "every scene") + \
        " (`vlref scenes` lists the techniques of each bundled scene)"


def add_scene_arguments(p: argparse.ArgumentParser, required: bool = False) -> None:
    """``scene`` (optional unless ``required``), ``--set`` and ``--ignore-memory-check``."""
    if required:
        p.add_argument("scene", help="scene file (TOML/JSON) or bundled scene name (see `vlref scenes`)")
    else:
        p.add_argument("scene", nargs="?", default=None,
                       help="scene file (TOML/JSON) or bundled scene name (default: the bundled default)")
    p.add_argument("--set", action="append", metavar="KEY.PATH=VALUE",
                   help="override any scene field, e.g. render.width=320 or lights.0.intensity=20 "
                        "(repeatable; default: none)")
    p.add_argument("--ignore-memory-check", action="store_true",
                   help="render even when the estimated peak memory exceeds the available memory "
                        "(default: refuse, exit 2)")


def check_report_outputs(output, junit) -> None:
    """Before any work: the report folder ``-o`` (when given) and the JUnit file ``--junit`` (when given) can be
    written (:func:`vlref.io.output_folders.check_output_dir`, :func:`vlref.io.output_folders.check_output_file`)."""
    if output:
        check_output_dir(output)
    if junit:
        check_output_file(junit, "--junit")


def add_scheduler_argument(p: argparse.ArgumentParser) -> None:
    """The ``--scheduler`` option shared by ``golden``, ``reference`` and ``sweep``
    (:func:`vlref.work_items.parse_scheduler` reads it)."""
    p.add_argument("--scheduler", metavar="local[:N]|tcp://HOST:PORT",
                   help="run the independent items on Dask (pip install 'vlref[distributed]'): a "
                        "LocalCluster of N worker processes (default: one per core), or an existing "
                        "scheduler; default: in this process")


def load_scene_checked(args):
    """The scene of ``args`` with its overrides; the output folder, the memory estimate (unless
    ``--ignore-memory-check``) and the main light ``urp`` needs are checked first (before any work)."""
    if getattr(args, "output", None):
        check_output_dir(args.output)
    overrides = list(args.set or [])
    if getattr(args, "technique", None):
        overrides.append(f'render.technique="{args.technique}"')
    scene = load_scene(args.scene, overrides)
    if scene.render.technique == "urp":
        main_light(scene)  # InputError naming the bundled scenes that have one
    if not args.ignore_memory_check:
        check_memory(scene, overrides=list(args.set or []))
    return scene


def preview_exposure(scene, image) -> tuple[float, dict[str, str], str]:
    """The PNG preview's exposure ``render.exposure x 1/p``, ``p`` the ``render.auto_exposure`` percentile of
    ``image``'s luminance (``render.exposure`` alone when that is 0); its PNG tEXt and a summary phrase."""
    r = scene.render
    if r.auto_exposure <= 0.0:
        rule = f"render.exposure {r.exposure:g}"
        return r.exposure, {"vlref_exposure_rule": rule}, f"preview exposure {r.exposure:.4g}"
    auto, level = percentile_exposure(luminance(image), r.auto_exposure)
    exposure = r.exposure * auto
    rule = (f"render.exposure {r.exposure:g} / luminance {level:.6g} at percentile {r.auto_exposure:g} of the "
            "image (render.auto_exposure; 0 = off)")
    return exposure, {"vlref_exposure_rule": rule}, f"preview exposure {exposure:.4g} = 1/p{r.auto_exposure:g} luminance"
