"""Turn a parsed TOML/JSON document into the frozen dataclasses of :mod:`vlref.scene.model`.

The dataclasses are the schema: each field's type hint says what it accepts, and its
``metadata`` states the constraints, checked here in one place:

=============== ==========================================================
``doc``         one line for the documentation
``min``/``max`` inclusive bounds;  ``gt``/``lt``: exclusive bounds
``choices``     the allowed strings
``nonzero``     a vector whose length must not be 0 (directions)
``file``        a path, relative to the scene file, that must exist
``union``       ``(tag, {tag value: dataclass})`` for tagged tables (object shapes)
=============== ==========================================================

Every error is an :class:`vlref.errors.InputError` reading ``FILE: key.path: reason``, and
unknown keys come with the nearest known key as a suggestion.

A class may rename a key: ``RENAMED_KEYS = {old: (new, convert)}`` reads a number given under ``old``
as ``new = convert(value)`` with a :class:`DeprecationWarning` naming the new key.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import typing
import warnings
from pathlib import Path
from typing import Any, Union

from ..errors import InputError

__all__ = ["build", "join_path", "field_docs"]


def join_path(base: str, key: str | int) -> str:
    """``join_path("lights", 1) -> "lights[1]"``, ``join_path("lights[1]", "range") -> "lights[1].range"``."""
    if isinstance(key, int):
        return f"{base}[{key}]"
    return f"{base}.{key}" if base else key


class _Ctx:
    def __init__(self, file: str, base_dir: Path):
        self.file = file
        self.base_dir = base_dir

    def fail(self, path: str, reason: str) -> typing.NoReturn:
        raise InputError(self.file, path, reason)


def build(cls: type, data: Any, file: str, base_dir: Path | None = None, path: str = "") -> Any:
    """Validate ``data`` (dicts/lists/scalars) against dataclass ``cls`` and build it."""
    base = Path(base_dir) if base_dir is not None else Path(file).resolve().parent
    return _build_dataclass(cls, data, _Ctx(file, base), path)


def _type_name(value: Any) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(value), type(value).__name__)


def _build_dataclass(cls: type, data: Any, ctx: _Ctx, path: str) -> Any:
    if not isinstance(data, dict):
        ctx.fail(path or "(top level)", f"expected a table, got {_type_name(data)}")
    data = _renamed(cls, data, ctx, path)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init and not f.metadata.get("internal")}
    for key in data:
        if key not in fields:
            close = difflib.get_close_matches(str(key), list(fields), n=1, cutoff=0.6)
            hint = f", did you mean {close[0]}?" if close else f" (known keys: {', '.join(sorted(fields))})"
            ctx.fail(join_path(path, str(key)), "unknown key" + hint)
    hints = typing.get_type_hints(cls)
    kwargs = {}
    for name, f in fields.items():
        if name in data:
            kwargs[name] = _convert(hints[name], data[name], f.metadata, ctx, join_path(path, name))
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            ctx.fail(join_path(path, name), "missing required key")
    obj = cls(**kwargs)
    check = getattr(obj, "check", None)
    if check is not None:
        problem = check()
        if problem:
            key, reason = problem
            ctx.fail(join_path(path, key) if key else path, reason)
    return obj


def _renamed(cls: type, data: dict, ctx: _Ctx, path: str) -> dict:
    """``data`` with each deprecated key of ``cls.RENAMED_KEYS`` replaced by its new key (module docstring)."""
    for old, (new, convert) in getattr(cls, "RENAMED_KEYS", {}).items():
        if old not in data:
            continue
        old_path, new_path = join_path(path, old), join_path(path, new)
        if new in data:
            ctx.fail(old_path, f"deprecated alias of {new_path}; give {new_path} only")
        value = data[old]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            ctx.fail(old_path, f"expected a number, got {_type_name(value)}")
        warnings.warn(f"{ctx.file}: {old_path} is deprecated: use {new_path} = {convert(value)!r}",
                      DeprecationWarning, stacklevel=2)
        data = {**{k: v for k, v in data.items() if k != old}, new: convert(value)}
    return data


def _convert(tp: Any, value: Any, meta: Any, ctx: _Ctx, path: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin is Union:  # Optional[X]
        if value is None:
            return None
        inner = [a for a in args if a is not type(None)]
        return _convert(inner[0], value, meta, ctx, path)
    if "union" in meta and origin is tuple:
        if not isinstance(value, list):
            ctx.fail(path, f"expected a list of tables, got {_type_name(value)}")
        return tuple(_build_tagged(meta["union"], v, ctx, join_path(path, i)) for i, v in enumerate(value))
    if dataclasses.is_dataclass(tp):
        return _build_dataclass(tp, value, ctx, path)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        if not isinstance(value, list):
            ctx.fail(path, f"expected a list, got {_type_name(value)}")
        return tuple(_convert(args[0], v, meta, ctx, join_path(path, i)) for i, v in enumerate(value))
    if origin is tuple:  # fixed-length numeric vector
        if isinstance(value, bool) or not isinstance(value, list) or len(value) != len(args):
            ctx.fail(path, f"expected a list of {len(args)} numbers, got {_describe(value)}")
        out = tuple(_scalar(float, v, {}, ctx, join_path(path, i)) for i, v in enumerate(value))
        if meta.get("nonzero") and math.sqrt(sum(v * v for v in out)) == 0.0:
            ctx.fail(path, "zero-length vector: a direction needs a non-zero length")
        for i, v in enumerate(out):
            _check_bounds(v, meta, ctx, join_path(path, i))
        return out
    return _scalar(tp, value, meta, ctx, path)


def _describe(value: Any) -> str:
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return _type_name(value)


def _build_tagged(union: tuple, value: Any, ctx: _Ctx, path: str) -> Any:
    tag, classes = union
    if not isinstance(value, dict):
        ctx.fail(path, f"expected a table, got {_type_name(value)}")
    kind = value.get(tag)
    if kind not in classes:
        close = difflib.get_close_matches(str(kind), list(classes), n=1, cutoff=0.6)
        hint = f", did you mean {close[0]}?" if close else ""
        ctx.fail(join_path(path, tag), f"must be one of {', '.join(classes)}, got {kind!r}" + hint)
    return _build_dataclass(classes[kind], value, ctx, path)


def _scalar(tp: Any, value: Any, meta: Any, ctx: _Ctx, path: str) -> Any:
    if tp is bool:
        if not isinstance(value, bool):
            ctx.fail(path, f"expected true or false, got {_type_name(value)}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            ctx.fail(path, f"expected an integer, got {_type_name(value)}")
        _check_bounds(value, meta, ctx, path)
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            ctx.fail(path, f"expected a number, got {_type_name(value)}")
        value = float(value)
        if not math.isfinite(value):
            ctx.fail(path, "must be finite")
        _check_bounds(value, meta, ctx, path)
        return value
    if tp is str:
        if not isinstance(value, str):
            ctx.fail(path, f"expected a string, got {_type_name(value)}")
        choices = meta.get("choices")
        if choices and value not in choices:
            close = difflib.get_close_matches(value, list(choices), n=1, cutoff=0.5)
            hint = f", did you mean {close[0]}?" if close else ""
            ctx.fail(path, f"must be one of {', '.join(choices)}, got {value!r}" + hint)
        if meta.get("file"):
            resolved = (ctx.base_dir / value).resolve()
            if not resolved.is_file():
                ctx.fail(path, f"file not found: {resolved}")
            return str(resolved)
        return value
    raise TypeError(f"unsupported schema type {tp!r} at {path}")  # a bug in the model, not input


def _check_bounds(value: float, meta: Any, ctx: _Ctx, path: str) -> None:
    if "min" in meta and value < meta["min"]:
        ctx.fail(path, f"must be >= {meta['min']}, got {value}")
    if "max" in meta and value > meta["max"]:
        ctx.fail(path, f"must be <= {meta['max']}, got {value}")
    if "gt" in meta and not value > meta["gt"]:
        ctx.fail(path, f"must be > {meta['gt']}, got {value}")
    if "lt" in meta and not value < meta["lt"]:
        ctx.fail(path, f"must be < {meta['lt']}, got {value}")


def field_docs(cls: type, prefix: str = "") -> list[tuple[str, str, str, str]]:
    """``(key path, type, default, doc)`` rows for every field, for generated documentation."""
    rows = []
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if f.metadata.get("internal"):
            continue
        tp = hints[f.name]
        key = join_path(prefix, f.name)
        default = f.default if f.default is not dataclasses.MISSING else (
            "(table)" if f.default_factory is not dataclasses.MISSING else "required")
        rows.append((key, getattr(tp, "__name__", str(tp)), repr(default), f.metadata.get("doc", "")))
        inner = [a for a in typing.get_args(tp) if dataclasses.is_dataclass(a)]
        target = tp if dataclasses.is_dataclass(tp) else (inner[0] if inner else None)
        if target is not None:
            rows.extend(field_docs(target, key))
    return rows
