"""Numba's one-time initialisation of its CPU target, without importing ``scipy.linalg``.

The first compiled call of a process (a kernel compiled, or loaded from Numba's cache) initialises Numba's CPU
target: ``BaseContext.refresh`` imports ``numba.np.*``, ``numba.typed`` and the other implementation modules,
installs ~2 300 typing and lowering registrations and compiles the NRT functions. Part of it, the body of
``numba.np.arraymath``, asks whether a BLAS is there for ``np.dot`` (``_HAVE_BLAS = _check_blas()``, which runs
``numba.np.linalg.ensure_blas``: ``import scipy.linalg.cython_blas``). That import first executes the package
``scipy.linalg``'s ``__init__`` (all of SciPy's dense linear algebra: 0.17-0.2 s on the 2-core dev box, 0.27 s on
the 16-core device, BENCHMARKS.md "Numba's start without scipy.linalg") before the extension module itself
(0.01 s), and vlref's kernels use no BLAS.

:func:`initialise_numba` runs that initialisation with ``scipy.linalg.cython_blas`` loaded on its own, from its
file, through the import system's own loader (``importlib.machinery.PathFinder`` on ``scipy/linalg``): the module
is entered in ``sys.modules`` under its name for the duration of ``refresh()`` only, Numba's unchanged check
(``ensure_blas``, with its integer-width test where the Numba has one) imports it from there and answers as it
would have, and the entry is removed again, so the import system's state afterwards is the one before, less
``scipy.linalg``. Nothing of Numba is patched: a later ``import scipy.linalg.cython_blas`` (Numba's own, at a
user's first ``np.dot`` or ``np.linalg`` call in compiled code) imports the package and finds the extension
already initialised (the same module object; tests/test_jit_init.py). Where any precondition fails (Numba's
target already initialised, ``scipy.linalg`` or the module already imported, SciPy or the file not found, the
load raising, a Numba without ``numba.core.registry.cpu_target``), Numba initialises as it always does.

``render`` and ``render_reference`` call it before their first kernel; it costs nothing once Numba is initialised.

**A process that runs vlref's kernels alone** (the ``vlref render`` program's own process: no user code runs
in it; :func:`vlref.processes.declare_own_kernels_only`, called by :func:`vlref.cli.commands.program_command`)
initialises Numba without two parts that serve only other code: its cffi support
(``numba.core.typing.cffi_utils`` imports ``cffi`` and builds a ``cffi.FFI()``, whose C parser imports
``pycparser``, where cffi is installed: it is wherever wgpu is) and the ``numba_extensions`` entry points of every
installed distribution (``numba.core.entrypoints.init_all``: ``importlib.metadata`` reads the metadata of each
one). With ``cffi`` absent from ``sys.modules`` for the duration of ``refresh()`` only, Numba's module finds no
cffi and registers no cffi types, exactly as where cffi is not installed; the entry points are marked loaded
(Numba's own flag) before they are scanned. vlref's kernels call no cffi function and no Numba extension; a later
``import cffi`` in the process is a complete import (only Numba's cffi support stays off in it). Dev box: the
initialisation 0.19-0.22 → 0.16-0.18 s; device 0.139 → 0.112 s (BENCHMARKS.md
"The program's own process: Numba without cffi and extensions, files synced beside the writing").

**Loading only, until a compile** (that process, for the render's first kernels: ``initialise_numba()`` without
``compiling``): a kernel loaded from Numba's cache needs little of the initialisation: the NRT (its C functions'
symbols and the atomic functions it compiles), ``typeof`` of every argument (the first-class function values of
:func:`vlref.parallel.work` are typed by ``numba.experimental.function_type``), and the Numba modules that the
kernels' cached environments name, which their load imports (``numba.np.arrayobj``, which imports
``numba.np.arraymath``: its BLAS check then runs here, with the module alone as above). The ~2 300 typing and
lowering registrations and the other implementation modules serve only the compiler. So there the target's
``refresh`` is made a no-op for the loads (``Cache.load_overload`` calls it before every load) and a listener of
Numba's ``numba:compile`` event (its public event API: the dispatcher triggers it after a cache miss, before it
compiles) puts the target's own ``refresh`` back and runs it, without cffi and the extension scan as above, before
the first kernel that the process compiles: a cold cache compiles as it always does. Dev box: the initialisation
0.11-0.15 s -> 0.05-0.06 s; device, the whole render's geometry stage (the initialisation and the BVH build) 0.20 ->
0.07 s, its ray cast 0.07 -> 0.12 s (explained since: SciPy's BLAS threads, below; BENCHMARKS.md "Numba's
initialisation deferred to the first compile").

**Loaded libraries linked on demand** (that process, from the same initialisation on): Numba's cache keeps a compiled
function as its machine code (an object file) and the LLVM bitcode of its library, for linking into a later compile;
a load parses that bitcode and scans it for the names the library defines (Numba's
``CPUCodeLibrary._unserialize``), which tell Numba's JIT engine the symbols it may look up
(``JitEngine.is_symbol_defined``: an entry point's address, a C wrapper's). A render compiles nothing that links a
loaded library, and on the dev box the parse and the scan were 73 % of the 10 loads of a warm render of bench (b)
(0.24 of 0.33 s). There a library loaded from the cache (:class:`_LinkedOnDemand`) takes the defined names from its
object file's own symbol table (:func:`object_symbols`: for the libraries of a render the same names as the scan,
tests/test_jit_init.py) and keeps the bitcode as bytes, parsed on the first compile that links the library; an object
file that is not ELF (another platform) loads as Numba loads it. Device, one host, 20 fresh processes each
alternated: the 10 loads 0.189 -> 0.076 s, the shadow-map stage (which the loads ran beside) 0.094 -> 0.036 s, the
render from its start to its files in place 1.407 -> 1.283 s (medians; BENCHMARKS.md "The whole render part by part
on one clock").

**The NRT's library kept** (that process, for the loads): Numba's runtime compiles a small library of its own (its
atomic reference counts and memory-info functions) when it initialises, on every process's first compiled call: 19-28
ms on the device, 38-64 ms on the dev box (LLVM's optimisation and code generation), at the head of the chain of
loads the render waits on. There :func:`_initialise_for_loading` keeps that library's object code and linking bitcode
in a file (:func:`runtime_file`, named by a digest of the Numba, LLVM, llvmlite and Python versions and the CPU as
Numba's cache index names it) and loads it from there as Numba loads a cached kernel (``unserialize_library``);
the file carries the SHA-256 of its contents, and where that does not check (or the file is missing) the library is
compiled as Numba compiles it and the file written. Numba's own ``rtsys.initialize`` runs unchanged around it (its
C helpers' symbols are registered first, as always). Dev box: the initialisation 0.105 -> 0.073 s (medians of 8,
beside another job); device, one host, fresh processes alternated: 0.0545 -> 0.0412 s (medians of 24), the render's
geometry stage, which waits on it, 0.091 -> 0.067 s (medians of 10; BENCHMARKS.md "The writing: EXR files at deflate
level 1", its last part).

**SciPy's BLAS on one thread** (in a process that runs vlref's kernels alone): loading
``scipy.linalg.cython_blas`` loads SciPy's OpenBLAS, which starts a thread per core beyond the first, and each new
thread spins (``sched_yield``) for about 2^28 cycles (~0.1 s) before it sleeps. Right after the initialisation
the render computes the camera's rays (NumPy on a thread per core), which then shared the cores with 15 spinning
threads: on the 16-core device 0.072 s against 0.036 s with the initialisation in full, which ends ~0.1 s later
(BENCHMARKS.md "SciPy's BLAS threads, kernels loaded ahead"). No vlref kernel calls a BLAS, so there the library
is loaded with ``OPENBLAS_NUM_THREADS=1`` (unless the user set it): it starts no thread; a BLAS call in compiled
code runs on the calling thread.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import importlib.machinery
import importlib.util
import os
import pickle
import struct
import sys
from typing import Iterator

import llvmlite
import llvmlite.binding as llvm
import numba
from numba.core import compiler_lock, entrypoints, event, registry
from numba.core.codegen import JITCodeLibrary
from numba.core.runtime import nrtdynmod, rtsys

from .io.files import write_bytes
from .processes import not_importable, own_kernels_only

__all__ = ["initialise_numba", "object_symbols", "runtime_file", "BLAS_MODULE"]

BLAS_MODULE = "scipy.linalg.cython_blas"
"""The module Numba's BLAS check imports (``numba.np.linalg.ensure_blas``)."""

