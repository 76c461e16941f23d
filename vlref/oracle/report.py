"""The files a comparison writes: report.json, diff.exr, heatmap.png, flip.png and report.html.

* ``report.json``: :meth:`Report.to_dict` with non-finite floats spelled ``"inf"``, ``"-inf"``, ``"nan"``.
* ``diff.exr``: ``|test - ref|`` per channel, float32, 0 outside the compared pixels.
* ``heatmap.png``: per pixel ``max_c |t_c - r_c| / top`` (linear; ``top`` from :func:`heat_top`, the
  99th percentile of that error, larger errors saturate) through :func:`colour_map`; pixels outside
  the mask are dark grey.
* ``flip.png``: the HDR-FLIP error map (already in [0, 1]) through the same colour map.
* ``report.html``: one self-contained page (PNG images embedded as base64) with the reference, the
  test, the heat map, the failing pixels, the FLIP map and the numbers. Reference and test previews
  share one exposure (given, or automatic: the 99th percentile of the reference's compared values
  maps to 1), tone-mapped as in :func:`vlref.io.srgb8`.
"""

from __future__ import annotations

import base64
import html
import json
import math
from pathlib import Path

import numpy as np

from ..io import (default_channel_names, output_dir, percentile_exposure, png_bytes, srgb8, write_bytes, write_exr,
                  write_text)

__all__ = ["colour_map", "heat_top", "json_ready", "write_outputs", "render_html", "preview_exposure"]

# A dark-to-bright ramp (black, purple, red, orange, pale yellow) with monotonically increasing
# lightness, so the error order reads correctly in grey too; stops evenly spaced on [0, 1].
_RAMP = np.array([[0.00, 0.00, 0.02], [0.32, 0.07, 0.48], [0.78, 0.21, 0.40], [0.98, 0.55, 0.25],
                  [0.99, 0.96, 0.72]])
_MASKED = np.array([40, 40, 40], np.uint8)


def colour_map(values: np.ndarray) -> np.ndarray:
    """``(H, W)`` values in [0, 1] (clipped; NaN -> 0) -> ``(H, W, 3)`` uint8 by linear interpolation of the ramp."""
    v = np.clip(np.nan_to_num(np.asarray(values, dtype=np.float64)), 0.0, 1.0)
    stops = np.linspace(0.0, 1.0, len(_RAMP))
    rgb = np.stack([np.interp(v, stops, _RAMP[:, c]) for c in range(3)], axis=-1)
    return np.round(rgb * 255.0).astype(np.uint8)


def json_ready(obj):
    """``obj`` with NumPy scalars as Python numbers, paths as strings and non-finite floats as strings."""
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return "nan" if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    if isinstance(obj, Path):
        return str(obj)
    return obj


def _display(image: np.ndarray) -> np.ndarray:
    """Channels shown in a preview: 1 -> grey, 2 -> (R, G, 0), 3+ -> the first three."""
    c = image.shape[2]
    if c == 1:
        return image[:, :, 0]
    if c == 2:
        return np.concatenate([image, np.zeros_like(image[:, :, :1])], axis=2)
    return image[:, :, :3]


def preview_exposure(report) -> float:
    """1 / (99th percentile of the reference's finite compared values), or 1 when that is not positive."""
    return percentile_exposure(np.abs(report.ref[report.mask]), 99.0)[0]


