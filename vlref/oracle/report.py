"""The files a comparison writes: report.json, diff.exr, heatmap.png, flip.png and report.html.

* ``report.json``: :meth:`Report.to_dict` with non-finite floats spelled ``"inf"``, ``"-inf"``, ``"nan"``.
* ``diff.exr``: ``|test - ref|`` per channel, float32, 0 outside the compared pixels.
* ``heatmap.png``: per pixel ``max_c |t_c - r_c| / top`` (linear; ``top`` from :func:`heat_top`, the
  99th percentile of that error, larger errors saturate) through :func:`colour_map`; pixels outside
  the mask are dark grey.
* ``flip.png``: the HDR-FLIP error map (already in [0, 1]) through the same colour map.
* ``report.html``: one self-contained page, an image-diff viewer: the reference, the test, the heat map,
  the failing pixels and the FLIP map side by side (PNGs embedded as base64), zoom and pan shared by every
  panel, an A/B flip of the first panel (reference <-> test in place, key F), and under the cursor the
  pixel's reference, test, error and bound per channel and its verdict (the values embedded as zlib-packed
  float32, float16 beyond :data:`FLOAT32_PIXELS`, byte-shuffled and deflated; the masks as packed bits); then the numbers, each value
  cell tagged ``data-key="metrics.max_abs"`` etc. Reference and test previews share one exposure (given,
  or automatic: the 99th percentile of the reference's compared values maps to 1), tone-mapped as in
  :func:`vlref.io.tonemap.srgb8`.
"""

from __future__ import annotations

import base64
import html
import json
import math
import zlib
from pathlib import Path

import numpy as np

from ..io.exposure import percentile_exposure
from ..io.exr import default_channel_names, write_exr
from ..io.files import write_bytes, write_text
from ..io.output_folders import output_dir
from ..io.png import png_bytes
from ..io.tonemap import srgb8

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


FLOAT32_PIXELS = 1 << 20
"""Images up to this many pixels embed their values as float32 for the pixel readout; larger ones as float16
(a 1920x1080x3 report is about 26 MB; the readout then shows 3-4 significant digits, the in-bound verdict
stays exact: it is the comparison's own failing-pixel mask)."""


def _packed(array: np.ndarray) -> str:
    """``array``'s little-endian bytes, byte-shuffled (every value's byte 0, then every byte 1, ...: a quarter
    smaller once deflated), zlib-compressed, base64; the page inflates them with ``DecompressionStream``."""
    a = np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("<")).reshape(-1)
    return base64.b64encode(zlib.compress(a.view(np.uint8).reshape(-1, a.itemsize).T.tobytes(), 6)).decode("ascii")


def _pixel_data(report) -> str:
    """The JSON object the viewer's readout reads: size, channel count, value encoding, thresholds and the
    packed reference, test, compared-mask and failing-mask arrays."""
    h, w, c = report.ref.shape
    dtype = np.float32 if h * w <= FLOAT32_PIXELS else np.float16
    with np.errstate(over="ignore"):
        ref, test = (np.asarray(a, dtype=dtype) for a in (report.ref, report.test))
    data = {"width": w, "height": h, "channels": c, "dtype": np.dtype(dtype).name,
            "abs_threshold": report.thresholds["abs_threshold"], "rel_tol": report.thresholds["rel_tol"],
            "ref": _packed(ref), "test": _packed(test), "mask": _packed(np.packbits(report.mask, axis=None)),
            "fail": _packed(np.packbits(report.fail, axis=None))}
    return json.dumps(json_ready(data), allow_nan=False)


def _img(title: str, rgb8: np.ndarray, caption: str = "", name: str = "") -> str:
    data = base64.b64encode(png_bytes(rgb8)).decode("ascii")
    return (f'<figure class="panel" data-name="{html.escape(name or title)}"><figcaption><b class="title">'
            f'{html.escape(title)}</b> {html.escape(caption)}</figcaption><div class="view">'
            f'<img alt="{html.escape(title)}" src="data:image/png;base64,{data}"></div></figure>')


