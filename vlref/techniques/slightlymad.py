"""The ``slightlymad`` technique: SlightlyMad/VolumetricLights, pass by pass (SOURCES §1).

Passes (``docs/TECHNIQUES.md`` lists formulas, constants and quirks):

1. depth: raw device depth of the camera (``depth_convention``), chessboard-downsampled to the march
   resolution (``downsample_vl``), linearised (``depth_march``, metres; the far plane on sky);
2. per light, in scene order: its ray segment (:func:`light_segments`) and the ``RayMarch`` loop
   (:func:`vlref.march.slightlymad.vl_march`) into an RGBA buffer cleared to (0, 0, 0, 1), blended
   additively (rounded to fp16 after each blend); directional lights overwrite alpha
   (``march``, one ``light{i}`` buffer per light before blending);
3. bilateral blur H then V (``blur_h``, ``blur_v``), 4. bilateral upsample to full resolution
   (``upsample``, half/quarter only), 5. ``BlitAdd`` composite (``final``).

``inscatter`` is the upsampled RGB, ``transmittance`` its alpha.
"""

from __future__ import annotations

import math

import numpy as np

from ..camera import linear_to_raw, look_rotation, raw_to_linear
from ..errors import InputError
from ..lights.attenuation import ATTENUATION_CODES, UNITY
from ..lights.cone import CONE_CODES
from ..lights.cookies import load_cookie
from ..lights.pack import F_CB, F_CR, KIND_CODES, KIND_DIRECTIONAL, pack_lights
from ..march.segments import volume_intervals
from ..march.slightlymad import (CONE_COOKIE_ONLY, VlLight, VlMarch, dither_offsets, spot_profile_cookie, vl_march,
                                 vl_view_tau)
from ..medium import pack_medium
from ..post.blur import vl_blur_pass
from ..post.composite import FP16_MAX, blend_add_fp16, composite_vl, fp16
from ..post.downsample import downsample_max, downsample_min, downsample_vl
from ..post.resolution import low_res_size
from ..post.upsample import vl_upsample
from ..scene.model import Cookie, HeightFog, Medium, Noise
from ..scene.technique_params import resolved

__all__ = ["render", "notes", "light_segments", "vl_medium", "srgb_to_linear", "cone_mesh_planes"]

SKY_LINEAR01 = 0.999999
"""VL's sky test: ``Linear01Depth > 0.999999`` (§1.4)."""
SPOT_MESH_SIDES = 16
LIGHT_VOLUME_NEAR = 0.01
"""VL rebuilds the light-volume projection with near = 0.01 (§1.2): volumes closer than this are clipped."""
OWN_NOISE_PERIOD = 32


