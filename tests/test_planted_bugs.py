"""The oracle catches real port bugs: each planted mistake FAILS `compare` under its port preset, while the
faithful float32/fp16 port PASSES (tests/planted_ports.py builds both from vlref's own passes)."""

import inspect

import pytest

from planted_ports import CASES, correct_port
from vlref.oracle.compare import compare_arrays
from vlref.render import render
from vlref.scene import load_scene


def _margin(report) -> str:
    m, t = report.metrics, report.thresholds
    margins = report.margins()  # value / bound, inf for failing pixels where none is allowed
    return (f"failing {m['failing_pixels']} px ({m['frac_failing']:.4f} / {t['max_fail_fraction']:g} = "
            f"{margins['failing_fraction']:.2f}x), mean {m['mean_abs']:.3g} / {t['mean_abs_bound']:.3g} "
            f"= {margins['mean_abs_error']:.2f}x")


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_planted_bug_fails_and_correct_port_passes(case, monkeypatch):
    scene = load_scene(case.scene, case.overrides)
    ref = render(scene).buffers["final"]

    good = compare_arrays(ref, correct_port(scene), case.preset, flip=False)
    assert good.passed, f"faithful port rejected: {_margin(good)}"

    port = case.port
    bad_img = port(scene, monkeypatch) if "monkeypatch" in inspect.signature(port).parameters else port(scene)
    bad = compare_arrays(ref, bad_img, case.preset, flip=False)
    print(f"{case.name}: correct port {_margin(good)}; planted bug {_margin(bad)}")
    assert not bad.passed, f"planted bug {case.name} passed {case.preset}: {_margin(bad)}"
    # the bug is not a borderline call: the faithful port fails no pixel, the bug fails at least 1 % of
    # them (a share, not one knife-edge pixel) or exceeds the mean-error bound by 1.5x
    assert good.metrics["failing_pixels"] == 0
    assert bad.metrics["frac_failing"] >= 0.01 or bad.margins()["mean_abs_error"] > 1.5