_done = [False]


def _without_foreign_support():
    """A block for Numba's ``refresh()``: in a process that runs vlref's kernels alone
    (:func:`vlref.processes.own_kernels_only`), Numba's extension entry points marked loaded where they are not yet,
    and ``cffi`` not importable (:func:`vlref.processes.not_importable`) where Numba's cffi module is not imported
    yet."""
    own = own_kernels_only()
    if own and not getattr(entrypoints, "_already_initialized", True):
        entrypoints._already_initialized = True
    return not_importable("cffi", own and "numba.core.typing.cffi_utils" not in sys.modules)


BLAS_THREADS_VARIABLE = "OPENBLAS_NUM_THREADS"
"""The variable OpenBLAS reads its thread count from when its library is loaded."""


@contextlib.contextmanager
def _blas_on_one_thread(when: bool) -> Iterator[None]:
    """A block in which a BLAS library loaded (SciPy's OpenBLAS, by ``scipy.linalg.cython_blas``) starts no threads
    of its own: :data:`BLAS_THREADS_VARIABLE` set to 1 for the block's duration where ``when`` and the user has not
    set it (module docstring, "SciPy's BLAS on one thread")."""
    if not when or BLAS_THREADS_VARIABLE in os.environ:
        yield
        return
    os.environ[BLAS_THREADS_VARIABLE] = "1"
    try:
        yield
    finally:
        os.environ.pop(BLAS_THREADS_VARIABLE, None)


