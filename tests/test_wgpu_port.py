"""The WebGPU killzone port (ports/wgpu: WGSL shaders driven by wgpu-py) checked by vlref end to end.

The port renders ports/wgpu/scenes/pillars_point.toml (a spot and a point light, both with shadow maps) and the
conformance scenes its variants need, with real render passes on whatever WebGPU adapter exists (CI: Mesa
lavapipe, a Vulkan driver on the CPU), exports its buffers as docs/PORTING.md says, ``vlref march`` runs the
technique on them, and ``vlref compare`` must pass every pass of the faithful port with 0 failing pixels, fail
every planted shader bug by at least 2x a bound and pass every benign variant within half of every bound, at
160x90 and at 1280x720 -- judged pass by pass (kz_check.judge_variant), raster bugs against the scene. The
port also runs every scene of the conformance suite in its scope and refuses the others with the reason.
"""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

PORT_DIR = Path(__file__).resolve().parents[1] / "ports" / "wgpu"
sys.path.insert(0, str(PORT_DIR))

import kz_check  # noqa: E402
import kz_port  # noqa: E402
from kz_variants import VARIANTS  # noqa: E402

STEPS = ("render.steps=16",)
SIZES = {"160x90": (160, 90), "1280x720": (1280, 720)}
REFUSED = {"directional_fog", "killzone_params", "killzone_unblurred", "physical", "radial_disenone",
           "radial_gpugems", "slightlymad_scene", "slightlymad_source", "urp"}
"""Conformance scenes outside the port's scope (directional lights, cookies, fog, other sampling/resolutions)."""


@pytest.fixture(scope="module")
def device():
    try:
        return kz_port.device()
    except kz_port.NoAdapter as exc:
        pytest.skip(f"no WebGPU adapter on Vulkan, so the GPU port cannot run here (CI installs "
                    f"mesa-vulkan-drivers): {exc}")


@pytest.fixture(scope="module")
def runs(device, tmp_path_factory):
    """``runs(scene, size)``: the faithful port of a scene at a size and the verdict's cache, made once."""
    cache = {}

    def get(scene: str, size: str):
        if (scene, size) not in cache:
            out = tmp_path_factory.mktemp(f"{scene}-{size}")
            cache[scene, size] = kz_check.scene_run(scene, SIZES[size], STEPS, device, out)
        return cache[scene, size]

    return get


@pytest.fixture(scope="module")
def faithful(device, tmp_path_factory):
    """The walk-through by hand: the faithful port of pillars_point at 160x90, `vlref march --stages` on it."""
    out = tmp_path_factory.mktemp("walk-through")
    port, passes, marched, _ = kz_check.render_and_march(out, ("render.width=160", "render.height=90") + STEPS,
                                                         device)
    return port, passes, marched, out


def test_port_depth_matches_vlref_ray_cast_depth_off_silhouettes(faithful):
    """The port's rasterised, reversed-Z depth32float buffer decodes (by vlref) to vlref's own ray-cast depth,
    except where tessellated cylinders and spheres and their silhouettes differ from the analytic shapes."""
    from vlref.io.images import read_image
    from vlref.render import prepare_frame

    port, _, marched, _ = faithful
    got = read_image(marched / "depth.exr")[..., 0]
    want = prepare_frame(port.scene).gbuffer.depth
    both = np.isfinite(got) & np.isfinite(want)
    assert both.mean() > 0.5 and (np.isfinite(got) != np.isfinite(want)).mean() < 0.01
    rel = np.abs(got[both] - want[both]) / want[both]
    assert np.median(rel) < 1e-5          # the floor: float32 reversed-Z
    assert (rel < 1e-2).mean() > 0.97     # all but silhouettes of tessellated curved objects


def test_faithful_port_passes_every_pass_with_zero_failing_pixels(faithful):
    _, passes, marched, _ = faithful
    for name, ref, preset, report in kz_check.pass_rows(passes, marched):
        assert report.passed, (name, preset, report.checks)
        assert report.metrics["failing_pixels"] == 0, (name, report.metrics)
        assert report.metrics["compared_pixels"] > 0.5 * report.metrics["total_pixels"]
    light = passes["blur_v"]
    assert light.mean() > 0.01 and np.all(np.isfinite(light))   # the lights are in the frame


