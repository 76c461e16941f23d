"""Lights: models, attenuation and cone laws, cookies, shadow maps, surface shading.

    pack.py           pack_lights -> PackedLights (the light record, I_* / F_* columns)
    attenuation.py    falloff laws;  cone.py  cone laws;  cookies.py  cookie textures
    shading.py        light incidence, scene colour (Lambert with shadow rays)
    shadow_pack.py    the shadow-map record: what each texel stores, ShadowMaps, pack_shadow_maps
    shadow_cast.py    build_shadow_maps: each light's faces cast from the light
    shadow_lookup.py  njit lookups (hard, pcf, exact) the marches call
    shadow_probes.py  cast_rays, lit_at_points: the maps probed by a caller's rays and points
"""

from .pack import PackedLights, pack_lights

__all__ = ["PackedLights", "pack_lights"]
