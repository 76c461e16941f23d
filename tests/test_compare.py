"""vlref.oracle: metrics, the pass/fail rule and its boundaries, presets, masks, outputs, exit codes."""

import base64
import dataclasses
import json
import math
import sys

import imageio.v3 as iio
import numpy as np
import pytest

from vlref.cli import main
from vlref.errors import InputError
from vlref.io.exr import read_exr, write_exr
from vlref.io.files import write_npy
from vlref.io.images import read_image
from vlref.oracle import compare_arrays, compare_files, load_presets, tolerance
from vlref.oracle.metrics import error_metrics, failing_pixels, hdr_flip
from vlref.oracle.presets import Tolerance
from vlref.oracle.report import colour_map, json_ready

H, W = 24, 32


def _tol(abs_tol=0.0, rel_tol=0.0, frac=0.0, mean=0.0, flip=None, scale="absolute"):
    return Tolerance(abs_tol, rel_tol, frac, mean, flip, scale)


def _hdr(seed=0, c=3):
    rng = np.random.default_rng(seed)
    return (rng.random((H, W, c)) * 4.0 + 0.05).astype(np.float32)


# --------------------------------------------------------------------------- metrics

def test_metrics_against_hand_computed_values():
    ref = np.array([[1.0, 2.0], [3.0, 4.0]])[:, :, None]
    test = np.array([[1.0, 2.5], [2.0, 4.0]])[:, :, None]  # |d| = 0, 0.5, 1, 0
    m = error_metrics(ref, test, np.ones((2, 2), bool), abs_thr=0.5, rel_tol=0.2)
    assert m["max_abs"] == 1.0
    assert m["mean_abs"] == 0.375
    assert m["rmse"] == pytest.approx(math.sqrt(1.25 / 4), rel=1e-15)
    assert m["rel_l2"] == pytest.approx(math.sqrt(1.25) / math.sqrt(30.0), rel=1e-15)
    assert m["peak"] == 4.0
    assert m["psnr"] == pytest.approx(10 * math.log10(16 / 0.3125), rel=1e-15)
    assert m["frac_over_abs"] == 0.25  # only d = 1 > 0.5 (d = 0.5 is at the threshold)
    assert m["frac_over_rel"] == 0.5  # 0.5 > 0.2*2 and 1 > 0.2*3
    assert m["frac_failing"] == 0.0  # d <= 0.5 + 0.2 r everywhere
    assert m["compared_pixels"] == 4
    masked = error_metrics(ref, test, np.array([[True, True], [False, True]]), 0.5, 0.2)
    assert masked["max_abs"] == 0.5 and masked["mean_abs"] == pytest.approx(0.5 / 3)


def test_metrics_degenerate_cases():
    z = np.zeros((2, 2, 1))
    same = error_metrics(z + 1, z + 1, np.ones((2, 2), bool), 0, 0)
    assert same["psnr"] == math.inf and same["rel_l2"] == 0.0 and same["max_abs"] == 0.0
    zero_ref = error_metrics(z, z + 1, np.ones((2, 2), bool), 0, 0)
    assert zero_ref["rel_l2"] == math.inf and zero_ref["psnr"] == -math.inf
    assert error_metrics(z, z, np.ones((2, 2), bool), 0, 0)["rel_l2"] == 0.0


def test_pixel_fails_when_any_channel_fails():
    ref = np.ones((1, 3, 3))
    test = ref.copy()
    test[0, 1, 2] = 1.2  # one channel of pixel 1 over the threshold 0.15
    test[0, 2, :] = 1.1  # every channel of pixel 2 off, but within the threshold
    fail = failing_pixels(ref, test, abs_thr=0.0, rel_tol=0.15)
    assert fail.tolist() == [[False, True, False]]


# --------------------------------------------------------------------------- the rule and its boundaries

def test_pixel_exactly_at_threshold_passes_and_one_ulp_above_fails():
    ref = np.ones((2, 2))
    tol = _tol(abs_tol=0.25, rel_tol=0.25, frac=0.0, mean=1.0)  # threshold 0.25 + 0.25*1 = 0.5 exactly
    at = ref.copy()
    at[0, 0] = 1.5
    rep = compare_arrays(ref, at, tol, flip=False)
    assert rep.passed and rep.metrics["failing_pixels"] == 0
    above = ref.copy()
    above[0, 0] = np.nextafter(1.5, 2.0)
    rep = compare_arrays(ref, above, tol, flip=False)
    assert not rep.passed and rep.metrics["failing_pixels"] == 1
    assert rep.fail.tolist() == [[True, False], [False, False]]
    assert [c.passed for c in rep.checks] == [False, True]


