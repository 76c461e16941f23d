"""Keyframe animation: the scene at a frame (``[animation]``, :class:`vlref.scene.model.Animation`).

Each animatable property (camera ``position``, ``look_at``, ``rotation``, ``fov``; per light
``position``, ``direction``, ``color``, ``intensity``; medium ``scattering``, ``absorption``,
``noise_offset``, ``noise_intensity``) has its own track: the keys that set it, in frame order. A
property no key sets keeps the scene's value; otherwise, at frame ``f`` between keys ``f0 < f1`` with
``u = (f - f0)/(f1 - f0)`` it is

* linear ``(1 - u) a + u b`` for positions, colours and scalars;
* slerp of the unit vectors for light directions (``sin((1-u)θ)/sin θ a + sin(uθ)/sin θ b``);
  consecutive keys with opposite directions are an input error (the arc is undefined);
* quaternion slerp (shortest arc, :class:`scipy.spatial.transform.Slerp`) for the camera's Euler
  ``rotation`` (Unity order: ``R = Ry Rx Rz``, i.e. intrinsic ``YXZ``);

and the first (last) key's value before (after) the keyed range: no extrapolation. The evaluated scene
has ``render.time = render.time + f / fps`` (the noise scrolls with its velocity) and no
``animation`` table, so evaluating it again changes nothing.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import InputError

__all__ = ["scene_at", "check_animation", "track_value"]

_CAMERA = ("position", "look_at", "rotation", "fov")
_LIGHT = ("position", "direction", "color", "intensity")
_MEDIUM = ("scattering", "absorption", "noise_offset", "noise_intensity")


def _slerp_vec(a, b, u: float) -> tuple:
    a = np.asarray(a, dtype=np.float64) / np.linalg.norm(a)
    b = np.asarray(b, dtype=np.float64) / np.linalg.norm(b)
    theta = float(np.arccos(np.clip(a @ b, -1.0, 1.0)))
    if theta < 1e-9:
        v = (1.0 - u) * a + u * b
    else:
        v = (np.sin((1.0 - u) * theta) * a + np.sin(u * theta) * b) / np.sin(theta)
    return tuple(float(x) for x in v / np.linalg.norm(v))


def _slerp_euler(a, b, u: float) -> tuple:
    from scipy.spatial.transform import Rotation, Slerp

    rots = Rotation.from_euler("YXZ", [[a[1], a[0], a[2]], [b[1], b[0], b[2]]], degrees=True)
    y, x, z = Slerp([0.0, 1.0], rots)([u]).as_euler("YXZ", degrees=True)[0]
    return float(x), float(y), float(z)


def track_value(track: list, frame: float, law: str):
    """Value of a track ``[(frame, value), ...]`` (increasing frames) at ``frame`` by ``law``
    (``linear``, ``slerp`` (unit vectors) or ``euler`` (camera rotation)), clamped at both ends."""
    if frame <= track[0][0]:
        return track[0][1]
    if frame >= track[-1][0]:
        return track[-1][1]
    for (f0, a), (f1, b) in zip(track, track[1:]):
        if f0 <= frame <= f1:
            u = (frame - f0) / (f1 - f0)
            if law == "slerp":
                return _slerp_vec(a, b, u)
            if law == "euler":
                return _slerp_euler(a, b, u)
            if isinstance(a, tuple):
                return tuple((1.0 - u) * x + u * y for x, y in zip(a, b))
            return (1.0 - u) * a + u * b
    raise AssertionError("unreachable: frames are increasing")


def _tracks(animation):
    """``{(section, index, name): [(frame, value), ...]}`` for every keyed property."""
    tracks: dict = {}
    for key in animation.keys:
        if key.camera is not None:
            for name in _CAMERA:
                value = getattr(key.camera, name)
                if value is not None:
                    tracks.setdefault(("camera", 0, name), []).append((key.frame, value))
        for lk in key.lights:
            for name in _LIGHT:
                value = getattr(lk, name)
                if value is not None:
                    tracks.setdefault(("lights", lk.light, name), []).append((key.frame, value))
        if key.medium is not None:
            for name in _MEDIUM:
                value = getattr(key.medium, name)
                if value is not None:
                    tracks.setdefault(("medium", 0, name), []).append((key.frame, value))
    return tracks


def check_animation(scene):
    """``(key path, reason)`` of the first animation that cannot apply to ``scene``, else None."""
    anim = scene.animation
    for i, key in enumerate(anim.keys):
        where = f"animation.keys[{i}]"
        if key.camera is not None:
            if key.camera.look_at is not None and scene.camera.look_at is None:
                return f"{where}.camera.look_at", "the scene's camera has no look_at to animate (it uses rotation)"
            if key.camera.rotation is not None and scene.camera.look_at is not None:
                return f"{where}.camera.rotation", "the scene's camera uses look_at; animate look_at instead"
        for j, lk in enumerate(key.lights):
            if lk.light >= len(scene.lights):
                return f"{where}.lights[{j}].light", f"no light {lk.light} (the scene has {len(scene.lights)})"
        if key.medium is not None and scene.medium.noise is None and (
                key.medium.noise_offset is not None or key.medium.noise_intensity is not None):
            return f"{where}.medium", "noise_offset/noise_intensity need a [medium.noise] table"
    frames = [k.frame for k in anim.keys]
    for (section, index, name), track in _tracks(anim).items():
        if name == "direction":
            for (f0, a), (f1, b) in zip(track, track[1:]):
                a, b = np.asarray(a) / np.linalg.norm(a), np.asarray(b) / np.linalg.norm(b)
                if a @ b < -1.0 + 1e-9:
                    i = frames.index(f1)
                    return (f"animation.keys[{i}].lights", f"light {index} direction is opposite to the one at frame "
                            f"{f0}: the slerp arc is undefined (add a key between)")
    return None


def scene_at(scene, frame: int | None = None):
    """``scene`` with its animation evaluated at ``frame`` (default ``render.frame``); module docstring."""
    frame = scene.render.frame if frame is None else int(frame)
    anim = scene.animation
    render = dataclasses.replace(scene.render, frame=frame)
    if anim is None:
        return scene.replace(render=render)
    render = dataclasses.replace(render, time=scene.render.time + frame / anim.fps)
    camera, medium, lights = scene.camera, scene.medium, list(scene.lights)
    for (section, index, name), track in _tracks(anim).items():
        law = "slerp" if name == "direction" else "euler" if name == "rotation" else "linear"
        value = track_value(track, frame, law)
        if section == "camera":
            camera = dataclasses.replace(camera, **{name: value})
        elif section == "lights":
            lights[index] = dataclasses.replace(lights[index], **{name: value})
        elif name.startswith("noise_"):
            medium = dataclasses.replace(medium, noise=dataclasses.replace(medium.noise, **{name[6:]: value}))
        else:
            medium = dataclasses.replace(medium, **{name: value})
    problem = camera.check()
    if problem:
        raise InputError(scene.source or "<scene>", f"animation (frame {frame}): camera.{problem[0]}", problem[1])
    return scene.replace(render=render, camera=camera, medium=medium, lights=tuple(lights), animation=None)
