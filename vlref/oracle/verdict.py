"""The whole-frame verdict on a GPU port: ``vlref verdict PORT.toml -o DIR`` (:func:`judge`), and on every
frame of a sequence, temporal history carried on both sides: ``vlref verdict A.toml B.toml ... -o DIR``
(:func:`judge_sequence`).

A port passes only when two judgments pass:

* **on its own buffers** (group ``own buffers``): each pass output the manifest declares (``[[passes]]``)
  against the same buffer of ``vlref march`` on the port's depth, scene colour and shadow maps
  (:mod:`vlref.port`): the march and post passes, isolated from the rasteriser;
* **against the scene** (group ``against the scene``): the port's inputs and its final frame against what
  the scene says, so that a bug in a raster pass cannot pass by feeding the march a wrong input:

  ``camera``              the port's camera matrices against the scene's camera;
  ``depth``               its depth buffer against vlref's ray-cast eye depth, compared as inverse depth
                          ``1/z`` (sky = 0, so a sky / surface mismatch fails; relative errors equal);
  ``shadow_map[light=i]`` each texel of its maps against vlref's map rendered through the *port's* texel
                          rays (its light matrices, :func:`vlref.port.decode.tile_rays`): the biased distance
                          along the ray (:func:`vlref.lights.shadow_probes.cast_rays`), as inverse distance
                          (empty = 0);
  ``shadow_test[light=i]`` the lit fraction its maps give at the scene's visible surface points the light
                          reaches (inside its range and cone) against vlref's maps' (the decision a map
                          implies where the camera looks and where it matters);
  ``scene_colour``        its lit scene colour against vlref's shading (:mod:`vlref.lights.shading`);
  ``end_to_end``          its final frame against ``vlref render`` of the scene.

Every comparison allows no failing pixel outside its edge zone (:mod:`vlref.oracle.edges`): depth
discontinuities of vlref's and the port's depth and, for the lit fraction (``shadow_test``), the *shadow zone*,
the surface points where either renderer's map decides close to its bias (:func:`shadow_zone`: the lit fraction
changes when each texel is replaced by the min or the max of its (2k+1)² neighbourhood; this holds a receiver
that is its own caster, the ground under a low sun, whose stored distance climbs from texel to texel by more
than the bias), all grown by ``edge_pixels`` pixels. The shading comparisons (``scene_colour``, ``end_to_end``)
set vlref's exact shadow rays against a port's map lookups, which differ only where a caster's edge is near:
their zone holds the surface points whose lookup lies within ``edge_pixels + LOOKUP_OFFSET_TEXELS`` texels of a
silhouette of either renderer's maps (:func:`silhouette_zone`), so sunlit ground stays judged pixel by pixel and
by the mean error outside the zone (ground that shadows itself fails there). A zone pixel there may differ either
way, but the zone may not lean one way: the colour presets bound the signed mean of port - vlref over it
(``max_zone_lean``: shadows grown or shrunk by a texel fail; reason "zone pixels lean one way"). The presets of
the against-the-scene comparisons are :data:`SCENE_PRESETS` (``vlref/data/presets.toml``). On its own buffers the
port may also take a *knife-edge* decision either way (:func:`knife_edges`: a march sample exactly on a shadow-volume,
texel or cone boundary, found by nudging the lights and the map distances by 1e-5): at those pixels the
reference is whichever of vlref's two decisions lies closest to the port's value. Every pixel may also differ by
vlref's own spread under float32-sized changes of the port's inputs (:func:`_rounding_allowance`: twice the change
when its depths move by 4 ulp, :func:`rounding_spread`, or the nudges' change), and a pixel where that spread is a
sizeable share of the preset's per-pixel threshold is in the zone too, with the preset's edge tolerance
(``gpu-float32``, whose per-pixel bounds are float32's, relies on it; for the fp16 presets the spread is far below
their bounds).

Degenerate comparisons fail: when vlref's render of the scene says a buffer carries light (the pass's
buffer, or for the final frame the in-scatter, is nonzero somewhere), a comparison whose reference is zero
over every compared pixel proves nothing and fails with that reason (a black port's maps that shadow
everything make vlref's march on its buffers black too). A port whose manifest declares no ``final`` or no ``[[passes]]`` cannot pass the
group it is missing. Missing shadow maps of shadowed lights are bad input (:func:`vlref.port.load_port`),
unless the manifest says ``shadows = false``: the port is then judged against the scene without shadows.
"""

from __future__ import annotations

import dataclasses
import hashlib
import html
import json
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
from scipy import ndimage

from ..errors import InputError
from ..io.files import write_text
from ..io.output_folders import output_dir
from ..lights import pack_lights
from ..lights.pack import I_KIND, KIND_DIRECTIONAL
from ..lights.shadow_pack import SHADOW_HARD, SHADOW_PCF, ShadowMaps
from ..lights.shadow_probes import cast_rays, lit_at_points
from ..port import load_port, port_frame
from ..port.decode import FAR_VALUE, tile_points, tile_rays
from ..render import prepare_frame, scene_hash
from ..techniques import TECHNIQUES
from .compare import Report, compare_arrays, margin, scale_of
from .edges import block_any, depth_discontinuities, dilate, edge_zone
from .presets import tolerance
from .report import json_ready, write_outputs

__all__ = ["GROUP_OWN", "GROUP_SCENE", "SCENE_PRESETS", "DEFAULT_PRESET", "PassVerdict", "Verdict",
           "SequenceVerdict", "judge", "judge_sequence", "shadow_zone", "silhouette_zone",
           "write_verdict"]

GROUP_OWN = "own buffers"
GROUP_SCENE = "against the scene"
DEFAULT_PRESET = "gpu-half"
"""Preset of a ``[[passes]]`` entry that names none, when neither the manifest nor the caller does."""
SCENE_PRESETS = {"depth": "raster-depth", "shadow_map": "raster-shadow-map", "shadow_test": "raster-shadow-test",
                 "scene_colour": "raster-colour", "end_to_end": "end-to-end"}