def test_failing_fraction_and_mean_bounds_are_inclusive():
    ref = np.zeros((2, 2))
    test = ref.copy()
    test[1, 1] = 0.5  # 1 of 4 pixels fails any zero threshold; mean |d| = 0.125
    assert compare_arrays(ref, test, _tol(frac=0.25, mean=0.125), flip=False).passed
    rep = compare_arrays(ref, test, _tol(frac=0.2499, mean=0.125), flip=False)
    assert not rep.passed and [c.passed for c in rep.checks] == [False, True]
    rep = compare_arrays(ref, test, _tol(frac=0.25, mean=0.1249), flip=False)
    assert not rep.passed and [c.passed for c in rep.checks] == [True, False]


def test_scale_mean_makes_bounds_relative_to_the_reference_level():
    ref = _hdr(1)
    s = float(np.mean(np.abs(ref.astype(np.float64))))
    tol = _tol(abs_tol=1e-3, rel_tol=0.0, frac=0.0, mean=2e-3, scale="mean")
    rep = compare_arrays(ref, ref, tol, flip=False)
    assert rep.thresholds["S"] == pytest.approx(s, rel=1e-12)
    assert rep.thresholds["abs_threshold"] == pytest.approx(1e-3 * s, rel=1e-12)
    assert rep.thresholds["mean_abs_bound"] == pytest.approx(2e-3 * s, rel=1e-12)
    # the verdict is invariant to a common scale factor (power of two: exact)
    test = ref + np.float32(0.9e-3 * s)
    for k in (1.0, 2.0 ** -20, 2.0 ** 30):
        assert compare_arrays(ref * k, test * k, tol, flip=False).passed
    assert not compare_arrays(ref, ref + np.float32(1.1e-3 * s), tol, flip=False).passed


def test_exact_preset_detects_one_ulp():
    ref = _hdr(2)
    assert compare_arrays(ref, ref.copy(), "exact", flip=False).passed
    test = ref.copy()
    test[5, 7, 1] = np.nextafter(test[5, 7, 1], np.float32(10))
    rep = compare_arrays(ref, test, "exact", flip=False)
    assert not rep.passed and rep.metrics["failing_pixels"] == 1


def test_float32_preset_passes_float32_rounding_and_fails_a_one_percent_error():
    ref64 = _hdr(3).astype(np.float64) * (1 + 1e-7 * np.arange(H * W * 3).reshape(H, W, 3))
    rounded = ref64.astype(np.float32)  # a faithful float32 port: errors <= 2^-24 relative
    assert compare_arrays(ref64, rounded, "float32").passed
    assert not compare_arrays(ref64, ref64 * 1.01, "float32").passed


# --------------------------------------------------------------------------- presets

def test_presets_load_and_loosen_in_order():
    presets = load_presets()
    order = ["float32", "gpu-full", "gpu-half", "gpu-quarter"]
    assert set(presets) == {"exact", *order, "raster-depth", "raster-shadow-map", "raster-shadow-test",
                            "raster-colour", "end-to-end", "gpu-sampled", "gpu-float32"}
    exact = presets["exact"]
    assert (exact.abs_tol, exact.rel_tol, exact.max_fail_fraction, exact.max_mean_abs) == (0, 0, 0, 0)
    for key in ("abs_tol", "rel_tol", "max_mean_abs", "edge_pixels", "edge_rel", "edge_abs"):
        values = [getattr(presets[n], key) for n in order]
        assert all(a < b for a, b in zip(values, values[1:])), key
    # GPU ports: no failing pixel outside the edge zone; float32 keeps its knife-edge share
    assert [presets[n].max_fail_fraction for n in order] == [1e-3, 0.0, 0.0, 0.0]
    # what a port reads through its sampler (8-bit filter weights): gpu-half per texel, plus a bounded share
    sampled, half = presets["gpu-sampled"], presets["gpu-half"]
    assert (sampled.rel_tol, sampled.abs_tol, sampled.max_mean_abs) == (half.rel_tol, half.abs_tol, half.max_mean_abs)
    assert 0 < sampled.max_fail_fraction <= 2e-2
    for p in presets.values():
        assert p.description and p.max_flip_mean is None


