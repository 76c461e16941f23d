"""vlref's pytest plugin (vlref/pytest_plugin.py), run by pytest's own `pytester` on a small port test file: a
missing golden fails asking for --vlref-generate; --vlref-generate writes vlref's render as the golden; a
faithful "port" passes, a 1 %-off one fails naming its report; a stale golden fails; `port=` judges against
`vlref march` on the port's own buffers; summary.json/html list every comparison of the session."""

import json

import numpy as np
import pytest

from vlref.io.images import read_image
from vlref.port import export_port
from vlref.render import render
from vlref.scene import load_scene

pytest_plugins = ["pytester"]

SET = ["render.width=48", "render.height=27", "render.steps=4", "lights.0.shadows.resolution=64"]

PORT_TESTS = f"""
import numpy as np
import pytest
from vlref.render import render
from vlref.scene import load_scene

SET = {SET!r}
FINAL = render(load_scene("pillars", SET + ['render.technique="killzone"'])).buffers["final"]


@pytest.mark.vlref(scene="pillars", technique="killzone", preset="float32", overrides=SET)
def test_faithful(vlref_compare):
    report = vlref_compare(FINAL * (1 + 1e-6), "final")     # within float32's relative 1e-4
    assert report.passed and report.metrics["failing_pixels"] == 0


@pytest.mark.vlref(scene="pillars", technique="killzone", preset="float32", overrides=SET)
def test_one_percent_off(vlref_compare):
    vlref_compare(FINAL * 1.01, "final")


def test_port_buffers(vlref_compare, pytestconfig):
    port = pytestconfig.rootpath / "port" / "port.toml"
    vlref_compare(FINAL, "final", port=port, preset="float32")
"""


@pytest.fixture
def port_project(pytester):
    pytester.makepyfile(test_team_port=PORT_TESTS)  # a name no module of this suite has
    export_port("pillars", pytester.path / "port", SET + ['render.technique="killzone"'])
    return pytester


def test_plugin_workflow(port_project):
    p = port_project
    first = p.runpytest_inprocess("-p", "no:cacheprovider")
    first.assert_outcomes(passed=1, failed=2)
    first.stdout.fnmatch_lines(["*no golden*vlref_golden/killzone/pillars-*/final.exr; run pytest --vlref-generate*"])

    gen = p.runpytest_inprocess("-p", "no:cacheprovider", "--vlref-generate")
    gen.assert_outcomes(passed=2, failed=1)
    [golden] = (p.path / "vlref_golden" / "killzone").glob("pillars-*/final.exr")
    want = render(load_scene("pillars", SET + ['render.technique="killzone"'])).buffers["final"]
    np.testing.assert_array_equal(read_image(golden), want.astype(np.float32))
    meta = json.loads((golden.parent / "golden.json").read_text())
    assert meta["overrides"] == SET and meta["technique"] == "killzone"

    again = p.runpytest_inprocess("-p", "no:cacheprovider")   # the stored golden is used
    again.assert_outcomes(passed=2, failed=1)
    again.stdout.fnmatch_lines(["*vlref: final fails preset float32 against *final.exr: failing_fraction 1 > 0.001*",
                                "*report: *vlref-report/test_team_port.py_test_one_percent_off/final/report.html*",
                                "*vlref: 3 comparison(s), 1 failed; summary *summary.html*"])
    folder = p.path / "vlref-report" / "test_team_port.py_test_one_percent_off" / "final"
    report = json.loads((folder / "report.json").read_text())
    assert report["verdict"] == "fail" and report["metrics"]["failing_pixels"] == 48 * 27
    assert sorted(x.name for x in (p.path / "vlref-report").iterdir()) == [
        "summary.html", "summary.json", "test_team_port.py_test_one_percent_off"]   # passes write no report

    summary = json.loads((p.path / "vlref-report" / "summary.json").read_text())
    assert (summary["comparisons"], summary["failed"]) == (3, 1)
    by_test = {r["test"].split("::")[1]: r for r in summary["records"]}
    assert by_test["test_faithful"]["passed"] and by_test["test_port_buffers"]["passed"]
    assert by_test["test_port_buffers"]["reference"].startswith("vlref march")
    off = by_test["test_one_percent_off"]
    assert not off["passed"] and off["report"] == str(folder / "report.html")
    assert off["metrics"]["failing_pixels"] == report["metrics"]["failing_pixels"]
    page = (p.path / "vlref-report" / "summary.html").read_text()
    assert page.count("<tr class=") == 3 and 'href="test_team_port.py_test_one_percent_off/final/report.html"' in page

    meta["scene_hash"] = "0" * 64   # the scene changed since the golden was generated
    (golden.parent / "golden.json").write_text(json.dumps(meta))
    stale = p.runpytest_inprocess("-p", "no:cacheprovider", "-k", "faithful")
    stale.assert_outcomes(failed=1)
    stale.stdout.fnmatch_lines(["*is stale: the scene changed*--vlref-generate*"])


def test_report_all_and_options(port_project):
    p = port_project
    out = p.path / "elsewhere"
    p.runpytest_inprocess("-p", "no:cacheprovider", "--vlref-generate", "--vlref-reports", "all",
                          "--vlref-report-dir", str(out), "--vlref-golden-dir", "g", "-k", "faithful"
                          ).assert_outcomes(passed=1)
    assert (out / "test_team_port.py_test_faithful" / "final" / "report.html").is_file()
    assert list((p.path / "g" / "killzone").glob("pillars-*/final.exr"))
    p.makepyfile(test_bad="""
import pytest
@pytest.mark.vlref(scene="pillars", technik="killzone")
def test_typo(vlref_compare):
    vlref_compare(None, "final")
""")
    p.runpytest_inprocess("-p", "no:cacheprovider", "test_bad.py").stdout.fnmatch_lines(
        ["*@pytest.mark.vlref: unknown argument(s) technik*"])
