"""`vlref march` on a port's exported buffers: decoding closed forms, camera matrices, manifest errors, and
the round trip: vlref's own buffers exported in every encoding and marched again reproduce `vlref render`."""

import numpy as np
import pytest

from vlref.camera import Camera, camera_from_settings, euler_matrix, linear_to_raw
from vlref.errors import InputError
from vlref.oracle.compare import compare_arrays
from vlref.cli import main
from vlref.port import FAR_VALUE, camera_from_matrices, decode_depth, export_port, march_port, orthographic
from vlref.render import render
from vlref.scene import load_scene

SMALL = ("render.width=48", "render.height=27", "render.steps=8", "lights.0.shadows.resolution=128")


@pytest.mark.parametrize("convention", ["d3d", "gl", "reversed"])
def test_decode_raw_depth_inverts_linear_to_raw_and_marks_sky(convention):
    z = np.array([[0.1, 0.5, 3.0], [40.0, 999.0, np.inf]])
    raw = np.where(np.isfinite(z), linear_to_raw(np.where(np.isfinite(z), z, 1.0), 0.1, 1000.0, convention),
                   FAR_VALUE[convention])
    out = decode_depth(raw[::-1], "raw", convention, 0.1, 1000.0, uv_origin="bottom")
    assert np.isinf(out[1, 2]) and np.isfinite(out).sum() == 5
    np.testing.assert_allclose(out[np.isfinite(z)], z[np.isfinite(z)], rtol=1e-9)


def test_orthographic_maps_near_and_far_to_the_convention_values():
    for conv in ("d3d", "gl", "reversed"):
        p = orthographic(2.0, 3.0, 1.0, 9.0, conv)
        ndc = p @ np.array([[2.0, 3.0, 1.0, 1.0], [-2.0, -3.0, 9.0, 1.0]]).T
        np.testing.assert_allclose(ndc[:3, 0], [1.0, 1.0, {"d3d": 0, "gl": -1, "reversed": 1}[conv]], atol=1e-15)
        np.testing.assert_allclose(ndc[:3, 1], [-1.0, -1.0, FAR_VALUE[conv]], atol=1e-15)


@pytest.mark.parametrize("forward", ["+z", "-z"])
@pytest.mark.parametrize("convention", ["d3d", "gl", "reversed"])
def test_camera_from_matrices_round_trip(forward, convention):
    cam = Camera(np.array([1.0, 2.0, -3.0]), euler_matrix((10.0, 35.0, 5.0)), 47.0, 64, 36, 0.3, 250.0)
    flip = np.diag([1.0, 1.0, 1.0 if forward == "+z" else -1.0, 1.0])
    got = camera_from_matrices(flip @ cam.view_matrix(), cam.projection_matrix(convention) @ flip, 64, 36,
                               convention, forward)
    np.testing.assert_allclose(got.position, cam.position, atol=1e-12)
    np.testing.assert_allclose(got.rotation, cam.rotation, atol=1e-12)
    assert got.fov == pytest.approx(47.0, abs=1e-10)
    assert (got.near, got.far) == pytest.approx((0.3, 250.0), rel=1e-9)


def test_camera_from_matrices_rejects_wrong_aspect_and_handedness():
    cam = Camera(np.zeros(3), np.eye(3), 60.0, 64, 36, 0.1, 100.0)
    with pytest.raises(InputError, match="port.toml: camera.projection: aspect"):
        camera_from_matrices(cam.view_matrix(), cam.projection_matrix(), 64, 64, file="port.toml")
    with pytest.raises(ValueError, match="camera.view") as err:  # a Python caller's matrices: not a file's
        camera_from_matrices(np.diag([1.0, 1.0, -1.0, 1.0]) @ cam.view_matrix(), cam.projection_matrix(), 64, 36)
    assert not isinstance(err.value, InputError)


def _roundtrip(tmp_path, scene, technique, **encodings):
    overrides = (*SMALL, f'render.technique="{technique}"')
    ref = render(load_scene(scene, overrides)).buffers
    manifest = export_port(scene, tmp_path / "port", overrides, **encodings)
    out = march_port(manifest)
    return compare_arrays(ref["final"], np.asarray(out["final"], np.float32), "float32", flip=False)


@pytest.mark.parametrize("encodings", [
    dict(depth_encoding="raw", depth_convention="reversed", uv_origin="top"),
    dict(depth_encoding="raw", depth_convention="d3d", uv_origin="bottom", camera_forward="-z"),
    dict(depth_encoding="raw", depth_convention="gl", shadow_convention="gl"),
    dict(depth_encoding="linear", shadow_encoding="distance", camera_matrices=False),
    dict(depth_encoding="linear", shadow_encoding="depth", shadow_convention="linear", uv_origin="bottom"),
], ids=["reversed", "d3d-bottom-glview", "gl", "linear-distance", "linear-lineardepth"])
def test_march_on_exported_spot_buffers_reproduces_render(tmp_path, encodings):
    report = _roundtrip(tmp_path, "pillars", "physical", **encodings)
    assert report.passed, report.summary()
    assert report.metrics["frac_failing"] == 0.0