def test_overrides_and_bad_knobs():
    t = tolerance("gpu-full", {"rel_tol": "0.5", "max_flip_mean": "0.1", "scale": "absolute"})
    assert (t.rel_tol, t.max_flip_mean, t.scale) == (0.5, 0.1, "absolute")
    assert t.abs_tol == load_presets()["gpu-full"].abs_tol
    assert tolerance("float32", {"max_flip_mean": "none"}).max_flip_mean is None
    with pytest.raises(InputError, match="did you mean rel_tol"):
        tolerance("float32", {"rel_tl": 1})
    with pytest.raises(InputError, match="did you mean gpu-half"):
        tolerance("gpu-hlf")
    with pytest.raises(InputError, match=">= 0"):
        tolerance("float32", {"abs_tol": -1})
    with pytest.raises(InputError, match="not a number"):
        tolerance("float32", {"abs_tol": "lots"})
    with pytest.raises(InputError, match="fraction"):
        tolerance("float32", {"max_fail_fraction": 2})
    with pytest.raises(InputError, match="scale"):
        tolerance("float32", {"scale": "peak"})


# --------------------------------------------------------------------------- masks

def _files(tmp_path, ref, test, kind="exr"):
    r, t = tmp_path / f"ref.{kind}", tmp_path / f"test.{kind}"
    write = write_exr if kind == "exr" else write_npy
    write(r, ref)
    write(t, test)
    return r, t


def test_border_mask(tmp_path):
    ref = _hdr(4)
    test = ref.copy()
    test[0, 5] += 10.0
    test[H - 2, W - 2] += 10.0
    r, t = _files(tmp_path, ref, test)
    assert not compare_files(r, t, "float32", border=1, flip=False).passed
    rep = compare_files(r, t, "float32", border=2, flip=False)
    assert rep.passed and rep.metrics["compared_pixels"] == (H - 4) * (W - 4)
    assert rep.metrics["total_pixels"] == H * W


def test_sky_masks(tmp_path):
    ref = _hdr(5)
    depth = np.full((H, W), 7.0)
    depth[:8] = np.inf  # sky in the top rows
    depth[8:10] = 1000.0  # far plane of an engine depth buffer
    test = ref.copy()
    test[:10] *= 3.0  # wrong only in the sky
    r, t = _files(tmp_path, ref, test)
    write_exr(tmp_path / "depth.exr", depth)
    assert not compare_files(r, t, flip=False, ignore_sky=str(tmp_path / "depth.exr")).passed
    rep = compare_files(r, t, flip=False, ignore_sky=str(tmp_path / "depth.exr"), sky_depth=1000.0)
    assert rep.passed and rep.metrics["compared_pixels"] == (H - 10) * W
    # comparing depth buffers: the reference's own non-finite pixels are its sky
    dr, dt = _files(tmp_path, depth[:, :, None], np.where(np.isinf(depth), np.inf, depth)[:, :, None], "npy")
    with pytest.raises(InputError, match="infinite values in compared pixels"):
        compare_files(dr, dt, flip=False)
    assert compare_files(dr, dt, "exact", flip=False, ignore_sky="ref").passed
    write_exr(tmp_path / "d2.exr", np.zeros((H, W, 3)))
    with pytest.raises(InputError, match="wrong channel count 3"):
        compare_files(r, t, flip=False, ignore_sky=str(tmp_path / "d2.exr"))


def test_user_mask_image(tmp_path):
    ref = _hdr(6)
    test = ref.copy()
    test[3:6, 4:9] = 0.0
    r, t = _files(tmp_path, ref, test)
    mask = np.full((H, W), 255, np.uint8)
    mask[3:6, 4:9] = 0
    iio.imwrite(tmp_path / "mask.png", mask)
    rep = compare_files(r, t, flip=False, mask=str(tmp_path / "mask.png"))
    assert rep.passed and rep.metrics["compared_pixels"] == H * W - 15
    assert not compare_files(r, t, flip=False).passed
    iio.imwrite(tmp_path / "small.png", mask[:-1])
    with pytest.raises(InputError, match="mask image is 32x23"):
        compare_files(r, t, flip=False, mask=str(tmp_path / "small.png"))
    iio.imwrite(tmp_path / "none.png", np.zeros((H, W), np.uint8))
    with pytest.raises(InputError, match="no pixel to compare"):
        compare_files(r, t, flip=False, mask=str(tmp_path / "none.png"))