def _fmt(v) -> str:
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.6g}"
    return html.escape(str(v))


def _rows(table: str, items) -> str:
    """Table rows ``name | value`` whose value cell carries ``data-key="table.name"`` (what the browser test reads)."""
    return "".join(f'<tr><td>{html.escape(k)}</td><td data-key="{html.escape(table)}.{html.escape(k)}">{_fmt(v)}</td>'
                   f"</tr>" for k, v in items)


# The viewer: zoom (wheel, + / -) and pan (drag) shared by every panel, the A/B flip of the first panel
# (F or space: reference <-> test in place), 0 resets the view; the readout under the cursor shows the pixel's
# reference, test, |error| and bound per channel and whether it is compared and within the bound.
_SCRIPT = r"""
(async () => {
const D = JSON.parse(document.getElementById("pixel-data").textContent);
async function inflate(b64, size) {
  const bytes = Uint8Array.from(atob(b64), ch => ch.charCodeAt(0));
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  const shuffled = new Uint8Array(await new Response(stream).arrayBuffer());
  if (size === 1) return shuffled;
  const n = shuffled.length / size, out = new Uint8Array(shuffled.length);
  for (let b = 0; b < size; b++) for (let i = 0; i < n; i++) out[i * size + b] = shuffled[b * n + i];
  return out;
}
function half(bits) {
  const s = bits & 0x8000 ? -1 : 1, e = (bits >> 10) & 0x1f, f = bits & 0x3ff;
  if (e === 0) return s * f * Math.pow(2, -24);
  if (e === 31) return f ? NaN : s * Infinity;
  return s * (1 + f / 1024) * Math.pow(2, e - 15);
}
function floats(bytes) {
  if (D.dtype === "float32") return new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4);
  const u = new Uint16Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 2);
  return Float32Array.from(u, half);
}
const size = D.dtype === "float32" ? 4 : 2;
const [ref, test, mask, fail] = await Promise.all(
  [inflate(D.ref, size), inflate(D.test, size), inflate(D.mask, 1), inflate(D.fail, 1)]);
const R = floats(ref), T = floats(test);
const bit = (bits, i) => (bits[i >> 3] >> (7 - (i & 7))) & 1;
const panels = [...document.querySelectorAll(".panel")];
const views = panels.map(p => p.querySelector(".view"));
const imgs = panels.map(p => p.querySelector("img"));
const viewW = views[0].clientWidth, base = viewW / D.width;
const state = {zoom: 1, ox: 0, oy: 0, showing: "reference"};
function apply() {
  const s = base * state.zoom;
  for (const img of imgs) img.style.transform = `translate(${state.ox}px, ${state.oy}px) scale(${s})`;
  document.getElementById("zoom").textContent = state.zoom.toFixed(state.zoom < 10 ? 2 : 1);
}
function zoomAt(vx, vy, factor) {
  const z = Math.min(Math.max(state.zoom * factor, 1), 64), k = z / state.zoom;
  state.ox = vx - (vx - state.ox) * k; state.oy = vy - (vy - state.oy) * k; state.zoom = z; apply();
}
function flip() {
  state.showing = state.showing === "reference" ? "test" : "reference";
  imgs[0].src = (state.showing === "reference" ? refSrc : imgs[1].src);
  panels[0].dataset.showing = state.showing;
  panels[0].querySelector(".title").textContent = state.showing === "reference" ? "A: reference" : "B: test";
}
const refSrc = imgs[0].src;
const fmt = v => Number.isFinite(v) ? v.toPrecision(6).replace(/\.?0+(e|$)/, "$1") : String(v);
function readout(vx, vy) {
  const s = base * state.zoom, x = Math.floor((vx - state.ox) / s), y = Math.floor((vy - state.oy) / s);
  const out = document.getElementById("readout");
  if (x < 0 || y < 0 || x >= D.width || y >= D.height) { out.dataset.x = ""; return; }
  const i = y * D.width + x, compared = bit(mask, i), failing = bit(fail, i);
  const cells = ["ref", "test", "err", "bound"].map(() => []);
  for (let c = 0; c < D.channels; c++) {
    const r = R[i * D.channels + c], t = T[i * D.channels + c];
    cells[0].push(fmt(r)); cells[1].push(fmt(t)); cells[2].push(fmt(Math.abs(t - r)));
    cells[3].push(fmt(D.abs_threshold + D.rel_tol * Math.abs(r)));
  }
  out.dataset.x = x; out.dataset.y = y;
  out.dataset.state = compared ? (failing ? "fail" : "pass") : "masked";
  document.getElementById("r-xy").textContent = `x ${x}, y ${y}`;
  ["ref", "test", "err", "bound"].forEach(
    (k, j) => document.getElementById(`r-${k}`).textContent = cells[j].join(", "));
  document.getElementById("r-state").textContent =
    compared ? (failing ? "FAILS: beyond the bound" : "within the bound") : "not compared (masked)";
}
let drag = null;
const at = (v, e) => { const box = v.getBoundingClientRect(); return [e.clientX - box.left, e.clientY - box.top]; };
for (const v of views) {
  v.addEventListener("wheel", e => { e.preventDefault(); zoomAt(...at(v, e), e.deltaY < 0 ? 1.25 : 0.8);
                                     readout(...at(v, e)); }, {passive: false});
  v.addEventListener("mousedown", e => { drag = {x: e.clientX, y: e.clientY}; e.preventDefault(); });
}
window.addEventListener("mousemove", e => {
  if (drag && e.buttons) {
    state.ox += e.clientX - drag.x; state.oy += e.clientY - drag.y; drag = {x: e.clientX, y: e.clientY}; apply();
  } else drag = null;
  const v = e.target.closest && e.target.closest(".view");
  if (v) readout(...at(v, e));
});
window.addEventListener("keydown", e => {
  const c = viewW / 2, h = views[0].clientHeight / 2;
  if (e.key === "f" || e.key === "F" || e.key === " ") { e.preventDefault(); flip(); }
  else if (e.key === "+" || e.key === "=") zoomAt(c, h, 2);
  else if (e.key === "-") zoomAt(c, h, 0.5);
  else if (e.key === "0") { state.zoom = 1; state.ox = 0; state.oy = 0; apply(); }
});
document.getElementById("flip").addEventListener("click", flip);
apply();
document.body.dataset.viewer = "ready";
})();
"""


