"""vlref's pytest plugin (entry point ``pytest11: vlref``, installed with vlref): judge a port's buffers in pytest.

The workflow of image-comparison plugins such as pytest-mpl, for GPU ports::

    @pytest.mark.vlref(scene="pillars", technique="killzone", preset="gpu-half",
                       overrides=["render.width=160", "render.height=90"])
    def test_final(vlref_compare):
        vlref_compare(my_port.render()["final"], "final")      # passes, or fails naming the report

**Fixture** ``vlref_compare(buffer, stage, *, scene, technique, preset, overrides, port, ignore_sky)``: compares
``buffer`` (an ``(H, W[, C])`` array, or a path of an EXR/PNG/NPY/NPZ image) with vlref's ``stage`` buffer
(``final``, ``inscatter``, ``transmittance`` or any ``--stages`` name) under ``preset`` (default ``float32``)
and returns the :class:`vlref.oracle.compare.Report`; a failure fails the test with the failed checks and the
path of the comparison's report.html. Keyword arguments left out come from the test's ``@pytest.mark.vlref``.

**The reference**, either

* a *golden*: vlref's render of ``scene`` (a bundled name or a TOML path) with ``technique`` and ``overrides``,
  stored as ``<golden dir>/<technique>/<scene>[-<hash of the overrides>]/<stage>.exr`` next to ``golden.json``
  (scene, technique, overrides, ``scene_hash``). ``pytest --vlref-generate`` renders and (re)writes the goldens
  a session uses, then compares; without it a missing golden fails ("run pytest --vlref-generate"), and so does
  a stale one (the scene's ``scene_hash`` changed since it was generated: regenerate deliberately); or
* ``port=PORT.toml``: ``vlref march`` on the port's own buffers (docs/PORTING.md), computed once per session
  and manifest; nothing is stored.

**Outputs** under the report folder (``--vlref-report-dir``, ini ``vlref_report_dir``, default ``vlref-report``
in the rootdir): ``<test id>/<stage>/`` with report.json, report.html, diff.exr, heatmap.png for every failed
comparison (``--vlref-reports all``: every comparison), and at the end of the session ``summary.json`` and
``summary.html``: one row per comparison of the session (test, stage, reference, preset, verdict, metrics,
report). Options: ``--vlref-golden-dir`` (ini ``vlref_golden_dir``, default ``vlref_golden`` in the rootdir).
Not pytest-xdist aware: each worker would write its own summary.
"""

from __future__ import annotations

import dataclasses
import hashlib
import html
import json
import re
from pathlib import Path

import numpy as np
import pytest

from . import __version__
from .io.exr import write_exr
from .io.files import write_text
from .io.images import read_image
from .io.output_folders import output_dir
from .oracle.compare import build_mask, compare_arrays
from .oracle.junit import report_case
from .oracle.report import json_ready, write_outputs
from .scene import load_scene

__all__ = ["VlrefSession", "golden_folder"]

MARK = "vlref"
KEYS = ("scene", "technique", "preset", "overrides", "port", "ignore_sky")
_SESSION = pytest.StashKey["VlrefSession"]()


def pytest_addoption(parser):
    group = parser.getgroup("vlref", "vlref: judge a port's buffers against the reference renderer")
    group.addoption("--vlref-generate", action="store_true", default=False,
                    help="(re)render the vlref goldens the vlref_compare calls use, then compare")
    group.addoption("--vlref-golden-dir", default=None,
                    help="folder of the goldens (default: ini vlref_golden_dir, else vlref_golden in the rootdir)")
    group.addoption("--vlref-report-dir", default=None,
                    help="folder of the reports and summary.html/json (default: ini vlref_report_dir, else "
                         "vlref-report in the rootdir)")
    group.addoption("--vlref-reports", choices=("failed", "all"), default="failed",
                    help="write a report for failed comparisons only, or for all (default: failed)")
    parser.addini("vlref_golden_dir", "folder of vlref's goldens, relative to the rootdir", default="vlref_golden")
    parser.addini("vlref_report_dir", "folder of vlref's reports, relative to the rootdir", default="vlref-report")


def pytest_configure(config):
    config.addinivalue_line("markers", "vlref(scene=None, technique=None, preset=None, overrides=(), port=None, "
                                       "ignore_sky=False): defaults of the vlref_compare calls of this test")
    root = Path(config.rootpath)
    golden = config.getoption("--vlref-golden-dir") or config.getini("vlref_golden_dir")
    reports = config.getoption("--vlref-report-dir") or config.getini("vlref_report_dir")
    config.stash[_SESSION] = VlrefSession(root / golden, root / reports, config.getoption("--vlref-generate"),
                                          config.getoption("--vlref-reports") == "all")


