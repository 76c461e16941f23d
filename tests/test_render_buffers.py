"""``RenderResult.buffers`` (:class:`vlref.render.RenderBuffers`): every buffer under its name in the documented
order; the albedo made only when it is asked for, then the G-buffer's own bit for bit and kept; the files
``vlref render`` writes made without it; a pickle is a plain dict of every buffer."""

import pickle

import numpy as np

import vlref.render
from vlref.bench import bench_scene
from vlref.cli.render import MAIN_BUFFERS
from vlref.geometry.raycast import per_object
from vlref.io.exr import read_exr
from vlref.io.render_files import save_render
from vlref.render import prepare_frame, render


def test_the_albedo_is_made_when_asked_for_and_is_the_gbuffers(monkeypatch, tmp_path):
    made = []
    monkeypatch.setattr(vlref.render, "per_object", lambda *args: made.append(1) or per_object(*args))
    scene = bench_scene(32, 18, 2, "four", 16)
    result = render(scene)
    assert list(result.buffers) == ["final", "inscatter", "transmittance", "scene_colour", "depth", "normal",
                                    "albedo", "object_id"]
    assert "albedo" in result.buffers and len(result.buffers) == 8 and made == []
    (tmp_path / "main").mkdir()
    save_render(tmp_path / "main", result, stages=False, main=MAIN_BUFFERS)
    assert sorted(p.name for p in (tmp_path / "main").iterdir()) == ["depth.exr", "final.exr", "final.png",
                                                                   "inscatter.exr", "transmittance.exr"]
    assert made == []  # the default outputs need no albedo
    albedo = result.buffers["albedo"]
    assert made == [1] and result.buffers["albedo"] is albedo and made == [1]  # made once, then kept
    ids = result.buffers["object_id"]
    table = np.array([o.material.albedo for o in scene.objects])
    assert (ids >= 0).any() and (ids < 0).any()  # objects and sky in view
    assert np.array_equal(albedo, np.where(ids[..., None] >= 0, table[ids], 0.0))
    assert np.array_equal(albedo, prepare_frame(scene).gbuffer.albedo)
    plain = pickle.loads(pickle.dumps(result.buffers))
    assert type(plain) is dict and list(plain) == list(result.buffers)
    assert all(np.array_equal(plain[name], result.buffers[name]) for name in plain)


def test_stages_write_the_albedo(tmp_path):
    result = render(bench_scene(32, 18, 2, "four", 16), stages=True)
    save_render(tmp_path, result, stages=True, main=MAIN_BUFFERS)
    channels, _ = read_exr(tmp_path / "albedo.exr")
    written = np.stack([channels[c] for c in "RGB"], axis=-1)
    assert np.array_equal(written, result.buffers["albedo"].astype(np.float32))
