"""vlref.io: EXR/PNG/NPY/NPZ writers and checked readers, atomic writes, all-or-nothing output folders."""

import json
import os
import struct
import types

import imageio.v3 as iio
import numpy as np
import OpenEXR
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from vlref import __version__
from vlref.errors import InputError
from vlref.io.exposure import percentile_exposure
from vlref.io.exr import ZIP_LEVEL, _openexr, _set_default_zip_level, read_exr, write_exr
from vlref.io.files import write_npy, write_npz, write_text
from vlref.io.images import read_image
from vlref.io.output_folders import output_dir
from vlref.io import png as png_module
from vlref.io.png import png_bytes, png_text, write_png
from vlref.io.render_files import save_buffers, save_render
from vlref.io.tonemap import _srgb8_values, _SRGB_BAND, _SRGB_CHUNK, srgb8


def _awkward_float32(rng, shape):
    """float32 values over the whole exponent range, with signs, subnormals, zeros and extremes."""
    mant = rng.standard_normal(shape)
    expo = rng.uniform(-45, 38, shape)
    a = (mant * 10.0 ** expo).astype(np.float32)
    flat = a.reshape(-1)
    special = np.array([0.0, -0.0, np.finfo(np.float32).max, -np.finfo(np.float32).max,
                        np.finfo(np.float32).tiny, np.float32(1.4e-45), 1.0, np.pi, np.inf, -np.inf],
                       dtype=np.float32)
    flat[:special.size] = special
    return a


def _no_stray_files(folder):
    return sorted(p.name for p in folder.iterdir())


# --------------------------------------------------------------------------- EXR

def test_exr_round_trip_is_bit_exact(tmp_path):
    rng = np.random.default_rng(1)
    img = _awkward_float32(rng, (24, 32, 3))
    path = write_exr(tmp_path / "a.exr", img)
    channels, _ = read_exr(path)
    assert sorted(channels) == ["B", "G", "R"]
    for i, name in enumerate("RGB"):
        assert channels[name].dtype == np.float32
        np.testing.assert_array_equal(channels[name].view(np.uint32), img[:, :, i].view(np.uint32))
    back = read_image(path)
    np.testing.assert_array_equal(back.view(np.uint32), img.view(np.uint32))


@settings(max_examples=25)
@given(hnp.arrays(np.float32, hnp.array_shapes(min_dims=3, max_dims=3, min_side=1, max_side=9),
                  elements=st.floats(width=32, allow_nan=False)))
def test_exr_round_trip_any_float32_array(tmp_path_factory, img):
    c = img.shape[2]
    names = tuple(f"c{i}" for i in range(c))
    path = write_exr(tmp_path_factory.mktemp("h") / "h.exr", img, channels=names)
    back = read_image(path)
    np.testing.assert_array_equal(back.view(np.uint32), img.view(np.uint32))


def test_exr_row_zero_is_top_and_float64_rounds_to_nearest(tmp_path):
    img = np.linspace(0.0, 1.0, 12 * 7).reshape(12, 7) + 1e-9  # float64, not float32-representable
    write_exr(tmp_path / "g.exr", img)
    back = read_image(tmp_path / "g.exr")
    assert back.shape == (12, 7, 1)
    np.testing.assert_array_equal(back[:, :, 0], img.astype(np.float32))
    assert back[0, 0, 0] < back[-1, -1, 0]  # first row written is the first row read


def test_exr_metadata_round_trip(tmp_path):
    settings = {"render": {"width": 32, "height": 24}, "medium": {"g": 0.7}}
    write_exr(tmp_path / "m.exr", np.ones((4, 5, 3)), metadata={"scene_hash": "abc123", "settings": settings})
    _, meta = read_exr(tmp_path / "m.exr")
    assert meta["vlref_version"] == __version__
    assert meta["scene_hash"] == "abc123"
    assert json.loads(meta["settings"]) == settings
    assert meta["vlref_channels"] == "R,G,B"