def test_cli_compare_on_the_exported_final(faithful):
    """The walk-through's `vlref compare REF TEST --preset gpu-half` and `vlref verdict PORT.toml` on the port's files."""
    from vlref.cli import main

    _, _, marched, out = faithful
    final = str(out / "port" / "port_final.npy")
    assert main(["compare", str(marched / "final.exr"), final, "--preset", "gpu-half", "-q"]) == 0
    assert main(["compare", str(marched / "final.exr"), final, "--preset", "float32", "-q"]) == 1
    assert main(["verdict", str(out / "port" / "port.toml"), "-o", str(out / "verdict"), "-q"]) == 0


@pytest.mark.parametrize("size", list(SIZES))
@pytest.mark.parametrize("variant", list(VARIANTS))
def test_variant_is_judged_as_expected_pass_by_pass(runs, device, variant, size):
    spec = VARIANTS[variant]
    result = kz_check.judge_variant(runs(spec.scene, size), variant, device)
    table = [(p.name, p.group, p.passed, p.margins, p.reason) for p in result.passes]
    if spec.expect == "pass":
        assert result.passed, table
        assert result.worst <= 0.5, table          # within half of every bound of every pass
    else:
        assert not result.passed, table
        c = result.caught_by   # caught by a margin, not on a knife edge: failing pixels (bound 0) or 2x a bound,
        # or a degenerate comparison / non-finite output, each failing with its reason
        assert c.worst >= 2.0 or "proves nothing" in c.reason or "infinite value" in c.reason, table


@pytest.mark.parametrize("scene, size", [("laws", "160x90"), ("laws", "1280x720"), ("inside_volume", "160x90"),
                                         ("inside_volume", "1280x720"), ("bright_behind", "160x90"),
                                         ("bright_behind", "1280x720")])
def test_faithful_port_on_the_variants_conformance_scenes(runs, device, scene, size):
    """``laws`` has lights of shadow strength 0.15 and 0.2: surfaces in their shadows keep ``1 - strength`` of the
    light in the port's lighting pass and in vlref's shading alike (at 1281x721 ground points at 14 m show it)."""
    result = kz_check.judge_variant(runs(scene, size), "faithful", device)
    assert result.passed and result.worst <= 0.5, [(p.name, p.margins) for p in result.passes]


def test_the_port_runs_the_conformance_suite_and_refuses_the_rest_with_reasons(device, tmp_path):
    rows = kz_check.run_suite(device, out=tmp_path)
    assert {r.scene for r in rows} == {p.stem for p in kz_check.SUITE.glob("*.toml")}
    assert {r.scene for r in rows if r.refused} == REFUSED
    for row in rows:
        if row.refused:
            assert row.refused.startswith("the wgpu port does not implement: ") or "render." in row.refused, row
            continue
        for p in row.passes:
            assert p.passed and p.worst <= 0.5, (row.scene, p.name, p.margins, p.reason)


def test_an_opengl_only_machine_is_refused_with_the_reason():
    """wgpu on GL (llvmpipe without Mesa's Vulkan driver) cannot textureLoad depth textures: no adapter."""
    gl = SimpleNamespace(info={"backend_type": "OpenGL", "device": "llvmpipe"})
    vk = SimpleNamespace(info={"backend_type": "Vulkan", "device": "lavapipe"})
    with pytest.raises(kz_port.NoAdapter, match="Vulkan"):
        kz_port.pick_adapter([gl])
    assert kz_port.pick_adapter([gl, vk]) is vk


def test_zero_bounds_are_reported_not_divided():
    """gpu-half allows no failing pixel (a bound of 0): one failing pixel is an infinite margin, none is 0."""
    from vlref.oracle.compare import compare_arrays

    ref = np.ones((4, 4, 3))
    for test, worst in ((ref.copy(), 0.0), (np.where(np.arange(16).reshape(4, 4, 1) == 5, 2.0, ref), float("inf"))):
        report = compare_arrays(ref, test, "gpu-half", flip=False)
        row = kz_check.PassResult("final", "gpu-half", report.passed, report.margins(),
                                  int(report.metrics["failing_pixels"]), 16)
        assert row.margins["failing_fraction"] == worst and row.passed == (worst == 0.0)
        assert kz_check.variant_row(kz_check.VariantResult("faithful", "pillars_point", "4x4", [row])).count("|") == 9