def pytest_sessionfinish(session):
    vs = session.config.stash.get(_SESSION, None)
    if vs is not None and vs.records:
        vs.write_summary()


def pytest_terminal_summary(terminalreporter, config):
    vs = config.stash.get(_SESSION, None)
    if vs is not None and vs.records:
        failed = sum(not r["passed"] for r in vs.records)
        terminalreporter.write_line(f"vlref: {len(vs.records)} comparison(s), {failed} failed; summary "
                                    f"{vs.report_dir / 'summary.html'}")


@pytest.fixture
def vlref_compare(request):
    """``vlref_compare(buffer, stage, **options) -> Report`` (module docstring); fails the test on a failed check."""
    vs = request.config.stash[_SESSION]
    marker = request.node.get_closest_marker(MARK)
    defaults = dict(marker.kwargs) if marker is not None else {}
    unknown = set(defaults) - set(KEYS)
    if unknown:
        raise pytest.UsageError(f"@pytest.mark.vlref: unknown argument(s) {', '.join(sorted(unknown))}; "
                                f"known: {', '.join(KEYS)}")

    def judge(buffer, stage: str, **options):
        bad = set(options) - set(KEYS)
        if bad:
            raise TypeError(f"vlref_compare: unknown argument(s) {', '.join(sorted(bad))}; known: {', '.join(KEYS)}")
        return vs.judge(request.node.nodeid, buffer, stage, **{**defaults, **options})

    return judge


def golden_folder(golden_dir: Path, scene: str, technique: str, overrides) -> Path:
    """``<golden_dir>/<technique>/<scene name>[-<first 8 hex of sha256 of the overrides, one a line>]``."""
    name = Path(scene).stem if str(scene).endswith(".toml") else str(scene)
    if overrides:
        name += "-" + hashlib.sha256("\n".join(overrides).encode()).hexdigest()[:8]
    return golden_dir / technique / name


