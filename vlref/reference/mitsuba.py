"""A vlref scene as a Mitsuba 3 scene: the independent renderer the quadrature reference is checked and timed against.

Mitsuba 3 (``pip install mitsuba``, optional) with ``volpath`` and ``max_depth = 2`` solves the same single-scattering
integral by Monte Carlo: the camera vertex and one scattering vertex, with next-event estimation toward the light.
Matched conventions (docs/PHYSICS.md): Mitsuba's point-light ``intensity`` is radiant intensity (W/sr), vlref's
``color × intensity``; Mitsuba's ``hg`` with ``g > 0`` scatters forward, the same physics as vlref's
``cos θ = dot(d, l)`` convention (its vectors point the other way, so its formula has the opposite sign on its own
cosine); the medium is a ``cube`` with a ``null`` BSDF and a ``homogeneous`` interior over ``medium.bounds``,
``albedo = σs/σt``; the light leg's extinction is always on (vlref's ``techniques.physical.light_extinction``, the
default). Objects are opaque and black (a ``diffuse`` BSDF of reflectance 0), so Mitsuba's radiance along a view
ray is vlref's ``inscatter``.

Only what both renderers define the same way is converted: point lights (inverse-square law, a range far beyond
the medium), a bounded homogeneous medium without height fog or noise, spheres and unrotated boxes. Anything else
raises :class:`ValueError` naming it.
"""

from __future__ import annotations

import itertools

from ..scene.model import Box, Scene, Sphere

__all__ = ["mitsuba_scene"]


def mitsuba_scene(scene: Scene, max_depth: int = 2) -> dict:
    """``scene`` as a dict for ``mitsuba.load_dict`` (no sensor: add one, or trace vlref's own pixel rays with
    the integrator). Needs a Mitsuba variant set (``mitsuba.set_variant``)."""
    import mitsuba as mi

    med = scene.medium
    if med.bounds is None or med.height_fog is not None or med.noise is not None:
        raise ValueError("mitsuba_scene: the medium must be bounded (medium.bounds), without height fog or noise")
    sigma_t = med.scattering + med.absorption
    if sigma_t <= 0.0:
        raise ValueError("mitsuba_scene: the medium must have scattering + absorption > 0")
    lo, hi = med.bounds.min, med.bounds.max
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    half = [(b - a) / 2 for a, b in zip(lo, hi)]
    out = {"type": "scene", "integrator": {"type": "volpath", "max_depth": max_depth},
           "medium_box": {"type": "cube", "to_world": mi.ScalarTransform4f().translate(centre).scale(half),
                          "bsdf": {"type": "null"},
                          "interior": {"type": "homogeneous", "sigma_t": sigma_t,
                                       "albedo": {"type": "rgb", "value": [med.scattering / sigma_t] * 3},
                                       "phase": {"type": "hg", "g": med.anisotropy}}}}
    for i, light in enumerate(scene.lights):
        if light.type != "point" or light.attenuation != "inverse_square" or light.cookie is not None:
            raise ValueError(f"mitsuba_scene: lights.{i}: only point lights with the inverse-square law convert")
        reach = max(sum((c - p) ** 2 for c, p in zip(corner, light.position)) ** 0.5
                    for corner in itertools.product(*zip(lo, hi)))
        if light.range < reach:
            raise ValueError(f"mitsuba_scene: lights.{i}.range: {light.range} m ends inside the medium box "
                             f"(its far corner is {reach:.3g} m away); Mitsuba's point light has no range")
        out[f"light_{i}"] = {"type": "point", "position": list(light.position),
                             "intensity": {"type": "rgb", "value": [c * light.intensity for c in light.color]}}
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    for i, obj in enumerate(scene.objects):
        if isinstance(obj, Sphere):
            out[f"object_{i}"] = {"type": "sphere", "center": list(obj.center), "radius": obj.radius, "bsdf": black}
        elif isinstance(obj, Box) and not any(obj.rotation):
            to_world = mi.ScalarTransform4f().translate(list(obj.center)).scale([s / 2 for s in obj.size])
            out[f"object_{i}"] = {"type": "cube", "to_world": to_world, "bsdf": black}
        else:
            raise ValueError(f"mitsuba_scene: objects.{i}: only spheres and unrotated boxes convert")
    return out