def _cython_blas_alone():
    """``scipy.linalg.cython_blas`` executed from its file without its package (None: not found or not loadable)."""
    scipy = sys.modules.get("scipy")  # imported by Numba's own import (its version check)
    if scipy is None or getattr(scipy, "__path__", None) is None:
        return None
    spec = importlib.machinery.PathFinder.find_spec(BLAS_MODULE, [os.path.join(p, "linalg") for p in scipy.__path__])
    if spec is None or spec.loader is None:
        return None
    try:
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    except Exception:  # any failure: Numba's own import path decides, as without this module
        return None
    return module


@contextlib.contextmanager
def _blas_alone() -> Iterator[None]:
    """A block in which Numba's BLAS check finds ``scipy.linalg.cython_blas`` loaded on its own (module docstring),
    where no precondition fails; the import system's entry is removed again after it."""
    module = None
    if "numba.np.arraymath" not in sys.modules and "scipy.linalg" not in sys.modules \
            and BLAS_MODULE not in sys.modules:
        module = _cython_blas_alone()
    if module is not None:
        sys.modules[BLAS_MODULE] = module
    try:
        yield
    finally:
        if module is not None and sys.modules.get(BLAS_MODULE) is module:
            del sys.modules[BLAS_MODULE]


def _no_registrations_to_install() -> None:
    """The target's ``refresh`` while this process loads kernels only (module docstring)."""


class _RefreshAtFirstCompile(event.Listener):
    """Numba's ``numba:compile`` listener of :func:`_initialise_for_loading`: at the first compile of the process,
    the target's own ``refresh`` put back and run (without cffi and the extension scan), as the initialisation
    would have run it; later compiles find it in place."""

    def __init__(self, context):
        self.context = context

    def on_start(self, ev) -> None:
        if vars(self.context).get("refresh") is _no_registrations_to_install:
            del self.context.refresh
            with _without_foreign_support():
                self.context.refresh()

    def on_end(self, ev) -> None:
        pass


