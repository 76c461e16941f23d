"""Switches of the WebGPU killzone port: the faithful port, planted shader bugs and benign variants.

Each variant sets WGSL override constants (declared in ``shaders/*.wgsl``), host-side switches
(:data:`HOST_SWITCHES`, read by :mod:`kz_port`) and/or the light-buffer format. ``raster`` variants plant
their bug in passes 1-3 (gbuffer, shadow, lighting: the buffers the port exports), the others in passes
4-9 (downsample .. composite). ``scene`` names the scene whose branches the bug lives in (kz_check.SCENES:
``pillars_point`` or a conformance scene of data/conformance). ``expect`` is what the verdict must say
(``kz_check``): a post-pass bug fails some pass against ``vlref march`` on the port's own buffers; a
raster bug passes those (vlref marches on the buggy buffers) and fails against the scene.
"""

from __future__ import annotations

from dataclasses import dataclass, field

HOST_SWITCHES = {
    "HOST_SHADOW_CLEAR_NEAR": "shadow maps cleared to 1 (the near plane under reversed-Z) instead of 0 (far)",
    "HOST_LIGHT_COLOUR_FP16": "the march's light buffer packs colour x intensity as fp16, saturating at 65504",
    "HOST_CULL_BEHIND_CAMERA": "light volumes culled when the light's position is behind the camera plane",
}
"""Host-side (Python) switches of :mod:`kz_port`: bugs in what the port uploads or how it schedules draws."""


@dataclass(frozen=True)
class Variant:
    description: str
    expect: str                                  # "pass" or "fail"
    overrides: dict = field(default_factory=dict)
    light_format: str = "rgba16float"            # march / upsample / blur targets
    final_format: str = "rgba16float"
    preset: str = "gpu-half"                     # the vlref compare preset this port configuration calls for
    scene: str = "pillars_point"                 # kz_check.SCENES: where the switch's branch is reached
    raster: bool = False                         # True: the switches apply to passes 1-3 only, else to 4-9 only


VARIANTS = {
    "faithful": Variant("the port as the docs describe it (fp16 light buffers)", "pass"),
    # benign: must pass
    "sum_order": Variant("upsample and blur sums in reversed tap order", "pass", {"BENIGN_REVERSED_SUM": 1}),
    "fp32": Variant("fp32 light buffers and final target instead of fp16", "pass", light_format="rgba32float",
                    final_format="rgba32float", preset="gpu-float32"),
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
    # planted bugs in post passes, in branches pillars_point never reached (conformance scenes)
    "shadow_planar": Variant("march: shadow-map depth taken as the radial distance (no texel-ray factor)", "fail",
                             {"BUG_SHADOW_PLANAR": 1}),
    "blur_gauss_no_two": Variant("blur: Gaussian exp(-k^2/sigma^2), the 2 of 2 sigma^2 missing", "fail",
                                 {"BUG_GAUSS_NO_TWO": 1}),
    "blur_eps_x10": Variant("upsample and blur: bilateral guard 10 eps (depth weights 10x too loose)", "fail",
                            {"BUG_BLUR_EPS_X10": 1}),
    "block_end_floor": Variant("downsample: block end rounded down (odd sizes lose a row and a column)", "fail",
                               {"BUG_BLOCK_END_FLOOR": 1}, scene="laws"),
    "unity_cone_unsquared": Variant("march: unity cone law saturate(a cos + b) without its square", "fail",
                                    {"BUG_UNITY_CONE_UNSQUARED": 1}, scene="laws"),
    "linear_cone_in_cos": Variant("march: linear cone law interpolated in cos instead of angle", "fail",
                                  {"BUG_LINEAR_CONE_IN_COS": 1}, scene="laws"),
    "unity_att_no_fade": Variant("march: unity attenuation without its saturate(5 (1 - sqrt u)) fade", "fail",
                                 {"BUG_UNITY_ATT_NO_FADE": 1}, scene="laws"),
    "strength_swapped": Variant("march: shadow strength as lerp(lit, 1, s) instead of lerp(1, lit, s)", "fail",
                                {"BUG_STRENGTH_SWAPPED": 1}, scene="laws"),
    "no_max_distance": Variant("march: view ray not cut at render.max_distance", "fail",
                               {"BUG_NO_MAX_DISTANCE": 1}, scene="inside_volume"),
    "ball_t0_unclamped": Variant("march: ray-ball entry not clamped at the eye (camera inside a volume)", "fail",
                                 {"BUG_BALL_T0_UNCLAMPED": 1}, scene="inside_volume"),
    "phase_schlick": Variant("march: Schlick's phase approximation instead of Henyey-Greenstein", "fail",
                             {"BUG_PHASE_SCHLICK": 1}, scene="bright_behind"),
    "cull_behind_camera": Variant("host: light volume culled when the light is behind the camera", "fail",
                                  {"HOST_CULL_BEHIND_CAMERA": 1}, scene="bright_behind"),
    "light_colour_fp16": Variant("host: march light buffer packs colour x intensity as fp16 (saturates at 65504)",
                                 "fail", {"HOST_LIGHT_COLOUR_FP16": 1}, scene="bright_behind"),
    # planted bugs in the raster passes (judged against the scene)
    "bias_sign": Variant("shadow: caster-side bias with the wrong sign (r - bias)", "fail", {"BUG_BIAS_SIGN": 1},
                         raster=True),
    "shadow_clear_near": Variant("shadow: maps cleared to 1 (near under reversed-Z) instead of 0", "fail",
                                 {"HOST_SHADOW_CLEAR_NEAR": 1}, raster=True),
    "slope_cot": Variant("shadow: slope bias scaled by cot instead of tan", "fail", {"BUG_SLOPE_COT": 1},
                         scene="laws", raster=True),
    "shadow_grown": Variant("lighting: a spot/point lookup also shadowed by a 4-neighbour texel whose caster is 10 % "
                            "nearer than its own (shadows grown by one texel)", "fail", {"BUG_SHADOW_GROWN": 1},
                            raster=True),
    "shadow_shrunk": Variant("lighting: a spot/point lookup also lit by a 4-neighbour texel whose surface is 10 % "
                             "farther than its own (shadows shrunk by one texel)", "fail", {"BUG_SHADOW_SHRUNK": 1},
                             raster=True),
    "no_inv_pi": Variant("lighting: Lambert without its 1/pi", "fail", {"BUG_NO_INV_PI": 1}, raster=True),
    "eye_depth_as_range": Variant("lighting: surface point at eye depth along the ray (as if ray length)", "fail",
                                  {"BUG_EYE_DEPTH_AS_RANGE": 1}, raster=True),
}
