"""vlref.jit.njit: Numba's njit with only the wrappers vlref calls. A helper (compiled code calls it) has no wrapper
and no machine code (its callers link its optimised module; cached as bitcode), and a call from Python reaches it
through its Python entry, a compile of its own under its own name and cache entry;
an entry point (``entry=True`` or ``parallel=True``: Python calls it) keeps its CPython wrapper and has no C wrapper; a
work function (``by_address=True``) has its C wrapper (vlref.parallel.work calls it through its address) and no
CPython wrapper; the function's own optimised code is Numba's; every compiled function of vlref is made by it."""

import ast
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import prange
from numba.core.registry import CPUDispatcher

import vlref
from vlref.phase import hg
from vlref.render import render
from vlref.scene import load_scene
from vlref.jit import PYTHON_ENTRY_SUFFIX, CompiledCallersDispatcher, LinkOnlyLibrary, njit
from vlref.parallel import COUNTER, WORKERS, take, task_counter, work


def _phase_sum(cos_theta, g):
    total = 0.0
    for c in cos_theta:
        total += hg(c, g)
    return total


def _fill(taken, out):
    while True:
        i = take(taken)
        if i >= out.size:
            return
        out[i] = math.sqrt(i)


def _entry(dispatcher, name, sig=None):
    """The address of the entry point ``name`` (a fndesc attribute) of ``dispatcher``'s function compiled for
    ``sig`` (default: its first), 0 if it was not compiled."""
    result = dispatcher.overloads[sig or dispatcher.signatures[0]]
    return result.library.get_pointer_to_function(getattr(result.fndesc, name))


def _body(dispatcher):
    """The optimised LLVM IR of ``dispatcher``'s compiled function itself (no wrapper), its own name blanked."""
    result = dispatcher.overloads[dispatcher.signatures[0]]
    name = result.fndesc.llvm_func_name
    return str(result.library.get_function(name)).replace(name, "F")


def test_an_entry_point_has_its_python_wrapper_and_no_c_wrapper():
    cos_theta = np.linspace(-1.0, 1.0, 2001)
    ours, numbas = njit(_phase_sum, entry=True), numba.njit(_phase_sum)
    assert ours(cos_theta, 0.5) == numbas(cos_theta, 0.5)  # called from Python
    assert ours(cos_theta, 0.0) == pytest.approx(2001 / (4 * math.pi), rel=1e-12)  # isotropic: 1 / 4π each
    assert _entry(ours, "llvm_cpython_wrapper_name") and _entry(numbas, "llvm_cpython_wrapper_name")
    assert _entry(ours, "llvm_cfunc_wrapper_name") == 0 and _entry(numbas, "llvm_cfunc_wrapper_name") != 0
    assert _body(ours) == _body(numbas)  # the same code, only the wrapper left out
    assert type(njit(_phase_sum, parallel=True)) is CPUDispatcher  # a parallel kernel is an entry point


def test_a_helper_has_no_wrapper_and_python_calls_it_through_its_python_entry():
    cos_theta = np.linspace(-1.0, 1.0, 2001)
    ours, numbas = njit(_phase_sum), numba.njit(_phase_sum)
    assert isinstance(ours, CompiledCallersDispatcher)
    assert ours(cos_theta, 0.5) == numbas(cos_theta, 0.5)  # from Python: through the Python entry
    assert ours.signatures == [] and len(ours.python_entry.signatures) == 1
    assert ours.python_entry.py_func.__qualname__ == _phase_sum.__qualname__ + PYTHON_ENTRY_SUFFIX
    assert _entry(ours.python_entry, "llvm_cpython_wrapper_name") != 0

    @numba.njit
    def caller(c, g):
        return ours(c, g)

    assert caller(cos_theta, 0.5) == numbas(cos_theta, 0.5)  # from compiled code: the helper's own compile
    assert len(ours.signatures) == 1
    assert _entry(ours, "llvm_cpython_wrapper_name") == 0 and _entry(ours, "llvm_cfunc_wrapper_name") == 0
    assert _no_wrapper(_body(ours))


def _no_wrapper(body: str) -> bool:
    """Whether an optimised function body (:func:`_body`) is the function itself: it calls no wrapper."""
    return body.startswith("; Function Attrs") and "wrapper" not in body and "define" in body


def test_a_helper_is_compiled_without_machine_code_and_its_callers_link_its_optimised_module():
    """Compiled code calls a helper's code linked into its own module, never the helper's machine code: the helper
    is compiled into a LinkOnlyLibrary, optimised as Numba optimises it and never given to the JIT engine."""
    cos_theta = np.linspace(-1.0, 1.0, 101)
    ours = njit(_phase_sum)
    sig = (numba.typeof(cos_theta), numba.float64)
    ours.compile(sig)
    result = ours.overloads[sig]
    engine = result.library._codegen._engine
    assert isinstance(result.library, LinkOnlyLibrary) and result.library._finalized
    assert not engine.is_symbol_defined(result.fndesc.mangled_name)  # no machine code
    assert _no_wrapper(_body(ours)) and "fdiv double" in _body(ours)  # its optimised module, for linking

    @numba.njit
    def caller(c, g):
        return ours(c, g)

    assert caller(cos_theta, 0.25) == numba.njit(_phase_sum)(cos_theta, 0.25)
    assert engine.is_symbol_defined(caller.overloads[caller.signatures[0]].fndesc.mangled_name)
    assert ours.overloads[sig] is result  # the caller linked the helper's compile, not a new one