def render_html(report, exposure: float | None = None) -> str:
    """The self-contained HTML page of a report (see the module docstring)."""
    exposure = preview_exposure(report) if exposure is None else exposure
    d = report.to_dict()
    verdict = "PASS" if report.passed else "FAIL"
    colour = "#1a7f37" if report.passed else "#cf222e"
    h, w, c = report.ref.shape
    figures = [
        _img("A: reference", srgb8(_display(_masked(report.ref, report.mask)), exposure), f"exposure {exposure:.4g}",
             "reference"),
        _img("test", srgb8(_display(_masked(report.test, report.mask)), exposure), f"exposure {exposure:.4g}"),
        _img("|test - ref| heat map", _heatmap(report), f"linear, top of the ramp = {heat_top(report):.4g}", "heat"),
        _img("failing pixels", _fail_overlay(report, exposure), f"{report.metrics['failing_pixels']} in red", "fail"),
    ]
    if report.flip.available:
        figures.append(_img("HDR-FLIP", _flip_png(report), f"mean {report.flip.mean:.4g}", "flip"))
    checks = "".join(
        f'<tr><td>{html.escape(c["name"])}</td><td data-key="checks.{html.escape(c["name"])}">{_fmt(c["value"])}</td>'
        f"<td>&le; {_fmt(c['bound'])}</td>"
        f"<td>{'skipped' if c['passed'] is None else ('ok' if c['passed'] else 'FAILED')} "
        f"{html.escape(c['note'])}</td></tr>" for c in d["checks"])
    flip_note = "" if report.flip.available else f"<p>HDR-FLIP unavailable: {html.escape(report.flip.note)}</p>"
    view_w = min(max(w, 320), 640)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>vlref compare: {verdict}</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 1.5em; color: #1f2328; }}
