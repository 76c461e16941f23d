"""The scene model: frozen dataclasses that are also the scene-file schema.

Conventions (see ``docs/CONVENTIONS.md``): Unity's world frame (left-handed, y up), metres,
degrees, light parameters named as Unity names them (``range``, ``spot_angle`` = the *full*
cone angle, ``intensity``, ``color``). Directions are the direction light *travels* (a spot
light's and a directional light's forward vector). Colours are linear RGB.

Each field's ``metadata`` holds its documentation and constraints; :mod:`vlref.scene.schema`
checks them. Cross-field rules live in each class's ``check()``, which returns
``(key, reason)`` for the first problem or ``None``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Optional

from .animation import check_animation
from .fields import F
from .technique_params import TechniqueParams

Vec3 = tuple[float, float, float]

TECHNIQUES = tuple(f.name for f in dataclasses.fields(TechniqueParams))
"""The accepted ``render.technique`` names, one per parameter table (the same as ``vlref.techniques``)."""
SAMPLINGS = ("none", "bayer2", "bayer4", "bayer8", "hash")
RESOLUTIONS = ("full", "half", "third", "quarter")
ATTENUATIONS = ("inverse_square", "unity", "windowed")
"""The distance laws of point and spot lights: the one list (:mod:`vlref.lights.attenuation` numbers them in
this order and evaluates each; a new law is a name here and its branch there)."""
CONE_LAWS = ("unity", "linear", "smoothstep")
"""The spot cone laws: the one list (:mod:`vlref.lights.cone` numbers them in this order and evaluates each)."""


@dataclass(frozen=True)
class RenderSettings:
    width: int = F(640, "image width in pixels", min=1, max=16384)
    height: int = F(360, "image height in pixels", min=1, max=16384)
    technique: str = F("physical", "which technique renders the volumetric passes", choices=TECHNIQUES)
    steps: Optional[int] = F(None, "ray-march steps per pixel and light (default: the technique's source value)",
                             min=1, max=4096)
    sampling: Optional[str] = F(None, "per-pixel start offset pattern (default: the technique's)",
                                choices=SAMPLINGS)
    resolution: Optional[str] = F(None, "march resolution relative to the frame (default: the technique's)",
                                  choices=RESOLUTIONS)
    seed: int = F(0, "seed of the hash pattern and of the procedural noise", min=0)
    frame: int = F(0, "frame index: the [animation] state rendered and the temporal jitter", min=0)
    time: float = F(0.0, "scene time in seconds (animates the noise)")
    max_distance: float = F(100.0, "view rays are cut at this distance (metres)", gt=0.0)
    precision: str = F("float64", "floating-point type of the march", choices=("float64", "float32"))
    sky_color: Vec3 = F((0.0, 0.0, 0.0), "radiance of pixels that hit nothing (linear RGB)", min=0.0)
    ambient: Vec3 = F((0.02, 0.02, 0.02), "ambient term of the scene colour (linear RGB)", min=0.0)
    exposure: float = F(1.0, "multiplier applied before tone mapping PNG previews (after auto_exposure)", gt=0.0)
    auto_exposure: float = F(99.0, "PNG previews: this percentile of the final image's luminance maps to 1 before "
                             "tone mapping (then times exposure); 0 = off, exposure alone", min=0.0, max=100.0)


@dataclass(frozen=True)
class CameraSettings:
    position: Vec3 = F((0.0, 1.0, -10.0), "camera position (world, metres)")
    look_at: Optional[Vec3] = F(None, "point the camera looks at (give this or rotation)")
    rotation: Optional[Vec3] = F(None, "Euler angles in degrees, Unity order (z, then x, then y)")
    up: Vec3 = F((0.0, 1.0, 0.0), "world up used with look_at", nonzero=True)
    fov: float = F(60.0, "vertical field of view in degrees", gt=0.0, lt=180.0)
    near: float = F(0.1, "near plane distance (metres)", gt=0.0)
    far: float = F(1000.0, "far plane distance (metres)", gt=0.0)

    def check(self):
        if self.look_at is not None and self.rotation is not None:
            return "look_at", "give either look_at or rotation, not both"
        if not self.far > self.near:
            return "far", f"must be greater than near ({self.near}), got {self.far}"
        if self.look_at is not None:
            d = [a - b for a, b in zip(self.look_at, self.position)]
            if sum(x * x for x in d) == 0.0:
                return "look_at", "must differ from position (zero-length view direction)"
            cross = (d[1] * self.up[2] - d[2] * self.up[1], d[2] * self.up[0] - d[0] * self.up[2],
                     d[0] * self.up[1] - d[1] * self.up[0])
            if sum(x * x for x in cross) <= 1e-18 * sum(x * x for x in d):
                return "up", "is parallel to the view direction; give another up vector"
        return None


@dataclass(frozen=True)
class HeightFog:
    base: float = F(0.0, "height (y, metres) where the fog factor is 1")
    falloff: float = F(0.1, "density factor exp(-(y - base) * falloff), per metre", min=0.0)


@dataclass(frozen=True)
class Noise:
    scale: float = F(0.1, "noise frequency: lattice cells per metre", gt=0.0)
    intensity: float = F(1.0, "density factor saturate(saturate(n - offset) * intensity)", min=0.0)
    offset: float = F(0.3, "subtracted from the noise value before scaling", min=-1.0, max=1.0)
    velocity: Vec3 = F((0.0, 0.0, 0.0), "wind: the field moves by velocity * time (m/s)")
    period: int = F(32, "the lattice repeats every `period` cells (tileable)", min=2, max=1024)
    seed: Optional[int] = F(None, "noise seed (default: render.seed)", min=0)
    path: Optional[str] = F(None, "optional 128^3 L8 DDS volume (VolumetricLights' NoiseVolume.bytes)",
                            file=True)


@dataclass(frozen=True)
class Bounds:
    min: Vec3 = F(doc="lower corner of the medium box (world)")
    max: Vec3 = F(doc="upper corner of the medium box (world)")

    def check(self):
        for i, (a, b) in enumerate(zip(self.min, self.max)):
            if not b > a:
                return "max", f"component {i} must exceed min ({a}), got {b}"
        return None


@dataclass(frozen=True)
class Medium:
    scattering: float = F(0.05, "scattering coefficient sigma_s (1/m)", min=0.0)
    absorption: float = F(0.0, "absorption coefficient sigma_a (1/m)", min=0.0)
    anisotropy: float = F(0.0, "Henyey-Greenstein g; > 0 scatters forward (toward the viewer looking into the light)",
                          gt=-1.0, lt=1.0)
    height_fog: Optional[HeightFog] = F(None, "exponential height fog")
    noise: Optional[Noise] = F(None, "animated 3D noise that scales density")
    bounds: Optional[Bounds] = F(None, "axis-aligned box holding the medium (default: unbounded)")

    @property
    def extinction(self) -> float:
        """sigma_t = sigma_s + sigma_a (1/m)."""
        return self.scattering + self.absorption


@dataclass(frozen=True)
class ShadowSettings:
    enabled: bool = F(True, "cast shadows from this light")
    filter: str = F("pcf", "lookup: hard (one compare), pcf (2x2 bilinear compare), exact (shadow ray)",
                    choices=("hard", "pcf", "exact"))
    resolution: int = F(1024, "shadow-map size in texels (per cube face / cascade)", min=8, max=8192)
    bias: float = F(0.02, "constant depth bias (metres)", min=0.0)
    slope_bias: float = F(0.0, "slope-scaled bias (metres per unit slope)", min=0.0)
    near: float = F(0.1, "shadow near plane (spot and point lights, metres)", gt=0.0)
    strength: float = F(1.0, "shadow strength: visibility = 1 - strength * (1 - lit)", min=0.0, max=1.0)
    cascades: int = F(4, "directional lights: number of cascades", min=1, max=8)
    split_lambda: float = F(0.75, "cascade splits: blend of logarithmic (1) and uniform (0)", min=0.0, max=1.0)
    distance: float = F(100.0, "directional lights: shadow distance covered by the cascades (metres)", gt=0.0)


@dataclass(frozen=True)
class Cookie:
    path: str = F(doc="greyscale or RGB image (PNG), relative to the scene file", file=True)
    wrap: str = F("clamp", "addressing outside [0,1]", choices=("clamp", "repeat"))
    filter: str = F("bilinear", "texture filter", choices=("bilinear", "nearest"))
    channel: str = F("luminance", "which channel modulates light", choices=("luminance", "alpha", "rgb"))
    size: float = F(10.0, "directional lights: world size of one tile (metres)", gt=0.0)


@dataclass(frozen=True)
class Light:
    type: str = F(doc="point, spot or directional", choices=("point", "spot", "directional"))
    position: Vec3 = F((0.0, 5.0, 0.0), "world position (point and spot)")
    direction: Vec3 = F((0.0, -1.0, 0.0), "direction of light travel (spot and directional)", nonzero=True)
    color: Vec3 = F((1.0, 1.0, 1.0), "linear RGB colour", min=0.0)
    intensity: float = F(1.0, "point/spot: radiant intensity scale (W/sr per unit colour); directional: irradiance",
                         min=0.0)
    range: float = F(10.0, "point/spot: radius of the light volume (metres)", gt=0.0)
    spot_angle: float = F(30.0, "spot: FULL cone angle in degrees (Unity's spotAngle)", gt=0.0, lt=180.0)
    inner_spot_angle: Optional[float] = F(None, "spot: full angle where the cone falloff starts (degrees)",
                                          min=0.0, lt=180.0)
    attenuation: str = F("inverse_square", "distance law", choices=ATTENUATIONS)
    cone: str = F("smoothstep", "spot cone falloff law", choices=CONE_LAWS)
    shadows: Optional[ShadowSettings] = F(None, "shadow settings (absent: no shadows)")
    cookie: Optional[Cookie] = F(None, "projected texture (spot) or tiled texture (directional)")

    def check(self):
        if self.inner_spot_angle is not None and self.inner_spot_angle > self.spot_angle:
            return "inner_spot_angle", f"must not exceed spot_angle ({self.spot_angle})"
        if self.cookie is not None and self.type == "point":
            return "cookie", "point-light cookies (cube maps) are not supported"
        return None


@dataclass(frozen=True)
class Material:
    albedo: Vec3 = F((0.8, 0.8, 0.8), "diffuse reflectance (linear RGB)", min=0.0, max=1.0)
    emission: Vec3 = F((0.0, 0.0, 0.0), "emitted radiance (linear RGB)", min=0.0)
    opacity: float = F(1.0, "1 = opaque; below 1 the object is a transparent occluder", min=0.0, max=1.0)
    tint: Vec3 = F((1.0, 1.0, 1.0), "colour of light passing a transparent occluder", min=0.0, max=1.0)


def _material():
    return Material()


@dataclass(frozen=True)
class _SceneObject:
    """Fields every object shape has."""

    material: Material = F(factory=_material, doc="surface material")
    name: str = F("", "optional name")


@dataclass(frozen=True)
class Plane(_SceneObject):
    shape: str = F("plane", choices=("plane",))
    point: Vec3 = F((0.0, 0.0, 0.0), "a point on the plane")
    normal: Vec3 = F((0.0, 1.0, 0.0), "plane normal", nonzero=True)


@dataclass(frozen=True)
class Box(_SceneObject):
    shape: str = F("box", choices=("box",))
    center: Vec3 = F((0.0, 0.0, 0.0), "box centre")
    size: Vec3 = F((1.0, 1.0, 1.0), "edge lengths along the box's own x, y, z", gt=0.0)
    rotation: Vec3 = F((0.0, 0.0, 0.0), "Euler angles in degrees (Unity order z, x, y)")


@dataclass(frozen=True)
class Sphere(_SceneObject):
    shape: str = F("sphere", choices=("sphere",))
    center: Vec3 = F((0.0, 0.0, 0.0), "sphere centre")
    radius: float = F(1.0, "radius (metres)", gt=0.0)


@dataclass(frozen=True)
class Cylinder(_SceneObject):
    shape: str = F("cylinder", choices=("cylinder",))
    center: Vec3 = F((0.0, 0.0, 0.0), "centre of the cylinder (middle of its axis)")
    radius: float = F(0.5, "radius (metres)", gt=0.0)
    height: float = F(2.0, "length along its local y axis (metres)", gt=0.0)
    rotation: Vec3 = F((0.0, 0.0, 0.0), "Euler angles in degrees (Unity order z, x, y)")


@dataclass(frozen=True)
class Mesh(_SceneObject):
    shape: str = F("mesh", choices=("mesh",))
    path: str = F("", "Wavefront OBJ file, relative to the scene file (required)", file=True)
    position: Vec3 = F((0.0, 0.0, 0.0), "translation")
    rotation: Vec3 = F((0.0, 0.0, 0.0), "Euler angles in degrees (Unity order z, x, y)")
    scale: Vec3 = F((1.0, 1.0, 1.0), "per-axis scale", gt=0.0)

    def check(self):
        return ("path", "missing required key") if not self.path else None


@dataclass(frozen=True)
class CameraKey:
    position: Optional[Vec3] = F(None, "camera position (linear)")
    look_at: Optional[Vec3] = F(None, "point looked at (linear; the scene's camera must use look_at)")
    rotation: Optional[Vec3] = F(None, "Euler angles in degrees (quaternion slerp; the scene's camera must use "
                                 "rotation or neither)")
    fov: Optional[float] = F(None, "vertical field of view in degrees (linear)", gt=0.0, lt=180.0)


@dataclass(frozen=True)
class LightKey:
    light: int = F(doc="index of the light in [[lights]]", min=0)
    position: Optional[Vec3] = F(None, "world position (linear)")
    direction: Optional[Vec3] = F(None, "direction of light travel (slerp of the unit vectors)", nonzero=True)
    color: Optional[Vec3] = F(None, "linear RGB colour (linear)", min=0.0)
    intensity: Optional[float] = F(None, "intensity (linear)", min=0.0)


@dataclass(frozen=True)
class MediumKey:
    scattering: Optional[float] = F(None, "sigma_s (1/m, linear)", min=0.0)
    absorption: Optional[float] = F(None, "sigma_a (1/m, linear)", min=0.0)
    noise_offset: Optional[float] = F(None, "medium.noise.offset (linear)", min=-1.0, max=1.0)
    noise_intensity: Optional[float] = F(None, "medium.noise.intensity (linear)", min=0.0)


@dataclass(frozen=True)
class Keyframe:
    frame: int = F(doc="frame index of this key", min=0)
    camera: Optional[CameraKey] = F(None, "camera values at this frame")
    lights: tuple[LightKey, ...] = F(factory=tuple, doc="light values at this frame ([[animation.keys.lights]])")
    medium: Optional[MediumKey] = F(None, "medium values at this frame")


@dataclass(frozen=True)
class Animation:
    frames: int = F(8, "sequence length: frames 0 .. frames - 1 (vlref render --frames default)", min=1, max=100000)
    fps: float = F(24.0, "frames per second: frame f renders at render.time + f / fps (noise scroll)", gt=0.0)
    keys: tuple[Keyframe, ...] = F(factory=tuple, doc="keyframes ([[animation.keys]]), in increasing frame order")

    def check(self):
        for i in range(1, len(self.keys)):
            if not self.keys[i].frame > self.keys[i - 1].frame:
                return f"keys[{i}].frame", (f"keys must be in increasing frame order: {self.keys[i].frame} after "
                                            f"{self.keys[i - 1].frame}")
        for i, key in enumerate(self.keys):
            seen = set()
            for j, lk in enumerate(key.lights):
                if lk.light in seen:
                    return f"keys[{i}].lights[{j}].light", f"light {lk.light} is keyed twice in this key"
                seen.add(lk.light)
        return None


SHAPES = {"plane": Plane, "box": Box, "sphere": Sphere, "cylinder": Cylinder, "mesh": Mesh}
SceneObject = Plane | Box | Sphere | Cylinder | Mesh


@dataclass(frozen=True)
class Scene:
    description: str = F("", "one line shown by `vlref scenes`")
    render: RenderSettings = F(factory=RenderSettings, doc="render settings")
    camera: CameraSettings = F(factory=CameraSettings, doc="camera")
    medium: Medium = F(factory=Medium, doc="participating medium")
    lights: tuple[Light, ...] = F(factory=tuple, doc="lights ([[lights]] tables)")
    objects: tuple[SceneObject, ...] = F(factory=tuple, doc="objects ([[objects]] tables, tagged by shape)",
                                   union=("shape", SHAPES))
    techniques: TechniqueParams = F(factory=TechniqueParams, doc="per-technique parameters")
    animation: Optional[Animation] = F(None, "keyframed camera, lights and medium (vlref render --frames)")
    source: str = F("", internal=True)

    def check(self):
        if not self.lights:
            return "lights", "a scene needs at least one light"
        if self.animation is not None:
            return check_animation(self)
        return None

    def replace(self, **changes) -> "Scene":
        """A copy with some top-level sections replaced (``dataclasses.replace``)."""
        return dataclasses.replace(self, **changes)