"""Preset of each against-the-scene comparison."""
KNIFE_EDGE = 1e-5
"""Relative nudge of the lights and the shadow-map distances that finds the knife-edge pixels of
:func:`knife_edges`: ~100x float32's unit roundoff, the precision a port computes its lookups with."""
DEPTH_ROUNDING = 2.0 ** -21
"""Relative rounding of the camera depth a float32 port decodes from its depth buffer (:func:`rounding_spread`):
4 ulp, the bound of a reversed-Z decode ``f n / (d (f - n) + n)`` in float32 (four correctly rounded operations,
0.5 ulp each, and a division, 2.5 ulp in Vulkan's precision rules); two decodes then differ by up to 8 ulp."""
ROUNDING_ZONE = 0.25
"""A pixel is sensitive to the depths' rounding when vlref's spread there (:func:`rounding_spread`) exceeds this share
of the preset's per-pixel threshold (:func:`_rounding_allowance`)."""
ROUNDING_REACH = 1
"""The rounding zone takes the depth-sensitive pixels of every buffer of a size, grown by this many pixels: a pixel
next to a sensitive one shares most of its taps, whose signs the eight patterns of :func:`rounding_patterns` may set
so that their changes cancel where a port's roundings do not."""
ROUNDING_SAFETY = 2.0
"""A pixel may differ from vlref by this many times vlref's depth-rounding spread (on top of the preset's threshold):
the eight sign patterns are eight of the 2^n ways n taps can round; a port's one way moves a pixel by at most
ROUNDING_SAFETY x their largest change (measured: docs/PORTING.md, "The float32 rounding allowance")."""
ROUNDING_PRESETS = 1e-3
"""The depth-rounding spread (:func:`rounding_spread`, eight renders) is taken for passes whose preset's ``rel_tol`` is
under this (float32's bounds): its largest measured value, ~20x float32's threshold (2e-3 relative, the WebGPU
port's frames), is under the fp16 presets' per-pixel thresholds (``gpu-half`` 1e-2 relative, ``gpu-full`` 5e-3 plus
a floor of 1e-3 of the mean level), whose fp16 stores dominate there. Nor is it taken for a
depth buffer (``depth_*``: the camera depth min-downsampled), which the rounding moves by itself, 4 ulp: 5e-3 of
float32's threshold."""
KNIFE_ZONE = 1.0
"""A pixel is knife-sensitive (in the rounding zone) when the knife-edge nudges move vlref's value by more than this
share of the preset's threshold: the nudges' continuous change is a fifth of float32's threshold at the median pixel
of the WebGPU port's frame (so a quarter, the depth's share, would take 42 % of the march texels), and beyond the
whole threshold it is a decision (a march sample on a shadow-volume, texel or cone boundary), its blurred share, or a
ray passing a point light within centimetres."""
KNIFE_JUMP = 1e-3
"""A change 100x the nudge: a discrete decision taken the other way, not a continuous change."""
MAP_JUMP = 5e-3
""":func:`~vlref.oracle.edges.depth_discontinuities` threshold on shadow maps: a slope-scaled bias jumps where
two flat casters meet (``slope_bias`` times the change of the slope, a few cm at metres: ~1e-3 relative),
so a crease of a biased map is an edge though far below the camera depth's ``DEPTH_JUMP``."""
LOOKUP_OFFSET_TEXELS = 1
"""Texels a port's shadow lookup may sit from the surface point's own texel, added to the preset's ``edge_pixels``
in the shading zone (:func:`silhouette_zone`): a port offsets its lookup along the normal against acne (ports/wgpu:
1.5 texels times ``1 - n·l``, Holbert 2011), which moves the texel it reads by up to about one."""
CAMERA_TOL = 1e-4
"""Largest accepted difference of the port's camera from the scene's: position (metres, relative to
``1 + |position|``), rotation matrix entries, and fov (degrees); float32 matrices round at ~1e-7."""


@dataclass(frozen=True)
class PassVerdict:
    """One comparison of the verdict: the port's ``name`` for it, its ``group`` (:data:`GROUP_OWN` or
    :data:`GROUP_SCENE`), the ``preset``, the outcome, why it failed (empty when passed), its numbers
    (``compared_pixels``, ``failing_pixels``, ``edge_pixels``, ..., ``margins``: check -> value / bound) and
    the path of its report.html (None without an output folder)."""

    name: str
    group: str
    preset: str
    passed: bool
    reason: str
    metrics: dict
    report: str | None = None


@dataclass(frozen=True)
class Verdict:
    """The whole-frame verdict: passed when every comparison passed."""

    passed: bool
    manifest: str
    preset: str | None
    passes: tuple[PassVerdict, ...]

    def to_dict(self) -> dict:
        """What ``verdict.json`` holds."""
        return {"verdict": "pass" if self.passed else "fail", "passed": self.passed, "manifest": self.manifest,
                "preset": self.preset, "passes": [dataclasses.asdict(p) for p in self.passes]}

    def table(self) -> str:
        """The verdict as a Markdown table (pass, group, preset, result, failing pixels, margins, reason)."""
        rows = ["| pass | group | preset | result | failing pixels | margins | reason |", "|---|---|---|---|---|---|---|"]
        for p in self.passes:
            m = p.metrics
            fail = f"{m['failing_pixels']} of {m['compared_pixels']}" if "compared_pixels" in m else "-"
            margins = ", ".join(f"{k} {_fmt_margin(v)}" for k, v in m.get("margins", {}).items()) or "-"
            rows.append(f"| {p.name} | {p.group} | {p.preset} | {'PASS' if p.passed else 'FAIL'} | {fail} | {margins} "
                        f"| {p.reason or '-'} |")
        rows.append(f"\n{'PASS' if self.passed else 'FAIL'}: {sum(p.passed for p in self.passes)} of "
                    f"{len(self.passes)} comparisons pass")
        return "\n".join(rows)


@dataclass(frozen=True)
class SequenceVerdict:
    """The whole-frame verdict on a sequence (:func:`judge_sequence`): each frame's :class:`Verdict`, in
    order; passed when every frame passed."""

    passed: bool
    frames: tuple[Verdict, ...]

    def failures(self) -> list[tuple[int, PassVerdict]]:
        """``(frame index, comparison)`` of every failing comparison, frame by frame in the verdict's order."""
        return [(i, p) for i, v in enumerate(self.frames) for p in v.passes if not p.passed]

    def to_dict(self) -> dict:
        """What the sequence's ``verdict.json`` holds: the outcome, each failure by frame and pass, and every
        frame's verdict (:meth:`Verdict.to_dict`) under ``frames``."""
        return {"verdict": "pass" if self.passed else "fail", "passed": self.passed,
                "failures": [{"frame": i, "name": p.name, "group": p.group, "preset": p.preset, "reason": p.reason}
                             for i, p in self.failures()],
                "frames": [{"frame": i, **v.to_dict()} for i, v in enumerate(self.frames)]}

    def table(self) -> str:
        """Every comparison of every frame as one Markdown table (frame, pass, group, preset, result, failing
        pixels, margins, reason), then the failures by frame and pass."""
        rows = ["| frame | pass | group | preset | result | failing pixels | margins | reason |",
                "|---|---|---|---|---|---|---|---|"]
        for i, v in enumerate(self.frames):
            rows += [f"| {i} {line}" for line in v.table().splitlines()[2:] if line.startswith("|")]
        total = sum(len(v.passes) for v in self.frames)
        failures = self.failures()
        rows.append(f"\n{'PASS' if self.passed else 'FAIL'}: {total - len(failures)} of {total} comparisons over "
                    f"{len(self.frames)} frames pass")
        rows += [f"- frame {i}, {p.name} ({p.group}): {p.reason}" for i, p in failures]
        return "\n".join(rows)


def _fmt_margin(v: float) -> str:
    return "inf" if math.isinf(v) else f"{v:.3g}x"


@dataclass
class _Comparison:
    """A comparison before its files are written: the report (None for a check without images)."""

    name: str
    group: str
    preset: str
    report: Report | None
    reason: str = ""
    metrics: dict = dataclasses.field(default_factory=dict)


