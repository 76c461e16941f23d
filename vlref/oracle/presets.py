"""Tolerance presets for image comparison, loaded from ``vlref/data/presets.toml``.

The pass/fail rule (Unity's graphics test framework and Filament's renderdiff combine the same three
knobs), evaluated over the compared pixels:

* a pixel fails when ``|t_c - r_c| > abs_tol * S + rel_tol * |r_c|`` in any channel ``c``;
* the image passes when the failing fraction ``<= max_fail_fraction`` and the mean absolute error
  ``<= max_mean_abs * S`` (and, when ``max_flip_mean`` is set and FLIP is available, the mean
  HDR-FLIP ``<= max_flip_mean``).

Edge zone (:mod:`vlref.oracle.edges`): when the caller gives one (``compare_arrays(edges=)``, built
``edge_pixels`` pixels wide around depth discontinuities and shadow silhouettes), its pixels fail only
beyond ``edge_abs_tol * S + edge_rel_tol * |r_c|`` (default: the base knobs) and the mean absolute error
is taken outside it (``max_mean_abs_all``, when set, bounds the mean absolute error over every compared
pixel, the zone included, by ``max_mean_abs_all * S``: a zone that covers much of a frame cannot hide an
error everywhere; ``max_zone_lean``, when set, bounds the *signed* mean of ``t - r`` over the zone's compared
values by ``max_zone_lean * S``: a zone pixel may differ either way, the zone as a whole may not lean one way);
the presets for GPU ports allow no failing pixel (``max_fail_fraction = 0``), so
what a rasteriser may change is absorbed by geometry, not by a share of the image that grows with it.

``S`` is the scale: ``"absolute"`` -> 1, ``"mean"`` -> the mean ``|ref|`` over the compared values
(so an all-zero reference under ``"mean"`` demands an exact match).
The data file documents the reasoning behind each preset's numbers.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Mapping

from ..errors import InputError
from ..tomlfile import loads as toml_loads

__all__ = ["Tolerance", "SCALES", "load_presets", "tolerance", "PRESETS_FILE"]

SCALES = ("absolute", "mean")
PRESETS_FILE = "data/presets.toml"
_SOURCE = "<command line>"


@dataclass(frozen=True)
class Tolerance:
    """The knobs of the pass/fail rule (see the module docstring); tolerances are >= 0."""

    abs_tol: float
    rel_tol: float
    max_fail_fraction: float
    max_mean_abs: float
    max_flip_mean: float | None = None
    scale: str = "absolute"
    name: str = "custom"
    description: str = ""
    edge_pixels: int = 0
    edge_rel_tol: float | None = None
    edge_abs_tol: float | None = None
    max_mean_abs_all: float | None = None
    max_zone_lean: float | None = None

    @property
    def edge_rel(self) -> float:
        """The relative tolerance inside the edge zone (``edge_rel_tol``, default ``rel_tol``)."""
        return self.rel_tol if self.edge_rel_tol is None else self.edge_rel_tol

    @property
    def edge_abs(self) -> float:
        """The absolute tolerance (times S) inside the edge zone (``edge_abs_tol``, default ``abs_tol``)."""
        return self.abs_tol if self.edge_abs_tol is None else self.edge_abs_tol

    def __post_init__(self):
        for key in _NUMBERS:
            value = getattr(self, key)
            if value is None and key in _OPTIONAL:
                continue
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) \
                    or value < 0:
                raise InputError(_SOURCE, key, f"must be a finite number >= 0, got {value!r}")
        if not isinstance(self.edge_pixels, int) or isinstance(self.edge_pixels, bool) or self.edge_pixels < 0:
            raise InputError(_SOURCE, "edge_pixels", f"must be an integer >= 0, got {self.edge_pixels!r}")
        if self.max_fail_fraction > 1:
            raise InputError(_SOURCE, "max_fail_fraction", f"is a fraction in [0, 1], got {self.max_fail_fraction}")
        if self.scale not in SCALES:
            raise InputError(_SOURCE, "scale", f"must be one of {', '.join(SCALES)}, got {self.scale!r}")


_KNOBS = tuple(f.name for f in dataclasses.fields(Tolerance) if f.name != "name")
"""Every knob a preset or ``--set`` may give, read off :class:`Tolerance`'s fields (one list: the class)."""
_NUMBERS = tuple(f.name for f in dataclasses.fields(Tolerance) if f.type in ("float", "float | None"))
"""The knobs that are numbers >= 0."""
_OPTIONAL = tuple(f.name for f in dataclasses.fields(Tolerance) if f.type == "float | None")
"""Knobs that may be unset (``none``): no FLIP gate; the edge zone's tolerance = the base one; no mean-error
bound over the edge zone too; no bound on the zone's signed mean."""
_TEXT = tuple(f.name for f in dataclasses.fields(Tolerance) if f.type == "str" and f.name != "name")
"""Knobs that are text (``scale``, ``description``)."""


def _suggest(word: str, options) -> str:
    close = difflib.get_close_matches(word, list(options), n=1)
    return f", did you mean {close[0]}?" if close else f" (known: {', '.join(options)})"


def _coerce(key: str, value) -> object:
    """A knob's value from TOML or from a ``--set key=value`` string."""
    if key not in _KNOBS:
        raise InputError(_SOURCE, key, "unknown tolerance key" + _suggest(key, _KNOBS))
    if key in _TEXT:
        return str(value)
    if key in _OPTIONAL and (value is None or str(value).strip().lower() in ("none", "off", "")):
        return None
    if key == "edge_pixels":
        try:
            return int(value) if isinstance(value, str) or (isinstance(value, float) and value.is_integer()) \
                else value
        except ValueError:
            raise InputError(_SOURCE, key, f"not an integer: {value!r}") from None
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            raise InputError(_SOURCE, key, f"not a number: {value!r}") from None
    if isinstance(value, bool):
        raise InputError(_SOURCE, key, f"not a number: {value!r}")
    return value


@lru_cache(maxsize=1)
def load_presets() -> dict[str, Tolerance]:
    """All presets of the data file, by name."""
    text = resources.files("vlref").joinpath(PRESETS_FILE).read_text(encoding="utf-8")
    table = toml_loads(text)
    out = {}
    for name, knobs in table.items():
        values = {k: _coerce(k, v) for k, v in knobs.items()}
        out[name] = Tolerance(name=name, **values)
    return out


def tolerance(preset: str = "float32", overrides: Mapping[str, object] | None = None) -> Tolerance:
    """The named preset with ``overrides`` (``{"rel_tol": 0.02}`` or string values) applied.

    Raises :class:`InputError` for an unknown preset or key and for invalid values.
    """
    presets = load_presets()
    if preset not in presets:
        raise InputError(_SOURCE, "preset", f"unknown preset {preset!r}" + _suggest(preset, presets))
    base = presets[preset]
    if not overrides:
        return base
    changes = {k: _coerce(k, v) for k, v in overrides.items()}
    return dataclasses.replace(base, name=f"{preset}+overrides", **changes)
