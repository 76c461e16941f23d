"""``njit`` for vlref's compiled functions: Numba's, with only the entry points each caller uses compiled.

Numba compiles two wrappers beside every function it compiles: a CPython wrapper (how Python calls it: each
argument unboxed from its Python object, tuples of arrays element by element) and a C wrapper (the C calling
convention, through which a first-class function value, :class:`vlref.parallel.Work`, calls it). Both are
generated as LLVM IR, optimised and turned into machine code with the function, each time Numba compiles it, and
linked into the LLVM module of every compiled caller. Calls between compiled functions use neither wrapper. vlref
calls a compiled function in one of three ways, and this ``njit`` compiles for each only the wrapper it needs:

* ``njit(...)``, **a function compiled code calls** (the helpers: traversal, lookups, medium, numeric): no
  wrapper at all. Called from Python (tests, notebooks), it goes to its *Python entry*
  (:attr:`CompiledCallersDispatcher.python_entry`): a second dispatcher of the same Python function, made on the
  first such call, compiled with the CPython wrapper under a name of its own (``NAME__from_python``: its own
  cache entries, its own symbols), so the same result as a call from compiled code, through a compile of its own.
* ``njit(..., entry=True)``, **a function Python calls** (the kernels; every ``parallel=True`` function is one: a
  ``prange`` kernel is launched from Python): Numba's ``njit(..., no_cfunc_wrapper=True)``, the CPython wrapper
  only. Called from compiled code as well, it works as any function does.
* ``njit(..., by_address=True)``, **the work of a parallel kernel**: Numba's ``njit(..., no_cpython_wrapper=True,
  no_cfunc_wrapper=False)``, the C wrapper only, callable from compiled code and through
  :func:`vlref.parallel.work`. Called from Python it would crash the process (Numba calls a null entry point):
  only ``vlref.parallel.work`` takes such a function.

The function's own machine code, and so every result, is the one it was with both wrappers (a wrapper only calls it;
tests/test_jit.py compares the compiled function bodies). The C wrappers were about a tenth of a cold render's
compile (BENCHMARKS.md "A cold render compiles fewer wrappers and parfors"), the helpers' CPython wrappers another
tenth (BENCHMARKS.md "The cold first render: no Python entry for the helpers"). The Python entry of a helper is
kept apart from the helper's own compile because Numba's cache keys an entry by signature and code, not by the
wrappers compiled: one cache entry without the CPython wrapper, found by a Python call, would be called through
address 0.
"""

from __future__ import annotations

import types

import numba
from numba.core.caching import FunctionCache, NullCache
from numba.core.registry import CPUDispatcher

__all__ = ["njit", "CompiledCallersDispatcher", "PYTHON_ENTRY_SUFFIX", "WithoutWrappersCache"]

PYTHON_ENTRY_SUFFIX = "__from_python"
"""What the name of a helper's Python entry adds to the function's name (its cache files and symbols)."""


class WithoutWrappersCache(FunctionCache):
    """Numba's cache of a function compiled without wrappers: its index keys marked as such. Numba keys an entry by
    signature, target and the function's bytecode, not by the wrappers compiled, and a module whose source did not
    change keeps its cache files across versions of vlref: without the mark, a version that compiles the function
    with its CPython wrapper would load this one's entry and call it from Python through address 0 (a crash), and
    this version would load that one's entries, wrappers and all."""

    def _index_key(self, sig, codegen):
        sig, target, code = super()._index_key(sig, codegen)
        return sig, target, code + ("without wrappers",)


class CompiledCallersDispatcher(CPUDispatcher):
    """Numba's dispatcher of a function that compiled code calls, compiled without wrappers (module docstring); a
    call from Python goes to :attr:`python_entry`."""

    def __init__(self, py_func, locals=None, targetoptions=None, **kwargs):
        super().__init__(py_func, locals, targetoptions, **kwargs)
        self._python_entry = None

    def __call__(self, *args, **kwargs):
        return self.python_entry(*args, **kwargs)

    def enable_caching(self):
        self._cache = WithoutWrappersCache(self.py_func)

    @property
    def python_entry(self) -> CPUDispatcher:
        """The dispatcher Python calls this function through: the same Python function, renamed with
        :data:`PYTHON_ENTRY_SUFFIX`, with the CPython wrapper and this dispatcher's options and caching."""
        if self._python_entry is None:
            f = self.py_func
            renamed = types.FunctionType(f.__code__, f.__globals__, f.__name__, f.__defaults__, f.__closure__)
            renamed.__kwdefaults__, renamed.__doc__ = f.__kwdefaults__, f.__doc__
            renamed.__qualname__ = f.__qualname__ + PYTHON_ENTRY_SUFFIX
            entry = CPUDispatcher(renamed, self.locals, dict(self.targetoptions, no_cpython_wrapper=False))
            if not isinstance(self._cache, NullCache):
                entry.enable_caching()
            self._python_entry = entry
        return self._python_entry


def _compiled_callers(function, options: dict) -> CompiledCallersDispatcher:
    """``function`` compiled without wrappers: what ``numba.njit(function, cache=..., **options)`` makes (Numba's
    ``jit``: ``nopython`` and ``boundscheck`` among the target options, the cache enabled on request; the function
    itself under ``NUMBA_DISABLE_JIT``), as a :class:`CompiledCallersDispatcher`."""
    if numba.config.DISABLE_JIT:
        return function
    cache = options.pop("cache", False)
    dispatcher = CompiledCallersDispatcher(function, {}, dict(options, nopython=True, boundscheck=None,
                                                             no_cpython_wrapper=True, no_cfunc_wrapper=True))
    if cache:
        dispatcher.enable_caching()
    return dispatcher


def njit(function=None, *, entry: bool = False, by_address: bool = False, **options):
    """``numba.njit(function, **options)`` with the wrappers of how the function is called (module docstring): none
    (default: compiled code calls it), the CPython wrapper (``entry=True``, implied by ``parallel=True``: Python calls
    it), the C wrapper (``by_address=True``: a parallel kernel's work). Used as ``@njit(cache=True, fastmath=False,
    ...)`` or ``@njit``."""
    def made(f):
        if by_address:
            return numba.njit(f, **options, no_cpython_wrapper=True, no_cfunc_wrapper=False)
        if entry or options.get("parallel"):
            return numba.njit(f, **options, no_cfunc_wrapper=True)
        return _compiled_callers(f, dict(options))

    return made if function is None else made(function)