def test_input_mismatches_are_input_errors():
    ref = _hdr(7)
    with pytest.raises(InputError, match="1 channel\\(s\\), the reference has 3"):
        compare_arrays(ref, ref[:, :, :1], "float32")
    with pytest.raises(InputError, match="size 32x23 differs"):
        compare_arrays(ref, ref[:-1], "float32")
    bad = ref.copy()
    bad[2, 3, 0] = np.nan
    with pytest.raises(InputError, match="NaN present .*x=3, y=2"):
        compare_arrays(ref, bad, "float32")


def test_any_matching_channel_count(tmp_path):
    ref = np.random.default_rng(8).random((H, W, 6))
    r, t = _files(tmp_path, ref, ref * 1.5, "npy")
    rep = compare_files(r, t, "gpu-full", out_dir=tmp_path / "out")
    assert not rep.passed and not rep.flip.available and "6" in rep.flip.note
    chans, _ = read_exr(tmp_path / "out" / "diff.exr")
    assert len(chans) == 6


# --------------------------------------------------------------------------- HDR-FLIP

def test_flip_identical_zero_different_positive():
    ref = _hdr(9)
    mask = np.ones((H, W), bool)
    same = hdr_flip(ref, ref, mask)
    assert same.available and same.mean == 0.0 and same.error_map.shape == (H, W)
    diff = hdr_flip(ref, ref * 1.5, mask)
    assert 0.0 < diff.mean <= 1.0 and np.all((diff.error_map >= 0) & (diff.error_map <= 1))
    grey = hdr_flip(ref[:, :, :1], ref[:, :, :1] * 1.5, mask)
    assert grey.available and grey.mean > 0


def test_flip_dark_and_black_references():
    ref = _hdr(10)
    mask = np.ones((H, W), bool)
    base = hdr_flip(ref, ref * 1.2, mask).mean
    # HDR-FLIP picks its exposures from the reference, so a common scale changes nothing
    dark = hdr_flip(ref * 1e-12, ref * 1.2e-12, mask).mean
    assert dark == pytest.approx(base, rel=1e-3)
    black = hdr_flip(np.zeros((H, W, 3)), np.ones((H, W, 3)), mask)  # the library would abort here
    assert not black.available and "black" in black.note
    neg = hdr_flip(ref - 1.0, ref, mask)
    assert "negative values clipped" in neg.note


def test_flip_unavailable_is_not_a_failure(monkeypatch):
    monkeypatch.setitem(sys.modules, "flip_evaluator", None)  # import raises ImportError
    ref = _hdr(11)
    rep = compare_arrays(ref, ref, tolerance("float32", {"max_flip_mean": 0.01}))
    assert rep.passed and not rep.flip.available and "not installed" in rep.flip.note
    assert rep.checks[-1].name == "flip_mean" and rep.checks[-1].passed is None


def test_flip_gate():
    ref = _hdr(12)
    rep = compare_arrays(ref, ref * 1.001, tolerance("float32", {"max_flip_mean": 1e-6, "rel_tol": 1,
                                                                 "max_mean_abs": 1}))
    assert rep.flip.mean > 1e-6 and not rep.passed
    assert [c.name for c in rep.checks if c.passed is False] == ["flip_mean"]


# --------------------------------------------------------------------------- outputs and exit codes

