"""Scene model, loading and validation, bundled scenes."""

from .bundled import DEFAULT_SCENE, bundled_scenes, find_bundled, scenes_dir
from .load import load_scene
from .model import (Bounds, Box, CameraSettings, Cookie, Cylinder, HeightFog, Light, Material, Medium, Mesh,
                    Noise, Plane, RenderSettings, Scene, ShadowSettings, Sphere)

__all__ = ["DEFAULT_SCENE", "bundled_scenes", "find_bundled", "scenes_dir", "load_scene", "Bounds", "Box",
           "CameraSettings", "Cookie", "Cylinder", "HeightFog", "Light", "Material", "Medium", "Mesh", "Noise",
           "Plane", "RenderSettings", "Scene", "ShadowSettings", "Sphere"]