def test_exr_channel_naming(tmp_path):
    h, w = 3, 4
    base = np.arange(h * w, dtype=np.float32).reshape(h, w)
    write_exr(tmp_path / "y.exr", base)
    assert list(read_exr(tmp_path / "y.exr")[0]) == ["Y"]
    write_exr(tmp_path / "z.exr", base, channels="Z")
    assert list(read_exr(tmp_path / "z.exr")[0]) == ["Z"]
    rgba = np.stack([base + k for k in range(4)], axis=-1)
    write_exr(tmp_path / "rgba.exr", rgba)
    np.testing.assert_array_equal(read_image(tmp_path / "rgba.exr"), rgba)  # back in R,G,B,A order
    # arbitrary names keep the written order (EXR itself sorts names)
    five = np.stack([base * (k + 1) for k in range(5)], axis=-1)
    names = ("zeta", "alpha", "mid", "C10", "C2")
    write_exr(tmp_path / "five.exr", five, channels=names)
    chans, _ = read_exr(tmp_path / "five.exr")
    assert set(chans) == set(names)
    np.testing.assert_array_equal(read_image(tmp_path / "five.exr"), five)
    # a dict writes its keys
    write_exr(tmp_path / "d.exr", {"depth": base, "R": base + 1})
    chans, _ = read_exr(tmp_path / "d.exr")
    np.testing.assert_array_equal(chans["depth"], base)
    np.testing.assert_array_equal(chans["R"], base + 1)
    with pytest.raises(ValueError):
        write_exr(tmp_path / "bad.exr", five)  # 5 channels need names
    with pytest.raises(ValueError):
        write_exr(tmp_path / "bad.exr", rgba, channels=("R", "G"))


def test_exr_integers_must_be_exact_in_float32(tmp_path):
    ids = np.array([[-1, 0], [7, 2 ** 24]], dtype=np.int32)
    write_exr(tmp_path / "ids.exr", ids)
    np.testing.assert_array_equal(read_image(tmp_path / "ids.exr")[:, :, 0], ids.astype(np.float32))
    with pytest.raises(ValueError, match="2\\*\\*24"):
        write_exr(tmp_path / "big.exr", np.array([[2 ** 24 + 1]], dtype=np.int64))
    with pytest.raises(ValueError, match="standard EXR attribute"):
        write_exr(tmp_path / "m.exr", ids, metadata={"compression": "none"})


def test_exr_half_is_widened_and_uint_rejected(tmp_path):
    half = (np.arange(12).reshape(3, 4) / 7).astype(np.float16)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"Y": half}) as f:
        f.write(str(tmp_path / "h.exr"))
    chans, _ = read_exr(tmp_path / "h.exr")
    assert chans["Y"].dtype == np.float32
    np.testing.assert_array_equal(chans["Y"], half.astype(np.float32))
    with OpenEXR.File(header, {"id": np.arange(12, dtype=np.uint32).reshape(3, 4)}) as f:
        f.write(str(tmp_path / "u.exr"))
    with pytest.raises(InputError, match="wrong dtype uint32") as exc:
        read_exr(tmp_path / "u.exr")
    assert exc.value.path == "id"


# --------------------------------------------------------------------------- PNG

def test_png_preview_written_readable_and_tone_mapped(tmp_path):
    values = np.array([[0.0, 0.18, 1.0, 1e9]], dtype=np.float64)
    img = np.repeat(values[:, :, None], 3, axis=2)
    write_png(tmp_path / "p.png", img, exposure=1.0)
    rgb = iio.imread(tmp_path / "p.png")
    assert rgb.shape == (1, 4, 3) and rgb.dtype == np.uint8

    def expected(v):  # ACES fit (Narkowicz 2015), then sRGB OETF, written out independently
        y = min(max(v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14), 0.0), 1.0)
        s = 12.92 * y if y <= 0.0031308 else 1.055 * y ** (1 / 2.4) - 0.055
        return round(255 * s)

    assert [int(c) for c in rgb[0, :, 0]] == [expected(0.0), expected(0.18), expected(1.0), 255]
    # exposure scales before the curve
    write_png(tmp_path / "e.png", img, exposure=2.0)
    assert int(iio.imread(tmp_path / "e.png")[0, 1, 0]) == expected(0.36)
    # grey input, NaN and negative values give valid pixels
    write_png(tmp_path / "g.png", np.array([[np.nan, -3.0, np.inf]]))
    assert [int(c) for c in iio.imread(tmp_path / "g.png")[0, :, 1]] == [0, 0, 255]


