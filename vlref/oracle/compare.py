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

Exit codes of :func:`main_compare`: 0 pass, 1 fail, 2 bad input (:class:`vlref.errors.InputError`).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from .. import __version__
from ..errors import InputError
from ..io import read_image
from .metrics import FLIP_MISSING, FlipResult, error_metrics, failing_pixels, hdr_flip
from .presets import Tolerance, tolerance

__all__ = [
    "Check", "Report", "RULE", "build_mask", "compare_arrays", "compare_files", "add_arguments", "run_compare",
    "main_compare",
]

RULE = ("pixel fails when |test-ref| > abs_tol*S + rel_tol*|ref| in any channel; image passes when "
        "failing fraction <= max_fail_fraction and mean |test-ref| <= max_mean_abs*S "
        "(and mean HDR-FLIP <= max_flip_mean when set and available); S = 1 (scale 'absolute') or "
        "mean |ref| over the compared values (scale 'mean'); values at a bound pass")


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

    @property
    def exit_code(self) -> int:
        return 0 if self.passed else 1

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


def _as_image(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    return a[:, :, None] if a.ndim == 2 else a


def _first_bad(bad: np.ndarray) -> str:
    y, x = np.argwhere(bad)[0]
    return f"{int(bad.sum())} pixel(s), first at x={x}, y={y}"


def compare_arrays(ref, test, tol: Tolerance | str, mask: np.ndarray | None = None, *, flip: bool = True,
                   names: tuple[str, str] = ("<reference>", "<test>"), inputs: Mapping | None = None) -> Report:
    """Compare two ``(H, W)`` / ``(H, W, C)`` arrays under ``tol`` (a :class:`Tolerance` or preset name).

    ``mask`` (``(H, W)`` bool, true = compared) defaults to every pixel. ``names`` label the arrays in
    error messages. Raises :class:`InputError` when shapes or channel counts differ, a value is NaN,
    a compared value is infinite, or the mask selects no pixel.
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
        raise InputError("<mask>", "shape", f"mask shape {mask.shape} differs from the images' {r.shape[:2]}")
    for a, name in ((r, names[0]), (t, names[1])):
        if np.isnan(a).any():
            raise InputError(name, "values", f"NaN present ({_first_bad(np.isnan(a).any(axis=2))})")
        bad = ~np.isfinite(a).all(axis=2) & mask
        if bad.any():
            raise InputError(name, "values", f"infinite values in compared pixels ({_first_bad(bad)}); "
                                             "mask them (e.g. ignore sky)")
    n = int(np.count_nonzero(mask))
    if n == 0:
        raise InputError("<mask>", "", "the masks leave no pixel to compare")

    s = 1.0 if tol.scale == "absolute" else float(np.mean(np.abs(r[mask])))
    abs_thr, mean_bound = tol.abs_tol * s, tol.max_mean_abs * s
    metrics = error_metrics(r, t, mask, abs_thr, tol.rel_tol)
    metrics["total_pixels"] = int(mask.size)
    rf = np.where(mask[:, :, None], r, 0.0)
    fail = failing_pixels(rf, np.where(mask[:, :, None], t, 0.0), abs_thr, tol.rel_tol) & mask
    fr = hdr_flip(r, t, mask) if flip else FlipResult(None, None, "not computed")
    metrics["flip_mean"] = fr.mean

    checks = [Check("failing_fraction", metrics["frac_failing"], tol.max_fail_fraction,
                    metrics["frac_failing"] <= tol.max_fail_fraction),
              Check("mean_abs_error", metrics["mean_abs"], mean_bound, metrics["mean_abs"] <= mean_bound)]
    if tol.max_flip_mean is not None:
        if fr.available:
            checks.append(Check("flip_mean", fr.mean, tol.max_flip_mean, fr.mean <= tol.max_flip_mean))
        else:
            checks.append(Check("flip_mean", None, tol.max_flip_mean, None, f"FLIP unavailable: {fr.note}"))
    passed = all(c.passed is not False for c in checks)
    thresholds = {"scale": tol.scale, "S": s, "abs_threshold": abs_thr, "rel_tol": tol.rel_tol,
                  "max_fail_fraction": tol.max_fail_fraction, "mean_abs_bound": mean_bound,
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
        raise InputError("<command line>", "border", f"must be an integer >= 0, got {border!r}")
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
    from .report import write_outputs

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


def _parse_set(items: Sequence[str] | None) -> dict[str, str]:
    out = {}
    for item in items or ():
        k, sep, v = item.partition("=")
        if not sep or not k.strip():
            raise InputError("<command line>", "--set", f"expected KEY=VALUE, got {item!r}")
        out[k.strip()] = v.strip()
    return out


def add_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of ``vlref compare`` (for a sub-parser or a stand-alone parser)."""
    p.add_argument("ref", help="reference image (.exr, .png, .npy, .npz)")
    p.add_argument("test", help="test image, same size and channel count")
    p.add_argument("--preset", default="float32",
                   help="tolerance preset: exact, float32, gpu-full, gpu-half, gpu-quarter (default float32)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a tolerance knob: abs_tol, rel_tol, max_fail_fraction, max_mean_abs, "
                        "max_flip_mean (none = off), scale (absolute|mean) (repeatable; default: the preset's)")
    p.add_argument("--ignore-sky", metavar="DEPTH|ref",
                   help="skip sky pixels: a depth image (inf or >= --sky-depth = sky) or 'ref' (non-finite "
                        "reference) (default: compare sky too)")
    p.add_argument("--sky-depth", type=float, default=math.inf,
                   help="depth at and beyond which a pixel is sky (default: inf, only infinite depth)")
    p.add_argument("--border", type=int, default=0, help="ignore this many pixels along every edge (default: 0)")
    p.add_argument("--mask", help="mask image: compare where nonzero (default: every pixel)")
    p.add_argument("--key", help="array name inside .npz inputs (default: the file's only array)")
    p.add_argument("-o", "--output", help="write report.json, diff.exr, heatmap.png, report.html and, when HDR-FLIP "
                   "runs (flip-evaluator installed, no --no-flip), flip.png here (default: write nothing)")
    p.add_argument("--exposure", type=float, help="preview exposure in the HTML page (default: automatic, "
                   "1/99th percentile of the reference)")
    p.add_argument("--no-flip", action="store_true", help="skip HDR-FLIP (default: computed when flip-evaluator "
                   "is installed)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing, use the exit code (default: off)")
    return p


def run_compare(args: argparse.Namespace) -> int:
    """Run a comparison from arguments parsed with :func:`add_arguments`; returns the exit code."""
    from ..io import check_output_dir
    try:
        if args.output:
            check_output_dir(args.output)
        report = compare_files(args.ref, args.test, args.preset, _parse_set(args.set),
                               ignore_sky=args.ignore_sky, sky_depth=args.sky_depth, border=args.border,
                               mask=args.mask, key=args.key, out_dir=args.output, exposure=args.exposure,
                               flip=not args.no_flip)
    except InputError as exc:
        print(f"vlref compare: error: {exc}", file=sys.stderr)
        return 2
    if not args.quiet and report.flip.note == FLIP_MISSING:
        print(f"vlref compare: note: HDR-FLIP skipped, {FLIP_MISSING}; no flip.png written", file=sys.stderr)
    if not args.quiet:
        print(report.summary())
        if args.output:
            print(f"wrote {Path(args.output) / 'report.html'}")
    return report.exit_code


def main_compare(argv: Sequence[str] | None = None) -> int:
    """``vlref compare`` with ``argv`` (default ``sys.argv[1:]``): 0 pass, 1 fail, 2 bad input (or usage)."""
    parser = add_arguments(argparse.ArgumentParser(
        prog="vlref compare", description="Compare a test image with a reference: exit 0 pass, 1 fail, 2 bad input."))
    try:
        args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:  # argparse: 2 on bad usage, 0 on --help
        return int(exc.code or 0)
    return run_compare(args)
