"""New output arrays from ``np.empty`` (``plain``) against :func:`vlref.pages.empty_faulted` (``faulted``), alternated
in one process (BENCHMARKS.md, "The scene colour's shadow rays inlined; the march's outputs faulted in on every
thread"): the scene colour of (b) and the march of (a) and (b) (``physical.render`` of a prepared frame, as the
bench's ``march`` section times it) at 1920x1080x64, medians of ``REPEATS`` after a warm-up, ``ROUNDS`` rounds.

    PYTHONPATH=$PWD python3 benchmarks/faulted_ab.py [ROUNDS] [REPEATS]
"""

import json
import sys

import numpy as np

from vlref.bench.config import bench_scene, median_time
from vlref.lights import shading
from vlref.render import prepare_frame
from vlref.techniques import physical

VARIANTS = {"plain": lambda shape, dtype=np.float64: np.empty(shape, dtype), "faulted": physical.empty_faulted}


def use(variant: str) -> None:
    shading.empty_faulted = physical.empty_faulted = VARIANTS[variant]


def main(rounds: int = 4, repeats: int = 3) -> None:
    frames = {}
    for name, lights in (("a", "one"), ("b", "four")):
        scene = bench_scene(1920, 1080, 64, lights, 1024)
        frame = prepare_frame(scene)
        frame.shadow_maps()
        frames[name] = (scene, frame)
    scene_b, frame_b = frames["b"]
    figures = {"shading_b": lambda: shading.scene_colour(frame_b.gbuffer, scene_b, frame_b.geometry, frame_b.lights)}
    figures.update({f"march_{name}": (lambda s=scene, f=frame: physical.render(s, f))
                    for name, (scene, frame) in frames.items()})
    results = {f"{figure} {variant}": [] for figure in figures for variant in VARIANTS}
    for _ in range(rounds):
        for figure, fn in figures.items():
            for variant in VARIANTS:
                use(variant)
                results[f"{figure} {variant}"].append(median_time(fn, repeats))
    use("faulted")
    for key, values in results.items():
        print(key, " ".join(f"{v:.4f}" for v in values), f"median {sorted(values)[len(values) // 2]:.4f}")
    print(json.dumps(results))


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
