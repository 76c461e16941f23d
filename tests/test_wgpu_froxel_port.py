"""The WebGPU froxel port (ports/wgpu_froxel: WGSL compute shaders driven by wgpu-py) judged by vlref frame by frame.

The port renders 4 frames of the animated scenes anim_spot (the spot turns, static camera) and anim_sun (the
camera dollies, the sun turns) at 96x54 with a 20x12x16 grid (not a multiple of the 8x8 workgroups), temporal
with the history clamp, on whatever WebGPU adapter exists (CI: Mesa lavapipe). Each frame's raster buffers
are exported as docs/PORTING.md says and vlref's froxel technique runs on them in sequence, carrying its own
history (``vlref march frame_0000/port.toml ... --stages``). Every exported pass of every frame (slices, lit
grid, history and its counts, integrated grid, inscatter, transmittance, final) must pass its preset with 0
failing pixels; every planted bug must fail some pass of some frame by a margin; the benign variants must pass
everything at <= 0.5x of every bound. Raster passes and vlref's sequence run once per scene (module fixture).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

PORT_DIR = Path(__file__).resolve().parents[1] / "ports" / "wgpu_froxel"
sys.path.insert(0, str(PORT_DIR))

import fx_check  # noqa: E402
import fx_port  # noqa: E402
import kz_port  # noqa: E402
from fx_variants import VARIANTS  # noqa: E402

SIZE = ("render.width=96", "render.height=54", "techniques.froxel.grid_width=20", "techniques.froxel.grid_height=12",
        "techniques.froxel.slices=16")
SCENES = {"anim_spot": (*SIZE, "lights.0.shadows.resolution=128"), "anim_sun": SIZE}
FRAMES = 4


@pytest.fixture(scope="module")
def device():
    try:
        return fx_port.device()
    except kz_port.NoAdapter as exc:
        pytest.skip(f"no WebGPU adapter, so no GPU port can run here (CI installs mesa-vulkan-drivers): {exc}")


@pytest.fixture(scope="module")
def sequences(device, tmp_path_factory):
    """Per scene: (port, its exported manifests, vlref's buffers of every frame on the port's buffers)."""
    out = {}
    for scene, overrides in SCENES.items():
        port, overrides = fx_check.setup(scene, FRAMES, overrides, device)
        folder = tmp_path_factory.mktemp(scene)
        out[scene] = (port, overrides, folder, fx_check.reference(port, scene, overrides, folder))
    return out


@pytest.mark.parametrize("scene", list(SCENES))
def test_faithful_port_passes_every_pass_of_every_frame(sequences, scene):
    port, _, _, refs = sequences[scene]
    frames = port.run("faithful")
    rows = fx_check.judge(frames, refs)
    assert {(f, name) for f, name, _, _ in rows} == {(f, name) for f in range(FRAMES) for name, _ in fx_check.PASSES}
    for f, name, preset, report in rows:
        assert report.passed, (f, name, preset, report.checks)
        assert report.metrics["failing_pixels"] == 0, (f, name, report.metrics)
    assert all(frames[f]["inscatter"].mean() > 1e-3 and np.all(np.isfinite(frames[f]["final"])) for f in range(FRAMES))
    later = frames[FRAMES - 1]
    assert later["froxel_history_valid"].mean() > 0.5                    # the history is reprojected and used
    assert later["froxel_history_frames"].max() == min(FRAMES, 10)       # and accumulates up to ceil(1/alpha)


def test_cli_march_of_the_sequence_and_compare_of_an_exported_history(sequences, tmp_path):
    """PORTING.md §5 command by command: the port's files, `vlref march` of the manifests in order, then
    `vlref compare` of the last frame's history (a 4-channel stacked-slice image) with the port's .npy."""
    from vlref.cli import main

    port, overrides, _, _ = sequences["anim_spot"]
    manifests = fx_port.export(port, tmp_path / "port", "anim_spot", overrides, port.run("faithful"))
    assert main(["march", *map(str, manifests), "-o", str(tmp_path / "marched"), "--stages", "-q"]) == 0
    last = f"frame_{FRAMES - 1:04d}"
    ref, test = tmp_path / "marched" / last / "froxel_history.exr", tmp_path / "port" / last / "port_froxel_history.npy"
    assert main(["compare", str(ref), str(test), "--preset", "gpu-sampled", "-q"]) == 0   # sampler-fetched history
    assert main(["compare", str(ref), str(test), "--preset", "float32", "-q"]) == 1    # rgba16float grids


@pytest.mark.parametrize("variant", [v for v in VARIANTS if v != "faithful"])
def test_variant_is_judged_as_expected(sequences, variant):
    spec = VARIANTS[variant]
    verdicts = {scene: fx_check.verdict(fx_check.judge(port.run(variant), refs))
                for scene, (port, _, _, refs) in sequences.items()}
    if spec.expect == "pass":
        for scene, (passed, worst, where) in verdicts.items():
            assert passed and worst <= 0.5, (variant, scene, worst, where)
    else:
        failing = {scene: v for scene, v in verdicts.items() if not v[0]}
        assert failing, (variant, verdicts)
        assert max(worst for _, worst, _ in failing.values()) > 2.0, (variant, failing)   # not on a knife edge


@pytest.mark.parametrize("scene", list(SCENES))
def test_first_lit_grid_matches_vlref_render_of_the_scene_and_its_shadows_matter(sequences, scene):
    """Against the scene, not the port's buffers: frame 0's lit and integrated grids (no history on either side)
    equal `vlref render`'s, whose depth and shadow maps (spot; the sun's cascades) are vlref's own ray casts, so
    the port's rasterised maps and their lookup agree with the scene; and the same grid differs from the scene
    rendered without shadows, so those maps shadow something."""
    from vlref.render import render
    from vlref.scene import load_scene

    port, overrides, _, _ = sequences[scene]
    got = port.run("faithful")[0]
    want = render(load_scene(scene, overrides), stages=True).buffers
    for name in ("froxel_scatter", "froxel_integrated"):
        report = fx_check.compare(want[name], got[name], "gpu-full")
        assert report.passed and report.metrics["failing_pixels"] == 0, (name, report.checks)
    unshadowed = render(load_scene(scene, [*overrides, "lights.0.shadows.enabled=false"]), stages=True).buffers
    report = fx_check.compare(unshadowed["froxel_scatter"], got["froxel_scatter"], "gpu-full")
    assert min(fx_check.margins(report)) > 3.0, report.checks