# --------------------------------------------------------------------------- shadow zone and lookups

def _lit(maps: ShadowMaps, packed, light: int, points: np.ndarray) -> np.ndarray:
    """(N,) lit fraction (mean over RGB, strength not applied) of ``light``'s map at world ``points``."""
    out = np.empty(len(points))
    lit_at_points(maps.table, int(packed.ints[light, I_KIND]), packed.floats.astype(np.float64), light,
                  np.ascontiguousarray(points, dtype=np.float64), out)
    return out


def _filtered(maps: ShadowMaps, light: int, k: int, extreme) -> ShadowMaps:
    """``maps`` with every texel of ``light``'s tiles replaced by ``extreme`` (min or max filter) of its
    (2k+1)² neighbourhood inside the tile."""
    data = maps.data.copy()
    for _, li, start, count in maps.names:
        if li == light:
            res = int(round(math.sqrt(count)))
            tile = data[start:start + count].reshape(res, res)
            data[start:start + count] = extreme(tile, size=2 * k + 1, mode="nearest").ravel()
    return ShadowMaps(maps.ints, maps.floats, data, maps.tint, maps.names)


CREASE_COS = math.cos(math.radians(10.0))
"""Neighbouring pixels whose vlref normals differ by more than 10 degrees lie on a crease (:func:`_creases`)."""


def _creases(normal: np.ndarray, hit: np.ndarray) -> np.ndarray:
    """(H, W) bool: the pixels on both sides of a crease of vlref's surface normals (a box's edge, a cylinder
    meeting its cap): there a rasteriser and a ray cast may take either face, so the shading may be either
    face's, though the depth is continuous."""
    n = np.where(hit[..., None], np.asarray(normal, dtype=np.float64), 0.0)
    out = np.zeros(hit.shape, bool)
    for axis in (0, 1):
        a = np.take(n, range(n.shape[axis] - 1), axis=axis)
        b = np.take(n, range(1, n.shape[axis]), axis=axis)
        ha = np.take(hit, range(hit.shape[axis] - 1), axis=axis)
        hb = np.take(hit, range(1, hit.shape[axis]), axis=axis)
        bend = ha & hb & (np.sum(a * b, axis=-1) < CREASE_COS)
        index = [slice(None)] * 2
        index[axis] = slice(0, hit.shape[axis] - 1)
        out[tuple(index)] |= bend
        index[axis] = slice(1, hit.shape[axis])
        out[tuple(index)] |= bend
    return out


def _inside_volume(light, points: np.ndarray) -> np.ndarray:
    """(N,) bool: ``points`` a point or spot light can reach (closer than ``range``, inside the cone of full
    angle ``spot_angle``): every attenuation law is 0 at the range and every cone law 0 outside the cone, so
    elsewhere a shadow decision changes nothing. Directional lights reach every point."""
    if light.type == "directional":
        return np.ones(len(points), bool)
    w = np.asarray(points, dtype=np.float64) - np.asarray(light.position, dtype=np.float64)
    r = np.linalg.norm(w, axis=1)
    inside = r < light.range
    if light.type == "spot":
        axis = np.asarray(light.direction, dtype=np.float64)
        axis = axis / np.linalg.norm(axis)
        inside &= w @ axis > math.cos(math.radians(light.spot_angle) / 2.0) * r
    return inside


def _mapped(maps: ShadowMaps, light: int) -> bool:
    return maps.mode(light) in (SHADOW_HARD, SHADOW_PCF)


def shadow_zone(maps: ShadowMaps, packed, points: np.ndarray, k: int) -> np.ndarray:
    """(N,) bool: ``points`` whose lookup in some light's map lies within ``k`` texels of a shadow
    silhouette: the lit fraction differs between the map's min- and max-filtered ((2k+1)² texels) copies."""
    zone = np.zeros(len(points), bool)
    for light in range(packed.count):
        if _mapped(maps, light) and k > 0:
            lo = _lit(_filtered(maps, light, k, ndimage.minimum_filter), packed, light, points)
            hi = _lit(_filtered(maps, light, k, ndimage.maximum_filter), packed, light, points)
            zone |= lo != hi
    return zone


def _silhouettes_marked(maps: ShadowMaps, light: int, orthographic: bool, k: int) -> ShadowMaps:
    """``maps`` with ``light``'s texels within ``k`` texels of a silhouette of its map set to -1 (every lookup there
    shadowed) and its other texels empty (lit). A silhouette is a :func:`~vlref.oracle.edges.depth_discontinuities`
    (``MAP_JUMP``) of the quantity affine over a plane: the inverse of a perspective map's distance (spot, cube
    faces: nearly affine), an orthographic map's distance itself (a cascade: its inverse bends sharply where a
    receiver nears the cascade's ray plane)."""
    data = maps.data.copy()
    for _, li, start, count in maps.names:
        if li == light:
            res = int(round(math.sqrt(count)))
            tile = maps.data[start:start + count].reshape(res, res).astype(np.float64)
            edge = dilate(depth_discontinuities(_inverse(tile) if orthographic else tile, MAP_JUMP), k)
            data[start:start + count] = np.where(edge, -1.0, np.inf).ravel()
    return ShadowMaps(maps.ints, maps.floats, data, maps.tint, maps.names)


def silhouette_zone(maps: ShadowMaps, packed, points: np.ndarray, k: int) -> np.ndarray:
    """(N,) bool: ``points`` whose lookup in some light's map lies within ``k`` texels of a silhouette of that map
    (a caster's edge, where the first surface along the light's rays jumps): only there can a shadow decision
    taken per texel differ from an exact shadow ray. A receiver that is its own caster (the ground under a low
    sun) is smooth in its map and stays out, however steeply its stored distance climbs from texel to texel."""
    zone = np.zeros(len(points), bool)
    for light in range(packed.count):
        if _mapped(maps, light):
            orthographic = int(packed.ints[light, I_KIND]) == KIND_DIRECTIONAL
            # a marked tap darkens the lookup by its weight; PCF weights sum to 1 only up to rounding
            zone |= _lit(_silhouettes_marked(maps, light, orthographic, k), packed, light, points) < 1.0 - 1e-9
    return zone


def _on_pixels(values: np.ndarray, hit: np.ndarray, fill=0.0) -> np.ndarray:
    """Per-point ``values`` of the hit pixels back on the (H, W) image."""
    out = np.full(hit.shape, fill, dtype=values.dtype)
    out[hit] = values
    return out


def _inverse(z: np.ndarray) -> np.ndarray:
    """``1/z`` with non-finite or NaN ``z`` (sky, empty texel) as 0."""
    z = np.asarray(z, dtype=np.float64)
    ok = np.isfinite(z) & (z > 0)
    return np.where(ok, 1.0 / np.where(ok, z, 1.0), 0.0)


# --------------------------------------------------------------------------- shadow maps through the port's rays

