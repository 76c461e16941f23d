"""Temporal reprojection of the froxel grid: static-camera convergence, running-mean history, rejection."""

import dataclasses

import numpy as np
import pytest

from vlref.camera import camera_from_settings
from vlref.froxel.grid import column_rays, grid_from_image
from vlref.froxel.kernels import froxel_apply, froxel_integrate
from vlref.reference import render_reference
from vlref.render import render
from vlref.scene import load_scene
from vlref.sequence import render_sequence
from vlref.techniques.froxel import grid_bounds

SIZE = ["render.width=64", "render.height=36", "lights.0.shadows.resolution=128"]
GRID = ['render.technique="froxel"', "techniques.froxel.grid_width=64", "techniques.froxel.grid_height=36",
        "techniques.froxel.slices=16"]
FRAMES = 16


@pytest.fixture(scope="module")
def pillars_runs():
    """The converged quadrature (`vlref reference`, rel_tol 1e-4, ~2 s), the temporal sequence and the single
    jittered frames."""
    ref = render_reference(load_scene("pillars", SIZE), rel_tol=1e-4).inscatter
    temporal = load_scene("pillars", SIZE + GRID + ["techniques.froxel.temporal=true",
                                                    f"techniques.froxel.history_alpha={1 / FRAMES}"])
    seq = [r for _, r in render_sequence(temporal, range(FRAMES), stages=True)]
    single = load_scene("pillars", SIZE + GRID)
    singles = [render(single.replace(render=dataclasses.replace(single.render, frame=f)), stages=True)
               for f in range(FRAMES)]
    return ref, seq, singles, single


def rel_error(image, ref):
    return np.abs(image - ref).mean() / ref.mean()


