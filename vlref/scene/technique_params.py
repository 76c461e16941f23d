"""Per-technique parameters: the ``[techniques.NAME]`` tables of a scene file.

Each class holds every user parameter of its source with that source's default, so a scene
that names a technique and nothing else renders as the source does. ``docs/TECHNIQUES.md``
gives each parameter's origin. Fields are documented in their metadata (see ``model.F``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional


def F(default, doc: str = "", **meta):
    meta["doc"] = doc
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class PhysicalParams:
    """The energy-conserving march of DESIGN.md (Hillaire 2015 step integration)."""

    steps: int = F(32, "default step count when render.steps is not given", min=1, max=4096)
    sampling: str = F("bayer8", "default offset pattern", choices=("none", "bayer2", "bayer4", "bayer8", "hash"))
    light_extinction: bool = F(True, "extinction on the light leg (T_l)")


@dataclass(frozen=True)
class KillzoneParams:
    """The thesis (seed 000) after Vos, GPU Pro 5."""

    steps: int = F(32, "default step count when render.steps is not given", min=1, max=4096)
    sampling: str = F("bayer4", "Bayer offset texture: bayer2, bayer4 or bayer8",
                      choices=("none", "bayer2", "bayer4", "bayer8"))
    resolution: str = F("half", "default calculation resolution", choices=("full", "half", "quarter"))
    light_resolutions: tuple[str, ...] = F((), "per-light calculation resolution, in light order (full/half/quarter)")
    blur_radius: int = F(3, "blur taps each side of the centre (the thesis's 7 taps)", min=0, max=16)
    blur_sigma: float = F(1.5, "Gaussian sigma of the blur in texels [U: not stated in the thesis]", gt=0.0)
    blur_depth_factor: float = F(1.0, "depth weight exp(-(factor*|dz|)^2) of the blur [U]", min=0.0)
    upsample_epsilon: float = F(1e-3, "guard added to |dz| in the 9/16,3/16,1/16 upsample weights (metres)", gt=0.0)
    transmittance: bool = F(True, "Beer-Lambert view transmittance, as the thesis states it")


@dataclass(frozen=True)
class SlightlyMadParams:
    """SlightlyMad/VolumetricLights (seed 001 and its public shaders); defaults from VolumetricLight.cs."""

    steps: int = F(8, "SampleCount", min=1, max=64)
    resolution: str = F("half", "VolumetricLightRenderer.Resolution", choices=("full", "half", "quarter"))
    scattering: float = F(0.5, "ScatteringCoef (1/m)", min=0.0)
    extinction: float = F(0.01, "ExtinctionCoef (1/m)", min=0.0)
    skybox_extinction: float = F(0.9, "SkyboxExtinctionCoef", min=0.0, max=1.0)
    mie_g: float = F(0.1, "MieG (Henyey-Greenstein g)", gt=-1.0, lt=1.0)
    height_fog: bool = F(False, "HeightFog")
    height_scale: float = F(0.10, "HeightScale", min=0.0)
    ground_level: float = F(0.0, "GroundLevel (enters as +GroundLevel)")
    noise: bool = F(False, "Noise")
    noise_scale: float = F(0.015, "NoiseScale", gt=0.0)
    noise_intensity: float = F(1.0, "NoiseIntensity", min=0.0)
    noise_intensity_offset: float = F(0.3, "NoiseIntensityOffset")
    noise_velocity: tuple[float, float] = F((3.0, 3.0), "NoiseVelocity (x, z) in m/s")
    max_ray_length: float = F(400.0, "MaxRayLength (directional lights)", gt=0.0)
    dither: str = F("8x8", "dither texture (DITHER_4_4 off = 8x8)", choices=("8x8", "4x4"))


@dataclass(frozen=True)
class UrpParams:
    """Valerio Marty's URP tutorial (seed 002)."""

    steps: int = F(25, "steps (the loop runs steps - 1 times)", min=2, max=4096)
    resolution: str = F("full", "downsampling: full (off), half, third, quarter",
                        choices=("full", "half", "third", "quarter"))
    intensity: float = F(1.0, "composite gain", min=0.0)
    scattering: float = F(0.0, "HG g with the tutorial's reversed sign", gt=-1.0, lt=1.0)
    max_distance: float = F(75.0, "maxDistance (metres)", gt=0.0)
    jitter: float = F(250.0, "jitter, percent of a step", min=0.0)
    gauss_samples: int = F(4, "gaussBlur.samples (taps each side, at most 7)", min=0, max=7)
    gauss_amount: float = F(1.0, "gaussBlur.amount (uv offset x 1/1000 per tap)", min=0.0)


@dataclass(frozen=True)
class RadialParams:
    """GPU Gems 3 ch. 13 (Mitchell) and its Unity port (seed 004)."""

    num_samples: int = F(100, "NUM_SAMPLES", min=1, max=1024)
    density: float = F(0.84, "Density", min=0.0)
    weight: float = F(5.65, "Weight", min=0.0)
    decay: float = F(1.0, "Decay", min=0.0)
    exposure: float = F(0.0034, "Exposure", min=0.0)


@dataclass(frozen=True)
class TechniqueParams:
    physical: PhysicalParams = field(default_factory=PhysicalParams, metadata={"doc": "physical march"})
    killzone: KillzoneParams = field(default_factory=KillzoneParams, metadata={"doc": "thesis / Killzone"})
    slightlymad: SlightlyMadParams = field(default_factory=SlightlyMadParams, metadata={"doc": "VolumetricLights"})
    urp: UrpParams = field(default_factory=UrpParams, metadata={"doc": "URP tutorial"})
    radial: RadialParams = field(default_factory=RadialParams, metadata={"doc": "GPU Gems 3 radial blur"})

    def of(self, name: str):
        """The parameter block of technique ``name``."""
        return getattr(self, name)

