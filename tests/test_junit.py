"""JUnit XML (vlref.oracle.junit) from `vlref compare --junit` and `vlref golden verify --junit`: valid against the
Jenkins/Ant JUnit schema (tests/data/junit.xsd), one test case per comparison, failures carrying the failed
checks, the metrics and the report's path."""

import hashlib
import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

import junit_schema
from vlref.cli import main
from vlref.io.exr import write_exr
from vlref.io.images import read_image
from vlref.oracle.golden import MANIFEST
from vlref.oracle.junit import Case, junit_xml

GOLDEN_DIR = Path(__file__).resolve().parents[1] / "data" / "golden"
ONE = "pillars/physical"


def _cases(path):
    root = ET.parse(path).getroot()
    return root, {tc.get("name"): tc for tc in root.iter("testcase")}


def test_the_validator_rejects_what_the_schema_forbids():
    good = junit_xml("s", [Case("a", True), Case("b", False, {"x": 1.5}, "r/report.html", "x too large")])
    assert junit_schema.problems(good) == []
    assert junit_schema.problems(good.replace('<testcase classname="s" name="a"', '<testcase classname="s"')) == [
        "/testsuites/testsuite/testcase: required attribute name missing"]
    assert junit_schema.problems(good.replace("<system-out>", "<stdout>").replace("</system-out>", "</stdout>"))
    assert junit_schema.problems(good.replace('errors="0" skipped', 'errorz="0" skipped'))
    assert junit_schema.problems(good.replace('time="0.000"', 'time="1 s"', 1))


def test_cases_counts_and_failure_details():
    xml = junit_xml("vlref port", [Case("march", True, {"failing_pixels": 0}),
                                   Case("final", False, {"failing_pixels": 12, "mean_abs": 0.25},
                                        "out/final/report.html", "failing_fraction 0.05 > 0.02", 1.25)])
    assert junit_schema.problems(xml) == []
    root = ET.fromstring(xml)
    suite = root.find("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors"), suite.get("time")) == ("2", "1", "0",
                                                                                                    "1.250")
    march, final = suite.findall("testcase")
    assert march.find("failure") is None and march.find("system-out").text == "failing_pixels = 0"
    failure = final.find("failure")
    assert failure.get("message") == "failing_fraction 0.05 > 0.02"
    assert failure.text.splitlines() == ["failing_pixels = 12", "mean_abs = 0.25", "report: out/final/report.html"]


def test_cli_compare_junit_pass_and_fail(tmp_path):
    ref = np.linspace(0.1, 1.0, 16 * 8 * 3).reshape(8, 16, 3)
    np.save(tmp_path / "ref.npy", ref)
    np.save(tmp_path / "same.npy", ref)
    bad = ref.copy()
    bad[:4] *= 1.5   # half the pixels 50 % off
    np.save(tmp_path / "bad.npy", bad)
    assert main(["compare", str(tmp_path / "ref.npy"), str(tmp_path / "same.npy"), "-q", "--no-flip",
                 "--junit", str(tmp_path / "pass.xml")]) == 0
    assert main(["compare", str(tmp_path / "ref.npy"), str(tmp_path / "bad.npy"), "-q", "--no-flip",
                 "-o", str(tmp_path / "out"), "--junit", str(tmp_path / "fail.xml")]) == 1
    for name in ("pass.xml", "fail.xml"):
        assert junit_schema.problems((tmp_path / name).read_text()) == []
    _, cases = _cases(tmp_path / "pass.xml")
    assert list(cases) == ["same.npy vs ref.npy"] and cases["same.npy vs ref.npy"].find("failure") is None
    root, cases = _cases(tmp_path / "fail.xml")
    failure = cases["bad.npy vs ref.npy"].find("failure")
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert failure.get("message").startswith("failing_fraction 0.5 > 0.001")
    lines = dict(line.split(" = ") for line in failure.text.splitlines() if " = " in line)
    assert int(lines["failing_pixels"]) == report["metrics"]["failing_pixels"] == 64
    assert float(lines["mean_abs"]) == float(f"{report['metrics']['mean_abs']:.6g}")
    assert f"report: {tmp_path / 'out' / 'report.html'}" in failure.text
    assert main(["compare", str(tmp_path / "ref.npy"), str(tmp_path / "bad.npy"), "-q", "--no-flip",
                 "--junit", str(tmp_path)]) == 2   # a folder is no file


def test_golden_verify_junit_one_case_per_buffer(tmp_path):
    """An edited golden (checksum updated): the inscatter case fails with its numbers, the other buffers pass."""
    golden = tmp_path / "golden"
    shutil.copytree(GOLDEN_DIR, golden)
    manifest = json.loads((golden / MANIFEST).read_text())
    record = next(e for e in manifest["entries"] if e["name"] == ONE)
    path = golden / record["files"]["inscatter"]["path"]
    write_exr(path, read_image(path) * np.float32(1.001))
    record["files"]["inscatter"]["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
    (golden / MANIFEST).write_text(json.dumps(manifest))
    out = tmp_path / "golden.xml"
    assert main(["golden", "verify", "-q", "--dir", str(golden), "--only", ONE, "--junit", str(out)]) == 1
    assert junit_schema.problems(out.read_text()) == []
    root, cases = _cases(out)
    assert set(cases) == {f"{ONE} {b}" for b in record["files"]}
    assert root.find("testsuite").get("failures") == "1"
    failure = cases[f"{ONE} inscatter"].find("failure")
    assert failure.get("message").startswith("inscatter: differs beyond preset float32")
    assert float(dict(line.split(" = ") for line in failure.text.splitlines())["frac_failing"]) > 0.001
    assert all(cases[f"{ONE} {b}"].find("failure") is None for b in record["files"] if b != "inscatter")


def test_verdict_junit_one_case_per_comparison(tmp_path):
    """vlref exported as its own port with its inscatter pass scaled by 1.5: `vlref verdict --junit` has one case
    per comparison of verdict.json, the inscatter case failing with verdict.json's reason and report path."""
    from vlref.port.export import export_port

    port = export_port("pillars", tmp_path / "port", ["render.width=64", "render.height=36", "render.steps=8",
                                                      "lights.0.shadows.resolution=128"], passes=True).parent
    path = port / "port_inscatter.npy"
    np.save(path, np.load(path) * 1.5)
    out, xml = tmp_path / "verdict", tmp_path / "verdict.xml"
    assert main(["verdict", str(port / "port.toml"), "-o", str(out), "-q", "--junit", str(xml)]) == 1
    assert junit_schema.problems(xml.read_text()) == []
    passes = json.loads((out / "verdict.json").read_text())["passes"]
    root, cases = _cases(xml)
    assert list(cases) == [f"{p['group']}: {p['name']}" for p in passes]
    assert root.find("testsuite").get("failures") == str(sum(not p["passed"] for p in passes)) != "0"
    for p in passes:
        failure = cases[f"{p['group']}: {p['name']}"].find("failure")
        assert (failure is None) == p["passed"]
        if failure is not None:
            assert failure.get("message") == p["reason"] and f"report: {p['report']}" in failure.text
            assert Path(p["report"]).is_file()
    bad = cases[next(f"{p['group']}: {p['name']}" for p in passes if p["name"] == "inscatter")].find("failure")
    lines = dict(line.split(" = ") for line in bad.text.splitlines() if " = " in line)
    assert int(lines["failing_pixels"]) > 0 and any(k.startswith("margins.") for k in lines)   # nested: flattened