_SHT_SYMTAB, _SHN_UNDEF, _STT_SECTION, _STT_FILE = 2, 0, 3, 4
"""ELF's section type of a symbol table, section index of an undefined symbol, symbol types of a section and a file."""


def object_symbols(obj: bytes) -> set[str] | None:
    """The names an ELF64 little-endian object file defines: the entries of its symbol table (``SHT_SYMTAB``) whose
    section is not ``SHN_UNDEF``, less the section and file entries (ELF's ``Elf64_Shdr`` and ``Elf64_Sym`` layouts);
    None for any other file (another format, no symbol table, a malformed one)."""
    if len(obj) < 64 or obj[:4] != b"\x7fELF" or obj[4] != 2 or obj[5] != 1:  # ELFCLASS64, ELFDATA2LSB
        return None
    table_at, = struct.unpack_from("<Q", obj, 0x28)
    entry_size, count = struct.unpack_from("<HH", obj, 0x3A)
    if entry_size != 64 or table_at + 64 * count > len(obj):
        return None
    sections = [struct.unpack_from("<IIQQQQIIQQ", obj, table_at + 64 * i) for i in range(count)]
    names, tables = set(), 0
    for _, section_type, _, _, offset, size, link, _, _, symbol_size in sections:
        if section_type != _SHT_SYMTAB:
            continue
        tables += 1
        if symbol_size != 24 or size % 24 or link >= count or offset + size > len(obj):
            return None
        strings = sections[link][4]
        for name, info, _, section, _, _ in struct.iter_unpack("<IBBHQQ", obj[offset:offset + size]):
            if section != _SHN_UNDEF and name != 0 and info & 0xF not in (_STT_SECTION, _STT_FILE):
                end = obj.find(b"\0", strings + name)
                if end < 0:
                    return None
                try:
                    names.add(obj[strings + name:end].decode())
                except UnicodeDecodeError:  # llvmlite reads LLVM's names as UTF-8: not a name Numba made
                    return None
    return names if tables else None


class _LinkedOnDemand(JITCodeLibrary):
    """Numba's JIT code library, whose load from the cache defines its names from its object file and leaves its
    linking bitcode unparsed until a compile links it (module docstring, "Loaded libraries linked on demand")."""

    _linking_bitcode = None  # bytes while unparsed
    _linking_module = None

    @property
    def _shared_module(self):
        """The library's module for linking into another (Numba's attribute), parsed here on first use."""
        if self._linking_bitcode is not None:
            self._linking_module, self._linking_bitcode = llvm.parse_bitcode(self._linking_bitcode), None
        return self._linking_module

    @_shared_module.setter
    def _shared_module(self, module) -> None:
        self._linking_module, self._linking_bitcode = module, None

    @classmethod
    def _unserialize(cls, codegen, state):
        """Numba's load of a cached library (``CPUCodeLibrary._unserialize``, its object-code branch) with the names
        read from the object file instead of the parsed bitcode, which waits for :attr:`_shared_module`."""
        name, kind, data = state
        names = object_symbols(data[0]) if kind == "object" else None
        if names is None:
            return super()._unserialize(codegen, state)
        self = codegen.create_library(name)
        self.enable_object_caching()
        self._set_compiled_object(data[0])
        self._linking_bitcode = data[1]
        self._finalize_final_module()
        codegen._engine._defined_symbols |= names
        return self


def runtime_file(codegen) -> str:
    """The file that keeps the NRT's compiled library for this Numba, LLVM, llvmlite, Python and CPU (module
    docstring, "The NRT's library kept"): in ``$NUMBA_CACHE_DIR`` or the ``__pycache__`` folder beside this module,
    named by a digest of the five (the CPU as Numba's cache index names it: ``codegen.magic_tuple()``)."""
    key = repr((numba.__version__, llvm.llvm_version_info, llvmlite.__version__, sys.version_info[:2],
                codegen.magic_tuple()))
    folder = numba.config.CACHE_DIR or os.path.join(os.path.dirname(os.path.abspath(__file__)), "__pycache__")
    return os.path.join(folder, f"numba-runtime-{hashlib.sha256(key.encode()).hexdigest()[:20]}.nrt")