def _masked(image: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``image`` with the pixels outside ``mask`` (possibly non-finite sky) set to 0."""
    return np.where(mask[:, :, None], image, 0.0)


def _abs_diff(report) -> np.ndarray:
    return np.abs(_masked(report.test, report.mask) - _masked(report.ref, report.mask))


def heat_top(report) -> float:
    """The error shown at the top of the heat map's ramp: the 99th percentile of the per-pixel error
    ``max_c |t_c - r_c|`` over the compared pixels (so a few outliers do not hide the rest), or the
    largest error when that percentile is 0."""
    err = _abs_diff(report).max(axis=2)[report.mask]
    p99 = float(np.percentile(err, 99.0))
    return p99 if p99 > 0 else float(err.max())


def _heatmap(report) -> np.ndarray:
    err = _abs_diff(report).max(axis=2)
    top = heat_top(report)
    rgb = colour_map(err / top if top > 0 else np.zeros_like(err))
    rgb[~report.mask] = _MASKED
    return rgb


def _fail_overlay(report, exposure: float) -> np.ndarray:
    """The reference preview darkened to 30 %, failing pixels red, masked pixels dark grey."""
    rgb = (srgb8(_display(_masked(report.ref, report.mask)), exposure) * 0.3).astype(np.uint8)
    rgb[report.fail] = (255, 32, 32)
    rgb[~report.mask] = _MASKED
    return rgb


def _flip_png(report) -> np.ndarray:
    rgb = colour_map(report.flip.error_map)
    rgb[~report.mask] = _MASKED
    return rgb


def _img(title: str, rgb8: np.ndarray, caption: str = "") -> str:
    data = base64.b64encode(png_bytes(rgb8)).decode("ascii")
    width = max(rgb8.shape[1], 320)
    return (f'<figure><figcaption><b>{html.escape(title)}</b> {html.escape(caption)}</figcaption>'
            f'<img alt="{html.escape(title)}" style="width:{width}px" src="data:image/png;base64,{data}"></figure>')


def _fmt(v) -> str:
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.6g}"
    return html.escape(str(v))


def render_html(report, exposure: float | None = None) -> str:
    """The self-contained HTML page of a report (see the module docstring)."""
    exposure = preview_exposure(report) if exposure is None else exposure
    d = report.to_dict()
    verdict = "PASS" if report.passed else "FAIL"
    colour = "#1a7f37" if report.passed else "#cf222e"
    figures = [
        _img("reference", srgb8(_display(_masked(report.ref, report.mask)), exposure), f"exposure {exposure:.4g}"),
        _img("test", srgb8(_display(_masked(report.test, report.mask)), exposure), f"exposure {exposure:.4g}"),
        _img("|test - ref| heat map", _heatmap(report), f"linear, top of the ramp = {heat_top(report):.4g}"),
        _img("failing pixels", _fail_overlay(report, exposure), f"{report.metrics['failing_pixels']} in red"),
    ]
    if report.flip.available:
        figures.append(_img("HDR-FLIP", _flip_png(report), f"mean {report.flip.mean:.4g}"))
    checks = "".join(
        f"<tr><td>{html.escape(c['name'])}</td><td>{_fmt(c['value'])}</td><td>&le; {_fmt(c['bound'])}</td>"
        f"<td>{'skipped' if c['passed'] is None else ('ok' if c['passed'] else 'FAILED')} "
        f"{html.escape(c['note'])}</td></tr>" for c in d["checks"])
    metrics = "".join(f"<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>" for k, v in d["metrics"].items())
    thresholds = "".join(f"<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>" for k, v in d["thresholds"].items())
    inputs = "".join(f"<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>" for k, v in d["inputs"].items())
    flip_note = "" if report.flip.available else f"<p>HDR-FLIP unavailable: {html.escape(report.flip.note)}</p>"
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>vlref compare: {verdict}</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 1.5em; color: #1f2328; }}
h1 span {{ color: {colour}; }}
.figs {{ display: flex; flex-wrap: wrap; gap: 1em; }}
figure {{ margin: 0; }} figcaption {{ font-size: 0.9em; margin-bottom: 0.3em; }}
img {{ image-rendering: pixelated; border: 1px solid #d0d7de; }}
.tables {{ display: flex; flex-wrap: wrap; gap: 2em; align-items: flex-start; }}
table {{ border-collapse: collapse; font-size: 0.9em; }} td, th {{ border: 1px solid #d0d7de; padding: 2px 8px; }}
code {{ font-size: 0.85em; }}
</style></head><body>
<h1>vlref compare: <span>{verdict}</span></h1>
<p>preset <b>{html.escape(report.tolerance.name)}</b> ({html.escape(report.tolerance.description)}),
{report.metrics['compared_pixels']} of {report.metrics['total_pixels']} pixels compared,
image {report.ref.shape[1]}&times;{report.ref.shape[0]}&times;{report.ref.shape[2]}.</p>
<p>Rule: <code>{html.escape(d['rule'])}</code></p>
{flip_note}
<div class="figs">{''.join(figures)}</div>
<div class="tables">
<table><tr><th>check</th><th>value</th><th>bound</th><th>result</th></tr>{checks}</table>
<table><tr><th>metric</th><th>value</th></tr>{metrics}</table>
<table><tr><th>threshold</th><th>value</th></tr>{thresholds}</table>
<table><tr><th>input</th><th>value</th></tr>{inputs}</table>
</div>
<p>vlref {html.escape(d['vlref_version'])}</p>
</body></html>
"""


def write_outputs(report, out_dir, exposure: float | None = None) -> list[Path]:
    """Write the report's files into ``out_dir`` (created; all or nothing); returns their paths."""
    c = report.ref.shape[2]
    names = default_channel_names(c) if c <= 4 else tuple(f"C{i}" for i in range(c))
    meta = {"preset": report.tolerance.name, "reference": report.inputs["reference"],
            "test": report.inputs["test"], "content": "abs(test - ref), 0 outside the compared pixels"}
    written = []
    with output_dir(out_dir) as tmp:
        text = json.dumps(json_ready(report.to_dict()), indent=2, allow_nan=False)
        written.append(write_text(tmp / "report.json", text + "\n"))
        written.append(write_exr(tmp / "diff.exr", _abs_diff(report), channels=names, metadata=meta))
        written.append(write_bytes(tmp / "heatmap.png", png_bytes(_heatmap(report))))
        if report.flip.available:
            written.append(write_bytes(tmp / "flip.png", png_bytes(_flip_png(report))))
        written.append(write_text(tmp / "report.html", render_html(report, exposure)))
    return [Path(out_dir) / p.name for p in written]
