"""``vlref bench``: throughput of every stage of a frame, measured in one run, reported against the targets.

Sections of the report (``--json`` prints it as one JSON object; keys as below):

``machine``       CPU model, the CPU LLVM compiles for (``llvm_cpu``: its tuning sets the vector width) and whether
                  ``NUMBA_CPU_FEATURES`` overrides its features, cores, Numba threads, Python/NumPy/Numba
                  versions, date, command.
``march``         the physical march kernel (:func:`vlref.techniques.physical.render`) on the
                  benchmark scene (:func:`bench_scene`): (a) ``one_spot`` -- one spot light with a PCF
                  shadow map, HG ``g = 0.5``, extinction on the view ray and on the light leg, height fog;
                  (b) ``four_lights`` -- two spot lights, a point light and a directional light, each with
                  PCF shadows. **Samples** are (pixel, light) pairs whose ray segment inside the light's
                  volume is not empty, times the step count: the work the kernel does. Both again with
                  ``render.precision = "float32"`` (``one_spot_float32``, ``four_lights_float32``), and (a)
                  without its height fog (``one_spot_no_fog``, float64): the homogeneous medium of most
                  bundled scenes, whose light leg takes another branch of the kernel.
``baseline``      the same computation as (a) in vectorised NumPy (:mod:`vlref.bench.baseline`), its
                  samples/s, its largest relative difference to the kernel, and the kernel/NumPy ratios;
                  and :func:`plain_march` (one ``exp``, one ``pow``, one hard shadow lookup per sample, on
                  (a)'s rays) at the full size on all threads and at the scaling size on one thread, with
                  the kernel/plain ratios.
``scaling``       (a) at 1, 2, 4, 8 and 16 Numba threads (counts above ``NUMBA_NUM_THREADS`` are skipped
                  and listed); speedup and parallel efficiency relative to one thread; and
                  ``machine_ceiling``: the efficiency at the same counts of two kernels that share no
                  memory, a scalar ``exp`` chain and a vectorised lane loop (:mod:`vlref.bench.ceiling`).
``raycast``       the G-buffer (primary rays/s); ``shadow_maps``: the four lights' maps (texels/s), and,
                  without ``--quick``, raycast and shadow maps of the bundled ``forest``, ``cage``, ``window``.
``post``          each post pass on a full-resolution frame (min-downsample, the three depth-aware
                  upsamples, the bilateral blur's horizontal and vertical passes one at a time, both into two
                  new arrays and, as Killzone calls them, the vertical pass into a buffer of the caller's, radial
                  blur, composite) and the ``preview`` render (``killzone``, half resolution, 16 steps, post
                  passes included).
``reference``     :func:`vlref.reference.render_reference` at ``rel_tol = 1e-4`` on a reduced
                  resolution of (a) (the same frustum): seconds per pixel, and the estimate for 640x360.
``first_render``  a fresh interpreter that imports vlref, renders (a) at 320x180 and writes its outputs as
                  ``vlref render`` does (cold kernels compiled ahead in second processes), with a fresh
                  (``cold``) and then a filled (``warm``) ``NUMBA_CACHE_DIR``: process wall time, its split.
``whole_render``  the ``vlref render`` of (b) at the full size in a fresh interpreter with this process's (warm)
                  cache, as the command renders and writes it: process wall time (median of ``repeats``) and its
                  split (:func:`~vlref.bench.renders.bench_whole_render`): the interpreter's start, vlref's
                  import, each render stage, the writing, the exit.
``memory``        peak memory of a frame of (b) at the memory size (steps do not change allocations):
                  ``tracemalloc`` peak of the NumPy allocations in this process, and the peak resident
                  set of a subprocess that renders the same frame (``VmHWM``; ``ru_maxrss`` where there
                  is no ``/proc``: on Linux ``ru_maxrss`` carries the parent's peak across ``exec``).
``targets``       each target of BENCHMARKS.md "Targets", the measured figure, and whether it is met.

Timings are medians of ``repeats`` runs after one warm-up run (JIT compile excluded except in
``first_render``); the ray cast, the shadow maps and the post passes (calls of milliseconds) take more runs, until
they add up to ``min_seconds`` (:func:`~vlref.bench.config.median_time`). :func:`run_bench` runs every section or
those named. Benchmarks report; they never fail on a timing. The core stack (NumPy, Numba, SciPy) is all this
module needs.

Modules, one per group of sections: :mod:`.config` (sizes, scene, timer), :mod:`.march` (``march``,
``scaling``, ``baseline``), :mod:`.ceiling` (the machine's own scaling), :mod:`.baseline` (the NumPy baseline), :mod:`.stages` (``raycast``,
``shadow_maps``, ``post``), :mod:`.renders` (``reference``, ``first_render``, ``memory``), :mod:`.report`
(``machine``, ``targets``, the text report). The command line is :mod:`vlref.cli.bench`.
"""

from .config import FULL, QUICK, SECTIONS, BenchConfig, bench_scene
from .report import format_report, run_bench

__all__ = ["BenchConfig", "FULL", "QUICK", "SECTIONS", "bench_scene", "run_bench", "format_report"]
