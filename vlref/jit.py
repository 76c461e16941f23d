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

The function's own optimised code, and so every result, is the one it was with both wrappers (a wrapper only calls
it; tests/test_jit.py compares the compiled bodies of an entry point and of a work function with Numba's). The C
wrappers were about a tenth of a cold render's compile (BENCHMARKS.md "A cold render compiles fewer wrappers and
parfors"), the helpers' CPython wrappers another tenth (BENCHMARKS.md "The cold first render: no Python entry for
the helpers").

**A helper has no machine code of its own.** Code that calls a helper never calls the helper's machine code: Numba
links the helper's optimised LLVM module into the caller's module, where it is inlined or compiled anew with the
caller. Numba still turns every function it compiles into machine code (its JIT engine's ``finalize_object``) and
caches that object code; for a helper both are work nobody uses (about a tenth of a cold render's compile,
BENCHMARKS.md "A helper without machine code"). A helper is therefore compiled into a :class:`LinkOnlyLibrary`:
Numba's code library, linked and optimised as Numba does, whose finalisation stops before the JIT engine. A caller
links the helper's module as Numba's module passes left it (before, as the engine's code generation had rewritten
it in place: loop strength reduction and the like), so the callers' code differs in places and their results' bits
do not (the kernels' buffers compared bit for bit, same section). With ``cache=True`` Numba's cache keeps the
helper's module as bitcode instead of object code (:class:`LinkOnlyCache`, its own kind of entry), so that another
process compiling a caller links it without compiling it again.
"""

from __future__ import annotations

import types

import numba
from llvmlite import binding as llvm
from numba.core.caching import CompileResultCacheImpl, FunctionCache
from numba.core.codegen import JITCodeLibrary
from numba.core.compiler import Compiler, CompileResult
from numba.core.registry import CPUDispatcher

__all__ = ["njit", "CompiledCallersDispatcher", "LinkOnlyCache", "LinkOnlyLibrary", "PYTHON_ENTRY_SUFFIX"]

LINK_ONLY = "link-only bitcode"
"""The kind of a helper's cache entry: its module for linking, as bitcode (Numba's own kinds: object code and the
bitcode of a module to finalise)."""

PYTHON_ENTRY_SUFFIX = "__from_python"
"""What the name of a helper's Python entry adds to the function's name (its cache files and symbols)."""


class LinkOnlyLibrary(JITCodeLibrary):
    """Numba's JIT code library of a helper (module docstring, "A helper has no machine code of its own"): its
    module linked with its callees' and optimised as Numba does, for the callers that link it, and never handed to
    the JIT engine. Numba's finalisation (``CPUCodeLibrary._finalize_final_module``) less the engine's part: the
    same checks of the module, no machine code, so no address (:meth:`get_pointer_to_function` answers 0, as
    Numba's does for a name the library does not define) and no object code to cache."""

    def _finalize_final_module(self) -> None:
        self._finalize_dynamic_globals()
        self._verify_declare_only_symbols()
        self._finalized = True

    def get_pointer_to_function(self, name) -> int:
        self._ensure_finalized()
        return 0

    @property
    def codegen(self):
        """Numba's code generator, as the helper's compile sees it: it does not store the address of the helper's
        environment in the engine's copy of the module (:class:`_WithoutEngineModule`)."""
        return _WithoutEngineModule(self._codegen)

    def serialize_using_object_code(self):
        """What Numba's cache saves of the library: the module callers link, as bitcode (kind :data:`LINK_ONLY`)."""
        self._ensure_finalized()
        return self.name, LINK_ONLY, self._get_module_for_linking().as_bitcode()

    @classmethod
    def from_cache(cls, codegen, state) -> "LinkOnlyLibrary":
        """The library :meth:`serialize_using_object_code` saved, finalised, ready for callers to link."""
        name, kind, bitcode = state
        if kind != LINK_ONLY:
            raise ValueError(f"a helper's cache entry of kind {kind!r}, not {LINK_ONLY!r}")
        self = cls(codegen, name)
        self._final_module = self._shared_module = llvm.parse_bitcode(bitcode)
        self._finalized = True
        return self


class _WithoutEngineModule:
    """Numba's code generator, for a library the JIT engine does not hold: ``set_env`` (Numba's store of the
    environment's address into the library's global in the engine) has no global to store into and does nothing;
    every other attribute is the code generator's."""

    def __init__(self, codegen):
        self._codegen = codegen

    def __getattr__(self, name):
        return getattr(self._codegen, name)

    def set_env(self, env_name, env) -> None:
        pass


class _LinkOnlyResults(CompileResultCacheImpl):
    """Numba's caching of compile results (``CompileResultCacheImpl``), for a helper's: its library saved as
    :class:`LinkOnlyLibrary` saves itself, and rebuilt as Numba's ``CompileResult._rebuild`` rebuilds a result, with
    :meth:`LinkOnlyLibrary.from_cache` in the place of the code generator's ``unserialize_library`` (which knows
    only Numba's kinds) and no environment stored in the engine (:class:`_WithoutEngineModule`)."""

    def rebuild(self, target_context, payload):
        libdata, fndesc, env, signature, objectmode, lifted, typeann, reload_init, referenced_envs = payload
        for reload in reload_init:
            reload()
        library = LinkOnlyLibrary.from_cache(target_context.codegen(), libdata)
        return CompileResult(target_context=target_context, typing_context=target_context.typing_context,
                             library=library, environment=env,
                             entry_point=target_context.get_executable(library, fndesc, env), fndesc=fndesc,
                             type_annotation=typeann, signature=signature, objectmode=objectmode, lifted=lifted,
                             typing_error=None, call_helper=None, metadata=None, reload_init=reload_init,
                             referenced_envs=referenced_envs)


class LinkOnlyCache(FunctionCache):
    """Numba's cache of a helper's compile results (:class:`_LinkOnlyResults`), its index keys marked as such.
    Numba keys an entry by signature, target and the function's bytecode, not by the kind of library saved, and a
    module whose source did not change keeps its cache files across versions of vlref: without the mark, a version
    that compiles the function with its wrappers (or plain Numba) would load this one's bitcode as object code, and
    this version would load that one's object code as bitcode."""

    _impl_class = _LinkOnlyResults

    def _index_key(self, sig, codegen):
        sig, target, code = super()._index_key(sig, codegen)
        return sig, target, code + (LINK_ONLY,)


class _HelperCompiler(Compiler):
    """Numba's compiler, compiling into a :class:`LinkOnlyLibrary` (Numba's native lowering creates a library only
    where the compile has none)."""

    def compile_extra(self, func):
        self.state.library = LinkOnlyLibrary(self.state.targetctx.codegen(), func.__qualname__)
        return super().compile_extra(func)


class CompiledCallersDispatcher(CPUDispatcher):
    """Numba's dispatcher of a function that compiled code calls, compiled without wrappers and machine code
    (module docstring); a call from Python goes to :attr:`python_entry`."""

    def __init__(self, py_func, locals=None, targetoptions=None):
        super().__init__(py_func, locals, targetoptions, pipeline_class=_HelperCompiler)
        self._python_entry = None

    def __call__(self, *args, **kwargs):
        return self.python_entry(*args, **kwargs)

    def enable_caching(self):
        self._cache = LinkOnlyCache(self.py_func)

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
            if isinstance(self._cache, LinkOnlyCache):
                entry.enable_caching()
            self._python_entry = entry
        return self._python_entry


def _compiled_callers(function, options: dict) -> CompiledCallersDispatcher:
    """``function`` compiled without wrappers and machine code: what ``numba.njit(function, cache=..., **options)``
    makes (Numba's ``jit``: ``nopython`` and ``boundscheck`` among the target options, the cache enabled on request;
    the function itself under ``NUMBA_DISABLE_JIT``), as a :class:`CompiledCallersDispatcher`."""
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