@pytest.mark.parametrize("shape", [(1, 1), (1, 2), (2, 1), (63, 5), (64, 5), (65, 5), (130, 97), (200, 1100)])
def test_png_bytes_decode_to_the_codes_and_do_not_depend_on_the_cores(shape, monkeypatch):
    # every Sub-filter edge (one pixel, one column), one block of rows, a block boundary (64 rows), several
    # blocks with blocks longer than deflate's 32 KiB window (200 x 1100 pixels: 64 rows = 211 kB)
    rng = np.random.default_rng(sum(shape))
    codes = rng.integers(0, 256, shape + (3,), dtype=np.uint8)
    codes[: shape[0] // 2] //= 17  # a smooth half as well as noise: back-references across the blocks
    data = png_bytes(codes, {"vlref_exposure": "2", "note": "\u00e9"})
    np.testing.assert_array_equal(iio.imread(data, extension=".png"), codes)
    assert png_text(data) == {"vlref_exposure": "2", "note": "\u00e9"}
    monkeypatch.setattr(png_module, "host_cores", lambda: 1)
    assert png_bytes(codes, {"vlref_exposure": "2", "note": "\u00e9"}) == data


def test_srgb8_is_monotonic():
    v = np.linspace(0.0, 20.0, 2001)[None, :]
    out = srgb8(v)[0, :, 0].astype(int)
    assert out[0] == 0 and out[-1] == 255 and np.all(np.diff(out) >= 0)


def test_read_png_scales_code_values(tmp_path):
    codes = np.array([[0, 51, 255]], dtype=np.uint8)
    iio.imwrite(tmp_path / "c.png", codes)
    np.testing.assert_allclose(read_image(tmp_path / "c.png")[:, :, 0], codes / 255.0, rtol=1e-7)
    wide = np.array([[0, 65535]], dtype=np.uint16)
    iio.imwrite(tmp_path / "w.png", wide)
    np.testing.assert_array_equal(read_image(tmp_path / "w.png")[:, :, 0], [[0.0, 1.0]])


# --------------------------------------------------------------------------- NPY / NPZ and reader errors

def test_npy_npz_round_trip(tmp_path):
    a = np.random.default_rng(2).random((5, 6, 2))
    write_npy(tmp_path / "a.npy", a)
    np.testing.assert_array_equal(read_image(tmp_path / "a.npy"), a)
    assert read_image(tmp_path / "a.npy").dtype == np.float64
    write_npz(tmp_path / "b.npz", {"x": a, "y": a[:, :, 0].astype(np.float16)})
    np.testing.assert_array_equal(read_image(tmp_path / "b.npz", key="x"), a)
    y = read_image(tmp_path / "b.npz", key="y")
    assert y.shape == (5, 6, 1) and y.dtype == np.float32
    write_npz(tmp_path / "one.npz", {"only": a}, compressed=False)
    np.testing.assert_array_equal(read_image(tmp_path / "one.npz"), a)


@pytest.mark.parametrize("setup, kwargs, field, reason", [
    (lambda p: np.save(p / "i.npy", np.zeros((3, 4), np.int32)), {}, "dtype", "wrong dtype int32"),
    (lambda p: np.save(p / "i.npy", np.zeros((3, 4), bool)), {}, "dtype", "wrong dtype bool"),
    (lambda p: np.save(p / "i.npy", np.array([[0.0, np.nan]])), {}, "values", "1 NaN value(s) present"),
    (lambda p: np.save(p / "i.npy", np.array([[0.0, np.inf]])), {"allow_inf": False}, "values", "infinite"),
    (lambda p: np.save(p / "i.npy", np.zeros((2, 3, 2))), {"channels": 3}, "channels",
     "wrong channel count 2 (expected 3)"),
    (lambda p: np.save(p / "i.npy", np.zeros(5)), {}, "shape", "wrong shape (5,)"),
    (lambda p: np.save(p / "i.npy", np.zeros((2, 2, 2, 2))), {}, "shape", "wrong shape"),
    (lambda p: np.save(p / "i.npy", np.zeros((0, 3))), {}, "shape", "wrong shape"),
    (lambda p: (p / "i.npy").write_bytes(b"not numpy"), {}, "", "unreadable NPY"),
])
def test_reader_errors(tmp_path, setup, kwargs, field, reason):
    setup(tmp_path)
    with pytest.raises(InputError) as exc:
        read_image(tmp_path / "i.npy", **kwargs)
    assert exc.value.path == field
    assert reason in exc.value.reason
    assert str(tmp_path / "i.npy") in str(exc.value)


def test_reader_error_cases_by_file_kind(tmp_path):
    (tmp_path / "c.exr").write_bytes(b"\x76\x2f\x31\x01garbage")
    with pytest.raises(InputError, match="unreadable EXR"):
        read_image(tmp_path / "c.exr")
    (tmp_path / "c.png").write_bytes(b"\x89PNG\r\n\x1a\nbroken")
    with pytest.raises(InputError, match="unreadable PNG"):
        read_image(tmp_path / "c.png")
    with pytest.raises(InputError, match="file not found"):
        read_image(tmp_path / "missing.exr")
    (tmp_path / "x.tif").write_bytes(b"")
    with pytest.raises(InputError, match="unsupported file type '.tif'"):
        read_image(tmp_path / "x.tif")
    np.savez(tmp_path / "two.npz", a=np.zeros((2, 2)), b=np.zeros((2, 2)))
    with pytest.raises(InputError, match="holds arrays a, b"):
        read_image(tmp_path / "two.npz")
    with pytest.raises(InputError, match="no such array") as exc:
        read_image(tmp_path / "two.npz", key="c")
    assert exc.value.path == "c"
    write_exr(tmp_path / "n.exr", np.array([[1.0, np.nan]]))
    with pytest.raises(InputError, match="NaN"):
        read_image(tmp_path / "n.exr")
    write_exr(tmp_path / "inf.exr", np.array([[1.0, np.inf]]))
    with pytest.raises(InputError, match="infinite value"):
        read_image(tmp_path / "inf.exr", allow_inf=False)
    assert np.isinf(read_image(tmp_path / "inf.exr")).sum() == 1  # inf is legal by default (sky depth)


# --------------------------------------------------------------------------- atomicity

def test_failed_exr_write_leaves_nothing(tmp_path, monkeypatch):
    def boom(self, target):
        target.write(b"partial bytes")
        raise RuntimeError("disk full")
    monkeypatch.setattr(OpenEXR.File, "write", boom)
    with pytest.raises(RuntimeError, match="disk full"):
        write_exr(tmp_path / "a.exr", np.zeros((2, 2)))
    assert _no_stray_files(tmp_path) == []


def test_failed_overwrite_keeps_the_old_file(tmp_path, monkeypatch):
    path = write_npy(tmp_path / "a.npy", np.arange(4.0))
    before = path.read_bytes()

    def boom(fh, arr, allow_pickle=False):
        fh.write(b"\x93NUMPY partial")
        raise KeyboardInterrupt
    monkeypatch.setattr(np, "save", boom)
    with pytest.raises(KeyboardInterrupt):
        write_npy(path, np.zeros(4))
    assert path.read_bytes() == before
    assert _no_stray_files(tmp_path) == ["a.npy"]


def test_written_files_have_ordinary_permissions(tmp_path):
    path = write_png(tmp_path / "p.png", np.zeros((2, 2, 3)))
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_output_dir_moves_files_in_on_success(tmp_path):
    out = tmp_path / "a" / "b" / "out"
    with output_dir(out) as tmp:
        assert tmp != out and not out.exists()
        write_npy(tmp / "x.npy", np.zeros(3))
        (tmp / "sub").mkdir()
        write_text(tmp / "sub" / "note.txt", "hello")
    assert sorted(p.name for p in out.iterdir()) == ["sub", "x.npy"]
    assert (out / "sub" / "note.txt").read_text() == "hello"
    assert _no_stray_files(out.parent) == ["out"]


def test_output_dir_leaves_nothing_on_failure(tmp_path):
    out = tmp_path / "new" / "out"
    with pytest.raises(ValueError):
        with output_dir(out) as tmp:
            write_npy(tmp / "x.npy", np.zeros(3))
            raise ValueError("render failed")
    assert _no_stray_files(tmp_path) == []  # not even the missing parent was created
    existing = tmp_path / "keep"
    existing.mkdir()
    (existing / "old.txt").write_text("old")
    with pytest.raises(ValueError):
        with output_dir(existing) as tmp:
            write_text(tmp / "old.txt", "new")
            raise ValueError
    assert (existing / "old.txt").read_text() == "old"
    assert _no_stray_files(tmp_path) == ["keep"]
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError, match="not a folder"):
        with output_dir(tmp_path / "file"):
            pass


