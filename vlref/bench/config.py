"""The benchmark's sizes (:class:`BenchConfig`: ``FULL``, ``QUICK``), its scene (:func:`bench_scene`) and
its timer (:func:`median_time`)."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ..scene.model import (Box, CameraSettings, Cylinder, HeightFog, Light, Medium, Plane, RenderSettings, Scene,
                           ShadowSettings, Sphere)

__all__ = ["SECTIONS", "THREADS", "BenchConfig", "FULL", "QUICK", "bench_scene", "median_time"]

SECTIONS = ("machine", "march", "baseline", "scaling", "raycast", "shadow_maps", "post", "reference",
            "first_render", "whole_render", "memory", "targets")
THREADS = (1, 2, 4, 8, 16)


@dataclass(frozen=True)
class BenchConfig:
    """Sizes of one benchmark run (``FULL`` the targets' sizes; ``QUICK`` a smoke run for CI)."""

    width: int = 1920
    height: int = 1080
    steps: int = 64
    repeats: int = 3
    small: tuple[int, int] = (480, 270)  # thread scaling
    baseline: tuple[int, int] = (240, 135)  # the NumPy baseline (about 60x slower than the kernel per core)
    preview: tuple[int, int, int] = (320, 180, 16)  # width, height, steps
    reference: tuple[int, int] = (64, 36)
    reference_target: tuple[int, int] = (640, 360)
    first_render: tuple[int, int] = (320, 180)
    memory_steps: int = 4
    bundled: tuple[str, ...] = ("forest", "cage", "window")
    shadow_resolution: int = 1024
    cold_cache: bool = True  # a cold first render compiles every kernel: ~90 s on 2 busy cores
    ceiling_steps: int = 2000  # steps per lane of the machine's scaling kernels (vlref.bench.ceiling)
    min_seconds: float = 0.5  # the ray cast, the shadow maps and the post passes: timed calls until they add up to it


FULL = BenchConfig()
QUICK = BenchConfig(width=48, height=27, steps=8, repeats=1, small=(32, 18), baseline=(16, 9), preview=(32, 18, 4),
                    reference=(4, 3),
                    first_render=(16, 9), memory_steps=2, bundled=(), shadow_resolution=64, cold_cache=False,
                    ceiling_steps=4, min_seconds=0.01)


def bench_scene(width: int, height: int, steps: int, lights: str = "one", shadow_resolution: int = 1024,
                technique: str = "physical", resolution: str | None = None) -> Scene:
    """The benchmark scene: a floor, two boxes, a sphere and a pillar in height fog (HG g = 0.5).

    ``lights = "one"``: one PCF-shadowed spot light whose cone covers most of the view;
    ``"four"``: that spot, a second spot, a point light and a directional light, all PCF-shadowed.
    """
    sh = ShadowSettings(resolution=shadow_resolution, bias=0.03)
    spot = Light(type="spot", position=(0.0, 7.0, -3.0), direction=(0.0, -1.0, 0.6), spot_angle=110.0, range=30.0,
                 intensity=80.0, color=(1.0, 0.9, 0.75), shadows=sh)
    chosen = (spot,)
    if lights == "four":
        chosen = (spot,
                  Light(type="spot", position=(-4.0, 5.0, 2.0), direction=(0.5, -1.0, 0.2), spot_angle=60.0,
                        range=15.0, intensity=40.0, color=(0.6, 0.7, 1.0), shadows=sh),
                  Light(type="point", position=(3.0, 2.5, 2.0), range=8.0, intensity=15.0, color=(1.0, 0.5, 0.3),
                        shadows=dataclasses.replace(sh, resolution=max(8, shadow_resolution // 2))),
                  Light(type="directional", direction=(0.3, -0.8, 0.5), intensity=1.5,
                        shadows=dataclasses.replace(sh, cascades=2, distance=40.0)))
    objects = (Plane(), Box(center=(-2.5, 1.0, 1.0), size=(1.0, 2.0, 1.0)),
               Box(center=(2.0, 1.5, 2.5), size=(1.0, 3.0, 1.0), rotation=(0.0, 30.0, 0.0)),
               Sphere(center=(0.5, 1.0, 4.0), radius=1.0), Cylinder(center=(-0.8, 1.5, 0.5), radius=0.3, height=3.0))
    return Scene(render=RenderSettings(width=width, height=height, steps=steps, max_distance=40.0,
                                       technique=technique, resolution=resolution),
                 camera=CameraSettings(position=(0.0, 2.0, -8.0), look_at=(0.0, 1.5, 0.0), fov=60.0),
                 medium=Medium(scattering=0.05, absorption=0.01, anisotropy=0.5,
                               height_fog=HeightFog(base=0.0, falloff=0.15)),
                 lights=chosen, objects=objects)


def median_time(fn, repeats: int, clock=time.perf_counter, min_seconds: float = 0.0, max_repeats: int = 64) -> float:
    """Median time of ``repeats`` calls of ``fn`` after one warm-up call, by ``clock`` (default wall time;
    ``time.process_time`` gives CPU time); more calls, up to ``max_repeats``, until the timed calls add up to
    ``min_seconds``.

    A call of a few milliseconds on 16 cores varies by 1.5-2x from call to call on the device (BENCHMARKS.md "The
    camera ray cast inside the bench's process, and twice as fast"), so the median of three such calls is one slow
    call away from a slow figure: the bench's short figures take ``min_seconds``."""
    fn()
    times = []
    while len(times) < repeats or (sum(times) < min_seconds and len(times) < max_repeats):
        start = clock()
        fn()
        times.append(clock() - start)
    return float(np.median(times))
