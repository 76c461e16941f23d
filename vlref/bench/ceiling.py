"""The machine's own thread scaling (part of section ``scaling``): two kernels that touch no shared memory.

* ``scalar_exp``: per item, a chain of dependent libm ``exp`` calls (one value at a time, latency-bound:
  the shape of the plain one-``exp`` kernel and of the march before it ran packets);
* ``vector_exp``: per item, 64 independent lanes through :func:`vlref.numeric.exp` in a loop that LLVM
  vectorises (throughput-bound: the shape of the march's stage loops).

Neither reads memory beyond its own 64 values, so a parallel efficiency below 1 is the machine's: cores
slowing down when they all run (turbo, vector-unit clocks), or logical CPUs sharing a physical core's
execution units. The march's efficiency is read against these (BENCHMARKS.md "Packets of rays").
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from ..jit import njit
from ..numeric import exp
from .config import THREADS, BenchConfig, median_time

__all__ = ["ITEMS", "LANES", "scalar_exp", "vector_exp", "bench_ceiling"]

ITEMS = 1024  # prange iterations of each kernel
LANES = 64  # values per item of vector_exp


@njit(cache=True, fastmath=False, parallel=True)
def scalar_exp(out, n):
    """``out[i]``: ``n`` steps of ``x <- exp(-x) + 0.5`` from ``x = 1 + i·1e-6`` (each step waits for the last)."""
    for i in prange(out.size):
        x = 1.0 + i * 1e-6
        for _ in range(n):
            x = math.exp(-x) + 0.5
        out[i] = x


@njit(cache=True, fastmath=False, parallel=True)
def vector_exp(out, n):
    """``out[i]``: the sum over ``LANES`` lanes of ``n`` steps of ``x <- exp(-x) + 0.5`` (lanes independent)."""
    for i in prange(out.size):
        x = np.empty(LANES)
        for m in range(LANES):
            x[m] = 1.0 + (i * LANES + m) * 1e-6
        for _ in range(n):
            for m in range(LANES):
                x[m] = exp(-x[m]) + 0.5
        out[i] = x.sum()


def bench_ceiling(cfg: BenchConfig) -> dict:
    """``{kernel: {threads: {"seconds", "exp_per_s", "efficiency"}}}`` for the thread counts of ``THREADS``
    that Numba allows (``cfg.ceiling_steps`` steps per lane; ``scalar_exp`` 8 times as many per item, which
    takes about as long)."""
    limit = numba.config.NUMBA_NUM_THREADS
    before = numba.get_num_threads()
    out = np.empty(ITEMS)
    n = cfg.ceiling_steps
    runs = {"scalar_exp": (lambda: scalar_exp(out, 8 * n), 8 * n), "vector_exp": (lambda: vector_exp(out, n), LANES * n)}
    result = {}
    try:
        for name, (run, per_item) in runs.items():
            result[name] = {}
            for threads in (t for t in THREADS if t <= limit):
                numba.set_num_threads(threads)
                seconds = median_time(run, cfg.repeats)
                result[name][str(threads)] = {"seconds": seconds, "exp_per_s": ITEMS * per_item / seconds}
            base = result[name]["1"]["exp_per_s"]
            for threads, r in result[name].items():
                r["efficiency"] = r["exp_per_s"] / base / int(threads)
    finally:
        numba.set_num_threads(before)
    return result
