"""The march's stages priced by taking them away: the physical march of bench scene (a) or (b) with the shadow lookup,
the light leg's extinction or the height fog switched off in the scene (BENCHMARKS.md, "The march's stages on the
device, priced by taking them away").

Each switch turns a stage of :mod:`vlref.march.physical` into its cheap branch of the same compiled kernel (no light
with shadows: ``_shadow_stage`` sets ``V = 1``; ``light_extinction = false``: ``_leg_stage`` sets ``T_l = 1``; no height
fog: ``_medium_stage`` takes the constant density and ``_leg_stage`` the homogeneous medium's ``exp(-σt · dist)``),
so a variant's time less the full scene's is what that stage costs, to within what the compiled loops share.
The samples (pixel, light) x steps are the same in every variant: no switch moves a segment.

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc python3 benchmarks/march_stages.py stages [one|four] [ROUNDS] [REPEATS]
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc python3 benchmarks/march_stages.py scenes LABEL [REPEATS]

``stages``: per round, every variant in turn, first at 1920x1080 on all threads, then at 480x270 on one thread.
``scenes``: the bundled scenes of :data:`SCENES` (homogeneous media, no height fog: the bundled scenes' common case,
which the bench scenes' fog does not take) at 1920x1080x64 on all threads, once, labelled ``LABEL`` (run it from two
trees in turn for an A/B). Each figure is the median of ``REPEATS`` calls of
:func:`vlref.techniques.physical.march_buffers` on a prepared frame (the frame, its shadow maps and a warm-up call
outside the time); one line per figure, printed and appended to ``$OUT/march_stages.jsonl``.
"""

import dataclasses
import json
import os
import sys

import numba

from vlref.bench.config import FULL, bench_scene, median_time
from vlref.bench.march import march_samples
from vlref.render import prepare_frame
from vlref.scene.load import load_scene
from vlref.scene.technique_params import PhysicalParams, resolved
from vlref.techniques import physical

VARIANTS = ("full", "no_shadows", "no_leg", "no_fog", "none")
SCENES = ("pillars", "coloured_lights", "cage")


def variant(lights: str, name: str, width: int, height: int):
    """Bench scene (a) (``lights = "one"``) or (b) (``"four"``) at ``width x height`` with the stages of ``name`` off."""
    scene = bench_scene(width, height, FULL.steps, lights, FULL.shadow_resolution)
    if name in ("no_shadows", "none"):
        scene = scene.replace(lights=tuple(dataclasses.replace(light, shadows=None) for light in scene.lights))
    if name in ("no_leg", "none"):
        scene = scene.replace(techniques=dataclasses.replace(scene.techniques,
                                                             physical=PhysicalParams(light_extinction=False)))
    if name in ("no_fog", "none"):
        scene = scene.replace(medium=dataclasses.replace(scene.medium, height_fog=None))
    return scene


def timed(scene, repeats: int) -> tuple[float, int]:
    """Median seconds of the march of ``scene`` over ``repeats`` calls after a warm-up, and its samples."""
    frame = prepare_frame(scene)
    maps = frame.shadow_maps()

    def march():
        return physical.march_buffers(scene, frame.camera, frame.gbuffer.distance, frame.lights, maps,
                                      frame.geometry.arrays, resolved(scene, "steps"), resolved(scene, "sampling"))

    march()
    return median_time(march, repeats), march_samples(scene, frame)


def _write(row: dict) -> None:
    print(json.dumps(row), flush=True)
    with open(os.path.join(os.environ.get("OUT", "."), "march_stages.jsonl"), "a") as fh:
        fh.write(json.dumps(row) + "\n")


def stages(lights: str = "one", rounds: int = 3, repeats: int = 3) -> None:
    threads = numba.get_num_threads()
    for r in range(rounds):
        for width, height, n in ((1920, 1080, threads), (480, 270, 1)):
            numba.set_num_threads(n)
            for name in VARIANTS:
                seconds, samples = timed(variant(lights, name, width, height), repeats)
                _write({"round": r, "lights": lights, "variant": name, "width": width, "height": height, "threads": n,
                        "seconds": seconds, "samples": samples, "msamples_per_s": samples / seconds / 1e6})
    numba.set_num_threads(threads)


def scenes(label: str, repeats: int = 3) -> None:
    for name in SCENES:
        seconds, samples = timed(load_scene(name, ("render.width=1920", "render.height=1080", "render.steps=64")),
                                 repeats)
        _write({"label": label, "scene": name, "threads": numba.get_num_threads(), "seconds": seconds,
                "samples": samples, "msamples_per_s": samples / seconds / 1e6})


if __name__ == "__main__":
    if sys.argv[1] == "stages":
        stages(sys.argv[2] if len(sys.argv) > 2 else "one", *(int(a) for a in sys.argv[3:5]))
    else:
        scenes(sys.argv[2], *(int(a) for a in sys.argv[3:4]))
