"""Lights: models, attenuation and cone laws, cookies, shadow maps, surface shading."""

from .pack import PackedLights, pack_lights

__all__ = ["PackedLights", "pack_lights"]
