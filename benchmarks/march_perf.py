"""The march's instructions under ``perf`` (BENCHMARKS.md, "The march on AVX2"): a perf map that names vlref's compiled
functions, and the code of one of them, for a profile by instruction of Numba's code, which ``perf`` alone sees as
anonymous memory.

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc perf record -F 2000 -o /tmp/march.perf \\
        python3 benchmarks/march_perf.py [SECONDS [LIGHTS [WIDTH HEIGHT]]]
    perf report -i /tmp/march.perf --sort sym --stdio | head              # time per compiled function
    perf script -i /tmp/march.perf -F ip > /tmp/march.ips                 # the samples' addresses
    objdump -D -b binary -m i386:x86-64 /tmp/march-code.bin > /tmp/march.asm  # the function's instructions

The process marches bench scene (a) (``LIGHTS = one``) or (b) (``four``) at ``WIDTH x HEIGHT`` (480x270) on one
thread, once to load the kernels, then writes ``/tmp/perf-PID.map`` (the entry address of every compiled overload of
every vlref dispatcher, each up to the next, at most 256 KiB) and the bytes of
:func:`vlref.march.physical._march_tasks`, into which LLVM inlines the stages, to ``/tmp/march-code.bin`` with its
address in ``/tmp/march-code.json``, and marches for ``SECONDS`` (10). A sample at address ``a`` is the instruction at
offset ``a - address`` of the listing.
"""

import ctypes
import json
import os
import sys
import time

import numba

from vlref.bench.config import FULL, bench_scene
from vlref.march import physical as march
from vlref.render import prepare_frame
from vlref.scene.technique_params import resolved
from vlref.techniques import physical

CODE_BYTES = 1 << 18  # more than _march_tasks' code (about 68 KiB on Zen 3)


def compiled_functions() -> list[tuple[int, str]]:
    """``(address, name)`` of every compiled overload of every vlref dispatcher loaded, by address."""
    found, seen = [], set()
    for module_name, module in sorted(sys.modules.items()):
        if not module_name.startswith("vlref"):
            continue
        for name, obj in vars(module).items():
            if not hasattr(obj, "overloads") or id(obj) in seen:
                continue
            seen.add(id(obj))
            for cres in obj.overloads.values():
                found.append((cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name),
                              f"{module_name}.{name}"))
    return sorted(found)


def main(seconds: float = 10.0, lights: str = "one", width: int = 480, height: int = 270) -> None:
    numba.set_num_threads(1)
    scene = bench_scene(width, height, FULL.steps, lights, FULL.shadow_resolution)
    frame = prepare_frame(scene)
    maps = frame.shadow_maps()

    def run():
        physical.march_buffers(scene, frame.camera, frame.gbuffer.distance, frame.lights, maps, frame.geometry.arrays,
                               resolved(scene, "steps"), resolved(scene, "sampling"))

    run()
    functions = compiled_functions()
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as fh:
        for (address, name), (after, _) in zip(functions, functions[1:] + [(functions[-1][0] + CODE_BYTES, "")]):
            fh.write(f"{address:x} {min(after - address, CODE_BYTES):x} {name}\n")
    code = dict((name, address) for address, name in functions)["vlref.march.physical._march_tasks"]
    with open("/tmp/march-code.bin", "wb") as fh:
        fh.write(ctypes.string_at(code, CODE_BYTES))
    with open("/tmp/march-code.json", "w") as fh:
        json.dump({"function": march._march_tasks.__name__, "address": code}, fh)
    start, calls = time.perf_counter(), 0
    while time.perf_counter() - start < seconds:
        run()
        calls += 1
    print(f"{calls} marches, {(time.perf_counter() - start) / calls:.4f} s each", flush=True)


if __name__ == "__main__":
    args = sys.argv[1:]
    main(float(args[0]) if args else 10.0, args[1] if len(args) > 1 else "one", *(int(a) for a in args[2:4]))
