"""The shape of the code: small signatures, named light kinds, named columns, imports at the top.

Kernels take records (:class:`vlref.lights.pack.PackedLights`, :class:`vlref.medium.PackedMedium`,
:class:`vlref.lights.shadow_pack.ShadowTable`, the geometry arrays) rather than long lists of positional
arrays, compare light kinds with the ``KIND_*`` constants of :mod:`vlref.lights.pack`, never with
digits, and read a record's columns by their names (``I_*``, ``F_*``, ``M_*``, ``S_*``), never by number.
A module imports vlref's own modules at its top, where a reader sees its dependencies; a function imports
only optional third-party packages (kept lazy so the core runs without them).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import vlref

MAX_ARGUMENTS = 16
UNPACKED_RECORDS = {"geometry/scene_geometry.py:_closest"}
"""The one kernel allowed more: the per-ray traversal takes the geo record's arrays one by one, because a record
field read costs an atomic reference count (~200 ns of a ray's ~350 ns, BENCHMARKS.md "Whole frame"), so
``closest_hits`` reads the record once per chunk of rays and hands the arrays down."""
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
                name = f"{path.relative_to(PACKAGE)}:{getattr(node, 'name', '<lambda>')}"
                if n > MAX_ARGUMENTS and name not in UNPACKED_RECORDS:
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


# the record tables and the names the kernels bind them to: 2-D (row, column) and 1-D (column) tables
TABLES_2D = {"ints", "floats", "li", "lf", "sm_i", "sm_f"}
TABLES_1D = {"params", "mp"}


def _raw_columns(source: str) -> list[int]:
    """Line numbers where a record table is indexed by a number in its column position."""
    hits = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Subscript):
            continue
        v = node.value
        name = v.attr if isinstance(v, ast.Attribute) else v.id if isinstance(v, ast.Name) else None
        index = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
        if name in TABLES_2D and len(index) == 2:
            column = index[1]
        elif name in TABLES_1D and len(index) == 1:
            column = index[0]
        else:
            continue
        if isinstance(column, ast.UnaryOp):
            column = column.operand
        if isinstance(column, ast.Constant) and isinstance(column.value, int):
            hits.append(node.lineno)
    return hits


def test_columns_are_read_by_name_outside_the_packing_modules():
    packing = {PACKAGE / "lights" / "pack.py", PACKAGE / "medium.py", PACKAGE / "lights" / "shadow_pack.py"}
    hits = [f"{path.relative_to(PACKAGE)}:{line}" for path in SOURCES if path not in packing
            for line in _raw_columns(path.read_text(encoding="utf-8"))]
    assert hits == []


def test_raw_column_check_sees_numbers_and_passes_names():
    assert _raw_columns("x = lf[k, 3] + mp[0] + lights.ints[k, -1] + medium.params[2]") == [1, 1, 1, 1]
    assert _raw_columns("x = lf[k, F_PX] + mp[M_ST] + lf[0] + rows[3] + lights.floats[k, F_DX]") == []


def _local_own_imports(source: str) -> list[str]:
    """``line: import`` of every import of vlref's own modules inside a function."""
    hits = []
    for fn in ast.walk(ast.parse(source)):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for node in ast.walk(fn):
                own = (isinstance(node, ast.ImportFrom) and (node.level > 0 or (node.module or "").split(".")[0]
                                                             == "vlref")
                       or isinstance(node, ast.Import) and any(a.name.split(".")[0] == "vlref" for a in node.names))
                if own:
                    hits.append(f"{node.lineno}: {ast.unparse(node)}")
    return hits


LAZY_ENTRY_POINTS = {"pytest_plugin.py"}
"""Files allowed to import vlref's rendering modules on first use: pytest loads the plugin in every session of an
environment where vlref is installed, and vlref.render / vlref.port load Numba's kernels (about 1 s)."""


def test_vlref_modules_are_imported_at_the_top_of_each_file():
    hits = [f"{path.relative_to(PACKAGE)}:{hit}" for path in SOURCES
            if str(path.relative_to(PACKAGE)) not in LAZY_ENTRY_POINTS
            for hit in _local_own_imports(path.read_text(encoding="utf-8"))]
    assert hits == []


def test_local_import_check_sees_own_modules_and_passes_optional_packages():
    src = ("def f():\n    from .io.exr import write_exr\n    import vlref.render\n    from vlref import scene\n"
           "def g():\n    import OpenEXR\n    from tqdm import tqdm\n")
    assert [h.split(":")[0] for h in _local_own_imports(src)] == ["2", "3", "4"]
