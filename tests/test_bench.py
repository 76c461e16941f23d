"""`vlref bench --quick --json`: every section present, every figure finite and the timings/rates positive,
the NumPy baseline equal to the march kernel, and the primitive BVH equal to a linear scan; `run_bench` of some
sections, the timer's repeats. No timing asserts."""

import dataclasses
import json
import math
import multiprocessing
import threading

import numba
import numpy as np
import pytest

from vlref.bench import QUICK, SECTIONS, run_bench
from vlref.bench.ceiling import bench_ceiling
from vlref.bench.config import median_time
from vlref.bench.march import march_samples
from vlref.bench.stages import SINGLE_POST_PASSES
from vlref.cli import main
from vlref.errors import InputError
from vlref.geometry import build_geometry, closest_hit, shadow_transmittance
from vlref.render import prepare_frame
from vlref.scene.load import load_scene
from vlref.scene.model import Box, Cylinder, Light, Material, Plane, Scene, Sphere
from vlref.techniques import resolved

POSITIVE_SUFFIXES = ("seconds", "_s", "per_s", "per_s_per_thread", "bytes", "samples", "texels", "speedup")


def numbers(node, path=""):
    """Every (path, number) in a JSON tree (booleans excluded)."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from numbers(v, f"{path}.{k}")
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from numbers(v, f"{path}[{i}]")
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield path, node


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench") / "bench.json"
    assert main(["bench", "--quick", "--json", "-o", str(out)]) == 0
    return json.loads(out.read_text())


def test_every_section_with_finite_positive_figures(report):
    assert set(SECTIONS) <= set(report)
    for path, value in numbers(report):
        assert math.isfinite(value), path
        if path.rsplit(".", 1)[-1].endswith(POSITIVE_SUFFIXES):
            assert value > 0, path
    assert {"one_spot", "four_lights"} <= set(report["march"])
    assert report["march"]["four_lights"]["samples"] > report["march"]["one_spot"]["samples"] > 0
    for name in ("one_spot", "four_lights"):  # float32 marches the same (pixel, light) pairs
        assert report["march"][name + "_float32"]["precision"] == "float32"
        assert report["march"][name + "_float32"]["samples"] == report["march"][name]["samples"]
    # (a) without its height fog: the same segments, so the same samples
    assert report["march"]["one_spot_no_fog"]["samples"] == report["march"]["one_spot"]["samples"]
    assert "1" in report["scaling"]["threads"]
    assert isinstance(report["machine"]["llvm_cpu"], str) and report["machine"]["llvm_cpu"]
    ceiling = report["scaling"]["machine_ceiling"]
    assert set(ceiling) == {"scalar_exp", "vector_exp"}
    assert all(runs["1"]["efficiency"] == 1.0 and runs["1"]["exp_per_s"] > 0 for runs in ceiling.values())
    assert report["first_render"]["warm"]["render_s"] > 0
    assert report["memory"]["subprocess_maxrss_bytes"] > report["memory"]["tracemalloc_peak_bytes"] > 0
    whole = report["whole_render"]
    assert whole["seconds"] > whole["split"]["write"] > 0 and whole["split"]["volumetrics"] > 0
    # the split's parts are disjoint spans of the process's life: each positive, together within its wall time
    assert {"interpreter_start", "import", "exit"} <= set(whole["split"]) and min(whole["split"].values()) > 0
    assert sum(whole["split"].values()) <= whole["seconds"] + 1e-3
    assert len(report["targets"]) == 14 and all(isinstance(t["met"], bool) for t in report["targets"])
    # "every other post pass": judged on its slowest single pass, the bilateral blur's two passes among them
    slowest = max(report["post"][name]["seconds"] for name in SINGLE_POST_PASSES)
    assert report["targets"][-1]["measured"] == slowest and "bilateral_blur_v" in SINGLE_POST_PASSES


def test_the_machine_ceiling_kernels_compute_their_chains():
    from vlref.bench.ceiling import ITEMS, LANES, scalar_exp, vector_exp

    out = np.empty(ITEMS)
    scalar_exp(out, 7)
    x = 1.0 + np.arange(ITEMS) * 1e-6
    for _ in range(7):
        x = np.exp(-x) + 0.5
    np.testing.assert_allclose(out, x, rtol=1e-14)
    vector_exp(out, 7)
    x = 1.0 + np.arange(ITEMS * LANES).reshape(ITEMS, LANES) * 1e-6
    for _ in range(7):
        x = np.exp(-x) + 0.5
    np.testing.assert_allclose(out, x.sum(axis=1), rtol=1e-14)


def test_median_time_runs_until_the_calls_add_up_to_min_seconds():
    now, calls = [0.0], []

    def call():  # takes 0.25 s by the fake clock
        calls.append(now[0])
        now[0] += 0.25

    assert median_time(call, 3, clock=lambda: now[0], min_seconds=1.0) == 0.25
    assert len(calls) == 1 + 4  # the warm-up, then calls until they add up to 1 s
    calls.clear()
    median_time(call, 3, clock=lambda: now[0], min_seconds=100.0, max_repeats=20)
    assert len(calls) == 1 + 20
    calls.clear()
    median_time(call, 3, clock=lambda: now[0])
    assert len(calls) == 1 + 3


def test_run_bench_runs_the_sections_named_and_leaves_nothing_behind():
    """Only the sections named, in the bench's order; the Numba thread count the caller set is the one after
    the scaling kernels' cycle; no Python thread or child process outlives a section."""
    logged, threads = [], threading.active_count()
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        r = run_bench(QUICK, [], lambda message, partial: logged.append(message), sections=["shadow_maps", "raycast"])
        bench_ceiling(QUICK)
        assert numba.get_num_threads() == 1
    finally:
        numba.set_num_threads(before)
    assert logged == ["raycast, shadow_maps"]
    assert set(r) == {"machine", "config", "raycast", "shadow_maps"}
    assert r["raycast"]["bench_four_lights"]["rays_per_s"] > 0
    assert threading.active_count() == threads and multiprocessing.active_children() == []
    with pytest.raises(InputError, match="unknown nope"):
        run_bench(QUICK, sections=["nope"])
    with pytest.raises(InputError, match="baseline needs march and scaling"):
        run_bench(QUICK, sections=["baseline", "march"])