_CACHED_HELPER = """
import sys
import numba
import numpy as np
from vlref.jit import njit


@(numba.njit if sys.argv[2:] == ["plain"] else njit)(cache=True)  # plain: as a vlref that compiles every wrapper
def helper(a):
    return a.sum() * 0.5


@numba.njit
def caller(a):
    return helper(a)


a = np.arange(10.0)
value = caller(a) if sys.argv[1] == "compiled" else helper(a)
print(value, len(helper.signatures), sum(helper.stats.cache_hits.values()))
"""


def test_a_helper_is_cached_as_bitcode_apart_from_its_python_entry_and_from_plain_numba(tmp_path):
    """A helper compiled for a compiled caller is cached as the module its callers link (bitcode, no machine code),
    which a later process's compile links without compiling the helper again; Numba's cache keys an entry by
    signature and code only, so that entry must never be what a Python call loads (its Python entry has a name and
    entry of its own), nor what a version of vlref that compiles every wrapper (plain Numba) loads, nor the reverse."""
    (tmp_path / "cached_helper.py").write_text(textwrap.dedent(_CACHED_HELPER))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(Path(vlref.__file__).parents[1]), os.environ.get("PYTHONPATH", "")]))

    def run(*how):
        proc = subprocess.run([sys.executable, str(tmp_path / "cached_helper.py"), *how], env=env, capture_output=True,
                              text=True, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return proc.stdout.split()

    assert run("compiled") == ["22.5", "1", "0"]  # the helper compiled without wrapper and machine code, cached
    assert run("compiled") == ["22.5", "1", "1"]  # a fresh process: the caller links the cached helper
    assert run("python") == ["22.5", "0", "0"]  # the Python entry, its own compile and cache entry
    assert run("python") == ["22.5", "0", "0"]  # its cache entry
    indexes = sorted(p.name.split("-")[0] for p in (tmp_path / "cache").rglob("*.nbi"))
    assert indexes == ["cached_helper.helper", "cached_helper.helper" + PYTHON_ENTRY_SUFFIX]
    # a version of vlref that compiles the helper with its wrappers (plain Numba), on the same unchanged source and
    # cache, never loads the bitcode entry (vlref.jit.LinkOnlyCache): it compiles its own and runs
    assert run("python", "plain") == ["22.5", "1", "0"]
    assert run("compiled") == ["22.5", "1", "1"]  # and this version still finds its own entry beside that one


def test_a_work_function_has_its_c_wrapper_and_no_python_entry():
    fill = njit(_fill, by_address=True)

    @numba.njit(parallel=True)
    def run(out, f):
        taken = task_counter()
        for _ in prange(WORKERS):
            f(taken, out)

    out = np.zeros(1000)
    run(out, work(fill, COUNTER, out))
    assert np.array_equal(out, np.sqrt(np.arange(1000.0)))
    assert _entry(fill, "llvm_cfunc_wrapper_name") != 0 and _entry(fill, "llvm_cpython_wrapper_name") == 0
    numbas = numba.njit(_fill)
    numbas.compile(fill.signatures[0])
    assert _body(fill) == _body(numbas)


def test_work_refuses_a_function_without_its_c_wrapper():
    with pytest.raises(TypeError, match="by_address=True"):
        work(njit(_fill), COUNTER, np.zeros(3))


def test_every_compiled_function_of_vlref_is_made_by_vlref_jit():
    """No ``from numba import njit`` / ``numba.njit`` / ``numba.jit`` in the package but in vlref.jit itself."""
    root = Path(vlref.__file__).parent
    found = []
    for path in sorted(root.rglob("*.py")):
        if path.name == "jit.py" and path.parent == root:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module == "numba" and \
                    any(a.name in ("njit", "jit") for a in node.names):
                found.append(f"{path.relative_to(root)}:{node.lineno}")
            if isinstance(node, ast.Attribute) and node.attr in ("njit", "jit") and \
                    isinstance(node.value, ast.Name) and node.value.id == "numba":
                found.append(f"{path.relative_to(root)}:{node.lineno}")
    assert not found


def test_a_render_compiles_each_function_with_the_wrapper_of_how_it_is_called():
    """After a render of the default scene, every compiled function of vlref has no wrapper but the entry points,
    the kernels Python calls (their CPython wrapper only), and the work functions of the parallel kernels (their C
    wrapper only)."""
    render(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]))
    dispatchers = {value.py_func.__qualname__: value for name, module in list(sys.modules.items())
                   if name.startswith("vlref.") for value in vars(module).values() if isinstance(value, CPUDispatcher)}
    compiled = {name: d for name, d in dispatchers.items() if d.signatures}
    render_work = {"_cast_rows", "_shade_rows", "_cast_chunks", "_march_tasks"}
    render_entries = {"_build", "_raycast_kernel", "_shade", "_cast_face", "_march_kernel", "_sum_composite"}
    # what the process compiled besides (the tests run before this one) is checked by its declaration: a work function
    # (by_address=True), an entry point (a parallel kernel, entry=True) or a helper (the rest)
    by_address = {name for name, d in compiled.items() if d.targetoptions.get("no_cpython_wrapper")
                  and not d.targetoptions.get("no_cfunc_wrapper")}
    entries = {name for name, d in compiled.items()
               if not isinstance(d, CompiledCallersDispatcher) and name not in by_address}
    assert render_work <= by_address and render_entries <= entries and "task_counter" not in entries | by_address
    assert all(name in entries for name, d in compiled.items() if d.targetoptions.get("parallel"))  # Python launches
    assert render_work | render_entries | {"task_counter"} <= set(compiled)
    for name, dispatcher in compiled.items():
        for sig in dispatcher.signatures:
            c_wrapper = bool(_entry(dispatcher, "llvm_cfunc_wrapper_name", sig))
            python_entry = bool(_entry(dispatcher, "llvm_cpython_wrapper_name", sig))
            expected = (True, False) if name in by_address else (False, name in entries)
            assert (c_wrapper, python_entry) == expected, name
