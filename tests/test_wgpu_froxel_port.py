"""The WebGPU froxel port (ports/wgpu_froxel: WGSL compute shaders driven by wgpu-py) judged by vlref frame by frame.

The port renders 4 frames of the animated scenes anim_spot (the spot turns, static camera) and anim_sun (the
camera dollies, the sun turns) at 96x54 with a 20x12x16 grid (not a multiple of the 8x8 workgroups), temporal
with the history clamp, on whatever WebGPU adapter exists (CI: Mesa lavapipe). Each frame's raster buffers
are exported as docs/PORTING.md says and vlref's froxel technique runs on them in sequence, carrying its own
history (``vlref march frame_0000/port.toml ... --stages``). Every exported pass of every frame (slices, lit
grid, history and its counts, integrated grid, inscatter, transmittance, final) must pass its preset with 0
failing pixels; every planted bug must fail some pass of some frame by a margin; the benign variants must pass
everything at <= 0.5x of every bound. Raster passes and vlref's sequence run once per scene (module fixture).

The whole-frame sequence verdict (``vlref verdict frame_0000/port.toml ...``) judges every frame twice: on the
port's own buffers, vlref marching each frame with the history of its march on the frames before, and against
the scene: the port's camera, depth, shadow maps and cascades, lit scene colour (the sun included) and final
frame against vlref's render of that frame with its own history. The faithful port passes both on every frame
of both scenes; a raster bug (frame 0's camera kept by the G-buffer) passes its own buffers and fails against the
scene from frame 1 on, named by frame and pass.
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

from vlref.oracle.verdict import GROUP_OWN, GROUP_SCENE  # noqa: E402

SIZE = ("render.width=96", "render.height=54", "techniques.froxel.grid_width=20", "techniques.froxel.grid_height=12",
        "techniques.froxel.slices=16")
SCENES = {"anim_spot": (*SIZE, "lights.0.shadows.resolution=128"), "anim_sun": SIZE}
VERDICT_SCENES = {"anim_spot": SIZE, "anim_sun": SIZE}
"""The sequence verdict's settings: the scenes' own map resolutions. (At 128² the spot's shadow edges on the
ground cover so many pixels that end_to_end's mean error over every pixel, shadow zone included, is 1.12x of
its bound at frame 0.)"""
FRAMES = 4
RASTER_VARIANTS = [name for name, v in VARIANTS.items() if v.is_raster]


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


@pytest.mark.parametrize("variant", [v for v in VARIANTS if v != "faithful" and v not in RASTER_VARIANTS])
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


@pytest.fixture(scope="module")
def verdicts(device, tmp_path_factory):
    """Per scene: the faithful port's sequence verdict (`vlref verdict frame_0000/port.toml ...` through the
    Python API, without reports: tests/test_verdict.py covers the command line and its files), the folder of
    its exports and the cache of vlref's renders and marches it filled."""
    out = {}
    for scene, overrides in VERDICT_SCENES.items():
        port, overrides = fx_check.setup(scene, FRAMES, overrides, device)
        folder, cache = tmp_path_factory.mktemp(f"{scene}-verdict"), {}
        out[scene] = (folder, cache, fx_check.sequence_verdict(port, scene, overrides, folder, cache=cache,
                                                               reports=False))
    return out


def test_sequence_verdict_of_the_faithful_port_passes_every_frame_and_names_each_comparison(verdicts):
    folder, _, verdict = verdicts["anim_spot"]
    data = verdict.to_dict()
    assert data["passed"] is True and data["failures"] == []
    assert [f["frame"] for f in data["frames"]] == list(range(FRAMES))
    for f in data["frames"]:
        assert f["manifest"] == str(folder / f"frame_{f['frame']:04d}" / "port.toml")
        names = {(p["group"], p["name"]) for p in f["passes"]}
        assert {(GROUP_OWN, name) for name, _ in fx_check.PASSES} | {
            (GROUP_SCENE, n) for n in ("camera", "depth", "shadow_map[light=0]", "shadow_test[light=0]",
                                       "scene_colour", "end_to_end")} == names
        for p in f["passes"]:
            assert p["passed"], (f["frame"], p["name"], p["reason"])
            if "compared_pixels" in p["metrics"]:
                assert p["metrics"]["failing_pixels"] == 0 and p["metrics"]["compared_pixels"] > 0


