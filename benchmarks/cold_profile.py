"""Where a cold first render's compile goes, per compiled function (BENCHMARKS.md, "The cold first render: no Python
entry for the helpers").

    python3 benchmarks/cold_profile.py one [JSON]          # the whole render in one process, nothing ahead
    python3 benchmarks/cold_profile.py real [JSON]         # as `vlref render` runs it: JSON and JSON.ahead-STAGE
    python3 benchmarks/cold_profile.py main [JSON]         # the render's main process, the march's stage cached first
    python3 benchmarks/cold_profile.py stage NAME [JSON]   # one stage as vlref.ahead compiles it (NAME: march, ...)

Run in a fresh interpreter with a fresh ``NUMBA_CACHE_DIR`` (the script refuses a cache folder that holds files).
Scene (a) at 320x180x64 with one spot (``vlref bench``'s ``first_render``). Every ``numba:compile`` event (Numba's
public event API: one per function and signature compiled, nested where a caller's typing compiles its callees) is
timed in process CPU seconds; a function's exclusive time is its event's less its nested events'. LLVM's share is
read by wrapping Numba's ``CPUCodeLibrary`` phases (function passes, module passes, machine code) and attributed to
the innermost compile. Prints a table (exclusive CPU, LLVM phases, the final module's size in IR lines, Numba's
inlining of ``inline="always"`` callees, its cache saves and look-ups) and writes every row to ``JSON`` when given.
"""

import json
import os
import pickle
import sys
import tempfile
import time
from collections import defaultdict

from numba.core import caching, codegen, event, inline_closurecall

_stack = []  # [key, start CPU, nested CPU]
_rows = defaultdict(lambda: defaultdict(float))


class _Timer(event.Listener):
    def on_start(self, ev):
        d = ev.data["dispatcher"]
        key = f"{d.py_func.__module__}.{d.py_func.__qualname__}{tuple(ev.data['args'])}"
        _stack.append([key, time.process_time(), 0.0])

    def on_end(self, ev):
        key, start, nested = _stack.pop()
        total = time.process_time() - start
        _rows[key]["compiles"] += 1
        _rows[key]["exclusive_s"] += total - nested
        _rows[key]["inclusive_s"] += total
        if _stack:
            _stack[-1][2] += total


def _timed(cls, name, column, size=False, count=False):
    original = getattr(cls, name)

    depth = [0]

    def wrapper(self, *args, **kwargs):
        start = time.process_time()
        depth[0] += 1
        try:
            return original(self, *args, **kwargs)
        finally:
            depth[0] -= 1
            key = _stack[-1][0] if _stack else "(outside a compile)"
            if depth[0] == 0:  # outermost only (nested inlining is inside its caller's time)
                _rows[key][column] += time.process_time() - start
            if count:
                _rows[key][column.replace("_s", "_calls")] += 1
            if size:
                _rows[key]["ir_lines"] += str(self._final_module).count("\n")
    setattr(cls, name, wrapper)


def _install() -> None:
    event.register("numba:compile", _Timer())
    _timed(codegen.CPUCodeLibrary, "_optimize_functions", "llvm_function_passes_s")
    _timed(codegen.CPUCodeLibrary, "_optimize_final_module", "llvm_module_passes_s", size=True)
    _timed(codegen.JITCodeLibrary, "_finalize_specific", "llvm_machine_code_s")
    _timed(inline_closurecall.InlineWorker, "run_untyped_passes", "inline_front_end_s", count=True)
    _timed(caching.Cache, "save_overload", "cache_save_s")
    _timed(caching.Cache, "load_overload", "cache_lookup_s")


def _rows_and_sums(cpu: float, wall: float) -> dict:
    rows = sorted(({"function": k, **v} for k, v in _rows.items()), key=lambda r: -r.get("exclusive_s", 0))
    return {"rows": rows, "cpu_s": cpu, "wall_s": wall}