def _record_syncs_and_moves(monkeypatch, fail: bool = False):
    """Wrap os.fsync and os.replace: the events in order, a file known by its inode (it survives renames);
    ``fail``: every fsync of a file (not of a folder) raises OSError."""
    import stat
    import threading

    events, fsync, replace = [], os.fsync, os.replace

    def recording_fsync(fd):
        st = os.fstat(fd)
        events.append(("fsync", st.st_ino, threading.current_thread().name))
        if fail and not stat.S_ISDIR(st.st_mode):
            raise OSError(5, "Input/output error")
        return fsync(fd)

    def recording_replace(src, dst):
        events.append(("replace", os.stat(src).st_ino, str(dst)))
        return replace(src, dst)

    monkeypatch.setattr(os, "fsync", recording_fsync)
    monkeypatch.setattr(os, "replace", recording_replace)
    return events


def _fake_result():
    rng = np.random.default_rng(11)
    return types.SimpleNamespace(buffers={"final": rng.random((8, 12, 3)), "depth": rng.random((8, 12)) * 50.0},
                                 metadata={"technique": "physical"})


def test_output_dir_has_every_file_on_disk_before_it_moves_one_in(tmp_path, monkeypatch):
    out = tmp_path / "out"
    events = _record_syncs_and_moves(monkeypatch)
    with output_dir(out) as tmp:
        save_render(tmp, _fake_result(), stages=False, main=("final", "depth"))
    names = sorted(p.name for p in out.iterdir())
    assert names == ["depth.exr", "final.exr", "final.png"]
    inodes = {(out / n).stat().st_ino: n for n in names}
    moves_in = [i for i, e in enumerate(events) if e[0] == "replace" and e[2].startswith(str(out) + os.sep)]
    assert sorted(inodes[events[i][1]] for i in moves_in) == names
    for ino, name in inodes.items():  # each file's data flushed, on an fsync thread, before the first move in
        syncs = [i for i, e in enumerate(events) if e[0] == "fsync" and e[1] == ino]
        assert syncs and max(syncs) < min(moves_in), name
        assert all(events[i][2].startswith("vlref-fsync") for i in syncs), name
    # then the destination folder's entries
    assert events[-1][0] == "fsync" and events[-1][1] == out.stat().st_ino
    # outside an output folder: the file flushed on the calling thread before its rename, as always
    events.clear()
    path = write_text(tmp_path / "alone.txt", "x")
    kinds = [(e[0], e[1] == path.stat().st_ino) for e in events]
    assert kinds[:2] == [("fsync", True), ("replace", True)]
    assert events[0][2] == __import__("threading").current_thread().name