def _port_tile_distances(tile, light, sh, encoding: str, convention: str, geometry):
    """(res, res) vlref's and the port's biased distance along each texel ray of a port ``tile``: the eye
    (perspective) or the view plane (orthographic) to the first opaque hit, plus bias (``inf`` = empty).
    Distances beyond the light's reach count as empty in both: for spot and point lights ``range`` (a
    port's far plane is a plane, vlref's range a sphere; no light reaches there), for a directional
    light's orthographic tile its far plane (``FAR_VALUE`` of the map's convention; ``d3d`` for linear)."""
    res = tile.texels.shape[0]
    origin_v, dir_v = tile_rays(tile, res)
    inv_v = np.linalg.inv(tile.view)
    rot, shift = inv_v[:3, :3], inv_v[:3, 3]
    origin, d = origin_v @ rot.T + shift, dir_v @ rot.T
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    if light.type == "directional":
        start, tmax = np.zeros(len(d)), np.full(len(d), np.inf)
    else:
        start = sh.near / np.abs(dir_v[:, 2])  # the light's near plane along each ray
        tmax = np.maximum(light.range - start, 0.0)
    ref = cast_rays(geometry, origin + start[:, None] * d, d, start, tmax, sh.bias, sh.slope_bias)
    port = np.einsum("ij,ij->i", tile_points(tile, encoding, convention) - origin, d)
    port = np.where(np.isnan(port), np.inf, port)
    if light.type == "directional":
        p = tile.projection
        reach = (FAR_VALUE["d3d" if convention == "linear" else convention] - p[2, 3]) / p[2, 2]
    else:
        reach = light.range
    ref, port = (np.where(a > reach, np.inf, a) for a in (ref, port))
    return ref.reshape(res, res), port.reshape(res, res)


# --------------------------------------------------------------------------- judging

def _reason(report: Report) -> str:
    """Why a report failed: its failing checks."""
    m = report.metrics
    parts = []
    for c in report.checks:
        if c.passed is False:
            if c.name == "failing_fraction":
                parts.append(f"{m['failing_pixels']} of {m['compared_pixels']} pixels fail "
                             f"({m['failing_pixels'] - m['failing_pixels_edge']} outside the edge zone of "
                             f"{m['edge_pixels']} pixels; allowed fraction {c.bound:g})")
            elif c.name == "zone_lean":
                parts.append(f"zone pixels lean one way: mean (port - vlref) over the edge zone of {m['edge_pixels']} "
                             f"pixels is {m['zone_mean_signed']:.4g}, |.| > {c.bound:.4g} (a rasteriser's choices "
                             f"there split both ways)")
            else:
                parts.append(f"{c.name} {c.value:.4g} > {c.bound:.4g}")
    return "; ".join(parts)


def _judged(name: str, group: str, report: Report, silent_check: bool, buffer: str) -> _Comparison:
    """A comparison from its report; a zero reference over every compared pixel fails when ``silent_check``
    (light reaches the camera, so such a comparison proves nothing)."""
    reason = _reason(report) if not report.passed else ""
    if silent_check and not np.any(report.ref[report.mask] != 0):
        reason = (f"reference {buffer} is zero over 100 % of the compared pixels: this comparison proves nothing"
                  + (f"; {reason}" if reason else ""))
    return _Comparison(name, group, report.tolerance.name, report, reason)


def _compare(name, group, ref, test, preset, mask, zone, signal: bool, buffer, names) -> _Comparison:
    """``compare_arrays`` of vlref's ``ref`` and the port's ``test``; a non-finite port value where vlref's is
    compared (finite) is a failing pixel (set to float32's max), not bad input."""
    tol = tolerance(preset)
    t = np.asarray(test, dtype=np.float64)
    t = t[:, :, None] if t.ndim == 2 else t
    compared = np.ones(t.shape[:2], bool) if mask is None else mask
    t = np.where(~np.isfinite(t) & compared[:, :, None], float(np.finfo(np.float32).max), t)
    report = compare_arrays(ref, t, tol, mask, flip=False, names=names, edges=zone)
    return _judged(name, group, report, signal, buffer)


def _camera_check(port, scene_camera) -> _Comparison:
    c = port.camera
    diffs = {"position": float(np.max(np.abs(c.position - scene_camera.position)))
             / (1.0 + float(np.linalg.norm(scene_camera.position))),
             "rotation": float(np.max(np.abs(c.rotation - scene_camera.rotation))),
             "fov": abs(c.fov - scene_camera.fov)}
    bad = [f"{k} differs by {v:.3g} (> {CAMERA_TOL:g})" for k, v in diffs.items() if not v <= CAMERA_TOL]
    metrics = {"margins": {k: margin(v, CAMERA_TOL) for k, v in diffs.items()}}
    reason = "the port's camera is not the scene's: " + ", ".join(bad) if bad else ""
    return _Comparison("camera", GROUP_SCENE, "-", None, reason, metrics)


def _scene_without_shadows(scene):
    return scene.replace(lights=tuple(dataclasses.replace(li, shadows=None) for li in scene.lights))


def _nudged(port, frame_p, sign: int):
    """The port's frame with every light moved by ``sign · KNIFE_EDGE · (1 + |position|)`` along (1, 1, 1)/√3
    and every shadow-map distance scaled by ``1 + sign · KNIFE_EDGE``."""
    step = sign * KNIFE_EDGE
    scene = port.scene.replace(lights=tuple(
        dataclasses.replace(li, position=tuple(np.asarray(li.position, dtype=np.float64)
                                               + step * (1.0 + np.linalg.norm(li.position)) / math.sqrt(3.0)))
        for li in port.scene.lights))
    cache = {k: ShadowMaps(m.ints, m.floats, (m.data * np.float32(1.0 + step)).astype(np.float32), m.tint, m.names)
             for k, m in frame_p.shadow_cache.items()}
    return scene, dataclasses.replace(frame_p, scene=scene, lights=pack_lights(scene), shadow_cache=cache)