def test_static_camera_history_is_the_running_mean_of_the_jittered_grids(pillars_runs):
    """A static camera reprojects every froxel onto itself: with α = 1/16 the history after n + 1 frames
    is exactly the mean of the n + 1 jittered scattering grids, and its integrated image is the grid's
    own high-sample limit (16 Halton samples per froxel). Froxels hidden behind every pixel that could
    read them restart each frame (the disocclusion rule) and are never read."""
    _, seq, singles, single = pillars_runs
    for n in (0, 4, FRAMES - 1):
        mean = np.mean([s.buffers["froxel_scatter"] for s in singles[:n + 1]], axis=0)
        valid = seq[n].buffers["froxel_history_valid"] == 1.0
        frames = seq[n].buffers["froxel_history_frames"]
        if n == 0:
            assert not valid.any()
            continue
        assert 0.7 < valid.mean() < 1.0  # the rest lies behind the pillars and the ground
        np.testing.assert_allclose(seq[n].buffers["froxel_history"][valid], mean[valid], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(frames[valid], n + 1, rtol=1e-12)
        np.testing.assert_array_equal(frames[~valid], 1.0)
    # the integrated + applied mean grid is the last frame's image
    cam = camera_from_settings(single.camera, 64, 36)
    bounds = grid_bounds(single, cam)
    lit = grid_from_image(np.mean([s.buffers["froxel_scatter"] for s in singles], axis=0), 16)
    integrated = np.empty_like(lit)
    froxel_integrate(lit, column_rays(cam, 64, 36), np.ascontiguousarray(cam.forward), bounds, integrated)
    inscatter, trans = np.empty((36, 64, 3)), np.empty((36, 64))
    froxel_apply(integrated, bounds, seq[-1].buffers["depth"], inscatter, trans)
    np.testing.assert_allclose(seq[-1].buffers["inscatter"], inscatter, rtol=1e-9, atol=1e-12)


def test_static_camera_error_falls_with_frame_count(pillars_runs):
    """Error against `vlref reference` of the same (static) frame: each jittered frame alone stays at
    0.18-0.35 (mean relative), the accumulated sequence falls towards the grid's own bias (measured: 0.177,
    0.120, 0.087, 0.079, 0.070, 0.064 after 1, 3, 5, 8, 12, 16 frames; benchmarks/froxel_temporal.py);
    the grid without jitter sits at 0.26."""
    ref, seq, singles, _ = pillars_runs
    e = np.array([rel_error(r.buffers["inscatter"], ref) for r in seq])
    e_single = np.array([rel_error(r.buffers["inscatter"], ref) for r in singles])
    assert e[-1] < 0.4 * e[0]
    assert e[12:].mean() < e[4:8].mean() < e[:4].mean()
    assert e[8:].max() < 0.5 * e_single[8:].min()
    no_jitter = render(load_scene("pillars", SIZE + GRID + ['techniques.froxel.jitter="none"'])).buffers["inscatter"]
    assert e[-1] < rel_error(no_jitter, ref)


def test_moving_camera_rejects_history_outside_the_previous_frustum():
    """anim_sun dollies the camera sideways: froxels entering the view from the side have no history
    (valid 0, value = the current frame's), the rest reuse it."""
    over = ["render.width=32", "render.height=18", "techniques.froxel.grid_width=16", "techniques.froxel.grid_height=9",
            "techniques.froxel.slices=16", "lights.0.shadows.resolution=64"]
    scene = load_scene("anim_sun", over)
    runs = [r for _, r in render_sequence(scene, range(2), stages=True)]
    valid = grid_from_image(runs[1].buffers["froxel_history_valid"][..., None], 16)[..., 0]
    assert 0.5 < valid.mean() < 1.0
    # the camera moves toward +x: the newly seen froxels are at the right edge, near the camera
    assert valid[:, -1, :4].mean() < valid[:, :-1, :4].mean()
    cur = grid_from_image(runs[1].buffers["froxel_scatter"], 16)
    hist = grid_from_image(runs[1].buffers["froxel_history"], 16)
    np.testing.assert_array_equal(hist[valid == 0], cur[valid == 0])
    assert np.abs(hist[valid == 1] - cur[valid == 1]).max() > 0
    # without camera motion (the spot light moves, the camera does not) only hidden froxels are rejected:
    # none of the first slices, which lie in front of every surface
    spot = load_scene("anim_spot", over)
    runs = [r for _, r in render_sequence(spot, range(2), stages=True)]
    still = grid_from_image(runs[1].buffers["froxel_history_valid"][..., None], 16)[..., 0]
    assert still[:, :, :4].min() == 1.0 and still[:, -1, :4].mean() > valid[:, -1, :4].mean()


def neighbourhood_bounds(grid):
    """Per channel min and max of ``grid`` (gh, gw, D, 4) over each froxel's 3x3x3 neighbourhood (cut at
    the grid's edges: ``nearest`` replicates an edge value, which changes neither the min nor the max)."""
    from scipy.ndimage import maximum_filter, minimum_filter

    return (minimum_filter(grid, size=(3, 3, 3, 1), mode="nearest"),
            maximum_filter(grid, size=(3, 3, 3, 1), mode="nearest"))


def test_history_clamp_keeps_the_history_inside_the_current_neighbourhood():
    """``history_clamp``: the fetched history is clamped per channel to the current grid's 3x3x3 min/max
    before the blend. The spot of anim_spot sweeps, so the unclamped history leaves that range; frame 1
    of the clamped run is the unclamped one with the fetched history ``h`` (recovered from
    ``out = h + a (cur - h)``, ``a = 1/frames`` at frame 1) clamped, and over frames 1-3 every blended
    froxel lies inside its current neighbourhood."""
    over = ["render.width=32", "render.height=18", "techniques.froxel.grid_width=16", "techniques.froxel.grid_height=9",
            "techniques.froxel.slices=16", "lights.0.shadows.resolution=64"]
    grids = {}
    for clamp in (False, True):
        scene = load_scene("anim_spot", over + [f"techniques.froxel.history_clamp={str(clamp).lower()}"])
        grids[clamp] = [{k: grid_from_image(r.buffers[k] if r.buffers[k].ndim == 3 else r.buffers[k][..., None], 16)
                         for k in ("froxel_scatter", "froxel_history", "froxel_history_frames", "froxel_history_valid")}
                        for _, r in render_sequence(scene, range(4), stages=True)]
    plain, clamped = grids[False][1], grids[True][1]
    cur = plain["froxel_scatter"]
    np.testing.assert_array_equal(clamped["froxel_scatter"], cur)
    lo, hi = neighbourhood_bounds(cur)
    valid = plain["froxel_history_valid"][..., 0] == 1.0
    assert valid.mean() > 0.9
    a = 1.0 / plain["froxel_history_frames"][valid]  # n = 1 fetched frame at frame 1: a = 1/2
    np.testing.assert_allclose(a, 0.5, rtol=1e-12)
    h = cur.copy()
    h[valid] = (plain["froxel_history"][valid] - a * cur[valid]) / (1.0 - a)
    outside = valid[..., None] & ((h < lo) | (h > hi))
    assert outside.mean() > 0.02  # the clamp acts on this scene
    hc = np.clip(h, lo, hi)
    np.testing.assert_allclose(clamped["froxel_history"][valid], hc[valid] + a * (cur[valid] - hc[valid]), rtol=1e-9,
                               atol=1e-15)
    np.testing.assert_array_equal(clamped["froxel_history"][~valid], cur[~valid])
    for g in grids[True][1:]:
        lo, hi = neighbourhood_bounds(g["froxel_scatter"])
        tol = 1e-12 * np.abs(hi)
        assert (g["froxel_history"] >= lo - tol).all() and (g["froxel_history"] <= hi + tol).all()
    assert any((g["froxel_history"] > neighbourhood_bounds(g["froxel_scatter"])[1] * (1 + 1e-6)).any()
               for g in grids[False][1:])


def test_history_clamp_reduces_ghosting_under_motion():
    """anim_sun (camera dolly + sun turn, frames 0-7, 64x36, grid 32x18x32, default α): against the physical
    march of frame 7 the unclamped history lags (error 0.49, the frame alone 0.093); the clamp removes most
    of that ghosting (0.12; BENCHMARKS.md "Froxel temporal" has every frame and scene)."""
    size = ["render.width=64", "render.height=36"]
    grid = ["techniques.froxel.grid_width=32", "techniques.froxel.grid_height=18", "techniques.froxel.slices=32"]
    march = load_scene("anim_sun", size + ['render.technique="physical"', "render.steps=256", 'render.sampling="none"',
                                           "render.frame=7"])
    ref = render(march).buffers["inscatter"]
    single = render(load_scene("anim_sun", size + grid + ["techniques.froxel.temporal=false", "render.frame=7"]))
    e_single = rel_error(single.buffers["inscatter"], ref)
    e = {}
    for clamp in ("false", "true"):
        scene = load_scene("anim_sun", size + grid + [f"techniques.froxel.history_clamp={clamp}"])
        *_, (_, last) = render_sequence(scene, range(8))
        e[clamp] = rel_error(last.buffers["inscatter"], ref)
    assert e["false"] > 3 * e_single
    assert e["true"] - e_single < 0.2 * (e["false"] - e_single)
