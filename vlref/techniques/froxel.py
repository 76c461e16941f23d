"""The ``froxel`` technique: a camera-aligned froxel grid lit, integrated and applied (Wronski 2014, AC4
"Volumetric fog"; Hillaire 2015, Frostbite), with optional temporal reprojection.

Passes (:mod:`vlref.froxel`; stage buffers in brackets, grids as the stacked-slice images of
:func:`vlref.froxel.grid.grid_image`, ``(D·gh, gw, C)``):

0. slices: ``techniques.froxel.slices`` boundaries from the camera's near plane to the grid's far depth
   ``min(render.max_distance, camera.far)`` with ``depth_distribution`` [``froxel_slices`` (1, D+1)];
   jitter ``ξ`` of frame ``render.frame`` (``jitter``, ``jitter_period``);
1. light: ``(S, σt)`` per froxel [``froxel_scatter``];
2. temporal (``temporal = true``): blend with the previous frame's reprojected history
   (:mod:`vlref.froxel.temporal`) [``froxel_history`` (the blended grid, next frame's history),
   ``froxel_history_frames``, ``froxel_history_valid``]; without a previous frame every froxel starts
   its history;
3. integrate front to back (Hillaire's energy-conserving step) [``froxel_integrated`` = ``(L, T)``];
4. apply: trilinear lookup by pixel depth, ``final = scene · T + L``.

Everything runs in float64 (``render.precision`` does not apply). With noise, the light leg uses
``ceil(sqrt(render.steps))`` midpoint sub-steps (``render.steps`` default 32). The technique returns its
temporal state under the key ``history`` (:class:`vlref.froxel.temporal.History`), which
:func:`vlref.render.render` hands back as ``RenderResult.history``.
"""

from __future__ import annotations

import math

import numpy as np

from ..froxel.grid import column_rays, grid_image, jitter_offsets, slice_depths
from ..froxel.kernels import froxel_apply, froxel_integrate, froxel_scatter
from ..froxel.temporal import History, reproject_blend, tile_depth
from ..medium import pack_medium
from ..post.composite import composite_physical
from ..scene.technique_params import resolved

__all__ = ["render", "grid_bounds", "notes"]


def grid_bounds(scene, camera) -> np.ndarray:
    """The slice boundaries of ``scene``'s froxel grid seen by ``camera`` (pass 0)."""
    p = scene.techniques.froxel
    far = min(scene.render.max_distance, camera.far)
    return slice_depths(camera.near, max(far, camera.near * (1.0 + 1e-6)), p.slices, p.depth_distribution)


def render(scene, frame) -> dict:
    """The froxel passes of ``scene`` (module docstring); ``frame.history`` is the previous frame's state."""
    p = scene.techniques.froxel
    cam = frame.camera
    gw, gh = p.grid_width, p.grid_height
    bounds = grid_bounds(scene, cam)
    xi = jitter_offsets(scene.render.frame, p.jitter, p.jitter_period)
    forward = np.ascontiguousarray(cam.forward)
    origin = np.asarray(cam.position, dtype=np.float64)
    medium = pack_medium(scene, np.float64)
    lights = frame.lights.astype(np.float64)
    sm = frame.shadow_maps()
    scatter = np.empty((gh, gw, p.slices, 4))
    froxel_scatter(origin, column_rays(cam, gw, gh, xi[0], xi[1]), forward, bounds, xi[2], medium, lights, sm.table,
                   frame.geometry.arrays, bool(p.light_extinction), int(math.ceil(math.sqrt(resolved(scene, "steps")))),
                   scatter)
    centre = column_rays(cam, gw, gh)
    out = {"froxel_slices": bounds[None, :], "froxel_scatter": grid_image(scatter)}
    lit = scatter
    if p.temporal:
        prev = frame.history
        lit = np.empty_like(scatter)
        frames = np.ones((gh, gw, p.slices))
        valid = np.zeros((gh, gw, p.slices))
        if prev is None:
            lit[...] = scatter
        else:
            reproject_blend(scatter, centre, origin, forward, bounds, prev.camera.view_projection(),
                            prev.grid, prev.frames, prev.bounds, prev.tile_depth, p.history_alpha, p.history_clamp, lit,
                            frames, valid)
        out.update({"froxel_history": grid_image(lit), "froxel_history_frames": grid_image(frames[..., None])[..., 0],
                    "froxel_history_valid": grid_image(valid[..., None])[..., 0],
                    "history": History(lit, frames, cam, bounds, tile_depth(frame.gbuffer.depth, gw, gh))})
    integrated = np.empty_like(lit)
    froxel_integrate(lit, centre, forward, bounds, integrated)
    inscatter = np.empty((cam.height, cam.width, 3))
    trans = np.empty((cam.height, cam.width))
    froxel_apply(integrated, bounds, frame.gbuffer.depth, inscatter, trans)
    out.update({"froxel_integrated": grid_image(integrated), "inscatter": inscatter, "transmittance": trans,
                "final": composite_physical(frame.scene_colour, trans, inscatter)})
    return out


def notes(scene, out) -> list[str]:
    """What ``vlref render`` tells the user: a single frame's vertical stripes in the haze are faithful."""
    if scene.techniques.froxel.temporal:
        return []
    return ["froxel: vertical stripes in the haze are the grid's: one jittered light sample per froxel of a "
            "single frame, faithful to Wronski/Hillaire; temporal = true over --frames averages them "
            "(docs/TECHNIQUES.md, Faithful artifacts)"]