def knife_edges(port, frame_p, technique) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per float image buffer of the technique: ``(jump, lo, hi)``, the (h, w) bool knife-edge pixels and the
    buffer rendered with the lights moved by ``∓KNIFE_EDGE`` (relative) and the map distances scaled by
    ``1 ∓ KNIFE_EDGE``. A jump pixel's march sample lies on a discrete decision (a shadow-volume boundary, a
    shadow-map texel boundary, a light cone's surface) that a float32 port may take either way: its value
    changes by more than ``KNIFE_JUMP · (|value| + mean |value|)`` in a channel (continuous changes are
    ~KNIFE_EDGE). Downstream passes (upsample, blur, composite) carry the jump, so each buffer's own pixels
    are marked; ``lo`` and ``hi`` are the two decisions (``(h, w, C)``)."""
    lo = technique.render(*_nudged(port, frame_p, -1))
    hi = technique.render(*_nudged(port, frame_p, 1))
    out = {}
    for name, a in lo.items():
        a, b = np.asarray(a), np.asarray(hi.get(name))
        if a.dtype.kind != "f" or a.ndim not in (2, 3) or b.shape != a.shape:
            continue
        a, b = (x[:, :, None] if x.ndim == 2 else x for x in (a, b))
        finite = np.isfinite(a) & np.isfinite(b)
        level = float(np.mean(np.abs(a[finite]))) if finite.any() else 0.0
        fa, fb = np.where(finite, a, 0.0), np.where(finite, b, 0.0)
        jump = np.where(finite, np.abs(fb - fa) > KNIFE_JUMP * (np.abs(fa) + level), a != b)
        out[name] = (jump.any(axis=2), a, b)
    return out


def rounding_spread(port, frame_p, technique, own: dict) -> dict[str, np.ndarray]:
    """Per float image buffer of the technique: ``(h, w, C)`` how far vlref's value moves when the port's camera
    depths round differently: the buffer rendered with ``depth · (1 + DEPTH_ROUNDING · s)`` for each sign
    pattern ``s`` of :func:`rounding_patterns`, its largest change from ``own`` (vlref's buffers on the port's
    depth). A depth-aware pass weighs a tap by ``1 / (|z - z_k| + ε)`` (ε = 1 mm): a float32 decode moves
    ``z - z_k`` by up to 8 ulp of z (~1e-6 z) and the weight by up to ``1e-6 z / ε``, far over float32's 1e-4
    at 10 m, and the blur passes sum such changes over their taps."""
    spread: dict[str, np.ndarray] = {}
    for signs in rounding_patterns(port.depth):
        moved = dataclasses.replace(port, depth=port.depth * (1.0 + DEPTH_ROUNDING * signs))
        for name, a in technique.render(port.scene, port_frame(moved)).items():
            a, b = np.asarray(a), np.asarray(own.get(name))
            if a.dtype.kind != "f" or a.ndim not in (2, 3) or b.shape != a.shape:
                continue
            with np.errstate(invalid="ignore"):
                d = np.nan_to_num(np.abs(a - b), nan=0.0, posinf=0.0)
            d = d[:, :, None] if d.ndim == 2 else d
            spread[name] = np.maximum(spread.get(name, d), d)
    return spread


def rounding_patterns(depth: np.ndarray) -> list[np.ndarray]:
    """Eight (H, W) patterns of signs ±1 keyed by the stored depth value: bit ``b`` of the rank of the pixel's depth
    among the frame's distinct depths, modulo 16, and the four negated (a min-depth downsample picks another texel
    only when the nearer of two depths moves away and the other closer: one direction of the pair). A port decodes
    each stored value by one formula, so pixels of one stored depth round alike (a level camera sees a ground plane's
    rows at one depth each: the bilateral taps along such a row are equally deep in any decode, and moving them
    apart would invent the spread of a 1 mm guard at every ground pixel); two distinct depths less than 16 apart in
    rank differ in one of the bits, so some pattern moves them in opposite directions, each way round."""
    z = np.asarray(depth, dtype=np.float64)
    _, rank = np.unique(np.where(np.isfinite(z), z, np.inf), return_inverse=True)
    code = rank.reshape(z.shape) % 16
    signs = [np.where((code >> b) & 1, 1.0, -1.0) for b in range(4)]
    return signs + [-s for s in signs]


def _either_decision(ref: np.ndarray, test: np.ndarray, knife) -> np.ndarray:
    """``ref`` with each knife-edge pixel replaced by whichever of vlref's decisions (``ref``, ``lo``, ``hi``)
    lies closest to the port's value (largest channel difference): a knife-edge decision may go either way.
    A pixel fed by several knife-edge samples (an upsampled or blurred one) may take some one way and some the
    other: the port's value is then moved toward the chosen decision by up to ``|hi - lo|`` per channel."""
    jump, lo, hi = knife
    options = np.stack([ref, lo, hi])
    with np.errstate(invalid="ignore"):
        dist = np.nan_to_num(np.abs(options - test[None]), nan=np.inf).max(axis=3)
    pick = np.argmin(dist, axis=0)
    chosen = np.take_along_axis(options, pick[None, :, :, None], axis=0)[0]
    with np.errstate(invalid="ignore"):
        mixed = _within(chosen, test, np.nan_to_num(np.abs(hi - lo), nan=0.0, posinf=0.0))
    return np.where(jump[:, :, None], mixed, ref)


def _knife_spread(knife: dict) -> dict[str, np.ndarray]:
    """Per buffer ``|hi - lo|`` of :func:`knife_edges`: how far vlref's value moves with the lights and the map
    distances moved by ``KNIFE_EDGE`` (~100x float32's rounding of the positions a port computes its march
    samples and lookups with; a ray passing a point light within centimetres amplifies a port's rounding past
    1e-4 of the march, 13 pixels of the WebGPU port's 1280x720 frame on lavapipe)."""
    out = {}
    for name, (_, lo, hi) in knife.items():
        with np.errstate(invalid="ignore"):
            out[name] = np.nan_to_num(np.abs(hi - lo), nan=0.0, posinf=0.0)
    return out


def _sensitive(tol, ref: np.ndarray, spread: np.ndarray, share: float) -> np.ndarray:
    """(h, w) bool: the finite pixels of ``ref`` (``(h, w, C)``) where ``spread`` exceeds ``share`` of the preset's
    per-pixel threshold ``abs_tol · S + rel_tol · |ref|`` in a channel."""
    finite = np.isfinite(ref)
    compared = finite.all(axis=2)
    if not compared.any():
        return compared
    r = np.where(finite, ref, 0.0)
    s = scale_of(tol, r, compared)
    return np.any(spread > share * (tol.abs_tol * s + tol.rel_tol * np.abs(r)), axis=2) & compared


def _rounding_allowance(tol, own: dict, rounding: dict, knife_spread: dict, buffer: str):
    """``(zone, widen)`` of ``buffer``: where float32 rounding of the port's inputs, not the pass, can decide whether
    a pixel passes ((h, w) bool; the preset's edge tolerance applies there), and by how much vlref's value may move
    ((h, w, C), :func:`_within`). The zone holds every pixel within ``ROUNDING_REACH`` of a pixel of some buffer of
    its size whose depth-rounding spread (:func:`rounding_spread`) exceeds ``ROUNDING_ZONE`` of the threshold, and
    the buffer's own pixels that the knife-edge nudges move by more than ``KNIFE_ZONE`` of it (a decision, or its
    blurred share). Every pixel may move by ``ROUNDING_SAFETY`` times its depth spread or by the nudges' whole
    change ``|hi - lo|``, whichever is larger: that change measures how a pixel's march amplifies the rounding of
    positions (near a point light a float32 march errs by up to ~1e-4, as much as the nudges move it; elsewhere
    the change is a fifth of float32's threshold)."""
    ref = _as_3d(own[buffer])
    shape = ref.shape[:2]
    depth = np.zeros(shape, bool)
    for name, d in rounding.items():
        if d.shape[:2] == shape:
            depth |= _sensitive(tol, _as_3d(own[name]), d, ROUNDING_ZONE)
    zone = dilate(depth, ROUNDING_REACH) | _sensitive(tol, ref, knife_spread[buffer], KNIFE_ZONE)
    widen = knife_spread[buffer]
    if buffer in rounding and rounding[buffer].shape == ref.shape:
        widen = np.maximum(widen, ROUNDING_SAFETY * rounding[buffer])
    return zone, widen


