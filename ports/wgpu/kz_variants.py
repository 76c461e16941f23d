"""Switches of the WebGPU killzone port: the faithful port, planted shader bugs and benign variants.

Each variant sets WGSL override constants (declared in ``shaders/*.wgsl``) and/or the light-buffer
format; ``expect`` is what ``vlref compare --preset <preset>`` must say about its ``final`` against
``vlref march`` on the port's buffers (fp16 targets: ``gpu-half``; float32 targets: ``float32``).
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Variant:
    description: str
    expect: str                                  # "pass" or "fail"
    overrides: dict = field(default_factory=dict)
    light_format: str = "rgba16float"            # march / upsample / blur targets
    final_format: str = "rgba16float"
    preset: str = "gpu-half"                     # the vlref compare preset this port configuration calls for


VARIANTS = {
    "faithful": Variant("the port as the docs describe it (fp16 light buffers)", "pass"),
    # benign: must pass
    "sum_order": Variant("upsample and blur sums in reversed tap order", "pass", {"BENIGN_REVERSED_SUM": 1}),
    "fp32": Variant("fp32 light buffers and final target instead of fp16", "pass", light_format="rgba32float",
                    final_format="rgba32float", preset="float32"),
    # planted bugs: must fail
    "steps_minus_one": Variant("march loop runs N - 1 samples, step still (b - a)/N", "fail",
                               {"BUG_STEPS_MINUS_ONE": 1}),
    "advance_twice": Variant("t advanced by the step twice per iteration", "fail", {"BUG_ADVANCE_TWICE": 1}),
    "bayer_transposed": Variant("Bayer matrix read as B[x mod 4][y mod 4]", "fail", {"BUG_BAYER_TRANSPOSED": 1}),
    "no_range_window": Variant("windowed attenuation without its range window", "fail", {"BUG_NO_RANGE_WINDOW": 1}),
    "shadow_half_texel": Variant("shadow texel chosen at u*res - 0.5 (half-texel offset)", "fail",
                                 {"BUG_SHADOW_HALF_TEXEL": 1}),
    "cube_v_up": Variant("cube-map face v not flipped (GL t axis)", "fail", {"BUG_CUBE_V_UP": 1}),
    "average_depth": Variant("depth downsample averages instead of taking the min", "fail", {"BUG_AVERAGE_DEPTH": 1}),
    "upsample_no_depth": Variant("upsample with bilinear weights only (no depth weights)", "fail",
                                 {"BUG_UPSAMPLE_NO_DEPTH": 1}),
    "sigma_s_for_t": Variant("extinction sigma_t replaced by sigma_s (march and composite)", "fail",
                             {"BUG_SIGMA_S_FOR_T": 1}),
    "t_on_light": Variant("composite attenuates the in-scattered light too: (scene + L) T", "fail",
                          {"BUG_T_ON_LIGHT": 1}),
}