def test_output_dir_whose_file_cannot_be_synced_leaves_nothing(tmp_path, monkeypatch):
    events = _record_syncs_and_moves(monkeypatch, fail=True)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="Input/output error"):
        with output_dir(out) as tmp:
            save_render(tmp, _fake_result(), stages=False, main=("final", "depth"))
    assert _no_stray_files(tmp_path) == []  # neither the destination nor the temporary folder
    assert not any(e[0] == "replace" and e[2].startswith(str(out)) for e in events)


def test_save_buffers_and_save_render(tmp_path):
    rng = np.random.default_rng(3)
    buffers = {"final": rng.random((4, 6, 3)), "depth": np.where(rng.random((4, 6)) < 0.3, np.inf, 5.0),
               "object_id": np.full((4, 6), -1, np.int32)}
    paths = save_buffers(tmp_path, buffers, {"scene_hash": "h"})
    assert [p.name for p in paths] == ["final.exr", "depth.exr", "object_id.exr"]  # the buffers' order
    # each file holds the bytes write_exr writes alone
    alone = tmp_path / "alone"
    alone.mkdir()
    for name, array in buffers.items():
        write_exr(alone / f"{name}.exr", array, metadata={"scene_hash": "h"})
        assert (alone / f"{name}.exr").read_bytes() == (tmp_path / f"{name}.exr").read_bytes(), name
    np.testing.assert_array_equal(read_image(tmp_path / "depth.exr")[:, :, 0],
                                  buffers["depth"].astype(np.float32))
    assert read_exr(tmp_path / "final.exr")[1]["scene_hash"] == "h"
    checked = tmp_path / "checked"
    checked.mkdir()
    with pytest.raises(ValueError, match="safe file name"):
        save_buffers(checked, {"ok": np.zeros((2, 2)), "../evil": np.zeros((2, 2))})
    assert _no_stray_files(checked) == []  # validated before the first write
    result = types.SimpleNamespace(buffers=buffers, metadata={"technique": "physical"})
    out = tmp_path / "render"
    out.mkdir()
    written = save_render(out, result, stages=False, main=("final", "depth", "inscatter"), exposure=1.0)
    assert sorted(p.name for p in written) == ["depth.exr", "final.exr", "final.png"]
    assert read_exr(out / "final.exr")[1]["technique"] == "physical"


