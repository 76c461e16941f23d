"""Switches of the WebGPU froxel port: the faithful port, planted bugs typical of froxel code, benign variants.

Each variant sets WGSL override constants (declared in ``shaders/*.wgsl``) and/or host-side switches;
``expect`` is what vlref must say about it: ``pass`` (every pass of every frame within its preset, at
<= 0.5x of every bound) or ``fail`` (some pass of some frame beyond its preset: :mod:`fx_check`).
A raster variant (:attr:`Variant.is_raster`) plants its bug in the raster passes (the killzone port's,
``ports/wgpu/shaders``: ``raster`` override constants, or a host switch) instead: vlref's march on the port's
own buffers inherits the bug, so it passes there, and only the verdict against the scene
(:func:`fx_check.sequence_verdict`) can fail it: :attr:`Variant.fails` names the comparisons that must fail (the
first by at least 2x a bound) in every frame from :attr:`Variant.from_frame` on, and the frames before must pass.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional


@dataclass(frozen=True)
class Variant:
    description: str
    expect: str                                  # "pass" or "fail"
    overrides: dict = field(default_factory=dict)
    depth_distribution: Optional[float] = None   # host: slice law λ (None: the scene's)
    frozen_jitter: bool = False                  # host: frame 0's Halton point every frame
    partial_groups: bool = False                 # host: floor(size / 8) workgroups per axis
    raster: dict = field(default_factory=dict)   # override constants of the raster passes (ports/wgpu/shaders)
    stale_raster_camera: bool = False            # host: G-buffer and lighting keep frame 0's camera (raster)
    scene: Optional[str] = None                  # the one scene whose motion shows a raster bug (None: every one)
    fails: tuple = ()                            # raster: the comparisons against the scene that must fail (the
    from_frame: int = 0                          # first by >= 2x a bound) in every frame from this one on, none before

    @property
    def is_raster(self) -> bool:
        """True when the bug lives in the raster passes (the port's exported inputs), not the froxel passes."""
        return bool(self.raster) or self.stale_raster_camera


VARIANTS = {
    "faithful": Variant("the port as the docs describe it (rgba16float grids, hardware trilinear)", "pass"),
    # benign: must pass at <= 0.5x of every bound
    "weights8": Variant("history fetch and apply by a trilinear with 8-bit sub-texel weights (a GPU texture "
                        "unit's precision, written out)", "pass", {"BENIGN_WEIGHTS8": 1}),
    "optical_depth": Variant("integration: T = exp(-Σ σt Δ) instead of the running product of exp(-σt Δ)", "pass",
                             {"BENIGN_OPTICAL_DEPTH": 1}),
    # planted bugs: must fail
    "lambda_exponential": Variant("slice law read with λ = 1 (purely exponential) instead of the scene's", "fail",
                                  depth_distribution=1.0),
    "back_to_front": Variant("integration walks the slices from the far end", "fail", {"BUG_BACK_TO_FRONT": 1}),
    "half_texel": Variant("apply samples the volume at w = s/D (half-texel offset in the 3-D lookup)", "fail",
                          {"BUG_HALF_TEXEL": 1}),
    "current_vp": Variant("reprojection with the current instead of the previous view-projection", "fail",
                          {"BUG_CURRENT_VP": 1}),
    "no_clamp": Variant("history clamp missing (the scene asks for it)", "fail", {"BUG_NO_CLAMP": 1}),
    "frozen_jitter": Variant("the jitter sequence does not advance per frame", "fail", frozen_jitter=True),
    "partial_group": Variant("dispatch of floor(size/8) groups: the last partial group is not covered", "fail",
                             partial_groups=True),
    "no_transmittance_carry": Variant("transmittance not carried across slices (restarts at 1 per slice)", "fail",
                                      {"BUG_NO_TRANSMITTANCE_CARRY": 1}),
    # a planted raster bug: own buffers pass (vlref marches on the buggy maps), the scene fails
    "stale_raster_camera": Variant("the G-buffer and lighting passes keep frame 0's camera (their uniform is not "
                                   "updated per frame); shadow maps, froxel passes and manifest have each frame's",
                                   "fail", stale_raster_camera=True, scene="anim_sun", fails=("end_to_end", "depth"),
                                   from_frame=1),
    "sun_travel_dir": Variant("lighting: the sun's n.l taken with its direction of travel instead of toward it", "fail",
                              raster={"BUG_SUN_TRAVEL_DIR": 1}, scene="anim_sun", fails=("scene_colour", "end_to_end")),
    "sun_acne": Variant("lighting: the sun's cascades looked up at the surface point, without the normal offset "
                        "(sunlit ground shadows itself: acne)", "fail", raster={"BUG_NO_NORMAL_OFFSET": 1},
                        scene="anim_sun", fails=("scene_colour", "end_to_end")),
}
