"""Per-technique parameters: the ``[techniques.NAME]`` tables of a scene file.

Each class holds every user parameter of its source with that source's default, so a scene
that names a technique and nothing else renders as the source does. Switches named after a
quirk (``docs/TECHNIQUES.md`` lists them all) default to the source's behaviour; setting one to
its other value neutralises that quirk. ``docs/TECHNIQUES.md`` gives each parameter's origin
(file / section of ``docs/SOURCES.md`` or of the thesis). Values a source does
not state are marked ``[U]`` and are inputs with a documented default.

:func:`resolved` reads the settings a technique may default itself (``render.steps``, ``sampling``,
``resolution``): the scene's value, else the technique's own field of that name, else
:data:`RESOLVED_DEFAULTS`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from .fields import F

__all__ = ["PhysicalParams", "KillzoneParams", "SlightlyMadParams", "UrpParams", "RadialParams", "FroxelParams",
           "TechniqueParams", "RESOLVED_DEFAULTS", "resolved"]


@dataclass(frozen=True)
class PhysicalParams:
    """The energy-conserving march of docs/PHYSICS.md "The integral" (Hillaire 2015 step integration)."""

    steps: int = F(32, "default step count when render.steps is not given", min=1, max=4096)
    sampling: str = F("bayer8", "default offset pattern", choices=("none", "bayer2", "bayer4", "bayer8", "hash"))
    light_extinction: bool = F(True, "extinction on the light leg (T_l)")


@dataclass(frozen=True)
class KillzoneParams:
    """The thesis (TH in docs/SOURCES.md; sections 2.2.3, 2.2.4, 2.6, 4.2) after Vos, GPU Pro 5 (SOURCES §4).

    The medium (``[medium]``: scattering, absorption, anisotropy, fog, noise) and the lights'
    own attenuation / cone / cookie laws are the scene's.
    """

    steps: int = F(32, "default step count when render.steps is not given [U: the thesis tests 30 and 100]",
                   min=1, max=4096)
    sampling: str = F("bayer4", "Bayer offset texture (thesis 4.2.5: 2x2, 4x4 or 8x8; Vos: 4x4)",
                      choices=("none", "bayer2", "bayer4", "bayer8"))
    resolution: str = F("half", "default calculation resolution (Vos: half)", choices=("full", "half", "quarter"))
    light_resolutions: tuple[str, ...] = F((), "per-light calculation resolution, in light order (full/half/quarter);"
                                           " lights not listed use render.resolution")
    shadow_filter: str = F("hard", "shadow lookup: Vos samples ONE point (hard); pcf/exact for comparison",
                           choices=("hard", "pcf", "exact"))
    blur: bool = F(True, "the separable bilateral Gaussian blur (thesis 4.2.6)")
    blur_radius: int = F(3, "blur taps each side of the centre (the thesis's 7 taps)", min=0, max=16)
    blur_sigma: float = F(1.5, "Gaussian sigma of the blur in texels [U: not stated in the thesis]", gt=0.0)
    blur_depth_weight: str = F("inverse", "blur depth weight: inverse = G/(|dz| + eps), 'in the same way as the "
                               "up-sampling' (thesis 4.2.6); gaussian = G exp(-(factor |dz|)^2)",
                               choices=("inverse", "gaussian"))
    blur_depth_factor: float = F(1.0, "factor of the gaussian depth weight (1/m) [U]", min=0.0)
    upsample_epsilon: float = F(1e-3, "guard added to |dz| in the 9/16,3/16,1/16 / |dz| upsample and blur "
                                "weights (metres) [U]", gt=0.0)
    transmittance: bool = F(True, "Beer-Lambert view transmittance (thesis 2.2.4, 4.2.2); false = Vos (none)")


@dataclass(frozen=True)
class SlightlyMadParams:
    """SlightlyMad/VolumetricLights@d20b6f9 (SOURCES §1); defaults from VolumetricLight.cs.

    The VL component parameters apply to every light of the scene (VL sets them per light). The medium is
    the scene's by default (``medium = "scene"``); ``medium = "source"`` switches to VL's own parameters.
    """

    steps: int = F(8, "SampleCount", min=1, max=64)
    resolution: str = F("half", "VolumetricLightRenderer.Resolution", choices=("full", "half", "quarter"))
    medium: str = F("scene", "where scattering, extinction, MieG, height fog and noise come from: scene = the "
                    "scene's [medium] (sigma_t = sigma_s + sigma_a), so techniques compare on one scene; source = "
                    "the VL parameters below (VL's defaults, its own preset)", choices=("source", "scene"))
    scattering: float = F(0.5, "ScatteringCoef (1/m)", min=0.0)
    extinction: float = F(0.01, "ExtinctionCoef (1/m)", min=0.0)
    skybox_extinction: float = F(0.9, "SkyboxExtinctionCoef (directional alpha on sky pixels)", min=0.0, max=1.0)
    mie_g: float = F(0.1, "MieG (Henyey-Greenstein g)", gt=-1.0, lt=1.0)
    height_fog: bool = F(False, "HeightFog")
    height_scale: float = F(0.10, "HeightScale", min=0.0)
    ground_level: float = F(0.0, "GroundLevel (enters as +GroundLevel: reference height y = -GroundLevel)")
    noise: bool = F(False, "Noise")
    noise_scale: float = F(0.015, "NoiseScale (texture tiles per metre)", gt=0.0)
    noise_intensity: float = F(1.0, "NoiseIntensity", min=0.0)
    noise_intensity_offset: float = F(0.3, "NoiseIntensityOffset")
    noise_velocity: tuple[float, float] = F((3.0, 3.0), "NoiseVelocity (x, z) in m/s")
    noise_path: Optional[str] = F(None, "VL's NoiseVolume.bytes (128^3 L8 DDS); default: vlref's own noise",
                                  file=True)
    max_ray_length: float = F(400.0, "MaxRayLength (directional lights)", gt=0.0)
    dither: str = F("8x8", "dither texture (DITHER_4_4 off = 8x8); none neutralises quirk 7",
                    choices=("8x8", "4x4", "none"))
    dither_bytes: bool = F(True, "dither values floor(255k/65)/255 (Alpha8); false: exact k/N^2 of the same matrix")
    uv_origin: str = F("bottom", "pixel-row origin of dither index and chessboard parity (Unity: bottom)",
                       choices=("bottom", "top"))
    depth_convention: str = F("d3d", "raw depth the chessboard compares (Unity 5.3: d3d; 5.5+ D3D: reversed)",
                              choices=("d3d", "reversed"))
    depth_downsample: str = F("chessboard", "DOWNSAMPLE_DEPTH_MODE 2 (chessboard), 0 (min), 1 (max)",
                              choices=("chessboard", "min", "max"))
    upsample_threshold: float = F(1.5, "UPSAMPLE_DEPTH_THRESHOLD (metres, sum of |dz|)", gt=0.0)
    blur_depth_factor: float = F(0.5, "BLUR_DEPTH_FACTOR", min=0.0)
    gauss_blur_deviation: float = F(1.5, "GAUSS_BLUR_DEVIATION (sigma = radius / deviation)", gt=0.0)
    blur: bool = F(True, "the bilateral blur passes (VL always blurs; false skips them for comparisons)")
    blur_radius_full: int = F(7, "blur kernel radius (taps each side) at full resolution", min=0, max=16)
    blur_radius_half: int = F(5, "blur kernel radius at half resolution", min=0, max=16)
    blur_radius_quarter: int = F(6, "blur kernel radius at quarter resolution", min=0, max=16)
    attenuation: str = F("unity_lut", "point/spot distance law: Unity's _LightTextureB0 (unity_lut) or the "
                         "light's own law (scene)", choices=("unity_lut", "scene"))
    attenuation_lut_path: Optional[str] = F(None, "1-D LUT (.npy) indexed by d^2/R^2 replacing the default "
                                            "1/(1+25u)*saturate(5(1-sqrt u)) [U: Unity's texture]", file=True)
    spot_cone: str = F("cookie", "spot falloff: only the cookie (VL) or the light's own cone law (scene)",
                       choices=("cookie", "scene"))
    spot_cookie_path: Optional[str] = F(None, "DefaultSpotCookie image (VL spot.png, alpha = grey); default: "
                                        "the measured radial profile table", file=True)
    light_mesh: str = F("analytic", "light volumes: analytic sphere/cone, or unity = the 16-sided cone mesh with "
                        "+1 degree for the pass-3 start point (exact parity)", choices=("analytic", "unity"))
    point_srgb_quirk: bool = F(True, "quirk 14: point-light colour x intensity goes sRGB -> linear (SetColor)")
    right_endpoint: bool = F(True, "quirk 1: tau is updated before use; false: after (left endpoint)")
    initial_half_tau: bool = F(True, "quirk 2: point/spot start with tau = 0.5 sigma_t |c - x0|; false: the full "
                               "camera-to-x0 optical depth")
    point_spot_alpha_zero: bool = F(True, "quirk 3: point/spot lights leave the scene unattenuated; false: "
                                    "their view transmittance multiplies the scene")
    skybox_extinction_quirk: bool = F(True, "directional alpha on sky pixels is lerped toward 1 by 1 - "
                                      "SkyboxExtinctionCoef; false: plain exp(-tau)")
    cube_shadow_factor: float = F(0.97, "point shadow: the reference distance is this x |x - light| / R", gt=0.0)
    fp16: bool = F(True, "quirk 18: round to fp16 after each light's additive blend and each post pass")


@dataclass(frozen=True)
class UrpParams:
    """Valerio Marty's URP tutorial (SOURCES §2: the Medium article's listing P1).

    ``scattering`` (the tutorial's ``_Scattering``, HG g with the reversed sign) is a deprecated alias
    read as ``anisotropy = -scattering``.
    """

    RENAMED_KEYS = {"scattering": ("anisotropy", lambda value: -value)}

    steps: int = F(25, "steps (the loop runs steps - 1 times and divides by steps)", min=2, max=4096)
    resolution: str = F("full", "downsampling: full (off), half, third, quarter",
                        choices=("full", "half", "third", "quarter"))
    intensity: float = F(1.0, "composite gain", min=0.0)
    anisotropy: float = F(0.0, "Henyey-Greenstein g in vlref's sign (> 0: forward scattering, bright toward the "
                          "sun); the tutorial's _Scattering is -anisotropy", gt=-1.0, lt=1.0)
    max_distance: float = F(75.0, "maxDistance (metres)", gt=0.0)
    jitter: float = F(250.0, "jitter, percent of a step", min=0.0)
    jitter_path: Optional[str] = F(None, "inject the hash buffer rand(uv) (.npy or .exr, march resolution, row 0 "
                                   "at the top, values in [0, 1)) instead of computing it", file=True)
    gauss_samples: int = F(4, "gaussBlur.samples (taps each side, at most 7) [U: unset in the article]",
                           min=0, max=7)
    gauss_amount: float = F(1.0, "gaussBlur.amount (uv offset x 1/1000 per tap) [U: unset in the article]",
                            min=0.0)
    depth_convention: str = F("reversed", "raw depth of _CameraDepthTexture (URP on D3D11/Vulkan/Metal: reversed)",
                              choices=("reversed", "d3d"))
    uv_origin: str = F("bottom", "uv origin of the hash input and of the upsample's (0,+1) tie (Unity: bottom)",
                       choices=("bottom", "top"))
    shadow_filter: str = F("pcf", "main-light shadow lookup (URP atlas: 2x2 comparison PCF) before the binary "
                           "test", choices=("hard", "pcf", "exact"))
    r16: bool = F(True, "R16 UNORM storage of the fog and low-res depth buffers (clamp to [0,1], 1/65535 steps)")


@dataclass(frozen=True)
class RadialParams:
    """GPU Gems 3 ch. 13 (Mitchell, Listing 13-1) and disenone's Unity port (SOURCES §3).

    Unset (``None``) values take the variant's default: ``gpugems`` uses F. Sanglard's GLSL port
    values (NOT from the book, which gives none); ``disenone`` uses its C# ``Params`` defaults.
    """

    variant: str = F("gpugems", "gpugems (Listing 13-1) or disenone (Unity port: radiate disc, 32 taps)",
                     choices=("gpugems", "disenone"))
    num_samples: Optional[int] = F(None, "NUM_SAMPLES (gpugems 100; disenone 32, fixed in its shader)",
                                   min=1, max=1024)
    density: Optional[float] = F(None, "Density (gpugems 0.84; disenone 1.0)", min=0.0)
    weight: Optional[float] = F(None, "Weight (gpugems 5.65; disenone 1/32, times the shader's 0.03125)", min=0.0)
    decay: Optional[float] = F(None, "Decay (gpugems 1.0; disenone 1.0)", min=0.0)
    exposure: Optional[float] = F(None, "Exposure (gpugems 0.0034; disenone 0.8)", min=0.0)
    light: int = F(-1, "index of the light that radiates (-1: the first directional light, else the first light)",
                   min=-1)
    light_radius: Optional[float] = F(None, "light disc radius in pixels of the occlusion target (disenone: 100, "
                                      "its C#; gpugems: 0.05 x target height [U])", gt=0.0)
    occlusion_height: int = F(0, "occlusion target height in pixels (0: the frame height; disenone: 512)", min=0)
    fade: Optional[bool] = F(None, "exposure dimming by the angle between view and light, disenone's law "
                             "(default: on for disenone; off for gpugems, whose chapter names fading without a law)")


@dataclass(frozen=True)
class FroxelParams:
    """Froxel volumetrics: Wronski 2014 (AC4 "Volumetric fog"), Hillaire 2015 (Frostbite); docs/TECHNIQUES.md."""

    grid_width: int = F(160, "froxel columns across the screen (Wronski's AC4 grid: 160x90x64)", min=1, max=1024)
    grid_height: int = F(90, "froxel rows", min=1, max=1024)
    slices: int = F(64, "depth slices (AC4, Frostbite: 64)", min=1, max=1024)
    depth_distribution: float = F(0.9, "slice law: 1 = exponential (Wronski, Hillaire), 0 = uniform; blend between "
                                  "[U: 0.9 keeps the first metre from taking a third of the slices]", min=0.0, max=1.0)
    jitter: str = F("halton", "sample offset inside each froxel per frame: halton (2, 3, 5) or none (the centre)",
                    choices=("halton", "none"))
    jitter_period: int = F(16, "the Halton index cycles with this period of frames [U]", min=1, max=4096)
    light_extinction: bool = F(True, "extinction on the light leg (T_l), as the physical march")
    temporal: bool = F(False, "blend with the previous frame's reprojected grid (sequences: vlref render --frames)")
    history_alpha: float = F(0.1, "weight of the current frame in the exponential history blend (Unreal's "
                             "HistoryWeight 0.9; the sources give none [U])", gt=0.0, max=1.0)
    history_clamp: bool = F(False, "clamp the history to the current 3x3x3 neighbourhood [U: not in the sources]")


@dataclass(frozen=True)
class TechniqueParams:
    physical: PhysicalParams = field(default_factory=PhysicalParams, metadata={"doc": "physical march"})
    killzone: KillzoneParams = field(default_factory=KillzoneParams, metadata={"doc": "thesis / Killzone"})
    slightlymad: SlightlyMadParams = field(default_factory=SlightlyMadParams, metadata={"doc": "VolumetricLights"})
    urp: UrpParams = field(default_factory=UrpParams, metadata={"doc": "URP tutorial"})
    radial: RadialParams = field(default_factory=RadialParams, metadata={"doc": "GPU Gems 3 radial blur"})
    froxel: FroxelParams = field(default_factory=FroxelParams, metadata={"doc": "froxel grid (Wronski, Hillaire)"})

    def of(self, name: str):
        """The parameter block of technique ``name``."""
        return getattr(self, name)


RESOLVED_DEFAULTS = {"steps": 32, "sampling": "none", "resolution": "full"}
"""``render.steps``/``sampling``/``resolution`` of a technique whose parameter class sets none."""


def resolved(scene, name: str):
    """``render.steps``/``sampling``/``resolution`` (``name``), or the scene's technique's own default
    (its ``[techniques.NAME]`` field of that name) when the scene leaves it unset, else :data:`RESOLVED_DEFAULTS`."""
    value = getattr(scene.render, name)
    if value is not None:
        return value
    default = getattr(scene.techniques.of(scene.render.technique), name, None)
    return RESOLVED_DEFAULTS[name] if default is None else default