def test_numpy_baseline_is_the_same_computation(report):
    assert report["baseline"]["samples"] > 0
    assert report["baseline"]["max_abs_diff_relative_to_peak"] < 1e-9


MATS = (Material(), Material(opacity=0.5, tint=(1.0, 0.6, 0.3)))


def random_scene(rng):
    objects = [Plane(point=(0.0, -2.0, 0.0), normal=tuple(rng.normal(size=3) * 0.2 + (0, 1, 0)))]
    for _ in range(int(rng.integers(1, 25))):
        c = tuple(rng.uniform(-4, 4, 3))
        m = MATS[int(rng.random() < 0.25)]
        kind = rng.integers(0, 3)
        if kind == 0:
            objects.append(Sphere(center=c, radius=float(rng.uniform(0.1, 1.5)), material=m))
        elif kind == 1:
            objects.append(Box(center=c, size=tuple(rng.uniform(0.1, 2.0, 3)), rotation=tuple(rng.uniform(0, 90, 3)),
                               material=m))
        else:
            objects.append(Cylinder(center=c, radius=float(rng.uniform(0.1, 1.0)), height=float(rng.uniform(0.2, 3)),
                                    rotation=tuple(rng.uniform(0, 90, 3)), material=m))
    # exact duplicates: equal t from different objects, the lower index must win
    objects.append(objects[1])
    return Scene(lights=(Light(type="point"),), objects=tuple(objects))


@pytest.mark.parametrize("seed", range(6))
def test_primitive_bvh_equals_linear_scan(seed):
    """closest_hit / shadow_transmittance through the primitive BVH give the bits of a linear scan."""
    rng = np.random.default_rng(seed)
    geometry = build_geometry(random_scene(rng))
    geo = geometry.arrays
    n = geo.prim_kind.shape[0]
    linear = geo._replace(lin_prims=np.arange(n, dtype=np.int64), pnode_min=np.zeros((0, 3)),
                          pnode_max=np.zeros((0, 3)), pnode_first=np.zeros(0, np.int32),
                          pnode_count=np.zeros(0, np.int32), pnode_prims=np.zeros(0, np.int64))
    assert geo.pnode_prims.shape[0] + geo.lin_prims.shape[0] == n
    for _ in range(300):
        o = rng.uniform(-7, 7, 3)
        d = rng.uniform(-4, 4, 3) - o
        d[rng.integers(0, 3)] *= rng.integers(0, 2)  # some exact zero components
        for opaque_only in (True, False):
            assert closest_hit(geo, *o, *d, 0.0, math.inf, opaque_only) == \
                closest_hit(linear, *o, *d, 0.0, math.inf, opaque_only)
        assert shadow_transmittance(geo, *o, *d, 1.0) == shadow_transmittance(linear, *o, *d, 1.0)


def test_march_samples_count_the_steps_the_march_takes():
    """A scene that leaves ``render.steps`` unset is marched with its technique's default: the samples count those
    steps, pairs x steps, as with the same count set explicitly and half of twice as many."""
    scene = load_scene("pillars", ("render.width=32", "render.height=18"))
    assert scene.render.steps is None
    steps = resolved(scene, "steps")
    samples = march_samples(scene, prepare_frame(scene))
    set_steps = scene.replace(render=dataclasses.replace(scene.render, steps=steps))
    doubled = scene.replace(render=dataclasses.replace(scene.render, steps=2 * steps))
    assert samples > 0 and samples % steps == 0
    assert samples == march_samples(set_steps, prepare_frame(set_steps))
    assert 2 * samples == march_samples(doubled, prepare_frame(doubled))
