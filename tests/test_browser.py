"""The two pages a technical artist opens, in a real browser (Debian's Chromium driven by Playwright):

* the compare report (report.html): every image decodes, the numbers shown are report.json's, the A/B flip
  swaps reference and test in place, the pixel readout shows the pixel's true values and verdict, zoom and pan
  keep the readout on the pixel under the cursor;
* the parameter explorer (notebooks/02, ipywidgets) in JupyterLab: run it, move a slider, and the image
  changes and the render counter rises, within a time limit.

Needs `pip install playwright jupyterlab` (the `test` extra) and a Chromium (`apt-get install chromium`;
Playwright's own browser download is not used): .ci/run installs both; elsewhere the tests skip saying why.
``VLREF_SCREENSHOTS=DIR`` also saves the screenshots of docs/PORTING.md there (docs/images).
"""

import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from vlref.oracle.compare import compare_arrays
from vlref.oracle.report import write_outputs
from vlref.render import render
from vlref.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = os.environ.get("VLREF_CHROMIUM") or shutil.which("chromium") or shutil.which("chromium-browser")
SHOTS = os.environ.get("VLREF_SCREENSHOTS")


@pytest.fixture(scope="module")
def browser():
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed (pip install "
                                   "playwright; the test extra has it)")
    if CHROMIUM is None:
        pytest.skip("no Chromium found (apt-get install chromium, or set VLREF_CHROMIUM); .ci/run installs it")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield b
        b.close()


def _shot(element, name):
    data = element.screenshot()
    if SHOTS:
        Path(SHOTS).mkdir(parents=True, exist_ok=True)
        Path(SHOTS, name).write_bytes(data)
    return data


# --------------------------------------------------------------------------- the compare report

W, H = 96, 54


@pytest.fixture(scope="module")
def report_page(tmp_path_factory):
    """A port of pillars/killzone with a planted 5 % error in one block, the 2-pixel border masked."""
    ref = render(load_scene("pillars", [f"render.width={W}", f"render.height={H}", "render.steps=8",
                                        'render.technique="killzone"'])).buffers["final"]
    test = ref.copy()
    test[20:34, 40:70] *= 1.05
    mask = np.zeros((H, W), bool)
    mask[2:-2, 2:-2] = True
    report = compare_arrays(ref, test, "gpu-full", mask, names=("vlref final", "port final"))
    out = tmp_path_factory.mktemp("report")
    write_outputs(report, out)
    return out, ref, test, report


def _readout(page):
    r = page.locator("#readout")
    values = {k: [float(v) for v in page.locator(f"#r-{k}").inner_text().split(", ")]
              for k in ("ref", "test", "err", "bound")}
    return int(r.get_attribute("data-x")), int(r.get_attribute("data-y")), r.get_attribute("data-state"), values


def test_report_in_a_browser(browser, report_page):
    out, ref, test, report = report_page
    data = json.loads((out / "report.json").read_text())
    page = browser.new_page(viewport={"width": 1400, "height": 1100})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto((out / "report.html").as_uri())
    page.wait_for_selector("body[data-viewer=ready]", timeout=10_000)

    # every image decodes, at the image's size
    sizes = page.eval_on_selector_all("img", "els => els.map(e => [e.complete, e.naturalWidth, e.naturalHeight])")
    assert len(sizes) == 5 and all(s == [True, W, H] for s in sizes)

    # the numbers shown are report.json's
    shown = page.eval_on_selector_all("[data-key]", "els => els.map(e => [e.dataset.key, e.textContent])")
    assert len(shown) >= 20
    checks = {c["name"]: c["value"] for c in data["checks"]}
    for key, text in shown:
        table, name = key.split(".", 1)
        want = checks[name] if table == "checks" else data[table][name]
        if isinstance(want, bool):
            assert text == ("yes" if want else "no"), key
        elif isinstance(want, (int, float)):
            assert float(text) == pytest.approx(want, rel=1e-5, abs=1e-300), key
        else:
            assert text == ("n/a" if want is None else str(want) if not isinstance(want, dict) else text), key

    # the readout: a failing pixel, a passing one, a masked one; the values are the arrays' own
    view = page.locator(".panel[data-name=reference] .view")
    box = view.bounding_box()
    scale = box["width"] / W

    def hover(x, y):
        page.mouse.move(box["x"] + (x + 0.5) * scale, box["y"] + (y + 0.5) * scale)
        return _readout(page)

    for (x, y), state in (((50, 25), "fail"), ((10, 10), "pass"), ((0, 30), "masked")):
        rx, ry, got, v = hover(x, y)
        assert (rx, ry, got) == (x, y, state)
        np.testing.assert_allclose(v["ref"], ref[y, x], rtol=1e-5)
        np.testing.assert_allclose(v["test"], test[y, x], rtol=1e-5)
        np.testing.assert_allclose(v["err"], np.abs(test[y, x] - ref[y, x]), rtol=1e-4, atol=1e-12)
        bound = data["thresholds"]["abs_threshold"] + data["thresholds"]["rel_tol"] * np.abs(ref[y, x])
        np.testing.assert_allclose(v["bound"], bound, rtol=1e-5)
        assert report.fail[y, x] == (state == "fail") and report.mask[y, x] == (state != "masked")

    # the A/B flip: the first panel shows the test in place, and back
    panel = page.locator(".panel[data-name=reference]")
    ref_src, test_src = page.eval_on_selector_all("img", "els => [els[0].src, els[1].src]")
    page.mouse.move(0, 0)
    before = _shot(view, "report_ref.png")
    page.keyboard.press("f")
    assert panel.get_attribute("data-showing") == "test" and panel.locator(".title").inner_text() == "B: test"
    assert page.eval_on_selector("img", "e => e.src") == test_src != ref_src
    assert view.screenshot() != before
    page.keyboard.press("f")
    assert page.eval_on_selector("img", "e => e.src") == ref_src and view.screenshot() == before

    # zoom about the cursor (wheel) and pan (drag): the readout follows the pixel under the cursor, every panel
    page.mouse.move(box["x"] + 50.5 * scale, box["y"] + 25.5 * scale)
    page.mouse.wheel(0, -100)
    page.mouse.wheel(0, -100)   # x 1.25 x 1.25
    assert page.locator("#zoom").inner_text() == "1.56"
    assert _readout(page)[:2] == (50, 25)
    page.mouse.move(box["x"] + 50.5 * scale + 25 * 1.5625 * scale, box["y"] + 25.5 * scale)
    assert _readout(page)[:2] == (75, 25)           # 25 pixels to the right, at 1.5625x
    transforms = page.eval_on_selector_all("img", "els => els.map(e => e.style.transform)")
    assert len(set(transforms)) == 1                 # shared by all panels
    page.mouse.down()
    page.mouse.move(box["x"] + 50.5 * scale, box["y"] + 25.5 * scale, steps=4)   # drag 25 pixels left
    page.mouse.up()
    assert _readout(page)[:2] == (75, 25)           # the image moved with the cursor
    if SHOTS:
        page.keyboard.press("0")
        page.mouse.move(box["x"] + 50.5 * scale, box["y"] + 25.5 * scale)
        page.set_viewport_size({"width": 1100, "height": 700})
        Path(SHOTS, "report.png").write_bytes(page.screenshot(clip={"x": 0, "y": 0, "width": 1100, "height": 700}))
        Path(SHOTS, "report_ref.png").unlink()
    assert errors == []
    page.close()