def _profiled_stage_process(stage: str, scene, composite_claim=None) -> None:
    """``vlref.ahead``'s process, profiled; its rows written to ``$VLREF_COLD_PROFILE.ahead-STAGE``."""
    from vlref.ahead import _compile_composite_unless_claimed, compile_stage
    from vlref.jit_init import initialise_numba
    from vlref.processes import declare_own_kernels_only
    start_cpu, start = time.process_time(), time.perf_counter()
    declare_own_kernels_only()
    initialise_numba(compiling=True)
    _install()
    compile_stage(stage, scene)
    _compile_composite_unless_claimed(composite_claim, scene)
    with open(f"{os.environ['VLREF_COLD_PROFILE']}.ahead-{stage}", "w") as fh:
        json.dump(_rows_and_sums(time.process_time() - start_cpu, time.perf_counter() - start), fh, indent=1)


def main(mode: str, *rest: str) -> None:
    cache = os.environ.get("NUMBA_CACHE_DIR")
    if not cache or (os.path.isdir(cache) and os.listdir(cache)):
        raise SystemExit("set NUMBA_CACHE_DIR to an empty or new folder")
    from vlref.bench.config import bench_scene
    scene = bench_scene(320, 180, 64, "one", 1024)
    out = None
    start_cpu, start = time.process_time(), time.perf_counter()
    if mode == "stage":
        stage, out = rest[0], (rest[1] if len(rest) > 1 else None)
        from vlref.ahead import compile_stage
        from vlref.jit_init import initialise_numba
        from vlref.processes import declare_own_kernels_only
        declare_own_kernels_only()
        initialise_numba(compiling=True)
        _install()
        compile_stage(stage, scene)
    else:
        out = rest[0] if rest else None
        import vlref.ahead
        from vlref.cli.commands import program_command
        render_to_folder = program_command("render").render_to_folder
        if mode == "main":  # what the compile-ahead process compiles, compiled first in another process
            import subprocess
            subprocess.run([sys.executable, "-c", "import pickle, sys; from vlref.ahead import _compile_stage_process;"
                            "_compile_stage_process('march', pickle.loads(sys.stdin.buffer.read()))"],
                           input=pickle.dumps(scene), check=True)
        if mode == "real":
            os.environ["VLREF_COLD_PROFILE"] = out or "/tmp/vlref_cold_profile.json"
            vlref.ahead._compile_stage_process = _profiled_stage_process
        else:
            vlref.ahead.host_cores = lambda: 1  # nothing compiled ahead: the rest in this process
        _install()
        start_cpu, start = time.process_time(), time.perf_counter()
        with tempfile.TemporaryDirectory() as folder:
            render_to_folder(scene, folder + "/out")
    cpu, wall = time.process_time() - start_cpu, time.perf_counter() - start
    rows = _rows_and_sums(cpu, wall)["rows"]
    columns = ("exclusive_s", "llvm_function_passes_s", "llvm_module_passes_s", "llvm_machine_code_s", "ir_lines",
               "inline_front_end_s", "inline_front_end_calls", "cache_save_s", "cache_lookup_s")
    widths = {"exclusive_s": (9, 2), "ir_lines": (7, 0), "inline_front_end_calls": (7, 0)}
    print(f"{'exclusive':>9} {'fpm':>6} {'mpm':>6} {'mc':>6} {'lines':>7} {'inline':>6} {'calls':>7} {'save':>6} {'look':>6}  function")
    for r in rows:
        cells = [format(r.get(c, 0), "{}.{}f".format(*widths.get(c, (6, 2)))) for c in columns]
        print(" ".join(cells), "", r["function"][:150])
    sums = {c: sum(r.get(c, 0) for r in rows) for c in columns}
    print(f"{len(rows)} functions, {int(sum(r.get('compiles', 0) for r in rows))} compiles; sums", json.dumps(sums),
          f"process CPU {cpu:.2f} s, wall {wall:.2f} s")
    if out:
        with open(out, "w") as fh:
            json.dump(_rows_and_sums(cpu, wall), fh, indent=1)


if __name__ == "__main__":
    main(*sys.argv[1:])
