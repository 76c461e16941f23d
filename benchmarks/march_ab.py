"""March A/B of two trees on one machine (BENCHMARKS.md, "Four lights"): the physical march of bench scenes (a) one
spot and (b) four lights at 1920x1080x64, float64 and float32, timed as ``vlref bench``'s ``march`` section does
(:func:`vlref.techniques.physical.render` of a prepared frame, median of ``--repeats`` after a warm-up).

Run from a tree's root, once per precision with ``warm`` (compiles into the tree's ``NUMBA_CACHE_DIR`` at 32x18; the
processes of two trees and precisions can run side by side), then alternate the trees with ``time``:

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/march_ab.py warm LABEL float64
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/march_ab.py time LABEL

``time`` prints one line per figure and appends them to ``$OUT/march_ab.jsonl``. ``split LABEL`` times, for both
scenes in float64, the parts of ``physical.render``: the march (:func:`~vlref.techniques.physical.march_buffers`), the
sum over lights and the composite (medians of ``--repeats``), into the same file.
"""

import dataclasses
import json
import os
import sys

from vlref.bench.config import FULL, bench_scene, median_time
from vlref.bench.march import march_samples
from vlref.post.composite import sum_and_composite
from vlref.render import prepare_frame
from vlref.scene.technique_params import resolved
from vlref.techniques import physical

SCENES = (("one_spot", "one"), ("four_lights", "four"))


def scene_for(lights: str, precision: str, width: int, height: int):
    scene = bench_scene(width, height, FULL.steps, lights, FULL.shadow_resolution)
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, precision=precision))


def _write(row: dict) -> None:
    with open(os.path.join(os.environ.get("OUT", "."), "march_ab.jsonl"), "a") as fh:
        fh.write(json.dumps(row) + "\n")


def split(label: str, repeats: int = 3) -> None:
    for name, lights in SCENES:
        scene = scene_for(lights, "float64", FULL.width, FULL.height)
        frame = prepare_frame(scene)
        maps = frame.shadow_maps()

        def march():
            return physical.march_buffers(scene, frame.camera, frame.gbuffer.distance, frame.lights, maps,
                                          frame.geometry.arrays, resolved(scene, "steps"), resolved(scene, "sampling"))

        per_light, trans = march()
        row = {"label": label, "scene": name, "precision": "float64", "split": {
            "render": median_time(lambda: physical.render(scene, frame), repeats),
            "march_buffers": median_time(march, repeats),
            "sum_and_composite": median_time(lambda: sum_and_composite(per_light, frame.scene_colour, trans),
                                             repeats)}}
        print(label, name, " ".join(f"{k} {v:.4f} s" for k, v in row["split"].items()), flush=True)
        _write(row)


def main(phase: str, label: str, precisions: list[str], repeats: int = 3) -> None:
    size = (32, 18) if phase == "warm" else (FULL.width, FULL.height)
    for precision in precisions:
        for name, lights in SCENES:
            scene = scene_for(lights, precision, *size)
            frame = prepare_frame(scene)
            frame.shadow_maps()
            if phase == "warm":
                physical.render(scene, frame)
                continue
            seconds = median_time(lambda: physical.render(scene, frame), repeats)
            samples = march_samples(scene, frame)
            row = {"label": label, "scene": name, "precision": precision, "seconds": seconds,
                   "samples_per_s": samples / seconds}
            print(f"{label} {name} {precision}: {seconds:.3f} s, {samples / seconds / 1e6:.1f} M samples/s", flush=True)
            _write(row)


if __name__ == "__main__":
    if sys.argv[1] == "split":
        split(sys.argv[2])
    else:
        main(sys.argv[1], sys.argv[2], sys.argv[3:] or ["float64", "float32"])
