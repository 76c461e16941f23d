"""Geometry: analytic primitives, OBJ meshes, the triangle BVH, packed scene geometry, G-buffer ray casting.

    primitives.py      ray/plane, sphere, box, cylinder, triangle intersection (njit)
    obj.py             Wavefront OBJ loading and the mesh-object transform
    bvh.py             binned-SAH BVH build and traversal
    scene_geometry.py  build_geometry -> Geometry (the "geo" tuple), closest_hit, closest_hits (a row or
                       chunk of rays), shadow_transmittance, trace_distances
    raycast.py         raycast -> GBuffer (depth, distance, normal, object_id; position, albedo, emission derived)
"""

from .bvh import Bvh, build_bvh, traversal_stack
from .obj import load_obj, transform_vertices, write_obj
from .raycast import GBuffer, raycast
from .scene_geometry import (EVERY_SURFACE, OPAQUE_ONLY, RAY_CHUNK, SHADOW_EPS, GeoArrays, Geometry, build_geometry,
                             closest_hit, closest_hits, inline_shadow_transmittance, shadow_transmittance,
                             trace_distances)

__all__ = ["Bvh", "build_bvh", "traversal_stack", "RAY_CHUNK", "load_obj", "transform_vertices", "write_obj",
           "GBuffer", "raycast", "SHADOW_EPS", "GeoArrays", "Geometry", "build_geometry", "closest_hit", "closest_hits",
           "shadow_transmittance", "inline_shadow_transmittance", "trace_distances", "OPAQUE_ONLY", "EVERY_SURFACE"]