@pytest.mark.parametrize("scene,technique", [("cage", "killzone"), ("urp_sun", "urp"), ("valley", "slightlymad")])
def test_march_on_exported_cube_and_cascade_maps_reproduces_render(tmp_path, scene, technique):
    report = _roundtrip(tmp_path, scene, technique, shadow_encoding="depth", shadow_convention="d3d")
    assert report.passed, report.summary()


def test_marched_port_differs_when_its_shadow_map_is_wrong(tmp_path):
    """The shadow maps are really read from the files: an emptied map changes the result."""
    from vlref.io.exr import write_exr
    from vlref.io.images import read_image

    overrides = (*SMALL, 'render.technique="physical"')
    ref = render(load_scene("pillars", overrides)).buffers["final"]
    manifest = export_port("pillars", tmp_path / "port", overrides)
    shadow = read_image(tmp_path / "port" / "shadow_0.exr")[:, :, 0]
    write_exr(tmp_path / "port" / "shadow_0.exr", np.zeros_like(shadow))  # reversed-Z far plane: nothing cast
    report = compare_arrays(ref, march_port(manifest)["final"], "gpu-full", flip=False)
    assert not report.passed


def test_cli_writes_buffers_and_rejects_bad_manifests(tmp_path, capsys):
    manifest = export_port("pillars", tmp_path / "port", (*SMALL, 'render.technique="killzone"'))
    assert main(["march", str(manifest), "-o", str(tmp_path / "out"), "-q"]) == 0
    assert {p.name for p in (tmp_path / "out").iterdir()} >= {"final.exr", "inscatter.exr", "depth.exr"}

    text = manifest.read_text()
    cases = {"no_depth.toml": text.replace('path = "depth.exr"', 'path = "missing.exr"'),
             "bad_atlas.toml": text.replace("atlas = [1, 1]", "atlas = [2, 1]"),
             "bad_conv.toml": text.replace('encoding = "raw"', 'encoding = "log"'),
             "bad_light.toml": text.replace("light = 0", "light = 3"),
             "typo.toml": text.replace('uv_origin = "top"', 'uv_orgin = "top"', 1),
             "bad_matrix.toml": text.replace("view = [[", "view = [[0.0, 0.0, 0.0, 0.0], [", 1)}
    for name, body in cases.items():
        (tmp_path / "port" / name).write_text(body)
        assert main(["march", str(tmp_path / "port" / name), "-o", str(tmp_path / name)]) == 2, name
        assert not (tmp_path / name).exists()
    err = capsys.readouterr().err
    assert "depth.path" in err and "atlas" in err and "depth.encoding" in err and "no light 3" in err
    assert "depth.uv_orgin: unknown key, did you mean uv_origin?" in err
    assert "camera.view: must be a 4x4 matrix (4 rows of 4), got 5 rows" in err


def test_camera_defaults_to_the_scene_camera(tmp_path):
    overrides = (*SMALL, 'render.technique="physical"')
    manifest = export_port("pillars", tmp_path / "p", overrides, camera_matrices=False)
    from vlref.port import load_port
    port = load_port(manifest)
    cam = camera_from_settings(load_scene("pillars", overrides).camera, 48, 27)
    np.testing.assert_array_equal(port.camera.rotation, cam.rotation)


def test_march_sequence_on_exported_frames_reproduces_a_temporal_render_sequence(tmp_path):
    """A temporal froxel sequence of an animated scene (the spot turns): each frame exported as a port would
    (``render.frame=F``) and marched in order with the history carried (``march_sequence``; the CLI with several
    manifests) reproduces ``render --frames``: the manifest's scene is evaluated at its frame, and frame 2's
    history depends on frames 0 and 1."""
    from vlref.port import load_port, march_sequence
    from vlref.sequence import render_sequence

    grid = ("techniques.froxel.grid_width=12", "techniques.froxel.grid_height=8", "techniques.froxel.slices=8",
            "techniques.froxel.history_clamp=true")
    overrides = (*SMALL, *grid)
    want = [r.buffers for _, r in render_sequence(load_scene("anim_spot", overrides), range(3), stages=True)]
    manifests = [export_port("anim_spot", tmp_path / f"f{f}", (*overrides, f"render.frame={f}")) for f in range(3)]
    got = list(march_sequence([load_port(m) for m in manifests]))
    for f in range(3):
        for name in ("froxel_scatter", "froxel_history", "final"):
            report = compare_arrays(want[f][name], np.asarray(got[f][name], np.float32), "float32", flip=False)
            assert report.passed, (f, name, report.summary())
    assert not np.allclose(got[2]["froxel_history"], got[2]["froxel_scatter"])   # the history is used
    assert main(["march", *map(str, manifests), "-o", str(tmp_path / "m"), "--stages", "-q"]) == 0
    assert sorted(p.name for p in (tmp_path / "m").iterdir()) == ["frame_0000", "frame_0001", "frame_0002"]
    assert (tmp_path / "m" / "frame_0002" / "froxel_history.exr").is_file()
