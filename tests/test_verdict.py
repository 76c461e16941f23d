"""The whole-frame verdict (vlref.oracle.verdict, `vlref verdict`): vlref exported as a port of itself must
pass on its own buffers AND against the scene; raster bugs planted in its exported buffers must fail the
against-the-scene comparison that owns them; degenerate inputs fail loudly; the edge zone does not grow
with the image."""

from __future__ import annotations

import dataclasses
import json
import math
import re
import shutil

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vlref.cli import main
from vlref.errors import InputError
from vlref.io.exr import write_exr
from vlref.io.images import read_image
from vlref.oracle.compare import compare_arrays, margin
from vlref.oracle.edges import block_any, depth_discontinuities, dilate, edge_zone
from vlref.oracle.presets import load_presets, tolerance
from vlref.oracle.verdict import (GROUP_OWN, GROUP_SCENE, judge, judge_sequence, rounding_patterns, shadow_zone,
                                  silhouette_zone)
from vlref.port import load_port, port_frame
from vlref.port.export import export_port
from vlref.render import prepare_frame
from vlref.scene import load_scene
from vlref.techniques import TECHNIQUES

SCENE = "pillars"
SMALL = ["render.width=64", "render.height=36", "render.steps=8", "lights.0.shadows.resolution=128"]
BIAS = 0.03  # lights.0.shadows.bias of data/scenes/pillars.toml


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """vlref's own buffers of the pillars scene as a port would write them, twice: raw reversed-Z depth and
    shadow maps (the default), and linear depth with distance shadow maps (easy to edit)."""
    root = tmp_path_factory.mktemp("verdict")
    raw = export_port(SCENE, root / "raw", SMALL, passes=True)
    linear = export_port(SCENE, root / "linear", SMALL, passes=True, depth_encoding="linear",
                         shadow_encoding="distance")
    return raw.parent, linear.parent


def _copy(src, dst):
    shutil.copytree(src, dst)
    return dst


def _by_name(verdict):
    return {p.name: p for p in verdict.passes}


def test_vlref_as_its_own_port_passes_both_judgments(exported, tmp_path):
    raw, _ = exported
    out = tmp_path / "verdict"
    assert main(["verdict", str(raw / "port.toml"), "-o", str(out), "-q"]) == 0
    data = json.loads((out / "verdict.json").read_text())
    assert data["passed"] is True
    groups = {p["group"] for p in data["passes"]}
    assert groups == {GROUP_OWN, GROUP_SCENE}
    names = {p["name"] for p in data["passes"]}
    assert {"final", "inscatter", "transmittance", "camera", "depth", "shadow_map[light=0]", "shadow_test[light=0]",
            "scene_colour", "end_to_end"} <= names
    for p in data["passes"]:
        if p["name"] != "camera":
            assert p["metrics"]["failing_pixels"] == 0 and p["metrics"]["compared_pixels"] > 0
            assert (out / p["report"].split(str(out) + "/")[1]).is_file()
    assert "PASS" in (out / "index.html").read_text()