def srgb_to_linear(c) -> np.ndarray:
    """Unity's ``Color.linear`` (sRGB EOTF per channel, the power branch extended above 1): quirk 14."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def vl_coefficients(scene, p) -> tuple[float, float]:
    """``(σs, σt)`` of the march: VL's parameters, or the scene's ``[medium]`` when ``medium = "scene"``.
    HG's ``g`` (``MieG``) is the packed medium's anisotropy (:func:`vl_medium`)."""
    if p.medium == "scene":
        m = scene.medium
        return m.scattering, m.extinction
    return p.scattering, p.extinction


def vl_medium(scene, p):
    """The VL density as a :class:`~vlref.scene.model.Medium` for :func:`vlref.medium.pack_medium`.

    With ``medium = "scene"`` it is the scene's own medium.

    Height fog ``exp(-(y + GroundLevel) HeightScale)`` = base ``-GroundLevel``, falloff ``HeightScale``.
    Noise sampled at ``frac(s x + t s v)`` in texture space = lattice scale ``n s`` cells per metre
    (``n`` = 128 for ``NoiseVolume.bytes``, 32 for ours) and velocity ``-v`` (vlref's field moves by
    ``+v t``, VL's by ``-v t``).
    """
    if p.medium == "scene":
        return scene.medium
    fog = HeightFog(base=-p.ground_level, falloff=p.height_scale) if p.height_fog else None
    noise = None
    if p.noise:
        n = 128 if p.noise_path is not None else OWN_NOISE_PERIOD
        noise = Noise(scale=n * p.noise_scale, intensity=p.noise_intensity, offset=p.noise_intensity_offset,
                      velocity=(-p.noise_velocity[0], 0.0, -p.noise_velocity[1]), period=OWN_NOISE_PERIOD,
                      path=p.noise_path)
    return Medium(scattering=p.scattering, absorption=0.0, anisotropy=p.mie_g, height_fog=fog, noise=noise)


def cone_mesh_planes(light) -> np.ndarray:
    """Half-spaces ``n·x <= c`` (rows ``(nx, ny, nz, c)``, world) of VL's 16-sided spot mesh (§1.3).

    The mesh is a pyramid: apex at the light, a regular 16-gon cap of circumradius ``R tan θc`` at
    distance ``R`` along the axis, ``θc = (spot_angle + 1°)/2``; ring vertex ``k`` at angle
    ``2πk/16`` with light-local ``x = -cos, y = sin``.
    """
    rot = look_rotation(light.direction)
    r = light.range * math.tan(math.radians(light.spot_angle + 1.0) / 2.0)
    ang = 2.0 * math.pi * np.arange(SPOT_MESH_SIDES + 1) / SPOT_MESH_SIDES
    ring = np.stack([-np.cos(ang) * r, np.sin(ang) * r, np.full(ang.shape, light.range)], axis=1) @ rot.T
    p = np.asarray(light.position, dtype=np.float64)
    planes = []
    for k in range(SPOT_MESH_SIDES):
        n = np.cross(ring[k], ring[k + 1])
        n /= np.linalg.norm(n)
        if n @ rot[:, 2] > 0.0:
            n = -n
        planes.append([*n, n @ p])
    a = rot[:, 2]
    planes.append([*a, a @ p + light.range])
    return np.asarray(planes)


def _convex_interval(planes, cam, dirs):
    """Entry and exit distances of the rays ``cam + t d`` through the convex set ``n·x <= c`` (inf-safe)."""
    n, c = planes[:, :3], planes[:, 3]
    nd = dirs @ n.T
    dist = c - n @ cam
    with np.errstate(divide="ignore", invalid="ignore"):
        t = dist / nd
    enter = np.where(nd < 0.0, t, -np.inf).max(axis=-1)
    leave = np.where(nd > 0.0, t, np.inf).min(axis=-1)
    parallel_out = ((nd == 0.0) & (dist < 0.0)).any(axis=-1)
    leave = np.where(parallel_out, -np.inf, leave)
    return enter, leave


def _cone_interval(light, cam, dirs, half_angle_deg):
    """Entry and exit of the analytic cone of half-angle ``half_angle_deg`` capped at ``range`` along the axis."""
    a = look_rotation(light.direction)[:, 2]
    p = np.asarray(light.position, dtype=np.float64)
    cos_h = math.cos(math.radians(half_angle_deg))
    big = light.range / cos_h * 1.001
    enter, leave = volume_intervals(cam, dirs, p, a, cos_h, big, True, -1e9, 1e9)
    # the flat cap: a.(x - p) <= R
    cap = np.asarray([[*a, a @ p + light.range]])
    e2, l2 = _convex_interval(cap, cam, dirs)
    return np.maximum(enter, e2), np.minimum(leave, l2)


def light_segments(light, cam, dirs, t_surf, params, max_ray_length):
    """VL's ray segment per march pixel (§1.3): ``(t0, length, covered)``, each (h, w).

    * directional: ``t0 = 0``, ``L = min(t_surf, MaxRayLength)``, every pixel covered;
    * point: camera inside ``|p - c| < R + 1``: ``t0 = 0``, ``L = min(t_exit, t_surf)``; outside:
      ``t0`` = sphere entry, ``L = min(t_exit, t_surf) - t0`` (negative when hidden: clamps to 0);
    * spot (cone ``θc = (spot_angle + 1°)/2`` capped at ``R``): inside (``a·(c - p) <= R + 1`` and the
      angle to the axis ``<= (spot_angle + 3°)/2``): ``t0 = 0``, ``L = min(t_exit, t_surf)``; outside:
      ``t0`` = the volume's entry, ``L = min(t_exit - (t0 + 0.001), t_surf - t0)`` (the shader measures
      the exit from ``w + 0.001 d``). With ``light_mesh = "unity"`` entry (and the inside exit) come from
      the 16-sided mesh, the outside exit from the analytic +1° cone, as in the shader.

    A pixel is covered when the volume's front face (back face for the inside passes) lies beyond the
    light-volume near plane (0.01 m).
    """
    h, w = t_surf.shape
    if light.type == "directional":
        return np.zeros((h, w)), np.minimum(t_surf, max_ray_length), np.ones((h, w), dtype=bool)
    p = np.asarray(light.position, dtype=np.float64)
    R = light.range
    if light.type == "point":
        enter, leave = volume_intervals(cam, dirs, p, p, 1.0, R, False, -1e9, 1e9)
        inside = np.sum((p - cam) ** 2) < (R + 1.0) ** 2
        a_exit = leave
    else:
        axis = look_rotation(light.direction)[:, 2]
        v = cam - p
        dist = np.linalg.norm(v)
        angle = math.degrees(math.acos(min(1.0, max(-1.0, axis @ v / dist)))) if dist > 0 else 0.0
        inside = axis @ v <= R + 1.0 and angle <= (light.spot_angle + 3.0) / 2.0
        a_enter, a_exit = _cone_interval(light, cam, dirs, (light.spot_angle + 1.0) / 2.0)
        if params.light_mesh == "unity":
            enter, leave = _convex_interval(cone_mesh_planes(light), cam, dirs)
        else:
            enter, leave = a_enter, a_exit
    if inside:
        covered = leave > LIGHT_VOLUME_NEAR
        return np.zeros((h, w)), np.where(covered, np.minimum(leave, t_surf), 0.0), covered
    covered = (leave > enter) & (enter > LIGHT_VOLUME_NEAR)
    t0 = np.where(covered, enter, 0.0)
    if light.type == "point":
        length = np.minimum(leave, t_surf) - t0
    else:
        length = np.minimum(a_exit - (t0 + 0.001), t_surf - t0)
    return t0, np.where(covered, length, 0.0), covered


def _march_depth(frame, p, resolution):
    """Linear eye depth at the march resolution through VL's raw-depth chessboard (metres; far on sky)."""
    cam = frame.camera
    eye = np.minimum(frame.gbuffer.depth, cam.far)
    raw = linear_to_raw(eye, cam.near, cam.far, p.depth_convention)
    if p.depth_downsample == "chessboard":
        raw_lo = downsample_vl(raw, resolution, p.uv_origin)
    else:
        fn = downsample_min if p.depth_downsample == "min" else downsample_max
        raw_lo = raw if resolution == "full" else fn(raw, resolution)
    return np.minimum(raw_to_linear(raw_lo, cam.near, cam.far, p.depth_convention), cam.far)