def _runtime_library(path: str):
    """A function in the place of Numba's ``nrtdynmod.compile_nrt_functions(ctx)`` while the NRT initialises: the
    library from ``path`` where the file holds one whose digest checks (:func:`_read_runtime`), else Numba's compile
    of it (the same steps, with its object code kept) and the file written (:func:`_write_runtime`)."""
    def compile_or_load(ctx):
        state = _read_runtime(path)
        if state is not None:
            return ctx.codegen().unserialize_library(state)
        module, library = nrtdynmod.create_nrt_module(ctx)
        library.enable_object_caching()
        library.add_ir_module(module)
        library.finalize()
        _write_runtime(path, library.serialize_using_object_code())
        return library
    return compile_or_load


def _read_runtime(path: str):
    """The serialised library in ``path`` (its SHA-256, then the pickled state), or None where the file is missing,
    unreadable or its digest does not check."""
    try:
        with open(path, "rb") as fh:
            digest, payload = fh.read(32), fh.read()
    except OSError:
        return None
    return pickle.loads(payload) if hashlib.sha256(payload).digest() == digest else None


def _write_runtime(path: str, state) -> None:
    """Write ``state`` to ``path`` as :func:`_read_runtime` reads it, atomically (:func:`vlref.io.files.write_bytes`:
    a reader sees the whole file or none); a folder that cannot take it is left as it was."""
    payload = pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)
    with contextlib.suppress(OSError):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        write_bytes(path, hashlib.sha256(payload).digest() + payload)


@contextlib.contextmanager
def _runtime_kept(context) -> Iterator[None]:
    """Numba's NRT initialised inside the block with its compiled library kept in :func:`runtime_file`
    (:func:`_runtime_library` in the place of ``nrtdynmod.compile_nrt_functions`` for the block)."""
    compile_nrt_functions = nrtdynmod.compile_nrt_functions
    nrtdynmod.compile_nrt_functions = _runtime_library(runtime_file(context.codegen()))
    try:
        yield
    finally:
        nrtdynmod.compile_nrt_functions = compile_nrt_functions


def _initialise_for_loading(context) -> None:
    """What loading vlref's kernels from the cache needs of Numba's initialisation, the rest deferred to the
    process's first compile (module docstring)."""
    with _blas_alone():
        importlib.import_module("numba.np.arraymath")
    codegen = context.codegen()
    if codegen._library_class is JITCodeLibrary:
        codegen._library_class = _LinkedOnDemand
    with _runtime_kept(context):
        rtsys.initialize(context)
    importlib.import_module("numba.experimental.function_type")
    context.refresh = _no_registrations_to_install
    event.register("numba:compile", _RefreshAtFirstCompile(context))


def initialise_numba(compiling: bool = False) -> None:
    """Initialise Numba's CPU target now (what the first compiled call would do), with its BLAS check served by
    ``scipy.linalg.cython_blas`` alone (module docstring). Idempotent. It holds Numba's compiler lock while it
    runs, as Numba's own loading of a cached kernel does, so a kernel loaded or compiled meanwhile on another
    thread waits for it. In a process that runs vlref's kernels alone, unless the caller is about to compile
    (``compiling``: :mod:`vlref.ahead`'s processes), the part that serves only the compiler waits for the first
    compile (module docstring, "Loading only"). A second thread that calls it meanwhile waits for it to finish."""
    if _done[0]:
        return
    cpu_target = getattr(registry, "cpu_target", None)
    if cpu_target is None:  # a Numba without it: its first kernel initialises it
        return
    with getattr(compiler_lock, "global_compiler_lock", None) or contextlib.nullcontext(), \
            _without_foreign_support(), _blas_on_one_thread(own_kernels_only()):
        if _done[0]:  # another thread initialised it while this one waited for the lock
            return
        _done[0] = True
        if own_kernels_only() and not compiling:
            _initialise_for_loading(cpu_target.target_context)
            return
        with _blas_alone():
            cpu_target.target_context.refresh()
