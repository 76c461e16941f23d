"""A technique's bias against the quadrature reference, and where it concentrates.

``technique_bias(scene, technique)`` renders the scene's inscatter with ``technique`` at each step
count of ``steps_list`` (``render.technique`` / ``render.steps`` overridden, everything else as the
scene says) through :func:`vlref.render.render`, and compares it with
:func:`vlref.reference.quadrature.render_reference`.

Metrics (``L`` the technique's inscatter, ``R`` the reference, per pixel ``e = max_c |L_c - R_c|``):

* ``mean_rel = Σ e / Σ max_c R_c``: error mass over signal mass (dark pixels cannot blow it up);
* ``max_rel = max e / max R``;
* concentration (of the error image at ``steps_list[0]``): the fraction
  of the error mass on *depth edges* (pixels whose linear depth differs from a 4-neighbour's by more
  than 5 % or sky/non-sky), on *shadow edges* (pixels whose number of shadow boundaries along the
  ray, found by the reference's visibility search, differs from a 4-neighbour's), in the top 1 % of
  pixels, and the bounding box ``(x0, y0, x1, y1)`` (inclusive, row 0 on top) of that worst 1 %;
* the error-vs-steps table and the least-squares slope of ``log(mean abs error)`` against
  ``log(steps)`` (about ``-1`` for a first-order scheme, ``-2`` for midpoint sampling). Rows whose
  error is within 10x of the reference's own error bound are left out of the fit (``fit_rows``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from pathlib import Path

import numpy as np

from ..io.exr import write_exr
from ..io.files import write_text
from ..render import render
from .quadrature import ReferenceResult, render_reference

DEFAULT_STEPS = (4, 8, 16, 32, 64)
"""Step counts of :func:`technique_bias` (and ``vlref bias``) by default."""

__all__ = ["DEFAULT_STEPS", "BiasReport", "technique_bias", "inscatter_error", "edge_mask", "error_concentration", "loglog_slope"]


@dataclass
class BiasReport:
    """See the module docstring. ``error`` (H, W) is ``e`` at ``steps_list[0]``; ``table`` rows are
    dicts ``steps`` and the keys of :func:`inscatter_error`."""

    technique: str
    error: np.ndarray
    mean_rel: float
    max_rel: float
    concentration: dict
    table: list = field(default_factory=list)
    slope: float = float("nan")
    fit_rows: int = 0
    reference_max_error: float = 0.0

    def summary(self) -> str:
        """A plain-text table: error against steps, the fitted order, where the error sits."""
        lines = [f"technique {self.technique}: mean relative error {self.mean_rel:.3e}, "
                 f"max relative error {self.max_rel:.3e} at {self.table[0]['steps']} steps",
                 f"reference error bound {self.reference_max_error:.2e}",
                 f"{'steps':>6} {'mean_abs':>11} {'max_abs':>11} {'mean_rel':>11} {'max_rel':>11}"]
        lines += [f"{r['steps']:>6} {r['mean_abs']:>11.4e} {r['max_abs']:>11.4e} {r['mean_rel']:>11.4e} "
                  f"{r['max_rel']:>11.4e}" for r in self.table]
        lines.append(f"log-log slope of mean_abs vs steps: {self.slope:.3f} (fitted on {self.fit_rows} rows)")
        lines.append("error concentration: " + ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                                                         for k, v in self.concentration.items()))
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"technique": self.technique, "mean_rel": self.mean_rel, "max_rel": self.max_rel,
                "table": self.table, "slope": self.slope, "fit_rows": self.fit_rows,
                "reference_max_error": self.reference_max_error,
                "concentration": {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                                  for k, v in self.concentration.items()}}

    def save(self, out_dir) -> None:
        """``bias.json`` (the numbers) and ``bias_error.exr`` (per-pixel error at the first step count)."""
        import json

        out = Path(out_dir)
        write_text(out / "bias.json", json.dumps(self.to_dict(), indent=2, default=float))
        write_exr(out / "bias_error.exr", self.error.astype(np.float32))


def edge_mask(values: np.ndarray, rel: float | None = 0.05) -> np.ndarray:
    """Pixels that differ from a 4-neighbour: relatively by more than ``rel`` (``inf`` vs finite counts),
    or at all when ``rel`` is None (integer labels)."""
    v = np.asarray(values, dtype=np.float64)
    mask = np.zeros(v.shape, dtype=bool)
    for axis in (0, 1):
        a = np.take(v, range(0, v.shape[axis] - 1), axis=axis)
        b = np.take(v, range(1, v.shape[axis]), axis=axis)
        if rel is None:
            diff = a != b
        else:
            with np.errstate(invalid="ignore"):
                diff = (np.isinf(a) != np.isinf(b)) | (np.isfinite(a) & np.isfinite(b)
                                                       & (np.abs(a - b) > rel * np.minimum(np.abs(a), np.abs(b))))
        lo = [slice(None)] * 2
        hi = [slice(None)] * 2
        lo[axis] = slice(0, v.shape[axis] - 1)
        hi[axis] = slice(1, v.shape[axis])
        mask[tuple(lo)] |= diff
        mask[tuple(hi)] |= diff
    return mask


def error_concentration(error: np.ndarray, depth: np.ndarray, shadow_boundaries: np.ndarray,
                        top: float = 0.01) -> dict:
    """Fractions of the error mass on depth edges, shadow edges and the worst ``top`` of the pixels,
    and the inclusive bounding box ``(x0, y0, x1, y1)`` of those worst pixels."""
    total = float(error.sum())
    k = max(1, int(round(top * error.size)))
    worst = np.argsort(error, axis=None, kind="stable")[-k:]
    ys, xs = np.unravel_index(worst, error.shape)
    frac = (lambda m: float(error[m].sum()) / total) if total > 0 else (lambda m: 0.0)
    return {"depth_edges": frac(edge_mask(depth)), "shadow_edges": frac(edge_mask(shadow_boundaries, None)),
            "top_fraction": top, "top_mass": (float(error.ravel()[worst].sum()) / total) if total > 0 else 0.0,
            "top_bbox": (int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max()))}


def loglog_slope(steps, errors) -> float:
    """Least-squares slope of ``log(errors)`` on ``log(steps)`` (nan with fewer than two points)."""
    s = np.asarray(steps, dtype=np.float64)
    e = np.asarray(errors, dtype=np.float64)
    if s.size < 2:
        return float("nan")
    return float(np.polyfit(np.log(s), np.log(e), 1)[0])


def inscatter_error(inscatter: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, dict]:
    """Per-pixel ``e = max_c |L_c - R_c|`` (H, W) and ``mean_abs, max_abs, mean_rel, max_rel`` (module docstring)
    with the two denominators: ``ref_sum = Σ max_c R`` (of ``mean_rel``) and ``ref_max = max R`` (of ``max_rel``).
    They differ, so ``mean_rel > max_rel`` where the error sits on pixels dimmer than the brightest."""
    r_max = reference.max(axis=-1)
    signal = float(r_max.sum())
    e = np.abs(np.asarray(inscatter, dtype=np.float64) - reference).max(axis=-1)
    return e, {"mean_abs": float(e.mean()), "max_abs": float(e.max()),
               "mean_rel": float(e.sum()) / signal if signal > 0 else 0.0,
               "max_rel": float(e.max() / r_max.max()) if r_max.max() > 0 else 0.0,
               "ref_sum": signal, "ref_max": float(r_max.max())}


def technique_bias(scene, technique: str, steps_list=DEFAULT_STEPS, reference: ReferenceResult | None = None,
                   rel_tol: float = 1e-4, progress=None) -> BiasReport:
    """Bias of ``technique`` on ``scene`` against the reference (module docstring).

    ``reference``: a precomputed :func:`render_reference` of the same scene (computed when None).
    ``progress``: optional callable receiving stage names: the reference's (when computed here), then
    ``"<n> steps"`` after each render.
    """
    ref = reference if reference is not None else render_reference(scene, rel_tol=rel_tol, progress=progress)
    rows, first, depth = [], None, None
    for steps in steps_list:
        s = scene.replace(render=dataclasses.replace(scene.render, technique=technique, steps=int(steps)))
        res = render(s)
        if progress is not None:
            progress(f"{steps} steps")
        e, row = inscatter_error(res.buffers["inscatter"], ref.inscatter)
        rows.append({"steps": int(steps), **row})
        if first is None:
            first, depth = e, res.buffers["depth"]
    usable = [r for r in rows if r["mean_abs"] > 10.0 * ref.max_error]
    slope = loglog_slope([r["steps"] for r in usable], [r["mean_abs"] for r in usable])
    conc = error_concentration(first, depth, ref.stats["shadow_boundaries"])
    return BiasReport(technique, first, rows[0]["mean_rel"], rows[0]["max_rel"], conc, rows, slope, len(usable),
                      ref.max_error)
