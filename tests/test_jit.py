"""vlref.jit.njit: Numba's njit with only the wrappers vlref calls. A function keeps its CPython wrapper (Python calls
it) and has no C wrapper; a work function (``by_address=True``) has its C wrapper (vlref.parallel.work calls it
through its address) and no CPython wrapper; the function's own optimised code is Numba's; every compiled function
of vlref is made by it."""

import ast
import math
import sys
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
from vlref.jit import njit
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


def test_a_function_has_its_python_entry_and_no_c_wrapper():
    cos_theta = np.linspace(-1.0, 1.0, 2001)
    ours, numbas = njit(_phase_sum), numba.njit(_phase_sum)
    assert ours(cos_theta, 0.5) == numbas(cos_theta, 0.5)  # called from Python
    assert ours(cos_theta, 0.0) == pytest.approx(2001 / (4 * math.pi), rel=1e-12)  # isotropic: 1 / 4π each
    assert _entry(ours, "llvm_cpython_wrapper_name") and _entry(numbas, "llvm_cpython_wrapper_name")
    assert _entry(ours, "llvm_cfunc_wrapper_name") == 0 and _entry(numbas, "llvm_cfunc_wrapper_name") != 0
    assert _body(ours) == _body(numbas)  # the same code, only the wrapper left out


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


def test_a_render_compiles_a_c_wrapper_for_the_work_functions_only():
    """After a render of the default scene, every compiled function of vlref has its CPython entry point and no C
    wrapper, but the work functions of the parallel kernels, which have their C wrapper and no CPython entry."""
    render(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]))
    compiled = {value.py_func.__qualname__: value for name, module in list(sys.modules.items())
                if name.startswith("vlref.") for value in vars(module).values()
                if isinstance(value, CPUDispatcher) and value.signatures}
    by_address = {"_cast_rows", "_shade_rows", "_cast_chunks", "_march_tasks"}
    assert by_address | {"_raycast_kernel", "_shade", "_cast_face", "_march_kernel", "_sum_composite",
                         "task_counter"} <= set(compiled)
    for name, dispatcher in compiled.items():
        for sig in dispatcher.signatures:
            c_wrapper = bool(_entry(dispatcher, "llvm_cfunc_wrapper_name", sig))
            python_entry = bool(_entry(dispatcher, "llvm_cpython_wrapper_name", sig))
            assert (c_wrapper, python_entry) == ((True, False) if name in by_address else (False, True)), name
