"""``njit`` for vlref's compiled functions: Numba's, with only the entry points vlref calls compiled.

Numba compiles two wrappers beside every function it compiles: a CPython wrapper (how Python calls it: each
argument unboxed from its Python object, tuples of arrays element by element) and a C wrapper (the C calling
convention, through which a first-class function value, :class:`vlref.parallel.Work`, calls it). Both are
generated as LLVM IR, optimised and turned into machine code with the function, each time Numba compiles it. vlref
calls its compiled functions in two ways only: from Python (kernels, and helpers the tests call) and, for the work of a
parallel kernel, through the address of its C wrapper (:func:`vlref.parallel.work`). No vlref function is called both
ways, and calls between compiled functions use neither wrapper. So this ``njit`` leaves out the C wrapper, and
``by_address=True`` (the work functions) leaves out the CPython wrapper instead:

* ``njit(...)``: Numba's ``njit(..., no_cfunc_wrapper=True)``: callable from Python and from compiled code;
* ``njit(..., by_address=True)``: Numba's ``njit(..., no_cpython_wrapper=True, no_cfunc_wrapper=False)``: callable
  from compiled code and through :func:`vlref.parallel.work` only. Called from Python it would crash the process
  (Numba calls a null entry point): only ``vlref.parallel.work`` takes such a function.

The function's own machine code, and so every result, is the one it was with both wrappers (a wrapper only calls it;
tests/test_jit.py compares the compiled function bodies). The wrappers were about a tenth of a cold render's
compile (BENCHMARKS.md "A cold render compiles fewer wrappers and parfors").
"""

from __future__ import annotations

import numba

__all__ = ["njit"]


def njit(function=None, *, by_address: bool = False, **options):
    """``numba.njit(function, **options)`` without the C wrapper, or with ``by_address`` without the CPython wrapper
    (module docstring). Used as ``@njit(cache=True, fastmath=False, ...)`` or ``@njit``."""
    options.setdefault("no_cfunc_wrapper", not by_address)
    if by_address:
        options["no_cpython_wrapper"] = True
    return numba.njit(**options) if function is None else numba.njit(function, **options)
