"""A warm render's later stages loaded ahead on a thread (vlref.ahead.compile_ahead): in the ``vlref render``
program's process with a warm cache, the block loads the functions chosen for the render's cached stages from
Numba's cache (nothing compiled, nothing else loaded) before the render calls them, and the render writes the same
bytes; the choice takes only a signature the cache holds alone (for the march's kernel, the scene's variant) of a
cached stage."""

import dataclasses
import json
import subprocess
import sys

import numba
import numpy as np

import vlref.ahead as ahead
from vlref.bench import bench_scene

LOADED = r"""
import hashlib, json, sys, tempfile
from pathlib import Path
from vlref.cli.commands import program_command
render_to_folder = program_command("render").render_to_folder
from vlref.ahead import LOADED_AHEAD, _to_load_ahead, compile_ahead
from vlref.bench import bench_scene

scene = bench_scene(32, 18, 2, "four", 16)
functions = [f for fs in LOADED_AHEAD.values() for f in fs]
state = {}
if sys.argv[1] == "ahead":  # the block alone: what its thread loaded by the time the block ends
    state["chosen"] = [f.py_func.__name__ for f, _ in _to_load_ahead(scene, cold=[])]
    with compile_ahead(scene):
        pass
    state["overloads"] = {f.py_func.__name__: len(f.overloads) for f in functions}
with tempfile.TemporaryDirectory() as folder:
    render_to_folder(scene, folder + "/out")
    state["files"] = {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(Path(folder, "out").iterdir())}
state["compiled"] = sum(sum(f.stats.cache_misses.values()) for f in functions)
print(json.dumps(state))
"""


def _run(mode: str) -> dict:
    proc = subprocess.run([sys.executable, "-c", LOADED, mode], capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_a_warm_render_loads_its_functions_ahead_and_writes_the_same_bytes():
    first = _run("render")  # fills the cache where it is cold
    warm = _run("ahead")
    assert warm["compiled"] == 0  # loaded from the cache, not compiled
    # the functions chosen (a signature the cache holds alone: which ones depends on what else the cache holds, but
    # the march's kernel is filtered by the scene's variant) are loaded once the block's thread has ended, before any
    # render call, and nothing else
    assert "_march_kernel" in warm["chosen"]
    names = [f.py_func.__name__ for fs in ahead.LOADED_AHEAD.values() for f in fs]
    assert warm["overloads"] == {name: int(name in warm["chosen"]) for name in names}
    assert warm["files"] == first["files"] and len(warm["files"]) == 5


def test_only_a_signature_the_cache_holds_alone_is_loaded_ahead(monkeypatch):
    float64 = (numba.typeof(np.zeros(3)),)
    float32 = (numba.typeof(np.zeros(3, dtype=np.float32)),)
    held = {f: ["one"] for fs in ahead.LOADED_AHEAD.values() for f in fs}
    held[ahead._shade] = ["one", "other"]  # two signatures: the render's call picks its own
    no_rays = (None,) * 7 + (numba.types.none,)  # the kernel's argument ``geo`` (8): None without shadow rays
    marches = {ahead._march_kernel: [float32 + no_rays, float64 + no_rays, float64 + (None,) * 8]}

    def signatures(function, wanted=lambda sig: True):
        return [sig for sig in marches.get(function, held[function]) if wanted(sig)]

    monkeypatch.setattr(ahead, "_cached_signatures", signatures)
    scene = bench_scene(32, 18, 2, "one", 16)  # a spot with PCF maps: no shadow rays in the march
    chosen = ahead._to_load_ahead(scene, cold=["shadow maps"])
    assert [f for f, _ in chosen] == [ahead._cast_rows, ahead._raycast_kernel, ahead._shade_rows, ahead._march_tasks,
                                      ahead._march_kernel, ahead._sum_composite]
    assert dict(chosen)[ahead._march_kernel] == float64 + no_rays  # the scene's variant, of the three held
    radial = scene.replace(render=dataclasses.replace(scene.render, technique="radial"))
    assert ahead._to_load_ahead(radial, cold=[])[-1][0] is ahead._cast_face  # no march for another technique