def test_sequence_verdict_names_the_frame_and_pass_of_each_failure(exported, tmp_path):
    """`vlref verdict A.toml B.toml -o DIR`: every frame judged as `vlref verdict` judges it alone (pillars'
    killzone keeps no history), its files under DIR/frame_NNNN, and the sequence's verdict.json naming each
    failure by frame and pass: here the second frame's inscatter pass scaled by 1.5."""
    raw, _ = exported
    second = _copy(raw, tmp_path / "second")
    np.save(second / "port_inscatter.npy", np.load(second / "port_inscatter.npy") * 1.5)
    cache = {}
    alone = judge(raw / "port.toml", cache=cache)
    seq = judge_sequence([raw / "port.toml", second / "port.toml"], cache=cache)
    assert [(p.name, p.passed, p.metrics) for p in seq.frames[0].passes] == \
        [(p.name, p.passed, p.metrics) for p in alone.passes]
    assert [(i, p.name, p.group) for i, p in seq.failures()] == [(1, "inscatter", GROUP_OWN)]
    assert not seq.passed and seq.frames[0].passed and "- frame 1, inscatter (own buffers)" in seq.table()

    out, xml = tmp_path / "verdict", tmp_path / "verdict.xml"
    assert main(["verdict", str(raw / "port.toml"), str(second / "port.toml"), "-o", str(out), "-q",
                 "--junit", str(xml)]) == 1
    data = json.loads((out / "verdict.json").read_text())
    assert data["passed"] is False and [(f["frame"], f["name"]) for f in data["failures"]] == [(1, "inscatter")]
    assert [f["passed"] for f in data["frames"]] == [True, False]
    for i in (0, 1):
        assert json.loads((out / f"frame_{i:04d}" / "verdict.json").read_text())["passes"] == \
            data["frames"][i]["passes"]
    assert (out / "frame_0001" / "own_buffers" / "inscatter" / "report.html").is_file()
    assert 'href="frame_0001/own_buffers/inscatter/report.html"' in (out / "index.html").read_text()
    cases = dict(re.findall(r'<testcase [^>]*name="([^"]+)"[^>]*>(\s*<failure)?', xml.read_text()))
    assert len(cases) == sum(len(f["passes"]) for f in data["frames"])
    assert [name for name, failed in cases.items() if failed] == ["frame 1: own buffers: inscatter"]
    with pytest.raises(InputError):
        judge_sequence([])


def _edit_exr(path, change):
    write_exr(path, change(read_image(path)))


def _ray_length(d):
    """Eye depth -> distance along the pixel ray (the bug: depth decoded as ray length)."""
    scene = load_scene(SCENE, SMALL)
    frame = prepare_frame(scene)
    return frame.camera.eye_depth_to_distance(d[..., 0], frame.camera.ray_directions())[..., None]


BUGS = {
    # name: (which export, file, edit, the against-the-scene comparison that must fail, ones that must pass)
    "shadow map cleared to the near value under reversed-Z": (
        0, "shadow_0.exr", lambda a: np.where(a == 0.0, 1.0, a), "shadow_map[light=0]", ("depth", "scene_colour")),
    "depth decoded as ray length": (1, "depth.exr", _ray_length, "depth", ("shadow_map[light=0]", "scene_colour")),
    "scene colour without 1/pi": (1, "colour.exr", lambda a: a * math.pi, "scene_colour",
                                  ("depth", "shadow_map[light=0]", "shadow_test[light=0]")),
    "shadow bias of the wrong sign": (1, "shadow_0.exr", lambda a: np.where(np.isfinite(a), a - 2 * BIAS, a),
                                      "shadow_map[light=0]", ("depth", "end_to_end")),
}


@pytest.mark.parametrize("bug", sorted(BUGS))
def test_raster_bug_fails_the_comparison_that_owns_it(exported, tmp_path, bug):
    which, name, edit, failing, passing = BUGS[bug]
    port = _copy(exported[which], tmp_path / "port")
    _edit_exr(port / name, edit)
    v = _by_name(judge(port / "port.toml"))
    assert not v[failing].passed and v[failing].group == GROUP_SCENE
    assert v[failing].metrics["failing_pixels"] - v[failing].metrics["failing_pixels_edge"] > 0
    assert "pixels fail" in v[failing].reason
    for name in passing:
        assert v[name].passed, (name, v[name].reason)


def test_a_zone_that_leans_one_way_fails_though_each_of_its_pixels_may_differ(exported, tmp_path):
    """The shading zone lets each pixel differ by any amount, either way: a rasteriser may take the other side of
    an edge, a map texel the other side of a silhouette. Darkening every depth-edge pixel (all inside the zone)
    passes every per-pixel check and the mean error outside the zone; only the zone's signed mean fails it, and
    the same changes with alternating signs pass."""
    def edited(sign):
        port = _copy(exported[1], tmp_path / f"port{sign}")
        depth = read_image(port / "depth.exr")[..., 0]
        edges = depth_discontinuities(np.where(np.isfinite(depth), depth, np.inf))
        signs = np.where(np.indices(edges.shape).sum(axis=0) % 2 == 0, 1.0, sign)
        _edit_exr(port / "colour.exr", lambda a: a * np.where(edges, 1.0 - 0.6 * signs, 1.0)[..., None])
        return _by_name(judge(port / "port.toml"))["scene_colour"]

    one_way, both_ways = edited(1.0), edited(-1.0)
    # the first failing check: no pixel fails, nor the mean error outside the zone or over every pixel
    assert not one_way.passed and one_way.reason.startswith("zone pixels lean one way: mean (port - vlref)")
    assert one_way.metrics["margins"]["zone_lean"] >= 2.0
    assert one_way.metrics["failing_pixels"] == 0 and one_way.metrics["zone_mean_signed"] < 0
    assert both_ways.passed and both_ways.metrics["margins"]["zone_lean"] <= 0.5, both_ways.metrics


