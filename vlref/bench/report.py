"""Section ``targets`` and the report: :func:`run_bench` runs every section, :func:`format_report` prints it."""

from __future__ import annotations

import dataclasses
import datetime
import os
import platform
from pathlib import Path

import llvmlite.binding as llvm
import numba
import numpy as np

from ..errors import InputError
from ..processes import host_cores
from .config import SECTIONS, BenchConfig
from .march import bench_baseline, bench_march, bench_scaling
from .renders import bench_first_render, bench_memory, bench_reference, bench_whole_render
from .stages import SINGLE_POST_PASSES, bench_geometry, bench_post

__all__ = ["targets", "machine_info", "run_bench", "format_report"]


def _target(name, value, limit, unit, better="lower", note=""):
    met = value <= limit if better == "lower" else value >= limit
    ratio = value / limit if better == "lower" else limit / value
    return {"target": name, "measured": value, "limit": limit, "unit": unit, "met": bool(met),
            "factor_off": None if met else ratio, "note": note}


def targets(cfg: BenchConfig, r: dict) -> list[dict]:
    """BENCHMARKS.md "Targets" against this run (meaningful only for the FULL sizes)."""
    one = r["march"]["one_spot"]
    cores = r["machine"]["numba_threads"]
    scaling = r["scaling"]["threads"]
    top = str(max(int(n) for n in scaling))
    per_core = scaling["1"]["samples_per_s"]
    ref = r["reference"]
    whole = r["whole_render"]
    slowest = max(SINGLE_POST_PASSES, key=lambda name: r["post"][name]["seconds"])
    return [
        _target("march samples/s per core (one spot, float64, 1 thread)", per_core, 100e6, "samples/s", "higher"),
        _target(f"parallel efficiency at {top} threads", scaling[top]["efficiency"], 0.85, "", "higher",
                ("target is at 16 threads on 16 cores; " if top != "16" else "") + _ceiling_note(r, top)),
        _target(f"{one['width']}x{one['height']} x {one['steps']} steps x 1 shadowed spot ({cores} threads)",
                one["seconds"], 0.25, "s", note="target is on 16 cores"),
        _target(f"{one['width']}x{one['height']} x {one['steps']} steps x 4 shadowed lights ({cores} threads)",
                r["march"]["four_lights"]["seconds"], 0.8, "s", note="target is on 16 cores"),
        _target("preview re-render {}x{}, {} steps, half res, incl. post passes".format(*cfg.preview),
                r["post"]["preview"]["seconds"], 0.150, "s", note="target is on 2 cores"),
        _target("first render, fresh process, warm cache", r["first_render"]["warm"]["process_s"], 3.0, "s"),
        _target(f"reference 1e-4 at 640x360 (estimate, {ref['threads']} threads)", ref["estimate_seconds"], 120.0,
                "s", note="target is on 16 cores"),
        _target(f"peak memory, {cfg.width}x{cfg.height}, four shadowed lights (subprocess maxrss)",
                r["memory"]["subprocess_maxrss_bytes"] / 2**30, 1.0, "GiB"),
        _target(f"vlref render {cfg.width}x{cfg.height} x {cfg.steps}, four shadowed lights, fresh process, warm cache",
                whole["seconds"], 1.5, "s", note="target is on 16 cores"),
        _target("writing the default outputs (EXR buffers, PNG preview)", whole["split"]["write"], 0.3, "s"),
        _target(f"camera ray cast {cfg.width}x{cfg.height}, four-light scene", r["raycast"]["bench_four_lights"]
                ["rays_per_s"], 100e6, "rays/s", "higher", note="target is on 16 cores"),
        _target("shadow maps of the four lights", r["shadow_maps"]["bench_four_lights"]["texels_per_s"], 50e6,
                "texels/s", "higher", note="target is on 16 cores"),
        _target(f"radial blur, 64 taps, {cfg.width}x{cfg.height}", r["post"]["radial_blur_64"]["seconds"], 0.05, "s",
                note="target is on 16 cores"),
        _target(f"every other post pass, {cfg.width}x{cfg.height}: the slowest ({slowest})",
                r["post"][slowest]["seconds"], 0.010, "s", note="target is on 16 cores"),
    ]


def _ceiling_note(r: dict, top: str) -> str:
    ceiling = r["scaling"].get("machine_ceiling", {})
    found = {name: runs[top]["efficiency"] for name, runs in ceiling.items() if top in runs}
    return ("this machine's own efficiency at these threads: "
            + ", ".join(f"{name} {eff:.2f}" for name, eff in found.items())) if found else ""


def machine_info(argv: list[str]) -> dict:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cores = host_cores()
    # the CPU LLVM compiles for: its tuning sets the vector width (Intel server cores: 256-bit even with
    # AVX-512; BENCHMARKS.md "Wider vectors"), so two machines' figures compare only with it
    llvm_cpu = numba.config.CPU_NAME or llvm.get_host_cpu_name()
    return {"cpu_model": model, "llvm_cpu": llvm_cpu, "cpu_features_set": bool(numba.config.CPU_FEATURES),
            "cores_available": cores, "cpu_count": os.cpu_count(),
            "numba_threads": numba.get_num_threads(), "numba_num_threads": numba.config.NUMBA_NUM_THREADS,
            "threading_layer": os.environ.get("NUMBA_THREADING_LAYER", "default"),
            "python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
            "platform": platform.platform(), "date": datetime.datetime.now(datetime.timezone.utc).isoformat(),
            "command": "vlref bench " + " ".join(argv)}