def test_outputs_json_exr_png_html(tmp_path):
    ref = _hdr(13)
    test = ref.copy()
    test[10:14, 10:20] *= 1.3
    r, t = _files(tmp_path, ref, test)
    out = tmp_path / "report"
    rep = compare_files(r, t, "gpu-full", {"rel_tol": 0.01}, out_dir=out)
    assert sorted(p.name for p in out.iterdir()) == ["diff.exr", "flip.png", "heatmap.png", "report.html",
                                                     "report.json"]
    data = json.loads((out / "report.json").read_text())
    assert data["verdict"] == "fail" and data["preset"] == "gpu-full+overrides"
    assert data["tolerance"]["rel_tol"] == 0.01 and data["inputs"]["test"] == str(t)
    assert data["metrics"]["max_abs"] == rep.metrics["max_abs"]
    assert data["metrics"]["failing_pixels"] == 40
    assert data["flip"]["mean"] == rep.flip.mean
    diff = read_image(out / "diff.exr")
    np.testing.assert_array_equal(diff, np.abs(test - ref))
    heat = iio.imread(out / "heatmap.png")
    assert heat.shape == (H, W, 3)
    assert heat[0, 0].tolist() == colour_map(np.zeros((1, 1)))[0, 0].tolist()  # no error: the ramp's bottom
    assert heat[10:14, 10:20].astype(int).sum() > 40 * 3 * 100  # errors are bright
    page = (out / "report.html").read_text()
    assert "FAIL" in page and "gpu-full+overrides" in page
    for key in ("max_abs", "mean_abs", "rmse", "psnr"):
        assert f"{rep.metrics[key]:.6g}" in page
    images = page.split('src="data:image/png;base64,')[1:]
    assert len(images) == 5  # reference, test, heat map, failing pixels, FLIP
    for chunk in images:
        assert base64.b64decode(chunk.split('"', 1)[0])[:8] == b"\x89PNG\r\n\x1a\n"
    assert "http://" not in page and "https://" not in page  # self-contained


def test_json_spells_non_finite_numbers():
    ref = _hdr(14)
    rep = compare_arrays(ref, ref, "exact", flip=False)
    text = json.dumps(json_ready(rep.to_dict()), allow_nan=False)
    assert json.loads(text)["metrics"]["psnr"] == "inf"


def test_failed_output_writing_leaves_no_folder(tmp_path, monkeypatch):
    from vlref.oracle import report
    ref = _hdr(15)
    r, t = _files(tmp_path, ref, ref)
    monkeypatch.setattr(report, "render_html", lambda *a, **k: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        compare_files(r, t, out_dir=tmp_path / "out")
    assert not (tmp_path / "out").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ref.exr", "test.exr"]


def test_compare_command_exit_codes(tmp_path, capsys):
    ref = _hdr(16)
    r, t = _files(tmp_path, ref, ref * np.float32(1 + 2 ** -22))
    assert main(["compare", str(r), str(t)]) == 0
    assert "PASS" in capsys.readouterr().out
    bad = tmp_path / "bad.exr"
    write_exr(bad, ref * 1.1)
    assert main(["compare", str(r), str(bad), "-q"]) == 1
    assert capsys.readouterr().out == ""
    assert main(["compare", str(r), str(bad), "--preset", "gpu-quarter", "--set", "rel_tol=0.2",
                         "--set", "max_mean_abs=0.2"]) == 0
    assert main(["compare", str(r), str(bad), "--set", "rel_tol=0.2", "--set", "max_mean_abs=1",
                         "--set", "max_flip_mean=0.0001", "-o", str(tmp_path / "o")]) == 1
    assert (tmp_path / "o" / "report.html").is_file()
    capsys.readouterr()
    write_exr(tmp_path / "grey.exr", ref[:, :, 0])
    for argv, message in (([str(r), str(tmp_path / "missing.exr")], "file not found"),
                          ([str(r), str(tmp_path / "grey.exr")], "channel(s), the reference has 3"),
                          ([str(r), str(t), "--preset", "gpu"], "unknown preset"),
                          ([str(r), str(t), "--set", "rel_tol"], "expected KEY=VALUE"),
                          ([str(r), str(t), "--border", "-1"], "border"),
                          ([str(r)], "")):
        assert main(["compare", *argv]) == 2, argv
        assert message in capsys.readouterr().err
    assert not (tmp_path / "missing.exr").exists()


def test_every_number_knob_is_checked_from_the_class_alone():
    """The knobs come from Tolerance's fields (no list beside it): each number refuses a negative value."""
    base = dict(abs_tol=0.0, rel_tol=0.0, max_fail_fraction=0.0, max_mean_abs=0.0)
    numbers = [f.name for f in dataclasses.fields(Tolerance) if f.type in ("float", "float | None")]
    assert len(numbers) == 9
    for key in numbers:
        with pytest.raises(InputError) as exc:
            Tolerance(**{**base, key: -1.0})
        assert exc.value.path == key