def _cookie(scene, p):
    if p.spot_cookie_path is None:
        return spot_profile_cookie()
    return load_cookie(Cookie(path=p.spot_cookie_path, channel="luminance"), scene.source or "<scene>",
                       "techniques.slightlymad.spot_cookie_path")


def _lut(scene, p):
    if p.attenuation_lut_path is None:
        return np.zeros((0, 0))
    key = "techniques.slightlymad.attenuation_lut_path"
    try:
        lut = np.load(p.attenuation_lut_path)
    except (OSError, ValueError) as exc:
        raise InputError(scene.source or "<scene>", key, f"cannot read LUT: {exc}") from None
    lut = np.atleast_2d(np.asarray(lut, dtype=np.float64))
    if lut.ndim != 2 or lut.size == 0 or not np.all(np.isfinite(lut)):
        raise InputError(scene.source or "<scene>", key, f"expected a finite 1-D or 2-D array, got {lut.shape}")
    return lut


def render(scene, frame) -> dict:
    """Render the VL passes of ``scene`` (module docstring); returns the buffers named there."""
    p = scene.techniques.slightlymad
    resolution = resolved(scene, "resolution")
    if resolution == "third":
        raise InputError(scene.source or "<scene>", "render.resolution", "VolumetricLights has full, half and "
                         "quarter resolution only (render.technique = \"slightlymad\")")
    n_steps = resolved(scene, "steps")
    cam = frame.camera
    H, W = cam.height, cam.width
    w, h = low_res_size(W, H, resolution)
    dirs = cam.ray_directions(w, h)
    eye_lo = _march_depth(frame, p, resolution)
    t_surf = eye_lo / (dirs @ cam.forward)
    sky = eye_lo / cam.far > SKY_LINEAR01
    beta = (np.zeros((h, w)) if p.dither == "none"
            else dither_offsets(w, h, 8 if p.dither == "8x8" else 4, p.dither_bytes, p.uv_origin))
    med = pack_medium(scene.replace(medium=vl_medium(scene, p)))
    packed = pack_lights(scene)
    lut, cookie = _lut(scene, p), _cookie(scene, p)
    camp = np.asarray(cam.position, dtype=np.float64)
    sm = frame.shadow_maps("hard")
    sigma_s, sigma_t = vl_coefficients(scene, p)
    march = VlMarch(n_steps, sigma_s, sigma_t, p.right_endpoint, p.initial_half_tau)
    shadows = sm.table

    out = {"depth_march": eye_lo, "dither": beta}
    volume = np.zeros((h, w, 4))
    volume[..., 3] = 1.0
    for i, light in enumerate(scene.lights):
        t0, length, covered = light_segments(light, camp, dirs, t_surf, p, p.max_ray_length)
        lf = packed.floats[i].copy()
        if light.type == "point" and p.point_srgb_quirk:
            lf[F_CR:F_CB + 1] = srgb_to_linear(lf[F_CR:F_CB + 1])
        att = UNITY if p.attenuation == "unity_lut" else ATTENUATION_CODES[light.attenuation]
        cone = CONE_COOKIE_ONLY if p.spot_cone == "cookie" else CONE_CODES[light.cone]
        kind = KIND_CODES[light.type]
        record = VlLight(i, kind, lf, att, cone, lut if p.attenuation == "unity_lut" else packed.lut, cookie,
                           p.cube_shadow_factor)
        rgb, tau = vl_march(camp, dirs, t0, length, covered, beta, march, record, med, packed, shadows,
                            frame.geometry.arrays)
        out[f"light{i}"] = rgb
        volume[..., :3] = blend_add_fp16(volume[..., :3], rgb) if p.fp16 else volume[..., :3] + rgb
        if kind == KIND_DIRECTIONAL:
            alpha = np.exp(-tau)
            if p.skybox_extinction_quirk:
                alpha = np.where(sky, alpha + (1.0 - alpha) * (1.0 - p.skybox_extinction), alpha)
            volume[..., 3] = fp16(alpha) if p.fp16 else alpha
    if not p.point_spot_alpha_zero and any(l.type != "directional" for l in scene.lights):
        view = np.exp(-vl_view_tau(camp, dirs, np.minimum(t_surf, p.max_ray_length), beta, n_steps, sigma_t, med))
        if not any(l.type == "directional" for l in scene.lights):
            volume[..., 3] = fp16(view) if p.fp16 else view
    out["march"] = volume.copy()

    store = fp16 if p.fp16 else (lambda a: a)
    radius = {"full": p.blur_radius_full, "half": p.blur_radius_half, "quarter": p.blur_radius_quarter}[resolution]
    blur_v = volume
    if p.blur:
        blur_h = store(vl_blur_pass(volume, eye_lo, 1, resolution, p.gauss_blur_deviation, p.blur_depth_factor,
                                    radius))
        blur_v = store(vl_blur_pass(blur_h, eye_lo, 0, resolution, p.gauss_blur_deviation, p.blur_depth_factor,
                                    radius))
        out["blur_h"], out["blur_v"] = blur_h, blur_v
    full = blur_v
    if resolution != "full":
        eye_full = np.minimum(frame.gbuffer.depth, cam.far)
        full = store(vl_upsample(blur_v, eye_lo, eye_full, p.upsample_threshold, p.uv_origin))
        out["upsample"] = full
    out["inscatter"] = full[..., :3]
    out["transmittance"] = full[..., 3]
    out["final"] = composite_vl(frame.scene_colour, full)
    return out


