"""The ``vlref`` command: one table of sub-commands, each a module of this package.

Every command module holds ``HELP`` (its line in ``vlref --help``; None: not listed there), ``parser()``
(its :class:`argparse.ArgumentParser`, ``prog="vlref <command>"``) and ``run(args) -> int`` (0 success;
``compare``/``golden verify``: 1 failed), which calls library functions that return values and raise
:class:`vlref.errors.InputError` on bad input. :func:`main` parses, runs, and maps the outcome to the
exit code: 2 and ``<prefix>: error: FILE: key: reason`` for bad input (nothing is written), the
cluster's code for failed items (:class:`vlref.work_items.ItemsFailed`), 130 / 143 on SIGINT / SIGTERM.
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import gc
import importlib
import os
import signal
import sys
import threading

from .. import __version__
from ..processes import declare_own_kernels_only, imported_lazily, not_importable
from ..work_items import ItemsFailed
from ..errors import InputError

__all__ = ["COMMANDS", "EXIT_AT_ONCE", "OWN_KERNELS_ONLY", "command", "program_command", "build_parser", "main",
           "exit_at_once", "Interrupted"]

COMMANDS = {
    # name: (module of vlref.cli, prefix of its error messages)
    "render": ("render", "vlref"),
    "scenes": ("scenes", "vlref"),
    "reference": ("reference", "vlref"),
    "bias": ("bias", "vlref"),
    "sweep": ("sweep", "vlref"),
    "compare": ("compare", "vlref compare"),
    "golden": ("golden", "vlref golden"),
    "march": ("march", "vlref march"),
    "march export": ("march_export", "vlref march export"),
    "verdict": ("verdict", "vlref verdict"),
    "bench": ("bench", "vlref bench"),
    "warmup": ("warmup", "vlref"),
}
"""Sub-commands; a two-word name (``march export``) is matched before its first word."""

EXIT_AT_ONCE = frozenset({"render"})
"""Commands whose program process ends through :func:`exit_at_once` once they have returned: they start no
cluster, server or thread that outlives them (a command that may, such as those with ``--scheduler``, ends as
the interpreter ends)."""

OWN_KERNELS_ONLY = frozenset({"render"})
"""Commands whose program process runs vlref's kernels alone (no user code, no plug-in): :func:`program_command`
declares it (:func:`vlref.processes.declare_own_kernels_only`), so Numba initialises there without its cffi support
and without scanning the installed distributions for Numba extensions (:mod:`vlref.jit_init`)."""


def command(name: str):
    """The module of sub-command ``name`` (imported when used)."""
    return importlib.import_module(f"vlref.cli.{COMMANDS[name][0]}")


def program_command(name: str):
    """:func:`command` as the ``vlref`` program imports it: with the garbage collector off while the modules
    (NumPy's, Numba's, vlref's: ~130 000 objects, none of them garbage) are imported, instead of its repeated
    collections walking them (10 % of the import's CPU time on the dev box), and the objects that exist then
    frozen out of its sight (:func:`gc.freeze`, see :func:`main`). For a command of :data:`OWN_KERNELS_ONLY` it
    declares the process one that runs vlref's kernels alone (:func:`vlref.processes.declare_own_kernels_only`)
    and imports Numba without the optional packages it does without there (:func:`_numba_alone`)."""
    own = name in OWN_KERNELS_ONLY
    if own:
        declare_own_kernels_only()
    enabled = gc.isenabled()
    gc.disable()
    try:
        with _numba_alone() if own else contextlib.nullcontext():
            return command(name)
    finally:
        gc.freeze()
        if enabled:
            gc.enable()


NUMBA_CONFIG_FILE = ".numba_config.yaml"
"""The file of settings Numba reads from the current folder at its import, with PyYAML (``numba.core.config``)."""


def _numba_alone() -> contextlib.ExitStack:
    """A block in which Numba, where it is still to be imported, is imported without four optional packages that its
    import brings in only for work the process does not do (:func:`vlref.processes.not_importable`; each is a complete
    import later), and with ``importlib.metadata`` imported lazily (below):

    * PyYAML, where the current folder holds no :data:`NUMBA_CONFIG_FILE`: Numba's configuration imports it only to
      read that file (and warns when the file exists without PyYAML); without the file its settings are the same
      either way (~0.01 s);
    * coverage.py, where it is not imported yet: Numba imports it (``numba.misc.coverage_support``) to report the
      lines it compiles to a coverage measurement running in the process, and a measurement imports coverage.py
      before the code it measures (``coverage run``, its start-up hook): where it is not imported, no measurement
      runs to report to (0.12 s of the import on the device, whose Python has coverage.py installed);
    * colorama, where it is not imported yet: Numba imports it (``numba.core.errors``) to highlight its error
      messages (ANSI bold even in its default ``no_color`` theme); without it they are plain text, as where colorama
      is not installed, and this process shows one only where a compile fails (0.007-0.010 s of the import on the
      device, whose Python has colorama installed);
    * Cython, where it is not imported yet: Numba's import imports SciPy (its version check), whose
      ``scipy._lib._testutils`` imports Cython to check its version for SciPy's own test helper that builds Cython
      extensions (``cython = None`` where it is missing: nothing else reads it); no Cython code is built here (0.022 s
      of the import on the device, whose Python has Cython installed).

    ``importlib.metadata``, where it is not imported yet, is imported lazily (:func:`vlref.processes.imported_lazily`):
    Numba's import imports it (``numba.core.entrypoints``) to scan the installed distributions for Numba extensions,
    a scan this process leaves out (:mod:`vlref.jit_init`); the module (and the ``email``, ``csv`` and ``calendar``
    modules it imports) runs at its first use, which a render does not make (0.016 s of the import on the dev box; on
    the device the import's median of 40 fresh processes 0.292 -> 0.275 s, BENCHMARKS.md "The writing: EXR files at
    deflate level 1").
    """
    fresh = "numba" not in sys.modules
    block = contextlib.ExitStack()
    block.enter_context(not_importable("yaml", fresh and not os.path.isfile(NUMBA_CONFIG_FILE)))
    block.enter_context(not_importable("coverage", fresh))
    block.enter_context(not_importable("colorama", fresh))
    block.enter_context(not_importable("cython", fresh and "scipy" not in sys.modules))
    block.enter_context(imported_lazily("importlib.metadata", fresh))
    return block


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser: ``--version``, and every listed sub-command with its help line."""
    p = argparse.ArgumentParser(prog="vlref", description="vlref: a CPU reference renderer for real-time "
                                "volumetric lighting (god rays). Exit codes: 0 ok, 1 compare/verify failed, 2 bad input, "
                                "130/143 interrupted (Ctrl-C / SIGTERM).")
    p.add_argument("--version", action="version", version=f"vlref {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        text = command(name).HELP
        if text is not None:
            sub.add_parser(name, help=text, add_help=False)  # listed in --help; run by main() with its own parser
    return p


class Interrupted(KeyboardInterrupt):
    """Raised in the main thread by SIGINT (Ctrl-C) or SIGTERM while a ``vlref`` command runs."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _callback_caller(frame):
    """The frame to raise in when a signal arrives in ``frame``: ``frame`` itself, unless ``frame`` or a
    caller runs Python code whose own caller does not pass an exception on; then the frame that called
    that code (the outermost such). Such code: ``numba.core.serialize._numba_unpickle``, which Numba's
    compiled code calls to box every array a kernel returns (it ignores the error and returns a result with
    an exception set: SystemError), imports (a C extension's initialisation turns any exception into
    ``ImportError: initialization failed``), finalizers (``__del__``: the interpreter prints "Exception
    ignored in ..." and goes on, e.g. llvmlite's objects freed while Numba compiles), weakref callbacks (the same:
    Numba's ``_on_type_disposal``, which forgets an interned type that dies, and :class:`weakref.finalize`'s) and
    llvmlite's Python code,
    which LLVM calls back through ctypes while Numba compiles or loads a kernel (``_raw_object_cache_notify``:
    ctypes prints "Exception ignored on calling ctypes callback function" and goes on)."""
    caller, current = frame, frame
    while current is not None:
        name = current.f_globals.get("__name__") or ""
        if (current.f_code.co_name == "_numba_unpickle" and name == "numba.core.serialize") or \
                name in ("importlib._bootstrap", "weakref") or name.startswith("llvmlite.") or \
                current.f_code.co_name == "__del__" or \
                (current.f_code.co_name == "_on_type_disposal" and name == "numba.core.types.abstract"):
            caller = current.f_back
        current = current.f_back
    return caller


def _raise_when_back_in(frame, signum: int) -> None:
    """Raise :class:`Interrupted` at ``frame``'s next bytecode: a trace function on that frame alone (new
    frames are not traced), removed when it fires; the thread's previous trace function is restored."""
    previous = sys.gettrace()

    def fire(f, event, arg):
        f.f_trace = None
        sys.settrace(previous)
        _raise_interrupted(signum, f)

    frame.f_trace_opcodes = True
    frame.f_trace = fire
    sys.settrace(lambda f, event, arg: None)


def _raise_interrupted(signum, frame):
    # A signal that arrives while a kernel runs is handled at the next Python bytecode: inside the kernel's
    # return boxing, whose Python callback (_numba_unpickle) Numba calls without checking for an exception.
    # There, and inside an import, it is raised when the interpreter is back in the frame that made the call.
    caller = _callback_caller(frame)
    if caller is not frame and caller is not None:
        _raise_when_back_in(caller, signum)
        return
    # Further signals are ignored from here on, so the clean-up the exception unwinds through (temporary
    # files and folders of vlref.io) runs to its end.
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    raise Interrupted(signum)


@contextlib.contextmanager
def _interruptible():
    """SIGINT and SIGTERM raise :class:`Interrupted` inside the block (main thread only); handlers restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.signal(sig, _raise_interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def main(argv: list[str] | None = None) -> int:
    """Run a command. Ctrl-C or SIGTERM: one line ``vlref: interrupted``, exit 130 / 143 (128 + signal),
    no partial output (files are written atomically, folders all or nothing: :mod:`vlref.io`).

    ``argv`` None: the program's own command line (the ``vlref`` executable, ``python -m vlref``), whose process
    ends with the command. Its modules are imported with the collector off (:func:`program_command`); the objects
    that exist once they are imported, and again once it has run, are then frozen out of the garbage collector's
    sight (:func:`gc.freeze`): later collections do not walk NumPy's and Numba's modules and the loaded kernels'
    type records (~130 000 objects) again, and neither does the interpreter's exit (a render's exit: 0.5-0.6 s on
    the dev box, 0.1 s frozen). A command of
    :data:`EXIT_AT_ONCE` then ends the process at once (:func:`exit_at_once`), without the tear-down of every
    module and loaded kernel."""
    program = argv is None
    argv = list(sys.argv[1:] if argv is None else argv)
    with _interruptible():
        try:
            code = _run(argv, program)
        except KeyboardInterrupt as exc:
            # on a line of its own: a progress bar cut short may have left the cursor after its text
            print("\r\x1b[K" if sys.stderr.isatty() else "\r", end="vlref: interrupted\n", file=sys.stderr)
            code = 128 + int(getattr(exc, "signum", signal.SIGINT))
        finally:
            if program:
                gc.freeze()
    if program and _command_name(argv) in EXIT_AT_ONCE:
        exit_at_once(code)
    return code


def exit_at_once(code: int) -> None:
    """End this process now with exit status ``code``, doing what the interpreter's exit does that a command's
    outcome depends on: the :mod:`atexit` handlers (temporary folders' finalizers, :mod:`multiprocessing`'s
    clean-up of child processes, :mod:`logging`'s flush, Numba's and llvmlite's shutdown flags), then flushing
    stdout and stderr (a flush that fails: status 120, as the interpreter's exit gives), then :func:`os._exit`.
    What it skips is the tear-down of every module, object and loaded kernel (llvmlite disposing of each
    kernel's machine code, the collector walking the frozen objects): 0.15-0.25 s after a 1080p render on the
    dev box against 0.04-0.07 s (BENCHMARKS.md "Numba's start without scipy.linalg, the exit at once").

    Returns without ending the process, leaving the exit to the interpreter, where another non-daemon thread
    still runs (the interpreter waits for it) or stdout or stderr cannot be flushed before the handlers run.
    For the ``vlref`` program's own process only (:func:`main` with ``argv`` None, :data:`EXIT_AT_ONCE`), and
    the bench's process that measures it (:func:`vlref.bench.renders.bench_whole_render`)."""
    if any(t is not threading.current_thread() and not t.daemon and t.is_alive() for t in threading.enumerate()):
        return
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
    except (OSError, ValueError):
        return
    atexit._run_exitfuncs()
    status = code
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            status = 120
    os._exit(status)


def _command_name(argv: list[str]) -> str | None:
    """The sub-command ``argv`` names (a two-word one first), None when it names none."""
    return " ".join(argv[:2]) if " ".join(argv[:2]) in COMMANDS else argv[0] if argv else None


def _run(argv: list[str], program: bool = False) -> int:
    name = _command_name(argv)
    if name not in COMMANDS:
        try:
            build_parser().parse_args(argv)  # --help, --version, or a usage error
        except SystemExit as exc:  # argparse: 2 on bad usage, 0 on --help/--version
            return int(exc.code or 0)
        return 2  # pragma: no cover - parse_args always exits here
    rest = argv[len(name.split()):]
    cmd, prefix = program_command(name) if program else command(name), COMMANDS[name][1]
    try:
        args = cmd.parser().parse_args(rest)
    except SystemExit as exc:
        return int(exc.code or 0)
    args.argv = rest
    try:
        return int(cmd.run(args))
    except InputError as exc:
        print(f"{prefix}: error: {exc}", file=sys.stderr)
        return 2
    except ItemsFailed as exc:
        print(f"{prefix}: {exc}", file=sys.stderr)
        return 2 if exc.bad_input else 1