def _safe(nodeid: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", nodeid).strip("_")[:150]


@dataclasses.dataclass
class VlrefSession:
    """The plugin's state for one pytest session: options, cached references and every comparison's record."""

    golden_dir: Path
    report_dir: Path
    generate: bool = False
    report_all: bool = False
    records: list = dataclasses.field(default_factory=list)
    _renders: dict = dataclasses.field(default_factory=dict)
    _marches: dict = dataclasses.field(default_factory=dict)

    def _render(self, scene_obj, key):
        # vlref.render and vlref.port load Numba's kernels (about 1 s): imported on first use, not with the plugin,
        # which pytest loads in every session of an environment where vlref is installed.
        from .render import render

        if key not in self._renders:
            self._renders[key] = render(scene_obj, stages=True).buffers
        return self._renders[key]

    def _golden(self, stage: str, scene: str, technique: str, overrides: tuple) -> tuple[np.ndarray, str]:
        from .render import scene_hash

        if not scene or not technique:
            pytest.fail("vlref_compare: give scene= and technique= (or port=), in the call or @pytest.mark.vlref",
                        pytrace=False)
        scene_obj = load_scene(scene, [*overrides, f'render.technique="{technique}"'])
        folder = golden_folder(self.golden_dir, scene, technique, overrides)
        path = folder / f"{stage}.exr"
        if self.generate:
            buffers = self._render(scene_obj, (scene, technique, overrides))
            if stage not in buffers:
                pytest.fail(f"vlref_compare: {technique} has no buffer {stage!r}; it has {', '.join(sorted(buffers))}",
                            pytrace=False)
            meta = {"scene": scene, "technique": technique, "overrides": list(overrides),
                    "scene_hash": scene_hash(scene_obj), "vlref_version": __version__}
            with output_dir(folder) as tmp:
                write_exr(tmp / path.name, np.asarray(buffers[stage], dtype=np.float32),
                          metadata={"scene_hash": meta["scene_hash"], "technique": technique})
                write_text(tmp / "golden.json", json.dumps(meta, indent=1) + "\n")
        if not path.is_file():
            pytest.fail(f"vlref: no golden {path}; run pytest --vlref-generate to render it", pytrace=False)
        recorded = json.loads((folder / "golden.json").read_text(encoding="utf-8"))
        if recorded.get("scene_hash") != scene_hash(scene_obj):
            pytest.fail(f"vlref: golden {path} is stale: the scene changed since it was generated (scene_hash "
                        f"differs); regenerate deliberately with pytest --vlref-generate", pytrace=False)
        return read_image(path), str(path)

    def _marched(self, stage: str, port, overrides: tuple) -> tuple[np.ndarray, str]:
        from .port import march_port

        key = (str(Path(port).resolve()), overrides)
        if key not in self._marches:
            self._marches[key] = march_port(port, overrides)
        buffers = self._marches[key]
        if stage not in buffers:
            pytest.fail(f"vlref_compare: vlref march has no buffer {stage!r}; it has {', '.join(sorted(buffers))}",
                        pytrace=False)
        return np.asarray(buffers[stage], dtype=np.float64), f"vlref march {port} ({stage})"

    def judge(self, nodeid: str, buffer, stage: str, *, scene=None, technique=None, preset=None,
              overrides=(), port=None, ignore_sky=False):
        """Compare ``buffer`` with the reference's ``stage`` under ``preset`` (None: ``float32``); record it; fail
        the test when it fails."""
        overrides, preset = tuple(overrides), preset or "float32"
        if port is not None:
            ref, source = self._marched(stage, port, overrides)
        else:
            ref, source = self._golden(stage, scene, technique, overrides)
        test = read_image(buffer) if isinstance(buffer, (str, Path)) else np.asarray(buffer, dtype=np.float64)
        ref = ref[:, :, None] if ref.ndim == 2 else ref
        mask = build_mask(ref, ignore_sky="ref") if ignore_sky else None
        report = compare_arrays(ref, test, preset, mask, flip=False, names=(source, f"{nodeid} {stage}"))
        html_path = None
        if self.report_all or not report.passed:
            folder = self.report_dir / _safe(nodeid) / stage
            write_outputs(report, folder)
            html_path = folder / "report.html"
        case = report_case(f"{nodeid} {stage}", report, html_path)
        self.records.append({"test": nodeid, "stage": stage, "reference": source, "scene": scene,
                             "technique": technique, "port": None if port is None else str(port),
                             **dataclasses.asdict(case)})
        if not report.passed:
            pytest.fail(f"vlref: {stage} fails preset {report.tolerance.name} against {source}: {case.reason}\n"
                        f"{report.summary()}\nreport: {html_path}", pytrace=False)
        return report

    def write_summary(self) -> None:
        """``summary.json`` (the records) and ``summary.html`` (a table linking each report) in the report folder."""
        self.report_dir.mkdir(parents=True, exist_ok=True)
        failed = sum(not r["passed"] for r in self.records)
        data = {"vlref_version": __version__, "comparisons": len(self.records), "failed": failed,
                "records": self.records}
        write_text(self.report_dir / "summary.json", json.dumps(json_ready(data), indent=1) + "\n")
        rows = []
        for r in self.records:
            m = r["metrics"]
            link = (f'<a href="{html.escape(Path(r["report"]).relative_to(self.report_dir).as_posix())}">report</a>'
                    if r["report"] else "")
            rows.append(f'<tr class="{"pass" if r["passed"] else "fail"}"><td>{html.escape(r["test"])}</td>'
                        f'<td>{html.escape(r["stage"])}</td><td>{html.escape(r["reference"])}</td>'
                        f'<td>{html.escape(str(m["preset"]))}</td><td>{"PASS" if r["passed"] else "FAIL"}</td>'
                        f'<td>{m["failing_pixels"]} of {m["compared_pixels"]}</td><td>{m["max_abs"]:.4g}</td>'
                        f'<td>{html.escape(r["reason"])}</td><td>{link}</td></tr>')
        write_text(self.report_dir / "summary.html", f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>vlref: {failed} of {len(self.records)} failed</title>
<style>body {{ font-family: system-ui, sans-serif; margin: 1.5em; }} table {{ border-collapse: collapse; }}
td, th {{ border: 1px solid #d0d7de; padding: 2px 8px; font-size: 0.9em; }} .fail td {{ background: #ffebe9; }}
</style></head><body>
<h1>vlref comparisons: {len(self.records) - failed} passed, {failed} failed</h1>
<table><tr><th>test</th><th>stage</th><th>reference</th><th>preset</th><th>verdict</th><th>failing pixels</th>
<th>max abs</th><th>failed checks</th><th></th></tr>
{chr(10).join(rows)}
</table><p>vlref {html.escape(__version__)}</p></body></html>
""")