def notes(scene, out) -> list[str]:
    """What ``vlref render`` tells the user about this render: that its banding, dither and halos are VL's, the
    VL defaults that replace the scene's own settings (each with its switch), and how many march pixels
    saturate fp16 (65504) when ``fp16`` is on."""
    p = scene.techniques.slightlymad
    kinds = {light.type for light in scene.lights}
    source = []
    if p.medium == "source":
        source.append(f"VL's medium (scattering {p.scattering:g}, extinction {p.extinction:g}, MieG {p.mie_g:g}; "
                      'medium = "scene" for the scene\'s)')
    if p.attenuation == "unity_lut" and any(l.type != "directional" and l.attenuation != "unity" for l in scene.lights):
        source.append('Unity\'s range-normalised attenuation LUT (attenuation = "scene" for the lights\' laws)')
    if p.spot_cone == "cookie" and "spot" in kinds:
        source.append('the spot cookie as the cone falloff (spot_cone = "scene")')
    if p.point_srgb_quirk and any(l.type == "point" and max(l.color) * l.intensity > 1.0 for l in scene.lights):
        source.append("point colour x intensity through sRGB->linear (point_srgb_quirk = false)")
    lines = ["slightlymad: horizontal banding, a checker dither and stair-stepped halos at depth edges are "
             "VolumetricLights' own (8x8 Bayer ray offsets, chessboard depth, fp16, nearest-depth upsample): "
             "faithful (docs/TECHNIQUES.md, Faithful artifacts)"]
    if source:
        lines.append("slightlymad uses VolumetricLights' defaults, not the scene's: " + "; ".join(source)
                     + " [techniques.slightlymad]")
    if p.fp16:
        stored = [out[k][..., :3] for k in ("march", "blur_h", "blur_v", "upsample") if k in out]
        saturated = max(int((a >= FP16_MAX).any(axis=-1).sum()) for a in stored)
        if saturated:
            lines.append(f"slightlymad: {saturated} texel(s) of a buffer saturate fp16 (65504); lower the "
                         "light intensity or the medium's scattering (fp16 = false lifts VL's fp16 storage)")
    return lines
