"""Animated scenes: keyframe interpolation laws, validation, and `vlref render --frames` sequences."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from vlref.camera import euler_matrix
from vlref.cli import main
from vlref.errors import InputError
from vlref.io.images import read_image
from vlref.scene import load_scene
from vlref.scene.animation import scene_at

BASE = """
[render]
width = 32
height = 18
[camera]
position = [0.0, 1.0, -10.0]
{camera}
[medium]
scattering = 0.05
{noise}
[[lights]]
type = "spot"
position = [0.0, 5.0, 0.0]
direction = [0.0, -1.0, 0.0]
intensity = 10.0
[animation]
frames = 9
fps = 4.0
{keys}
"""

KEYS = """
[[animation.keys]]
frame = 2
camera = {{ {cam0} }}
lights = [{{ light = 0, position = [0.0, 5.0, 0.0], direction = [0.0, -1.0, 0.0], intensity = 10.0, color = [1.0, 0.0, 0.5] }}]
medium = {{ scattering = 0.05 }}
[[animation.keys]]
frame = 6
camera = {{ {cam1} }}
lights = [{{ light = 0, position = [4.0, 1.0, 2.0], direction = [1.0, 0.0, 0.0], intensity = 30.0, color = [0.0, 1.0, 0.5] }}]
medium = {{ scattering = 0.15 }}
"""


def scene(tmp_path, camera="look_at = [0.0, 1.0, 0.0]", cam0="look_at = [0.0, 1.0, 0.0]",
          cam1="look_at = [4.0, 1.0, 0.0]", keys=None, noise=""):
    p = tmp_path / "anim.toml"
    p.write_text(BASE.format(camera=camera, noise=noise, keys=keys if keys is not None else
                             KEYS.format(cam0=cam0, cam1=cam1)))
    return load_scene(p)


def test_linear_tracks_clamp_outside_the_keys(tmp_path):
    s = scene(tmp_path)
    for frame, u in ((0, 0.0), (2, 0.0), (3, 0.25), (4, 0.5), (6, 1.0), (8, 1.0)):
        e = scene_at(s, frame)
        light = e.lights[0]
        np.testing.assert_allclose(light.position, (4 * u, 5 - 4 * u, 2 * u), atol=1e-12)
        assert light.intensity == pytest.approx(10 + 20 * u)
        np.testing.assert_allclose(light.color, (1 - u, u, 0.5), atol=1e-12)
        assert e.medium.scattering == pytest.approx(0.05 + 0.1 * u)
        np.testing.assert_allclose(e.camera.look_at, (4 * u, 1.0, 0.0), atol=1e-12)
        assert e.render.time == pytest.approx(frame / 4.0) and e.render.frame == frame
        assert e.animation is None and scene_at(e) == e  # evaluating again changes nothing


def test_directions_slerp_at_constant_angular_speed(tmp_path):
    s = scene(tmp_path)
    for frame in (2, 3, 4, 5, 6):
        d = np.asarray(scene_at(s, frame).lights[0].direction)
        u = (frame - 2) / 4
        assert np.linalg.norm(d) == pytest.approx(1.0)
        # from straight down to +x: a quarter circle in the x-y plane, angle u * 90 degrees
        np.testing.assert_allclose(d, (np.sin(u * np.pi / 2), -np.cos(u * np.pi / 2), 0.0), atol=1e-12)


def test_camera_rotation_slerps_the_quaternion(tmp_path):
    s = scene(tmp_path, camera="rotation = [0.0, 0.0, 0.0]", cam0="rotation = [10.0, 0.0, 0.0]",
              cam1="rotation = [10.0, 80.0, 20.0]")
    r0, r1 = euler_matrix((10.0, 0.0, 0.0)), euler_matrix((10.0, 80.0, 20.0))
    np.testing.assert_allclose(euler_matrix(scene_at(s, 2).camera.rotation), r0, atol=1e-12)
    np.testing.assert_allclose(euler_matrix(scene_at(s, 6).camera.rotation), r1, atol=1e-12)
    # halfway: the rotation from r0 is half the full relative rotation, about the same axis
    half = euler_matrix(scene_at(s, 4).camera.rotation)
    full = Rotation.from_matrix(r0.T @ r1).as_rotvec()
    np.testing.assert_allclose(Rotation.from_matrix(r0.T @ half).as_rotvec(), full / 2, atol=1e-9)


@pytest.mark.parametrize("kwargs, path, reason", [
    (dict(keys="[[animation.keys]]\nframe = 3\n[[animation.keys]]\nframe = 3\n"), "animation.keys[1].frame",
     "increasing frame order"),
    (dict(keys="[[animation.keys]]\nframe = 1\nlights = [{ light = 2, intensity = 1.0 }]\n"),
     "animation.keys[0].lights[0].light", "no light 2"),
    (dict(cam0="rotation = [0.0, 0.0, 0.0]"), "animation.keys[0].camera.rotation", "uses look_at"),
    (dict(camera="rotation = [0.0, 0.0, 0.0]", cam0="rotation = [0.0, 0.0, 0.0]"),
     "animation.keys[1].camera.look_at", "no look_at"),
    (dict(keys="[[animation.keys]]\nframe = 0\nlights = [{ light = 0, direction = [0.0, -1.0, 0.0] }]\n"
               "[[animation.keys]]\nframe = 4\nlights = [{ light = 0, direction = [0.0, 2.0, 0.0] }]\n"),
     "animation.keys[1].lights", "opposite"),
    (dict(keys="[[animation.keys]]\nframe = 0\nmedium = { noise_offset = 0.5 }\n"), "animation.keys[0].medium",
     "[medium.noise]"),
    (dict(keys="[[animation.keys]]\nframe = 0\nlights = [{ light = 0, direction = [0.0, 0.0, 0.0] }]\n"),
     "animation.keys[0].lights[0].direction", "zero-length"),
])
def test_bad_animation_names_the_key(tmp_path, kwargs, path, reason):
    with pytest.raises(InputError) as exc:
        scene(tmp_path, **kwargs)
    assert exc.value.path == path and reason in exc.value.reason


def test_camera_keys_that_meet_the_position_fail_at_that_frame(tmp_path):
    s = scene(tmp_path, cam1="look_at = [0.0, 1.0, -10.0]")  # looks at its own position at frame 6
    scene_at(s, 4)
    with pytest.raises(InputError, match="frame 6"):
        scene_at(s, 6)


def test_render_frames_writes_numbered_sequences_and_previews(tmp_path):
    import imageio.v3 as iio

    out = tmp_path / "seq"
    small = ["--set", "render.width=32", "--set", "render.height=18", "--set", "techniques.froxel.grid_width=16",
             "--set", "techniques.froxel.grid_height=9", "--set", "techniques.froxel.slices=16"]
    assert main(["render", "anim_spot", "--frames", "2:5", "-o", str(out), "-q", *small]) == 0
    names = {p.name for p in out.iterdir()}
    for f in (2, 3, 4):
        for b in ("final", "depth", "inscatter", "transmittance"):
            assert f"{b}.{f:04d}.exr" in names
        assert f"final.{f:04d}.png" in names
    assert "final.0001.exr" not in names and "final.0005.exr" not in names
    gif = iio.imread(out / "preview.gif", index=None)
    assert gif.shape[:3] == (3, 18, 32)
    # the spot sweeps: consecutive frames differ; each frame equals a single render of that frame
    a, b = read_image(out / "final.0002.exr"), read_image(out / "final.0004.exr")
    assert np.abs(a - b).max() > 1e-3
    # preview.mp4 needs the `video` extra (imageio-ffmpeg), which the `test` extra includes
    assert (out / "preview.mp4").stat().st_size > 0


@pytest.mark.parametrize("frames", ["3:1", "x", "-1:2"])
def test_bad_frames_exit_2_and_write_nothing(tmp_path, frames, capsys):
    out = tmp_path / "none"
    assert main(["render", "anim_spot", "--frames", frames, "-o", str(out), "-q"]) == 2
    assert not out.exists() and "--frames" in capsys.readouterr().err