def run_bench(cfg: BenchConfig, argv: list[str] = (), log=None, sections=None) -> dict:
    """Every section of the report (module docstring) for the sizes of ``cfg``, or those named in ``sections``
    (names of :data:`~vlref.bench.config.SECTIONS`; ``raycast`` and ``shadow_maps`` come together, ``baseline``
    needs ``march`` and ``scaling``, ``targets`` all of them), in the bench's own order.

    ``log(message, partial_report)`` is called before each section (cheapest and most-wanted first).
    """
    log = log or (lambda msg, report: None)
    wanted = set(SECTIONS if sections is None else sections)
    unknown = wanted - set(SECTIONS)
    if unknown:
        raise InputError("<command line>", "sections", f"unknown {', '.join(sorted(unknown))} (known: "
                         f"{', '.join(SECTIONS)})")
    if "baseline" in wanted and not {"march", "scaling"} <= wanted:
        raise InputError("<command line>", "sections", "baseline needs march and scaling")
    r = {"machine": machine_info(list(argv)), "config": dataclasses.asdict(cfg)}
    steps = (("march", lambda: bench_march(cfg)), ("scaling", lambda: bench_scaling(cfg)),
             (("raycast", "shadow_maps"), lambda: bench_geometry(cfg)), ("post", lambda: bench_post(cfg)),
             ("reference", lambda: bench_reference(cfg)), ("memory", lambda: bench_memory(cfg)),
             ("baseline", lambda: bench_baseline(cfg, r["march"], r["scaling"])),
             ("first_render", lambda: bench_first_render(cfg)), ("whole_render", lambda: bench_whole_render(cfg)))
    for key, fn in steps:
        if wanted.isdisjoint((key,) if isinstance(key, str) else key):
            continue
        log(key if isinstance(key, str) else ", ".join(key), r)
        value = fn()
        if isinstance(key, str):
            r[key] = value
        else:
            r.update(zip(key, value))
    if set(SECTIONS) <= wanted:
        r["targets"] = targets(cfg, r)
    return r


def _fmt(x) -> str:
    return f"{x:.4g}" if isinstance(x, float) else str(x)


def format_report(r: dict) -> str:
    """A plain-text summary of the report."""
    m = r["machine"]
    lines = [f"vlref bench  {m['date']}",
             f"machine: {m['cpu_model']} (LLVM: {m['llvm_cpu']}), {m['cores_available']} cores, "
             f"{m['numba_threads']} Numba threads; numpy {m['numpy']}, numba {m['numba']}, python {m['python']}", ""]
    for name, s in r["march"].items():
        lines.append(f"march {name:19s} {s['width']}x{s['height']}x{s['steps']}: {s['seconds']:.3f} s, "
                     f"{s['samples_per_s'] / 1e6:.2f} M samples/s ({s['samples_per_s_per_thread'] / 1e6:.2f} per thread)")
    b = r["baseline"]
    lines.append(f"numpy baseline {b['width']}x{b['height']}: {b['samples_per_s'] / 1e6:.3f} M samples/s; kernel/numpy "
                 f"{b['ratio_kernel_all_threads']:.1f}x (all threads), {_fmt(b['ratio_kernel_one_thread'])}x (1 thread)")
    lines.append(f"plain one-exp kernel: {b['plain_all_threads']['samples_per_s'] / 1e6:.2f} M samples/s (all threads), "
                 f"{b['plain_one_thread']['samples_per_s'] / 1e6:.2f} (1 thread); kernel/plain "
                 f"{b['ratio_kernel_plain_all_threads']:.2f}x, {_fmt(b['ratio_kernel_plain_one_thread'])}x")
    for n, s in r["scaling"]["threads"].items():
        lines.append(f"threads {n:>2s}: {s['samples_per_s'] / 1e6:.2f} M samples/s, speedup {s['speedup']:.2f}, "
                     f"efficiency {s['efficiency']:.2f}")
    for name, runs in r["scaling"].get("machine_ceiling", {}).items():
        lines.append(f"machine ceiling {name}: efficiency " + ", ".join(f"{n} thr {s['efficiency']:.2f}"
                                                                     for n, s in runs.items()))
    if r["scaling"]["note"]:
        lines.append(r["scaling"]["note"])
    for name, s in r["raycast"].items():
        sm = r["shadow_maps"][name]
        lines.append(f"{name}: raycast {s['width']}x{s['height']} {s['seconds']:.3f} s; shadow maps "
                     f"{sm['texels']} texels {sm['seconds']:.3f} s")
    for name, s in r["post"].items():
        lines.append(f"post {name}: {s['seconds'] * 1e3:.1f} ms")
    ref = r["reference"]
    lines.append(f"reference {ref['width']}x{ref['height']}: {ref['seconds_per_pixel'] * 1e3:.2f} ms/pixel, "
                 f"640x360 estimate {ref['estimate_seconds']:.1f} s")
    fr = r["first_render"]
    cold = f"{fr['cold']['process_s']:.2f} s" if fr["cold"] else "skipped"
    lines.append(f"first render: cold {cold}, warm {fr['warm']['process_s']:.2f} s")
    wr = r["whole_render"]
    lines.append(f"whole render {wr['width']}x{wr['height']} (four lights), fresh process: {wr['seconds']:.2f} s = "
                 + ", ".join(f"{k} {v:.3f}" for k, v in wr["split"].items()))
    mem = r["memory"]
    lines.append(f"memory: tracemalloc peak {mem['tracemalloc_peak_bytes'] / 2**20:.0f} MiB, subprocess maxrss "
                 f"{mem['subprocess_maxrss_bytes'] / 2**20:.0f} MiB")
    lines.append("")
    for t in r["targets"]:
        status = "met" if t["met"] else f"missed ({t['factor_off']:.1f}x off)"
        lines.append(f"target {t['target']}: {_fmt(t['measured'])} {t['unit']} vs {_fmt(t['limit'])}: {status}"
                     + (f" [{t['note']}]" if t["note"] else ""))
    return "\n".join(lines)
