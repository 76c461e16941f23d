"""Exporting vlref's own buffers as a port would (``vlref march export``): the camera depth, the scene
colour and every shadow map in a chosen encoding, with the ``port.toml`` manifest that reads them back
(:mod:`vlref.port`); round trips test the decoder against vlref's own frame."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np

from ..camera import Camera, linear_to_raw, look_rotation
from ..io.exr import write_exr
from ..io.files import write_text
from ..io.output_folders import output_dir
from ..lights.shadow_cast import cascade_splits, texel_grid
from ..lights.shadow_pack import CUBE_FACES, SHADOW_EXACT, SHADOW_NONE
from ..render import prepare_frame
from ..scene import load_scene
from ..techniques import TECHNIQUES
from .decode import FAR_VALUE, NEAR_VALUE, flip_z
from .manifest import bundled_name

__all__ = ["orthographic", "export_port"]


def orthographic(half_width: float, half_height: float, near: float, far: float, convention: str = "d3d") -> np.ndarray:
    """4x4 view -> clip of an orthographic box ``|x| <= half_width``, ``|y| <= half_height``,
    ``near <= z <= far`` (z forward), with NDC depth per ``convention`` (``NEAR_VALUE`` at near,
    ``FAR_VALUE`` at far, linear in z)."""
    p = np.eye(4)
    p[0, 0], p[1, 1] = 1.0 / half_width, 1.0 / half_height
    z0, z1 = NEAR_VALUE[convention], FAR_VALUE[convention]
    p[2, 2] = (z1 - z0) / (far - near)
    p[2, 3] = z0 - near * p[2, 2]
    return p


def _encode(stored: np.ndarray, z: np.ndarray, encoding: str, convention: str, near: float, far: float,
            ortho: bool) -> np.ndarray:
    """vlref's stored distance / view depth ``z`` of each texel -> the port's texel value."""
    if encoding == "distance":
        return stored
    if convention == "linear":
        return z
    empty = ~np.isfinite(z)
    zz = np.where(empty, far, z)
    if ortho:
        raw = orthographic(1.0, 1.0, near, far, convention)
        value = raw[2, 2] * zz + raw[2, 3]
    else:
        value = linear_to_raw(zz, near, far, convention)
    return np.where(empty, FAR_VALUE[convention], value)


def _light_tiles(scene, camera: Camera, maps, light: int, encoding: str, convention: str):
    """vlref's maps of ``light`` as a port would export them: ``(tiles [(texels, view, projection, face)],
    splits)``, texels row 0 = top."""
    lt = scene.lights[light]
    sh = lt.shadows
    rot = look_rotation(lt.direction)
    pos, fwd = np.asarray(lt.position, dtype=np.float64), rot[:, 2]
    bufs = [(name, maps.data[start:start + count]) for name, li, start, count in maps.names if li == light]
    res = int(round(math.sqrt(bufs[0][1].size)))
    x, y = texel_grid(res)
    tiles, splits = [], ()
    for k, (name, stored) in enumerate(bufs):
        stored = stored.astype(np.float64)
        if lt.type == "directional":
            centre, radius, back = maps.cascade(light, k)
            view = Camera(centre - back * fwd, rot, 90.0, res, res, 1.0, 2.0).view_matrix()
            near, far = 0.0, back + radius
            proj = orthographic(radius, radius, near, far, "d3d" if convention == "linear" else convention)
            z, face, ortho = stored, "", True
        else:
            if lt.type == "spot":
                fov, face = lt.spot_angle, ""
                scale = math.tan(math.radians(fov) / 2.0)
            else:
                face, r_f, u_f, f_f = CUBE_FACES[k]
                rot, fov, scale = np.array([r_f, u_f, f_f], dtype=np.float64).T, 90.0, 1.0
            near, far = sh.near, lt.range
            cam = Camera(pos, rot, fov, res, res, near, far)
            view, proj = cam.view_matrix(), cam.projection_matrix("d3d" if convention == "linear" else convention)
            z = stored / np.sqrt(1.0 + (x * scale) ** 2 + (y * scale) ** 2)
            ortho = False
        texels = _encode(stored, z, encoding, convention, near, far, ortho).reshape(res, res)
        tiles.append((texels, view, proj, face))
    if lt.type == "directional":
        far = min(sh.distance, camera.far)
        splits = tuple(cascade_splits(camera.near, max(far, camera.near * (1 + 1e-6)), len(bufs), sh.split_lambda))
    return tiles, splits


def _toml_value(v) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(a) for a in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    return '"' + str(v).replace("\\", "\\\\").replace('"', '\\"') + '"'


def export_port(scene_ref, out_dir, overrides: Sequence[str] = (), *, depth_encoding: str = "raw", depth_convention: str = "reversed",
                uv_origin: str = "top", shadow_encoding: str = "depth", shadow_convention: str = "reversed",
                camera_forward: str = "+z", camera_matrices: bool = True, passes: bool = False) -> Path:
    """Export vlref's own depth buffer, scene colour and shadow maps of a scene (a file or bundled name, with
    ``--set`` ``overrides``) in the given encodings, as a port would, and write ``port.toml`` referring to
    the scene (absolute path or bundled name, with ``set = overrides``); returns the manifest's path.

    Maps go one file per light (cube faces in a 3x2 atlas, cascades in an Nx1 atlas). ``passes``: also
    vlref's own pass outputs, as a port's (``final = "final.exr"`` and one ``[[passes]]`` entry per float image
    buffer of the technique, ``port_<buffer>.npy`` float32, preset ``gpu-float32``): vlref as a port of itself,
    for ``vlref verdict``.
    """
    scene = load_scene(scene_ref, overrides)
    frame = prepare_frame(scene)
    cam = frame.camera
    maps = frame.shadow_maps()
    flip = (lambda a: a[::-1]) if uv_origin == "bottom" else (lambda a: a)
    depth = frame.gbuffer.depth
    if depth_encoding == "raw":
        sky = ~np.isfinite(depth)
        depth = np.where(sky, FAR_VALUE[depth_convention],
                         linear_to_raw(np.where(sky, cam.far, depth), cam.near, cam.far, depth_convention))
    ref = str(scene_ref) if bundled_name(str(scene_ref)) else str(Path(scene_ref).resolve())
    lines = [f"scene = {_toml_value(ref)}", f"set = {_toml_value(list(overrides))}", 'colour = "colour.exr"', ""]
    if camera_matrices:
        f = flip_z(camera_forward)
        lines += ["[camera]", f'forward = "{camera_forward}"', f'convention = "{depth_convention}"',
                  f"view = {_toml_value(f @ cam.view_matrix())}",
                  f"projection = {_toml_value(cam.projection_matrix(depth_convention) @ f)}", ""]
    stages = TECHNIQUES[scene.render.technique].render(frame.scene, frame) if passes else {}
    stages = {k: np.asarray(v, dtype=np.float32) for k, v in stages.items()
              if isinstance(v, np.ndarray) and v.dtype.kind == "f" and v.ndim in (2, 3)}
    if passes:
        lines[2:2] = ['final = "final.exr"', 'preset = "gpu-float32"']
    lines += ["[depth]", 'path = "depth.exr"', f'encoding = "{depth_encoding}"', f'convention = "{depth_convention}"',
              f"near = {cam.near!r}", f"far = {cam.far!r}", f'uv_origin = "{uv_origin}"', ""]
    for name, a in stages.items():
        lines += ["[[passes]]", f'name = "{name}"', f'buffer = "{name}"', f'path = "port_{name}.npy"',
                  f"ignore_sky = {_toml_value(not bool(np.isfinite(a).all()))}", ""]
    with output_dir(out_dir) as tmp:
        for name, a in stages.items():
            np.save(tmp / f"port_{name}.npy", a)
        if passes:
            write_exr(tmp / "final.exr", stages["final"])
        write_exr(tmp / "depth.exr", flip(depth))
        write_exr(tmp / "colour.exr", frame.scene_colour)
        for light in range(frame.lights.count):
            if maps.mode(light) in (SHADOW_NONE, SHADOW_EXACT):
                continue
            tiles, splits = _light_tiles(frame.scene, cam, maps, light, shadow_encoding, shadow_convention)
            cols = 3 if len(tiles) == 6 else len(tiles)
            rows = len(tiles) // cols
            res = tiles[0][0].shape[0]
            atlas = np.zeros((rows * res, cols * res))
            for k, (texels, _, _, _) in enumerate(tiles):
                r, c = divmod(k, cols)
                atlas[r * res:(r + 1) * res, c * res:(c + 1) * res] = flip(texels)
            write_exr(tmp / f"shadow_{light}.exr", atlas)
            lines += ["[[shadow_maps]]", f"light = {light}", f'path = "shadow_{light}.exr"', f"atlas = [{cols}, {rows}]",
                      f'encoding = "{shadow_encoding}"', f'convention = "{shadow_convention}"', f'uv_origin = "{uv_origin}"']
            if splits:
                lines.append(f"splits = {_toml_value(splits)}")
            lines.append("")
            for texels, view, proj, face in tiles:
                lines += ["[[shadow_maps.tiles]]"] + ([f'face = "{face}"'] if face else [])
                lines += [f"view = {_toml_value(view)}", f"projection = {_toml_value(proj)}", ""]
        write_text(tmp / "port.toml", "\n".join(lines))
    return Path(out_dir) / "port.toml"