def _as_3d(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    return a[:, :, None] if a.ndim == 2 else a


def _within(ref: np.ndarray, test: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """The value within ``spread`` of ``ref`` closest to ``test`` (per channel): ``ref`` where ``test`` is farther,
    ``test`` itself where it is within; non-finite values keep ``ref``."""
    ok = np.isfinite(ref) & np.isfinite(test)
    return np.where(ok, np.clip(np.where(ok, test, 0.0), ref - spread, ref + spread), ref)


def _own_passes(port, frame_p, own: dict, preset: str, reference: dict, technique,
                memo: dict | None = None) -> list[_Comparison]:
    """The ``[[passes]]`` against ``vlref march`` on the port's own buffers. A pass whose buffer carries a
    signal in vlref's render of the scene (``reference``: nonzero somewhere) but is zero over every compared
    pixel of the march on the port's buffers fails as degenerate. ``memo`` keeps the knife-edge pixels and
    edge zones of these buffers for the next call (:func:`judge`'s cache)."""
    if not port.passes:
        return [_Comparison("passes", GROUP_OWN, "-", None, "the manifest declares no [[passes]]: the port's "
                                                           "march and post passes are not judged")]
    hit = np.isfinite(port.depth)
    points = frame_p.gbuffer.position[hit]
    memo = {} if memo is None else memo
    zones: dict[int, np.ndarray] = memo.setdefault("zones", {})
    if "knife" not in memo:
        memo["knife"] = knife_edges(port, frame_p, technique)
    knife = memo["knife"]
    knife_spread = _knife_spread(knife)
    out = []
    for k, p in enumerate(port.passes):
        if p.buffer not in own or np.asarray(own[p.buffer]).dtype.kind != "f":
            known = ", ".join(sorted(n for n, a in own.items() if np.asarray(a).dtype.kind == "f"))
            raise InputError(port.source, f"passes[{k}].buffer", f"vlref's {port.scene.render.technique} has no "
                                                                  f"buffer {p.buffer!r} (its buffers: {known})")
        name_preset = p.preset or preset
        tol = tolerance(name_preset)
        if tol.edge_pixels not in zones:
            surface = _on_pixels(shadow_zone(frame_p.shadow_maps(), frame_p.lights, points, tol.edge_pixels), hit, False)
            zones[tol.edge_pixels] = (edge_zone(tol.edge_pixels, depths=[port.depth], features=[surface])
                                      if tol.edge_pixels > 0 else np.zeros(hit.shape, bool))
        ref = _as_3d(own[p.buffer])
        fits = ref.shape[0] <= hit.shape[0] and ref.shape[1] <= hit.shape[1] and p.image.shape == ref.shape
        zone = block_any(zones[tol.edge_pixels], ref.shape[:2]) if fits else None
        if fits and p.buffer in knife and knife[p.buffer][0].shape == ref.shape[:2]:
            ref = _either_decision(ref, p.image, knife[p.buffer])
            zone = zone | knife[p.buffer][0]
        rounding = {}
        if tol.rel_tol < ROUNDING_PRESETS and not p.buffer.startswith("depth"):
            if "rounding" not in memo:
                memo["rounding"] = rounding_spread(port, frame_p, technique, own)
            rounding = memo["rounding"]
        if fits and p.buffer in knife_spread and knife_spread[p.buffer].shape == ref.shape:
            rounding_zone, widen = _rounding_allowance(tol, own, rounding, knife_spread, p.buffer)
            zone = zone | rounding_zone
            ref = _within(ref, p.image, widen)
        mask = np.isfinite(ref).all(axis=2) if p.ignore_sky else None
        signal = p.buffer in reference and bool(np.any(np.asarray(reference[p.buffer]) != 0))
        out.append(_compare(p.name, GROUP_OWN, ref, p.image, name_preset, mask, zone, signal, p.buffer,
                            (f"vlref march {p.buffer}", p.path)))
    return out


def _port_digest(port) -> str:
    """A digest of what vlref's march on a port reads: its scene, camera, depth, colour and shadow maps."""
    h = hashlib.sha256(scene_hash(port.scene).encode())
    h.update(repr((port.camera, port.has_shadows)).encode())
    for a in (port.depth, port.colour, *(t.texels for m in port.shadow_maps for t in m.tiles)):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def judge(manifest, out_dir=None, preset: str | None = None, overrides: Sequence[str] = (), *,
          cache: dict | None = None) -> Verdict:
    """The whole-frame verdict on the port of ``manifest`` (module docstring); with ``out_dir``, writes
    verdict.json, index.html and one report folder per comparison there (all or nothing).

    ``preset``: the preset of ``[[passes]]`` entries that name none and of a manifest without ``preset``
    (default :data:`DEFAULT_PRESET`); ``overrides``: ``--set`` overrides of the scene. ``cache``: a dict the
    caller keeps across calls: vlref's render of a scene, and its march (with the knife-edge pixels) on a
    port's buffers, are kept there by content (scene hash; a digest of the port's raster buffers), so that
    judging many variants of one port re-renders nothing they share. Raises :class:`InputError` on bad input
    (unknown preset, missing shadow map of a shadowed light, a pass naming no vlref buffer, sizes that differ).
    """
    port = load_port(manifest, overrides)
    _check_presets(port, preset)
    verdict, comparisons, _ = _judge_frame(manifest, port, preset, out_dir, {} if cache is None else cache, None)
    if out_dir is not None:
        write_verdict(verdict, comparisons, out_dir)
    return verdict


def judge_sequence(manifests: Sequence, out_dir=None, preset: str | None = None, overrides: Sequence[str] = (),
                   *, cache: dict | None = None) -> SequenceVerdict:
    """The whole-frame verdict on every frame of a sequence of port manifests, in order (the frames of
    ``vlref march A.toml B.toml ...``): frame ``i`` is judged as :func:`judge` judges one manifest, but with
    temporal state carried on both sides. On its own buffers, vlref's march on frame ``i``'s buffers is
    given the history of its march on frames ``0 .. i-1`` (:func:`vlref.port.march_sequence`); against the
    scene, vlref's render of frame ``i`` is given the history of its renders of frames ``0 .. i-1``
    (:func:`vlref.sequence.render_sequence`), so a port's reprojection, clamp and accumulation meet the
    scene's too. The first frame starts without history on both sides.

    With ``out_dir``: ``frame_NNNN/`` (NNNN the frame's index in ``manifests``) holding that frame's
    verdict.json, index.html and reports, plus the sequence's verdict.json and index.html naming the frame
    and pass of every failure (all or nothing). Every manifest is read and every preset checked before any
    work. ``preset``, ``overrides`` and ``cache`` as for :func:`judge` (cache entries are keyed by the
    frame's content and by every frame before it)."""
    if not manifests:
        raise InputError("<command line>", "manifest", "no port manifest to judge")
    ports = [load_port(m, overrides) for m in manifests]
    for port in ports:
        _check_presets(port, preset)
    cache = {} if cache is None else cache
    frames, written, state = [], [], None
    for i, (manifest, port) in enumerate(zip(manifests, ports)):
        folder = None if out_dir is None else Path(out_dir) / _frame_folder(i)
        verdict, comparisons, state = _judge_frame(manifest, port, preset, folder, cache, state)
        frames.append(verdict)
        written.append(comparisons)
    result = SequenceVerdict(all(v.passed for v in frames), tuple(frames))
    if out_dir is not None:
        with output_dir(out_dir) as tmp:
            for i, (verdict, comparisons) in enumerate(zip(frames, written)):
                _write_files(verdict, comparisons, tmp / _frame_folder(i))
            write_text(tmp / "verdict.json", json.dumps(json_ready(result.to_dict()), indent=2, allow_nan=False)
                       + "\n")
            write_text(tmp / "index.html", _sequence_html(result))
    return result


def _frame_folder(index: int) -> str:
    return f"frame_{index:04d}"


def _check_presets(port, preset: str | None) -> None:
    """Unknown presets are bad input before any work."""
    own_preset = port.preset or preset or DEFAULT_PRESET
    for name in {own_preset, *(p.preset for p in port.passes if p.preset), *SCENE_PRESETS.values()}:
        tolerance(name)


def _judge_frame(manifest, port, preset: str | None, out_dir, cache: dict, previous):
    """``(verdict, comparisons, state)`` of one frame; ``previous`` is the state of the frame before it (None:
    no history): the cache keys of vlref's render of the scene and of its march on the port's buffers, under
    which their histories are kept, so that each key names the frame's content and all the frames before it
    that left a history (a frame after one without history, e.g. of a technique without temporal state, is
    keyed by its content alone and shares the cache with a first frame)."""
    own_preset = port.preset or preset or DEFAULT_PRESET
    technique = TECHNIQUES[port.scene.render.technique]
    scene_before, port_before = (key if key is not None and cache[key][3] is not None else None
                                 for key in (previous if previous is not None else (None, None)))

    scene = port.scene if port.has_shadows else _scene_without_shadows(port.scene)
    scene_key = ("scene", scene_hash(scene), scene_before)
    if scene_key not in cache:
        frame = prepare_frame(scene)
        frame.history = cache[scene_before][3] if scene_before is not None else None
        reference = technique.render(frame.scene, frame)
        history = reference.pop("history", None)
        cache[scene_key] = frame, reference, bool(np.any(np.asarray(reference["inscatter"]) > 0)), history
    frame, reference, light_reaches, _ = cache[scene_key]
    port_key = ("port", _port_digest(port), port_before)
    if port_key not in cache:
        frame_p = port_frame(port)
        frame_p.history = cache[port_before][3] if port_before is not None else None
        own = technique.render(port.scene, frame_p)
        history = own.pop("history", None)
        cache[port_key] = frame_p, own, {}, history
    frame_p, own, memo, _ = cache[port_key]

    comparisons = _own_passes(port, frame_p, own, own_preset, reference, technique, memo)
    comparisons.append(_camera_check(port, frame.camera))
    comparisons += _against_scene(port, frame, frame_p, reference, light_reaches, memo)
    passes = tuple(PassVerdict(c.name, c.group, c.preset, not c.reason, c.reason, _metrics(c),
                               str(Path(out_dir) / _slug(c.group) / _slug(c.name) / "report.html")
                               if out_dir is not None and c.report is not None else None) for c in comparisons)
    verdict = Verdict(all(p.passed for p in passes), str(manifest), own_preset, passes)
    return verdict, comparisons, (scene_key, port_key)


def _against_scene(port, frame, frame_p, reference: dict, light_reaches: bool,
                   memo: dict | None = None) -> list[_Comparison]:
    """The port's depth, shadow maps, shadow decisions, scene colour and final frame against the scene;
    ``memo`` keeps what depends on the raster buffers only (all but ``end_to_end``) for the next call."""
    memo = {} if memo is None else memo
    if "against" not in memo:
        memo["against"] = _raster_against_scene(port, frame, frame_p, memo)
    out = list(memo["against"])
    if port.final is None:
        out.append(_Comparison("end_to_end", GROUP_SCENE, SCENE_PRESETS["end_to_end"], None,
                               "the manifest declares no `final`: the port's frame is not judged against the scene"))
    else:
        out.append(_compare("end_to_end", GROUP_SCENE, reference["final"], port.final, SCENE_PRESETS["end_to_end"],
                            None, memo["shading_zone"]("end_to_end"), light_reaches, "final",
                            ("vlref render final", "port final")))
    return out


def _raster_against_scene(port, frame, frame_p, memo: dict) -> list[_Comparison]:
    """The port's depth, shadow maps, shadow decisions and scene colour against the scene; puts the
    shading-zone function in ``memo["shading_zone"]``."""
    g = frame.gbuffer
    hit = np.isfinite(g.depth)
    points = g.position[hit]
    maps_ref, maps_port = frame.shadow_maps(), frame_p.shadow_maps()
    packed = frame.lights
    out = []

    def k_of(kind):
        return tolerance(SCENE_PRESETS[kind]).edge_pixels

    depth_edges = depth_discontinuities(g.depth) | depth_discontinuities(port.depth) | _creases(g.normal, hit)
    # the depth comparison's own zone finds every step it could fail on: a contact edge (a cylinder's foot on
    # the ground) steps 1/z by ~4 %, under DEPTH_JUMP but over raster-depth's tolerance
    jump = tolerance(SCENE_PRESETS["depth"]).rel_tol / 2.0
    steps = depth_discontinuities(g.depth, jump) | depth_discontinuities(port.depth, jump)
    out.append(_compare("depth", GROUP_SCENE, _inverse(g.depth), _inverse(port.depth), SCENE_PRESETS["depth"], None,
                        dilate(steps, k_of("depth")), False, "depth", ("vlref ray-cast depth", "port depth")))

    for m in port.shadow_maps:
        i = m.light
        if not (_mapped(maps_ref, i) and _mapped(maps_port, i)):
            continue
        light, sh = port.scene.lights[i], port.scene.lights[i].shadows
        ref_tiles, port_tiles, zones = [], [], []
        k = k_of("shadow_map")
        for tile in m.tiles:
            r, p = _port_tile_distances(tile, light, sh, m.encoding, m.convention, frame.geometry)
            ref_tiles.append(r)
            port_tiles.append(p)
            zones.append(dilate(depth_discontinuities(r, MAP_JUMP) | depth_discontinuities(p, MAP_JUMP), k))
        out.append(_compare(f"shadow_map[light={i}]", GROUP_SCENE, _inverse(np.hstack(ref_tiles)),
                            _inverse(np.hstack(port_tiles)), SCENE_PRESETS["shadow_map"], None, np.hstack(zones),
                            False, f"shadow map of light {i}",
                            (f"vlref map of light {i} through the port's texel rays", f"port map of light {i}")))
        k = k_of("shadow_test")
        zone = shadow_zone(maps_ref, packed, points, k) | shadow_zone(maps_port, packed, points, k)
        reached = _on_pixels(_inside_volume(light, points), hit, False)
        if not reached.any():   # the light reaches no visible surface: no decision of its maps shows
            continue
        out.append(_compare(f"shadow_test[light={i}]", GROUP_SCENE,
                            _on_pixels(_lit(maps_ref, packed, i, points), hit),
                            _on_pixels(_lit(maps_port, packed, i, points), hit), SCENE_PRESETS["shadow_test"],
                            reached,
                            dilate(_on_pixels(zone, hit, False) | depth_edges, k), False, f"lit fraction of light {i}",
                            (f"vlref map lookups of light {i} at the visible surface points",
                             f"port map lookups of light {i}")))

    zones: dict[str, np.ndarray] = {}

    def shading_zone(kind):
        if kind not in zones:
            k = k_of(kind)
            reach = k + LOOKUP_OFFSET_TEXELS
            zone = silhouette_zone(maps_ref, packed, points, reach) | silhouette_zone(maps_port, packed, points, reach)
            zones[kind] = dilate(_on_pixels(zone, hit, False) | depth_edges, k)
        return zones[kind]

    out.append(_compare("scene_colour", GROUP_SCENE, frame.scene_colour, port.colour, SCENE_PRESETS["scene_colour"],
                        None, shading_zone("scene_colour"), False,
                        "scene_colour", ("vlref scene colour", "port colour")))
    memo["shading_zone"] = shading_zone
    return out


def _metrics(c: _Comparison) -> dict:
    if c.report is None:
        return dict(c.metrics)
    m = c.report.metrics
    keys = ("compared_pixels", "failing_pixels", "failing_pixels_edge", "edge_pixels", "max_abs", "mean_abs",
            "mean_abs_outside_edges", "ref_mean_abs", "zone_mean_signed")
    return {**{k: m[k] for k in keys}, "margins": c.report.margins()}


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_")


# --------------------------------------------------------------------------- files

def write_verdict(verdict: Verdict, comparisons: Sequence[_Comparison], out_dir) -> None:
    """verdict.json, index.html and each comparison's report folder (:func:`vlref.oracle.report.write_outputs`)
    into ``out_dir``, all or nothing."""
    with output_dir(out_dir) as tmp:
        _write_files(verdict, comparisons, tmp)


def _write_files(verdict: Verdict, comparisons: Sequence[_Comparison], folder: Path) -> None:
    """What :func:`write_verdict` writes, into ``folder`` (created)."""
    folder.mkdir(parents=True, exist_ok=True)
    for c in comparisons:
        if c.report is not None:
            write_outputs(c.report, folder / _slug(c.group) / _slug(c.name))
    write_text(folder / "verdict.json", json.dumps(json_ready(verdict.to_dict()), indent=2, allow_nan=False) + "\n")
    write_text(folder / "index.html", _index_html(verdict))


def _sequence_html(result: SequenceVerdict) -> str:
    """The sequence's page: one row per frame (its manifest, outcome and failing comparisons, linking to the
    frame's own index.html and to each failing report)."""
    rows = []
    for i, v in enumerate(result.frames):
        folder = _frame_folder(i)
        bad = [p for p in v.passes if not p.passed]
        links = ", ".join(f'<a href="{folder}/{_slug(p.group)}/{_slug(p.name)}/report.html">{html.escape(p.name)}</a>'
                          if p.report else html.escape(p.name) for p in bad) or "-"
        style = "" if v.passed else ' style="color:#cf222e"'
        rows.append(f'<tr{style}><td><a href="{folder}/index.html">{i}</a></td><td>{html.escape(v.manifest)}</td>'
                    f"<td>{'PASS' if v.passed else 'FAIL'}</td><td>{len(v.passes) - len(bad)} of {len(v.passes)}</td>"
                    f"<td>{links}</td></tr>")
    return _page(result.passed, f"vlref verdict of {len(result.frames)} frames", f"""
<p>Each frame judged on the port's own buffers and against the scene, temporal state carried on both sides.</p>
<table><tr><th>frame</th><th>manifest</th><th>result</th><th>comparisons passed</th><th>failing</th></tr>
{''.join(rows)}</table>
""")


def _page(passed: bool, heading: str, body: str) -> str:
    """A verdict page: ``heading: PASS`` (green) or ``FAIL`` (red), then ``body`` (HTML)."""
    word = "PASS" if passed else "FAIL"
    colour = "#1a7f37" if passed else "#cf222e"
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>vlref verdict: {word}</title>
<style>body {{ font-family: system-ui, sans-serif; margin: 1.5em; }} h1 span {{ color: {colour}; }}
table {{ border-collapse: collapse; font-size: 0.9em; }} td, th {{ border: 1px solid #d0d7de; padding: 2px 8px; }}
img {{ image-rendering: pixelated; }}</style></head><body>
<h1>{heading}: <span>{word}</span></h1>{body}</body></html>
"""


def _index_html(verdict: Verdict) -> str:
    """The verdict page: the table (failing rows first in red, each linking to its report) and, for each
    failing comparison with images, its heat map of |port - vlref|."""
    rows, figures = [], []
    for p in sorted(verdict.passes, key=lambda p: p.passed):
        rel = f"{_slug(p.group)}/{_slug(p.name)}/report.html" if p.report else None
        link = f'<a href="{rel}">{html.escape(p.name)}</a>' if rel else html.escape(p.name)
        m = p.metrics
        fail = f"{m['failing_pixels']} of {m['compared_pixels']}" if "compared_pixels" in m else "-"
        margins = ", ".join(f"{html.escape(k)} {_fmt_margin(v)}" for k, v in m.get("margins", {}).items())
        style = "" if p.passed else ' style="color:#cf222e"'
        rows.append(f"<tr{style}><td>{link}</td><td>{html.escape(p.group)}</td><td>{html.escape(p.preset)}</td>"
                    f"<td>{'PASS' if p.passed else 'FAIL'}</td><td>{fail}</td><td>{margins}</td>"
                    f"<td>{html.escape(p.reason)}</td></tr>")
        if not p.passed and rel:
            figures.append(f'<figure><figcaption>{html.escape(p.name)} ({html.escape(p.group)}): |port - vlref|'
                           f'</figcaption><a href="{rel}"><img src="{_slug(p.group)}/{_slug(p.name)}/heatmap.png" '
                           f'width="480"></a></figure>')
    return _page(verdict.passed, "vlref verdict", f"""
<p>{html.escape(verdict.manifest)}: a port passes when every comparison passes, on its own buffers and against
the scene.</p>
<table><tr><th>pass</th><th>group</th><th>preset</th><th>result</th><th>failing pixels</th><th>margins</th>
<th>reason</th></tr>{''.join(rows)}</table>
{''.join(figures)}
""")