def test_half_float_buffers_round_trip_to_the_nearest_half(tmp_path):
    rng = np.random.default_rng(5)
    final = rng.random((5, 7, 3)) * 10.0
    final[0, 0] = (70000.0, -1e-9, 6e-8)  # beyond half's range -> inf; a negative underflow; a subnormal
    result = types.SimpleNamespace(buffers={"final": final, "depth": rng.random((5, 7)) * 100.0},
                                   metadata={"technique": "physical"})
    save_render(tmp_path, result, stages=False, main=("final", "depth"), half=("final",))
    channels, meta = read_exr(tmp_path / "final.exr")
    assert meta["technique"] == "physical" and channels["R"].dtype == np.float32
    with np.errstate(over="ignore"):
        want = final.astype(np.float32).astype(np.float16).astype(np.float32)
    assert np.array_equal(read_image(tmp_path / "final.exr"), want)
    assert read_image(tmp_path / "final.exr")[0, 0, 0] == np.inf
    # depth was not asked for: float32, bit for bit; half files are smaller
    np.testing.assert_array_equal(read_image(tmp_path / "depth.exr")[:, :, 0],
                                  result.buffers["depth"].astype(np.float32))
    with OpenEXR.File(str(tmp_path / "final.exr")) as f:
        assert f.channels()["RGB"].pixels.dtype == np.float16
    with pytest.raises(ValueError, match="stay float32"):
        save_buffers(tmp_path, {"object_id": np.zeros((2, 2), np.int32)}, half=("object_id",))


def test_exr_writer_uses_a_thread_per_core():
    _openexr()  # the pool is sized on first use
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert OpenEXR.global_thread_count() == cores


def _first_chunk_zlib_level(path):
    """The FLEVEL field (0 fastest .. 3 slowest, RFC 1950) of the zlib stream of a scanline EXR's first chunk: the
    header's attributes skipped to the empty name that ends them, the offset table's first entry, the chunk's
    (y, size) and its data."""
    data, pos = path.read_bytes(), 8
    while data[pos] != 0:
        type_end = data.index(b"\0", data.index(b"\0", pos) + 1)
        pos = type_end + 5 + struct.unpack_from("<i", data, type_end + 1)[0]
    chunk = struct.unpack_from("<Q", data, pos + 1)[0]
    cmf, flg = data[chunk + 8], data[chunk + 9]
    assert cmf == 0x78 and (cmf * 256 + flg) % 31 == 0  # deflate with a 32 KiB window, a valid check
    return flg >> 6


