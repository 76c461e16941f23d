"""JUnit XML for CI systems (Jenkins, GitLab, GitHub Actions): one ``<testcase>`` per compared buffer or pass.

The format is the de facto one of Ant's ``XMLJUnitResultFormatter`` as Jenkins' xunit plugin
(``junit-10.xsd``) and GitLab read it::

    <testsuites name=... tests=N failures=F errors=0 time=S>
      <testsuite name=... tests=N failures=F errors=0 skipped=0 time=S timestamp=... hostname=...>
        <testcase classname=SUITE name=CASE time=S>
          <failure type="vlref.compare" message=REASON>metrics, one ``key = value`` a line; report: PATH</failure>
          <system-out>the same lines (passed cases too)</system-out>
        </testcase> ...

A :class:`Case` is what every producer fills in (``vlref compare``, ``vlref golden verify`` and the port
verdict): the case's name, pass or fail, its metrics, the path of its report.html (or None) and the reason
of a failure. ``tests/junit_schema.py`` checks the output against ``tests/data/junit.xsd``.
"""

from __future__ import annotations

import datetime
import math
import socket
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

from ..io.files import write_text

__all__ = ["Case", "report_case", "junit_xml", "write_junit"]


@dataclass(frozen=True)
class Case:
    """One JUnit test case: ``name`` (e.g. ``pillars/killzone final``), ``passed``, ``metrics`` (numbers or
    strings; nested mappings are written ``outer.inner = value``), ``report`` (path of the comparison's
    report.html, or None), ``reason`` (why it failed; "" when it passed), ``seconds`` (0 when unknown)."""

    name: str
    passed: bool
    metrics: Mapping[str, object] = field(default_factory=dict)
    report: str | None = None
    reason: str = ""
    seconds: float = 0.0


def report_case(name: str, report, report_path=None, seconds: float = 0.0) -> Case:
    """The :class:`Case` of a :class:`vlref.oracle.compare.Report`: its pixel counts, errors and each check's
    value and bound as metrics; the reason names every failed check (``value > bound``)."""
    m = report.metrics
    metrics = {"preset": report.tolerance.name, "compared_pixels": m["compared_pixels"],
               "failing_pixels": m["failing_pixels"], "max_abs": m["max_abs"], "mean_abs": m["mean_abs"],
               "rmse": m["rmse"], "psnr": m["psnr"]}
    for c in report.checks:
        metrics[c.name] = "n/a" if c.value is None else c.value
        metrics[f"{c.name}_bound"] = c.bound
    reason = "; ".join(f"{c.name} {c.value:.6g} > {c.bound:.6g}" for c in report.checks if c.passed is False)
    return Case(name, report.passed, metrics, None if report_path is None else str(report_path), reason, seconds)


def _text(value) -> str:
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else str(value)
    return str(value)


def _flat(metrics: Mapping, prefix: str = ""):
    """``(key, value)`` pairs of ``metrics``, nested mappings spelled ``outer.inner``."""
    for k, v in metrics.items():
        if isinstance(v, Mapping):
            yield from _flat(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", v


def _details(case: Case) -> str:
    lines = [f"{k} = {_text(v)}" for k, v in _flat(case.metrics)]
    if case.report:
        lines.append(f"report: {case.report}")
    return "\n".join(lines)


def junit_xml(suite: str, cases: Iterable[Case], timestamp: datetime.datetime | None = None) -> str:
    """The JUnit XML document of ``cases`` in one test suite named ``suite`` (module docstring).

    ``timestamp`` (default: now, UTC) is the suite's start; times are seconds with millisecond precision."""
    cases = list(cases)
    failures = sum(not c.passed for c in cases)
    total = f"{sum(c.seconds for c in cases):.3f}"
    stamp = (timestamp or datetime.datetime.now(datetime.timezone.utc)).strftime("%Y-%m-%dT%H:%M:%S")
    root = ET.Element("testsuites", name=suite, tests=str(len(cases)), failures=str(failures), errors="0",
                      time=total)
    node = ET.SubElement(root, "testsuite", name=suite, tests=str(len(cases)), failures=str(failures), errors="0",
                         skipped="0", time=total, timestamp=stamp, hostname=socket.gethostname())
    for c in cases:
        tc = ET.SubElement(node, "testcase", classname=suite, name=c.name, time=f"{c.seconds:.3f}")
        details = _details(c)
        if not c.passed:
            failure = ET.SubElement(tc, "failure", type="vlref.compare", message=c.reason or "failed")
            failure.text = details
        ET.SubElement(tc, "system-out").text = details
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_junit(path, suite: str, cases: Iterable[Case]) -> Path:
    """Write :func:`junit_xml` to ``path`` atomically; returns the path."""
    return write_text(path, junit_xml(suite, cases))