def test_black_port_fails_with_the_reason(exported, tmp_path):
    port = _copy(exported[1], tmp_path / "port")
    for f in port.glob("port_*.npy"):
        np.save(f, np.zeros_like(np.load(f)))
    for name in ("final.exr", "colour.exr"):
        _edit_exr(port / name, np.zeros_like)
    _edit_exr(port / "shadow_0.exr", lambda a: np.full_like(a, 1e-3))  # every texel: a caster at the light
    out = tmp_path / "verdict"
    assert main(["verdict", str(port / "port.toml"), "-o", str(out), "-q"]) == 1
    v = {p["name"]: p for p in json.loads((out / "verdict.json").read_text())["passes"]}
    assert v["inscatter"]["reason"].startswith("reference inscatter is zero over 100 % of the compared pixels: "
                                               "this comparison proves nothing")
    assert not v["end_to_end"]["passed"] and not v["shadow_map[light=0]"]["passed"]
    page = (out / "index.html").read_text()
    assert "FAIL" in page and "this comparison proves nothing" in page
    assert "against_the_scene/end_to_end/heatmap.png" in page  # the page shows where


def test_missing_map_of_a_shadowed_light_is_bad_input(exported, tmp_path, capsys):
    port = _copy(exported[0], tmp_path / "port")
    text = (port / "port.toml").read_text()
    (port / "port.toml").write_text(text[:text.index("[[shadow_maps]]")])
    assert main(["verdict", str(port / "port.toml"), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "shadow_maps" in err and "light 0 (spot)" in err
    assert not (tmp_path / "out").exists()
    # a port that declares it has no shadows is judged against the scene without them
    (port / "port.toml").write_text("shadows = false\n" + text[:text.index("[[shadow_maps]]")])
    assert load_port(port / "port.toml").has_shadows is False


def test_unknown_pass_buffer_is_bad_input(exported, tmp_path):
    port = _copy(exported[0], tmp_path / "port")
    text = (port / "port.toml").read_text()
    (port / "port.toml").write_text(text.replace('buffer = "final"', 'buffer = "finale"'))
    with pytest.raises(InputError, match=r"passes\[\d\]\.buffer.*finale"):
        judge(port / "port.toml")


def test_edge_zone_shrinks_with_resolution_and_an_error_away_from_edges_fails_at_both_sizes():
    """The same scene at 160x90 and 640x360: the zone (depth discontinuities, 2 pixels) covers a smaller share
    of the larger image, and a 5 % error at a point far from every edge fails gpu-half at both sizes, while
    the unchanged image passes."""
    shares = []
    for w, h in ((160, 90), (640, 360)):
        frame = prepare_frame(load_scene(SCENE, [f"render.width={w}", f"render.height={h}"]))
        ref = frame.scene_colour
        zone = edge_zone(2, depths=[frame.gbuffer.depth])
        shares.append(zone.mean())
        y, x = int(0.85 * h), int(0.3 * w)  # on the floor in front of the pillars
        assert not zone[y - 2:y + 3, x - 2:x + 3].any() and ref[y, x].mean() > 0
        test = ref.copy()
        test[y, x] *= 1.05
        assert compare_arrays(ref, ref, "gpu-half", edges=zone, flip=False).passed
        planted = compare_arrays(ref, test, "gpu-half", edges=zone, flip=False)
        assert not planted.passed and planted.metrics["failing_pixels"] == 1
    assert shares[1] < 0.5 * shares[0]


def test_edge_zone_geometry():
    z = np.full((6, 8), 4.0)
    z[:, 5:] = 8.0   # a silhouette between columns 4 and 5
    z[0, 0] = np.inf  # sky next to a surface
    d = depth_discontinuities(z)
    assert d[:, 3:7].all() and not d[3:, :3].any() and not d[:, 7].any()
    assert d[0, :3].all() and d[:3, 0].all()
    assert dilate(d, 1)[5, 2] and not dilate(d, 1)[5, 1]
    low = block_any(d, (3, 4))  # 2x2 blocks
    assert low[:, 1:].all() and low[0, 0] and not low[2, 0]
    # a plane seen at any angle and resolution: inverse depth is affine on screen, no discontinuity
    y, x = np.mgrid[0:90, 0:160]
    assert not depth_discontinuities(1.0 / (0.01 + 0.002 * x + 0.05 * y)).any()


def test_gpu_presets_allow_no_failing_pixel_outside_the_edge_zone():
    """All but gpu-sampled: what a port reads through its sampler (3-D grids, no geometric zone yet) keeps a
    bounded share (tests/test_compare.py). gpu-float32's zone is not geometric (no edge_pixels): the knife-edge
    and depth-rounding pixels of the port's own buffers, with five times float32's per-pixel tolerance."""
    for name, tol in load_presets().items():
        if name.startswith(("gpu-", "raster-")) or name == "end-to-end":
            if name == "gpu-sampled":
                assert 0 < tol.max_fail_fraction <= 2e-2
                continue
            assert tol.max_fail_fraction == 0 and (tol.edge_pixels >= 1 or name == "gpu-float32"), name
    f32, g32, full = (load_presets()[n] for n in ("float32", "gpu-float32", "gpu-full"))
    assert (g32.rel_tol, g32.abs_tol, g32.max_mean_abs) == (f32.rel_tol, f32.abs_tol, f32.max_mean_abs)
    assert (g32.edge_rel, g32.edge_abs) == (5 * f32.rel_tol, 5 * f32.abs_tol)
    assert g32.edge_rel < full.edge_rel and g32.edge_abs < full.edge_abs


@settings(max_examples=40, deadline=None)
@given(value=st.sampled_from([0.0, 1e-30, 1.0]), other=st.sampled_from([0.0, 1.0, 2.0]),
       preset=st.sampled_from(sorted(load_presets())), with_edges=st.booleans())
def test_zero_and_constant_images_divide_by_no_zero_bound(value, other, preset, with_edges):
    ref = np.full((5, 7, 3), value)
    test = np.full((5, 7, 3), other)
    edges = np.zeros((5, 7), bool)
    edges[2, :] = with_edges
    with np.errstate(all="raise"):
        report = compare_arrays(ref, test, tolerance(preset), flip=False, edges=edges)
        margins = report.margins()
    assert report.passed == (value == other or all(c.passed for c in report.checks))
    assert all(not math.isnan(m) and m >= 0 for m in margins.values())
    assert margin(0.0, 0.0) == 0.0 and margin(1.0, 0.0) == math.inf and margin(1.0, 2.0) == 0.5


def test_table_names_every_pass(exported):
    verdict = judge(exported[0] / "port.toml")
    table = verdict.table()
    for p in verdict.passes:
        assert re.search(rf"^\| {re.escape(p.name)} \| {p.group} \|", table, re.M)


def test_gpu_float32_gives_each_pixel_vlrefs_own_rounding_spread_and_no_more(tmp_path):
    """A float32 port decodes each stored depth by one formula, which rounds otherwise than vlref's float64 one (here:
    the killzone's buffers on the port's depths, each distinct stored depth moved by 4 ulp with a random sign). It
    differs from vlref by more than float32's 1e-4 where the depth-aware upsample and blur weights 1 / (|dz| + 1 mm)
    amplify it: gpu-float32 gives each pixel twice vlref's own 4-ulp spread and a zone of the sensitive pixels (a
    small share of the frame), and passes with no failing pixel; a 0.1 % error fails outside that zone."""
    manifest = export_port(SCENE, tmp_path / "port", SMALL + ['render.technique="killzone"'], passes=True)
    port = load_port(manifest)
    values, rank = np.unique(port.depth, return_inverse=True)
    signs = np.random.default_rng(1).choice([-1.0, 1.0], size=len(values))[rank].reshape(port.depth.shape)
    moved = dataclasses.replace(port, depth=port.depth * (1.0 + 2.0 ** -21 * signs))
    exact, rounded = (TECHNIQUES["killzone"].render(p.scene, port_frame(p)) for p in (port, moved))
    bare = compare_arrays(exact["upsample"], rounded["upsample"], "gpu-float32", flip=False)
    assert not bare.passed and bare.metrics["failing_pixels"] > 0     # float32's bounds alone do not hold it
    for name in ("upsample", "blur_h", "blur_v", "inscatter", "final"):
        np.save(manifest.parent / f"port_{name}.npy", rounded[name].astype(np.float32))
    v = _by_name(judge(manifest))
    for name in ("upsample", "blur_h", "blur_v", "final"):
        assert v[name].passed and v[name].preset == "gpu-float32" and v[name].metrics["failing_pixels"] == 0, v[name]
        assert 0 < v[name].metrics["edge_pixels"] < 0.2 * v[name].metrics["compared_pixels"], v[name]
    np.save(manifest.parent / "port_upsample.npy", (rounded["upsample"] * 1.001).astype(np.float32))
    bug = _by_name(judge(manifest))["upsample"]
    assert not bug.passed and bug.metrics["failing_pixels"] - bug.metrics["failing_pixels_edge"] > 0


def test_shading_zone_leaves_out_a_ground_that_casts_onto_itself_under_a_low_sun():
    """anim_sun's ground under its sun 21 degrees high: the ground's own cascade climbs from texel to texel by more than
    the 3 cm bias, so the min/max-filtered maps change the decision on nearly all sunlit ground (``shadow_zone``); the
    shading comparisons' zone (``silhouette_zone``) holds only the points whose lookup is near a caster's edge in the
    map and leaves most of the sunlit ground to the per-pixel and mean-error checks (that the zone is wide enough
    for a faithful port's map lookups: tests/test_wgpu_port.py, tests/test_wgpu_froxel_port.py)."""
    size = ["render.width=96", "render.height=54"]
    frame = prepare_frame(load_scene("anim_sun", size))
    unshadowed = prepare_frame(load_scene("anim_sun", [*size, "lights.0.shadows.enabled=false"])).scene_colour
    g = frame.gbuffer
    hit = np.isfinite(g.depth)
    points = g.position[hit]
    maps = frame.shadow_maps()
    lit = frame.scene_colour.sum(axis=2) > 0.5 * unshadowed.sum(axis=2)   # the exact shadow ray's decision
    sunlit = (hit & (np.abs(g.position[..., 1]) < 1e-9) & lit)[hit]
    minmax, silhouettes = shadow_zone(maps, frame.lights, points, 1), silhouette_zone(maps, frame.lights, points, 2)
    assert sunlit.sum() > 1000 and silhouettes.any()
    assert minmax[sunlit].mean() > 0.9 and silhouettes[sunlit].mean() < 0.15, (minmax[sunlit].mean(),
                                                                                silhouettes[sunlit].mean())


def test_rounding_patterns_move_equal_stored_depths_alike_and_close_ones_apart():
    """The depth-rounding patterns are a function of the stored depth (a port decodes a value one way), and any two
    distinct depths less than 16 apart in rank move in opposite directions in some pattern, each way round."""
    rng = np.random.default_rng(3)
    depth = rng.choice(np.linspace(5.0, 6.0, 40), size=(30, 50))
    depth[0, :5] = np.inf
    patterns = rounding_patterns(depth)
    assert len(patterns) == 8 and all(set(np.unique(p)) <= {-1.0, 1.0} for p in patterns)
    assert all(np.array_equal(patterns[b + 4], -patterns[b]) for b in range(4))   # each pair moved both ways
    code = sum((p > 0).astype(int) << b for b, p in enumerate(patterns[:4]))
    values = np.unique(depth)
    by_value = [code[depth == v] for v in values]
    assert all(np.all(c == c[0]) for c in by_value)                  # equal depths, equal moves
    for i in range(len(values)):
        for j in range(i + 1, min(i + 16, len(values))):
            assert by_value[i][0] != by_value[j][0], (i, j)