def test_exr_files_are_deflated_at_the_fastest_level(tmp_path):
    # a smooth image, which deflate shrinks (OpenEXR stores a chunk that it cannot shrink as it is)
    img = np.add.outer(np.linspace(0, 1, 64), np.linspace(0, 2, 48)).astype(np.float32)
    assert ZIP_LEVEL == 1
    assert _first_chunk_zlib_level(write_exr(tmp_path / "vlref.exr", img)) == 0  # libdeflate: levels 0-1
    OpenEXR_module = _openexr()
    try:
        assert _set_default_zip_level(OpenEXR_module, 4)  # OpenEXR's own default, where the level is read
        assert _first_chunk_zlib_level(write_exr(tmp_path / "level4.exr", img)) == 1  # levels 2-5
    finally:
        _set_default_zip_level(OpenEXR_module, ZIP_LEVEL)
    for name in ("vlref.exr", "level4.exr"):  # lossless either way
        np.testing.assert_array_equal(read_image(tmp_path / name)[:, :, 0], img)


def _srgb8_formula(v, exposure):
    """srgb8's formula written out, on the whole array at once."""
    x = np.clip(np.nan_to_num(v * exposure, nan=0.0, posinf=1e6, neginf=0.0), 0.0, 1e6)
    y = np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    s = np.where(y <= 0.0031308, 12.92 * y, 1.055 * np.power(y, 1.0 / 2.4) - 0.055)
    return np.round(np.clip(s, 0.0, 1.0) * 255.0).astype(np.uint8)


def test_srgb8_in_bands_is_the_formula_on_the_whole_image():
    # the preview runs in bands of rows on threads, each in chunks of rows evaluated in place: the codes must be
    # those of the formula on the whole array at once, at and around every half code (the values that round
    # half way)
    rng = np.random.default_rng(2)
    s = (np.arange(255) + 0.5) / 255.0
    y = np.where(s <= 12.92 * 0.0031308, s / 12.92, ((s + 0.055) / 1.055) ** 2.4)  # sRGB OETF inverted
    a, b = 2.51 - 2.43 * y, 0.03 - 0.59 * y  # ACES fit inverted: a x^2 + b x - 0.14 y = 0
    x = (-b + np.sqrt(b * b + 4.0 * a * 0.14 * y)) / (2.0 * a)
    special = [np.nan, np.inf, -np.inf, -1.0, 0.0, 1e7]
    h, w = 1031, 701
    v = np.concatenate([np.tile(np.concatenate([x, np.nextafter(x, 0.0), np.nextafter(x, 9.0), special]), 40),
                        rng.random(3 * h * w - 40 * (3 * 255 + 6)) * 8.0]).reshape(h, w, 3)
    assert v.size // _SRGB_BAND >= 2 and v.shape[0] // (v.size // _SRGB_BAND) > _SRGB_CHUNK // (3 * w)  # bands, chunks
    for exposure in (1.0, 0.37):
        assert np.array_equal(srgb8(v, exposure), _srgb8_formula(v, exposure))
        assert np.array_equal(_srgb8_values(v, exposure), _srgb8_formula(v, exposure))
    assert np.array_equal(srgb8(v[:2, :2]), _srgb8_formula(v[:2, :2], 1.0))


def test_percentile_exposure_maps_the_percentile_of_the_finite_values_to_one_and_leaves_the_input_alone():
    rng = np.random.default_rng(5)
    lum = rng.random((37, 41)) * 10.0
    lum[::5, ::3] = np.inf
    before = lum.copy()
    exposure, level = percentile_exposure(lum, 99.0)
    assert level == np.percentile(lum[np.isfinite(lum)], 99.0) and exposure == 1.0 / level
    assert np.array_equal(lum, before)  # partitioned in place: a copy, not the caller's array
    assert percentile_exposure(np.zeros((3, 3))) == (1.0, 0.0)  # a black image keeps exposure 1