h1 span {{ color: {colour}; }}
.figs {{ display: flex; flex-wrap: wrap; gap: 1em; }}
figure {{ margin: 0; }} figcaption {{ font-size: 0.9em; margin-bottom: 0.3em; }}
.view {{ width: {view_w}px; height: {round(view_w * h / w)}px; overflow: hidden; position: relative;
        border: 1px solid #d0d7de; cursor: crosshair; background: #282828; }}
.view img {{ position: absolute; left: 0; top: 0; transform-origin: 0 0; image-rendering: pixelated;
            width: {w}px; height: {h}px; transform: scale({view_w / w:.6g}); }}
#readout {{ position: sticky; top: 0; z-index: 1; width: max-content; font: 0.85em ui-monospace, monospace;
           margin: 0.6em 0; padding: 0.4em 0.6em; background: #f6f8fa;
           border: 1px solid #d0d7de; display: grid; grid-template-columns: max-content auto; gap: 0 1em; }}
#readout[data-state=fail] #r-state {{ color: #cf222e; font-weight: bold; }}
#readout[data-state=pass] #r-state {{ color: #1a7f37; }}
.tables {{ display: flex; flex-wrap: wrap; gap: 2em; align-items: flex-start; }}
table {{ border-collapse: collapse; font-size: 0.9em; }} td, th {{ border: 1px solid #d0d7de; padding: 2px 8px; }}
code, kbd {{ font-size: 0.85em; }}
</style></head><body>
<h1>vlref compare: <span>{verdict}</span></h1>
<p>preset <b>{html.escape(report.tolerance.name)}</b> ({html.escape(report.tolerance.description)}),
<span data-key="metrics.compared_pixels">{report.metrics['compared_pixels']}</span> of
<span data-key="metrics.total_pixels">{report.metrics['total_pixels']}</span> pixels compared,
image {w}&times;{h}&times;{c}.</p>
<p>Rule: <code>{html.escape(d['rule'])}</code></p>
{flip_note}
<p><button id="flip">flip A/B</button> <kbd>F</kbd> or <kbd>space</kbd>: the first panel flips between reference
and test in place; wheel or <kbd>+</kbd>/<kbd>-</kbd>: zoom (all panels, &times;<span id="zoom">1</span>); drag: pan;
<kbd>0</kbd>: reset.</p>
<div id="readout"><span>pixel</span><span id="r-xy">(move the cursor over an image)</span>
<span>reference</span><span id="r-ref"></span><span>test</span><span id="r-test"></span>
<span>|test - ref|</span><span id="r-err"></span><span>bound</span><span id="r-bound"></span>
<span>verdict</span><span id="r-state"></span></div>
<div class="figs">{''.join(figures)}</div>
<div class="tables">
<table><tr><th>check</th><th>value</th><th>bound</th><th>result</th></tr>{checks}</table>
<table><tr><th>metric</th><th>value</th></tr>{_rows("metrics", d["metrics"].items())}</table>
<table><tr><th>threshold</th><th>value</th></tr>{_rows("thresholds", d["thresholds"].items())}</table>
<table><tr><th>input</th><th>value</th></tr>{_rows("inputs", d["inputs"].items())}</table>
</div>
<p>vlref {html.escape(d['vlref_version'])}; pixel values embedded as {"float32" if h * w <= FLOAT32_PIXELS else
"float16 (3-4 significant digits; the verdict is the comparison's own)"}.</p>
<script type="application/json" id="pixel-data">{_pixel_data(report)}</script>
<script>{_SCRIPT}</script>
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
