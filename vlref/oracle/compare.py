"""``vlref compare REF TEST``: does a port's image match the reference within a tolerance preset?

The rule (see :mod:`vlref.oracle.presets` and ``vlref/data/presets.toml``): a pixel fails when
``|t - r| > abs_tol*S + rel_tol*|r|`` in any channel; the image passes when the fraction of failing
pixels is at most ``max_fail_fraction`` and the mean absolute error at most ``max_mean_abs*S``
(and the mean HDR-FLIP at most ``max_flip_mean`` when that knob is set and FLIP is available).

Masks select the compared pixels: ``ignore_sky`` (a depth image whose non-finite values, or values
``>= sky_depth``, mark sky; or ``"ref"``: pixels where the reference itself is non-finite, e.g. when
comparing depth buffers), a border of ``border`` pixels on every edge, and a user mask image
(nonzero in any channel = compared). Non-finite values are only allowed outside the compared pixels;
NaN never.

The command line (exit 0 pass, 1 fail, 2 bad input) is :mod:`vlref.cli.compare`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from .. import __version__
from ..errors import InputError
from ..io.images import read_image
from .metrics import FlipResult, error_metrics, failing_pixels, hdr_flip
from .presets import Tolerance, tolerance
from .report import write_outputs

__all__ = [
    "Check", "Report", "RULE", "build_mask", "compare_arrays", "compare_files", "margin", "scale_of",
]

RULE = ("pixel fails when |test-ref| > abs_tol*S + rel_tol*|ref| in any channel; image passes when "
        "failing fraction <= max_fail_fraction and mean |test-ref| <= max_mean_abs*S "
        "(and mean HDR-FLIP <= max_flip_mean when set and available); S = 1 (scale 'absolute') or "
        "mean |ref| over the compared values (scale 'mean'); values at a bound pass; in an edge zone (pixels "
        "near depth discontinuities and shadow silhouettes) a pixel fails beyond edge_abs_tol*S + "
        "edge_rel_tol*|ref| and the mean error is taken outside the zone; with max_mean_abs_all set, the mean "
        "|test-ref| over every compared pixel, the zone included, <= max_mean_abs_all*S; with max_zone_lean set, "
        "|mean (test-ref)| over the zone's compared values (signed: the zone may not lean one way) <= "
        "max_zone_lean*S")


@dataclass
class Check:
    """One term of the pass/fail rule; ``passed`` is None when it could not be evaluated."""

    name: str
    value: float | None
    bound: float
    passed: bool | None
    note: str = ""


@dataclass
class Report:
    """The outcome of a comparison: numbers, checks, verdict, and the arrays for the output files."""

    passed: bool
    tolerance: Tolerance
    metrics: dict
    thresholds: dict
    checks: list[Check]
    flip: FlipResult
    inputs: dict
    ref: np.ndarray = field(repr=False)
    test: np.ndarray = field(repr=False)
    mask: np.ndarray = field(repr=False)
    fail: np.ndarray = field(repr=False)

    def to_dict(self) -> dict:
        """All numbers, the rule, the verdict, the preset and the inputs (JSON-ready after
        :func:`vlref.oracle.report.json_ready`, which spells non-finite floats as strings)."""
        return {
            "verdict": "pass" if self.passed else "fail",
            "passed": self.passed,
            "rule": RULE,
            "preset": self.tolerance.name,
            "tolerance": dataclasses.asdict(self.tolerance),
            "thresholds": self.thresholds,
            "checks": [dataclasses.asdict(c) for c in self.checks],
            "metrics": self.metrics,
            "flip": {"available": self.flip.available, "mean": self.flip.mean, "note": self.flip.note},
            "inputs": self.inputs,
            "shape": list(self.ref.shape),
            "vlref_version": __version__,
        }

    def margins(self) -> dict[str, float]:
        """Each evaluated check's value / bound (1 = at the bound): 0 for a zero value, ``inf`` for a nonzero
        value over a zero bound; no division by a zero bound."""
        return {c.name: margin(c.value, c.bound) for c in self.checks if c.value is not None}

    def summary(self) -> str:
        """A few lines for the terminal."""
        m = self.metrics
        lines = [f"{'PASS' if self.passed else 'FAIL'}  preset {self.tolerance.name}: "
                 f"{m['compared_pixels']} of {m['total_pixels']} pixels compared"]
        for c in self.checks:
            state = "skipped" if c.passed is None else ("ok" if c.passed else "FAILED")
            value = "n/a" if c.value is None else f"{c.value:.6g}"
            lines.append(f"  {c.name:<16s} {value:>12s}  <= {c.bound:.6g}  {state} {c.note}".rstrip())
        flip = f"{self.flip.mean:.4g}" if self.flip.available else f"n/a ({self.flip.note})"
        lines.append(f"  max abs {m['max_abs']:.6g}  rmse {m['rmse']:.6g}  rel L2 {m['rel_l2']:.6g}  "
                     f"PSNR {m['psnr']:.2f} dB  HDR-FLIP {flip}")
        return "\n".join(lines)


def margin(value: float, bound: float) -> float:
    """``value / bound`` for ``bound > 0``; for a zero bound 0 when ``value`` is 0, else ``inf``."""
    if bound > 0:
        return float(value) / float(bound)
    return 0.0 if value == 0 else math.inf


def scale_of(tol: Tolerance, ref: np.ndarray, mask: np.ndarray) -> float:
    """The scale ``S`` of the rule: 1 (``"absolute"``) or the mean ``|ref|`` over the compared pixels (``"mean"``)."""
    return 1.0 if tol.scale == "absolute" else float(np.mean(np.abs(ref[mask])))


def _as_image(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    return a[:, :, None] if a.ndim == 2 else a


def _first_bad(bad: np.ndarray) -> str:
    y, x = np.argwhere(bad)[0]
    return f"{int(bad.sum())} pixel(s), first at x={x}, y={y}"


def compare_arrays(ref, test, tol: Tolerance | str, mask: np.ndarray | None = None, *, flip: bool = True,
                   names: tuple[str, str] = ("<reference>", "<test>"), inputs: Mapping | None = None,
                   edges: np.ndarray | None = None) -> Report:
    """Compare two ``(H, W)`` / ``(H, W, C)`` arrays under ``tol`` (a :class:`Tolerance` or preset name).

    ``mask`` (``(H, W)`` bool, true = compared) defaults to every pixel. ``edges`` (``(H, W)`` bool, the
    edge zone of :mod:`vlref.oracle.edges`, already ``tol.edge_pixels`` wide) gets the edge tolerance
    (``tol.edge_rel``, ``tol.edge_abs``); the mean-error check then covers the compared pixels outside it. ``names`` label the arrays in
    error messages. Raises :class:`InputError` when shapes or channel counts differ, a value is NaN,
    a compared value is infinite, or the mask selects no pixel; :class:`ValueError` when ``mask`` is not
    ``(H, W)``.
    """
    tol = tolerance(tol) if isinstance(tol, str) else tol
    r, t = _as_image(ref), _as_image(test)
    for a, name in ((r, names[0]), (t, names[1])):
        if a.ndim != 3 or a.size == 0:
            raise InputError(name, "shape", f"wrong shape {a.shape} (expected non-empty (H, W) or (H, W, C))")
    if r.shape[:2] != t.shape[:2]:
        raise InputError(names[1], "shape", f"size {t.shape[1]}x{t.shape[0]} differs from the reference's "
                                            f"{r.shape[1]}x{r.shape[0]} (width x height)")
    if r.shape[2] != t.shape[2]:
        raise InputError(names[1], "channels", f"{t.shape[2]} channel(s), the reference has {r.shape[2]}")
    mask = np.ones(r.shape[:2], bool) if mask is None else np.asarray(mask, dtype=bool)
    if mask.shape != r.shape[:2]:
        raise ValueError(f"mask shape {mask.shape} differs from the images' {r.shape[:2]}")
    zone = np.zeros(r.shape[:2], bool) if edges is None else np.asarray(edges, dtype=bool)
    if zone.shape != r.shape[:2]:
        raise ValueError(f"edges shape {zone.shape} differs from the images' {r.shape[:2]}")
    for a, name in ((r, names[0]), (t, names[1])):
        if np.isnan(a).any():
            raise InputError(name, "values", f"NaN present ({_first_bad(np.isnan(a).any(axis=2))})")
        bad = ~np.isfinite(a).all(axis=2) & mask
        if bad.any():
            raise InputError(name, "values", f"infinite values in compared pixels ({_first_bad(bad)}); "
                                             "mask them (e.g. ignore sky)")
    n = int(np.count_nonzero(mask))
    if n == 0:
        raise InputError(names[0], "mask", "the masks leave no pixel to compare")

    s = scale_of(tol, r, mask)
    abs_thr, mean_bound = tol.abs_tol * s, tol.max_mean_abs * s
    metrics = error_metrics(r, t, mask, abs_thr, tol.rel_tol)
    metrics["total_pixels"] = int(mask.size)
    rf, tf = np.where(mask[:, :, None], r, 0.0), np.where(mask[:, :, None], t, 0.0)
    fail = failing_pixels(rf, tf, abs_thr, tol.rel_tol) & mask
    zone &= mask
    metrics["edge_pixels"] = int(np.count_nonzero(zone))
    if zone.any():
        fail = np.where(zone, failing_pixels(rf, tf, tol.edge_abs * s, tol.edge_rel), fail) & mask
        metrics["failing_pixels"] = int(np.count_nonzero(fail))
        metrics["frac_failing"] = metrics["failing_pixels"] / n
        outside = mask & ~zone
        metrics["mean_abs_outside_edges"] = float(np.mean(np.abs(t[outside] - r[outside]))) if outside.any() else 0.0
    metrics.setdefault("mean_abs_outside_edges", metrics["mean_abs"])
    metrics["failing_pixels_edge"] = int(np.count_nonzero(fail & zone))
    metrics["zone_mean_signed"] = float(np.mean(t[zone] - r[zone])) if zone.any() else 0.0
    fr = hdr_flip(r, t, mask) if flip else FlipResult(None, None, "not computed")
    metrics["flip_mean"] = fr.mean

    checks = [Check("failing_fraction", metrics["frac_failing"], tol.max_fail_fraction,
                    metrics["frac_failing"] <= tol.max_fail_fraction),
              Check("mean_abs_error", metrics["mean_abs_outside_edges"], mean_bound,
                    metrics["mean_abs_outside_edges"] <= mean_bound)]
    if tol.max_mean_abs_all is not None:
        checks.append(Check("mean_abs_all", metrics["mean_abs"], tol.max_mean_abs_all * s,
                            metrics["mean_abs"] <= tol.max_mean_abs_all * s))
    if tol.max_zone_lean is not None and zone.any():
        checks.append(Check("zone_lean", abs(metrics["zone_mean_signed"]), tol.max_zone_lean * s,
                            abs(metrics["zone_mean_signed"]) <= tol.max_zone_lean * s))
    if tol.max_flip_mean is not None:
        if fr.available:
            checks.append(Check("flip_mean", fr.mean, tol.max_flip_mean, fr.mean <= tol.max_flip_mean))
        else:
            checks.append(Check("flip_mean", None, tol.max_flip_mean, None, f"FLIP unavailable: {fr.note}"))
    passed = all(c.passed is not False for c in checks)
    thresholds = {"scale": tol.scale, "S": s, "abs_threshold": abs_thr, "rel_tol": tol.rel_tol,
                  "edge_pixels": tol.edge_pixels, "edge_abs_threshold": tol.edge_abs * s, "edge_rel_tol": tol.edge_rel,
                  "max_fail_fraction": tol.max_fail_fraction, "mean_abs_bound": mean_bound,
                  "mean_abs_all_bound": None if tol.max_mean_abs_all is None else tol.max_mean_abs_all * s,
                  "zone_lean_bound": None if tol.max_zone_lean is None else tol.max_zone_lean * s,
                  "max_flip_mean": tol.max_flip_mean}
    info = {"reference": names[0], "test": names[1], **(inputs or {})}
    return Report(passed, tol, metrics, thresholds, checks, fr, info, r, t, mask, fail)


def build_mask(ref: np.ndarray, *, ignore_sky: str | None = None, sky_depth: float = math.inf, border: int = 0,
               mask: str | None = None) -> np.ndarray:
    """The ``(H, W)`` bool mask of compared pixels for the reference image ``ref`` (``(H, W, C)``).

    ``ignore_sky``: ``"ref"`` (sky = pixels where ``ref`` is non-finite) or the path of a one-channel
    depth image (sky = non-finite depth or depth ``>= sky_depth``); ``border``: pixels to drop on every
    edge; ``mask``: path of an image, compared where any channel is nonzero.
    """
    h, w = ref.shape[:2]
    keep = np.ones((h, w), bool)
    if ignore_sky == "ref":
        keep &= np.isfinite(ref).all(axis=2)
    elif ignore_sky is not None:
        depth = read_image(ignore_sky, channels=1)[:, :, 0]
        if depth.shape != (h, w):
            raise InputError(ignore_sky, "shape", f"depth image is {depth.shape[1]}x{depth.shape[0]}, "
                                                  f"the reference {w}x{h}")
        keep &= np.isfinite(depth) & (depth < sky_depth)
    if not (isinstance(border, (int, np.integer)) and border >= 0):
        raise ValueError(f"border must be an integer >= 0, got {border!r}")
    if border:
        edge = np.zeros((h, w), bool)
        edge[border:h - border, border:w - border] = True
        keep &= edge
    if mask is not None:
        user = read_image(mask, allow_inf=False)
        if user.shape[:2] != (h, w):
            raise InputError(mask, "shape", f"mask image is {user.shape[1]}x{user.shape[0]}, the reference {w}x{h}")
        keep &= (user != 0).any(axis=2)
    return keep


def compare_files(ref_path, test_path, preset: str = "float32", overrides: Mapping[str, object] | None = None, *,
                  ignore_sky: str | None = None, sky_depth: float = math.inf, border: int = 0,
                  mask: str | None = None, key: str | None = None, out_dir=None, exposure: float | None = None,
                  flip: bool = True) -> Report:
    """Read two images (EXR, PNG, NPY, NPZ; ``key`` names the array of NPZ inputs), compare them under
    ``preset`` with ``overrides``, and, when ``out_dir`` is given, write report.json, diff.exr,
    heatmap.png, flip.png (when FLIP is available) and report.html there (all or nothing).
    ``exposure`` sets the preview exposure of the HTML page (default: automatic)."""
    tol = tolerance(preset, overrides)
    ref = read_image(ref_path, key=key)
    test = read_image(test_path, key=key)
    keep = build_mask(ref, ignore_sky=ignore_sky, sky_depth=sky_depth, border=border, mask=mask)
    inputs = {"ignore_sky": ignore_sky, "sky_depth": sky_depth, "border": border, "mask": mask, "key": key,
              "overrides": dict(overrides or {})}
    report = compare_arrays(ref, test, tol, keep, flip=flip, names=(str(ref_path), str(test_path)), inputs=inputs)
    if out_dir is not None:
        write_outputs(report, out_dir, exposure=exposure)
    return report