def test_sequence_verdict_of_the_faithful_port_passes_every_frame_against_the_sun(verdicts):
    """anim_sun: the camera moves and the sun turns; the scene colour is lit by the sun through its cascades."""
    _, _, verdict = verdicts["anim_sun"]
    assert verdict.passed and len(verdict.frames) == FRAMES, verdict.table()
    for f in verdict.frames:
        by_name = {p.name: p for p in f.passes}
        assert {"froxel_history", "shadow_map[light=0]", "scene_colour", "end_to_end"} <= set(by_name)
        for p in f.passes:
            assert max(p.metrics.get("margins", {"-": 0.0}).values()) <= 0.5, (p.name, p.metrics)


def test_sun_lights_the_port_scene_colour(verdicts, sequences):
    """The killzone raster lights surfaces with the sun through its cascades: where vlref's shading is lit by the
    sun, the port's scene colour is within 10 % of it on 95 % of the pixels (it would be the ambient alone, far
    below, if the raster ignored directional lights)."""
    from vlref.render import prepare_frame
    from vlref.scene import load_scene

    port, overrides, _, _ = sequences["anim_sun"]
    for fs in port.setups:
        want = prepare_frame(load_scene("anim_sun", [*overrides, f"render.frame={fs.frame}"])).scene_colour
        dark = prepare_frame(load_scene("anim_sun", [*overrides, f"render.frame={fs.frame}", "lights.0.intensity=0"]
                                        )).scene_colour
        got = fs.raster.raster_buffers()["colour"]
        sunlit = (want - dark).sum(axis=2) > 0.1 * want.sum(axis=2)
        assert sunlit.mean() > 0.2
        close = np.abs(got - want).max(axis=2) <= 0.1 * want.max(axis=2)
        assert close[sunlit].mean() > 0.95, (fs.frame, close[sunlit].mean())


@pytest.mark.parametrize("variant", RASTER_VARIANTS)
def test_raster_bug_passes_its_own_buffers_and_fails_against_the_scene_by_frame_and_pass(device, verdicts, variant):
    """A raster bug feeds vlref's march the same wrong inputs, so on the port's own buffers it passes every frame;
    only the sequence verdict against the scene catches it, naming the frames (``from_frame`` on: a stale camera
    shows once the camera has moved since frame 0, a wrong sun term from frame 0) and the passes (``fails``, the
    first by at least 2x a bound) where it fails. The sun's bugs (its n.l taken with the direction of travel; its
    cascades looked up without the normal offset, so sunlit ground shadows itself) darken ground that is no
    shadow silhouette of either map: outside the shading zone, where the mean error is bounded."""
    spec = VARIANTS[variant]
    scene = spec.scene or "anim_sun"
    folder, cache, _ = verdicts[scene]
    port, overrides = fx_check.setup(scene, FRAMES, VERDICT_SCENES[scene], device, variant)
    verdict = fx_check.sequence_verdict(port, scene, overrides, folder / variant, variant, cache, reports=False)
    assert all(p.passed for f in verdict.frames for p in f.passes if p.group == GROUP_OWN), verdict.table()
    failures = verdict.failures()
    assert failures and all(p.group == GROUP_SCENE for _, p in failures)
    assert {i for i, _ in failures} == set(range(spec.from_frame, FRAMES)), verdict.table()
    for i in range(spec.from_frame, FRAMES):
        failed = {p.name: max(p.metrics["margins"].values()) for j, p in failures if j == i}
        assert set(spec.fails) <= set(failed) and failed[spec.fails[0]] >= 2.0, (i, failed)
    assert f"- frame {spec.from_frame}, {spec.fails[0]} (against the scene)" in verdict.table()
