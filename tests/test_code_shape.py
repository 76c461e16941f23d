"""The shape of the code: small signatures and named light kinds.

Kernels take records (:class:`vlref.lights.pack.PackedLights`, :class:`vlref.medium.PackedMedium`,
:class:`vlref.lights.shadowmaps.ShadowTable`, the geometry arrays) rather than long lists of positional
arrays, and compare light kinds with the ``KIND_*`` constants of :mod:`vlref.lights.pack`, never with
digits.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import vlref

MAX_ARGUMENTS = 16
PACKAGE = Path(vlref.__file__).parent
SOURCES = sorted(PACKAGE.rglob("*.py"))


def _argument_count(fn: ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda) -> int:
    a = fn.args
    return (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + (a.vararg is not None)
            + (a.kwarg is not None))


def test_the_walk_sees_the_package():
    assert len(SOURCES) > 50
    assert PACKAGE / "march" / "physical.py" in SOURCES


def test_no_function_takes_more_than_16_arguments():
    too_long = []
    for path in SOURCES:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                n = _argument_count(node)
                if n > MAX_ARGUMENTS:
                    too_long.append(f"{path.relative_to(PACKAGE)}:{node.lineno} "
                                    f"{getattr(node, 'name', '<lambda>')} takes {n}")
    assert too_long == []


def test_argument_count_counts_every_kind_of_parameter():
    fn = ast.parse("def f(a, /, b, *c, d, **e): pass").body[0]
    assert _argument_count(fn) == 5


def test_light_kinds_are_compared_by_name():
    digit = re.compile(r"\bkind\s*[!=]=\s*\d")
    hits = [f"{path.relative_to(PACKAGE)}:{i}" for path in SOURCES
            for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if digit.search(line)]
    assert hits == []
