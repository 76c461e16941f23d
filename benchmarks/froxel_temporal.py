"""Froxel temporal figures of BENCHMARKS.md "Froxel temporal".

``python benchmarks/froxel_temporal.py ghosting``: frames 0-7 of each bundled animated scene at 64x36,
grid 32x18x32, default α; mean relative inscatter error of the temporal sequence without and with
``history_clamp`` and of each frame alone, against the physical march (256 steps, ``sampling none``)
of the same frame.

``python benchmarks/froxel_temporal.py convergence [W H]``: static camera (``pillars``, W x H = 64x36
by default, grid W x H x 16, α = 1/16, 16 frames; tests/test_froxel_temporal.py's settings): error of the accumulated sequence and of each jittered frame alone against
:func:`vlref.reference.render_reference` (rel_tol 1e-4) of the same frame.
"""

from __future__ import annotations

import dataclasses
import sys
import time

import numpy as np

from vlref.render import render
from vlref.scene import load_scene
from vlref.sequence import render_sequence


def rel_error(image, ref):
    """Mean |image - ref| over mean ref (all pixels and channels)."""
    return float(np.abs(image - ref).mean() / ref.mean())


def at_frame(scene, f):
    return scene.replace(render=dataclasses.replace(scene.render, frame=f))


def ghosting(frames=range(8)):
    size = ["render.width=64", "render.height=36"]
    grid = ["techniques.froxel.grid_width=32", "techniques.froxel.grid_height=18", "techniques.froxel.slices=32"]
    for name in ("anim_sun", "anim_spot", "anim_point"):
        march = load_scene(name, size + ['render.technique="physical"', "render.steps=256", 'render.sampling="none"'])
        refs = [render(at_frame(march, f)).buffers["inscatter"] for f in frames]
        rows = {}
        for label, over in (("temporal", []), ("temporal, clamp", ["techniques.froxel.history_clamp=true"]),
                            ("single frame", ["techniques.froxel.temporal=false"])):
            scene = load_scene(name, size + grid + over)
            if label == "single frame":
                runs = [render(at_frame(scene, f)) for f in frames]
            else:
                runs = [r for _, r in render_sequence(scene, frames)]
            rows[label] = [rel_error(r.buffers["inscatter"], ref) for r, ref in zip(runs, refs)]
        for label, errs in rows.items():
            print(f"| {name} | {label} | " + " | ".join(f"{e:.3f}" for e in errs) + " |", flush=True)


def convergence(w=64, h=36, n=16):
    from vlref.reference import render_reference

    size = [f"render.width={w}", f"render.height={h}", "lights.0.shadows.resolution=128"]
    grid = ['render.technique="froxel"', f"techniques.froxel.grid_width={w}", f"techniques.froxel.grid_height={h}",
            "techniques.froxel.slices=16"]
    t0 = time.perf_counter()
    ref = render_reference(load_scene("pillars", size)).inscatter
    print(f"reference: {time.perf_counter() - t0:.1f} s", flush=True)
    march = render(load_scene("pillars", size + ["render.steps=256", 'render.sampling="none"'])).buffers["inscatter"]
    print(f"physical(256) vs reference: {rel_error(march, ref):.4f}")
    seq = load_scene("pillars", size + grid + ["techniques.froxel.temporal=true", f"techniques.froxel.history_alpha={1 / n}"])
    e = [rel_error(r.buffers["inscatter"], ref) for _, r in render_sequence(seq, range(n))]
    single = load_scene("pillars", size + grid)
    es = [rel_error(render(at_frame(single, f)).buffers["inscatter"], ref) for f in range(n)]
    nj = render(load_scene("pillars", size + grid + ['techniques.froxel.jitter="none"'])).buffers["inscatter"]
    print("frames accumulated | " + " | ".join(str(f + 1) for f in range(n)))
    print("temporal | " + " | ".join(f"{x:.3f}" for x in e))
    print("single frame | " + " | ".join(f"{x:.3f}" for x in es))
    print(f"no jitter: {rel_error(nj, ref):.3f}")


if __name__ == "__main__":
    {"ghosting": ghosting, "convergence": convergence}[sys.argv[1]](*map(int, sys.argv[2:]))
