"""SHA-256 of every G-buffer and shadow-map array (and the scene colour) of the geometry scenes, to show that a change of the ray
casting or of the BVH keeps the bits (BENCHMARKS.md, "Whole frame").

Scenes: the bench scene (b) with four shadowed lights, and the bundled scenes whose geometry or maps exercise
something else: ``stained_glass`` (transparent layers), ``window``, ``cage``, ``forest`` (triangle meshes),
``coloured_lights``, ``valley``. Besides the G-buffer and the maps: :func:`vlref.lights.shadow_probes.cast_rays`
and :func:`~vlref.lights.shadow_probes.lit_at_points` on rays and points drawn from a fixed seed, and
:func:`vlref.geometry.shadow_transmittance` through ``exact_visibility`` (the verdict's and the exact filter's
paths).

    PYTHONPATH=$PWD python3 benchmarks/geometry_hashes.py > before.json      # on the old tree
    PYTHONPATH=$PWD python3 benchmarks/geometry_hashes.py before.json        # on the new one: exit 1 on a change
"""

import hashlib
import json
import sys

import numpy as np

from vlref.bench.config import bench_scene
from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry, raycast, trace_distances
from vlref.lights import pack_lights
from vlref.lights.pack import I_KIND
from vlref.lights.shading import scene_colour
from vlref.lights.shadow_cast import build_shadow_maps
from vlref.lights.shadow_pack import SHADOW_HARD, SHADOW_PCF
from vlref.lights.shadow_probes import cast_rays, lit_at_points
from vlref.scene.load import load_scene

SCENES = ("stained_glass", "window", "cage", "forest", "coloured_lights", "valley")
SIZE = ("render.width=320", "render.height=180")
GBUFFER = ("depth", "distance", "position", "normal", "albedo", "emission", "object_id")  # stored or derived


def _digest(array: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()[:16]


def hashes(scene) -> dict:
    """Digest of each buffer of ``scene``'s G-buffer, shadow maps and probes."""
    camera = camera_from_settings(scene.camera, scene.render.width, scene.render.height)
    geometry = build_geometry(scene)
    packed = pack_lights(scene)
    gbuffer = raycast(scene, camera, geometry)
    maps = build_shadow_maps(scene, camera, geometry, packed)
    out = {f"gbuffer.{k}": _digest(getattr(gbuffer, k)) for k in GBUFFER}
    out["scene_colour"] = _digest(scene_colour(gbuffer, scene, geometry, packed))
    out["maps.data"], out["maps.tint"] = _digest(maps.data), _digest(maps.tint)
    rng = np.random.default_rng(7)
    lo, hi = geometry.bounds_min - 2.0, geometry.bounds_max + 2.0
    origins = rng.uniform(lo, hi, size=(4096, 3))
    dirs = rng.normal(size=(4096, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    out["cast_rays"] = _digest(cast_rays(geometry, origins, dirs, np.full(4096, 0.25), np.full(4096, 50.0), 0.03,
                                         0.5))
    t, obj = trace_distances(geometry.arrays, origins, dirs, 50.0, opaque_only=False)
    out["trace_distances"] = _digest(t) + _digest(obj)
    seen = gbuffer.position[gbuffer.hit]
    for light in range(packed.count):
        if maps.mode(light) in (SHADOW_HARD, SHADOW_PCF):
            lit = np.empty(len(seen))
            lit_at_points(maps.table, int(packed.ints[light, I_KIND]), packed.floats, light, seen, lit)
            out[f"lit_at_points.{light}"] = _digest(lit)
    return out


def main() -> int:
    scenes = {"bench_four": bench_scene(480, 270, 16, "four", 512)}
    scenes.update({name: load_scene(name, SIZE) for name in SCENES})
    result = {name: hashes(scene) for name, scene in scenes.items()}
    if len(sys.argv) < 2:
        print(json.dumps(result, indent=1))
        return 0
    with open(sys.argv[1]) as f:
        before = json.load(f)
    changed = [f"{s}: {k}" for s in before for k in before[s] if result.get(s, {}).get(k) != before[s][k]]
    print("\n".join(changed) if changed else f"same bits: {sum(len(v) for v in result.values())} arrays")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
