"""Numba's one-time initialisation without ``scipy.linalg`` (vlref.jit_init): a render leaves ``scipy.linalg``
unimported, Numba's BLAS check answers as it would have, and linear algebra in a user's own compiled code still
works in the same process afterwards. The ``vlref render`` program's own process (it runs vlref's kernels alone)
initialises Numba without cffi support and extension entry points, and imports it without PyYAML unless Numba has a
``.numba_config.yaml`` to read, without coverage.py unless a measurement runs, without colorama or Cython, and with
``importlib.metadata`` imported lazily, and keeps the NRT's compiled library in a file; other processes as always.
Each case runs in a fresh interpreter (the initialisation happens once a process)."""

import hashlib
import json
import os
import subprocess
import sys

import numpy as np

from vlref.jit_init import object_symbols
from vlref.render import render
from vlref.scene import load_scene

AFTER_RENDER = r"""
import json, sys
import numpy as np
from numba import njit
from vlref.render import prepare_frame
from vlref.scene import load_scene

prepare_frame(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]))
state = {"scipy.linalg": "scipy.linalg" in sys.modules, "cython_blas": "scipy.linalg.cython_blas" in sys.modules}
import numba.np.arraymath
state["have_blas"] = numba.np.arraymath._HAVE_BLAS

@njit(cache=False)
def user_linear_algebra(a, b):
    return np.dot(a, b), np.linalg.solve(a, b[:, 0])

n = 6
a = np.eye(n) * 4.0 + np.ones((n, n))  # symmetric, eigenvalues 4 (x n-1) and 4 + n: well conditioned
b = np.arange(2 * n, dtype=np.float64).reshape(n, 2)
dot, x = user_linear_algebra(a, b)
# closed forms: (4 I + J) b = 4 b + (column sums); (4 I + J)^-1 = (I - J / (4 + n)) / 4
state["dot_error"] = float(np.max(np.abs(dot - (4.0 * b + b.sum(axis=0)))))
state["solve_residual"] = float(np.max(np.abs(a @ x - b[:, 0])))
state["solve_error"] = float(np.max(np.abs(x - (b[:, 0] - b[:, 0].sum() / (4.0 + n)) / 4.0)))
import scipy.linalg.cython_blas
cb = sys.modules["scipy.linalg.cython_blas"]
state["same_module"] = scipy.linalg.cython_blas is cb  # the package's attribute: a complete import
state["ddot"] = "ddot" in cb.__pyx_capi__
print(json.dumps(state))
"""

LINALG_FIRST = r"""
import json, sys
import scipy.linalg
from vlref.jit_init import initialise_numba
initialise_numba()
import numba.np.arraymath
print(json.dumps({"have_blas": numba.np.arraymath._HAVE_BLAS,
                  "cython_blas": sys.modules.get("scipy.linalg.cython_blas") is not None}))
"""

NOT_LOADABLE = r"""
import importlib.util, json, sys
from vlref import jit_init


def refuse(spec):  # loading the extension on its own fails (the import system's own path does not use this name)
    raise ImportError("refused")


importlib.util.module_from_spec = refuse
jit_init.initialise_numba()
import numba.np.arraymath
print(json.dumps({"have_blas": numba.np.arraymath._HAVE_BLAS, "scipy.linalg": "scipy.linalg" in sys.modules}))
"""


def _state(code: str, *args: str, site=None) -> dict:
    """The JSON line ``code`` prints last in a fresh interpreter given ``args``; ``site``: a folder of stand-in
    packages put first on its path."""
    env = None if site is None else dict(
        os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, check=True, env=env)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_a_render_leaves_scipy_linalg_unimported_and_user_linear_algebra_works():
    state = _state(AFTER_RENDER)
    assert not state["scipy.linalg"] and not state["cython_blas"]  # the render did not import the package
    assert state["have_blas"] is True  # Numba's check found the BLAS: np.dot takes its BLAS path
    assert state["dot_error"] == 0.0  # small integers: exact in any summation order
    assert state["solve_residual"] <= 1e-13 and state["solve_error"] <= 1e-14
    assert state["same_module"] and state["ddot"]  # the package imported afterwards, its extension complete


def test_with_scipy_linalg_already_imported_numba_initialises_as_usual():
    state = _state(LINALG_FIRST)
    assert state == {"have_blas": True, "cython_blas": True}


def test_where_the_extension_cannot_be_loaded_alone_numba_initialises_as_usual():
    assert _state(NOT_LOADABLE) == {"have_blas": True, "scipy.linalg": True}


OWN_KERNELS = r"""
import json, sys
import numba.core.entrypoints
from vlref.cli.commands import program_command
program_command(sys.argv[1])  # only "render" declares its process one that runs vlref's kernels alone
from vlref.cli.render import render_to_folder
import tempfile
from vlref.scene import load_scene
with tempfile.TemporaryDirectory() as folder:
    render_to_folder(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]), folder + "/out")
# Numba's cffi module is imported by the initialisation's registrations (at once, or at the first compile of a
# process that loaded its kernels from the cache only): its support where it was imported, none where it was not
cffi_utils = sys.modules.get("numba.core.typing.cffi_utils")
state = {"cffi imported": "cffi" in sys.modules, "pycparser imported": "pycparser" in sys.modules,
         "numba cffi support": cffi_utils is not None and cffi_utils.SUPPORTED,
         "extensions loaded": numba.core.entrypoints._already_initialized}
import cffi  # a complete import afterwards, whatever Numba's support
state["cffi works"] = cffi.FFI().sizeof("int") == 4
print(json.dumps(state))
"""


def test_the_render_programs_process_initialises_numba_without_cffi_and_extensions():
    # cffi is installed wherever wgpu is (the test extra): it must be, for this to test anything
    import importlib.util
    assert importlib.util.find_spec("cffi") is not None, "cffi is a dependency of wgpu, which the test extra installs"
    program = json.loads(subprocess.run([sys.executable, "-c", OWN_KERNELS, "render"], capture_output=True,
                                        text=True, check=True).stdout.strip().splitlines()[-1])
    assert program == {"cffi imported": False, "pycparser imported": False, "numba cffi support": False,
                       "extensions loaded": True, "cffi works": True}
    # another command's process (it may run a user's code or a cluster): Numba as it always initialises
    other = json.loads(subprocess.run([sys.executable, "-c", OWN_KERNELS, "scenes"], capture_output=True, text=True,
                                      check=True).stdout.strip().splitlines()[-1])
    assert other == {"cffi imported": True, "pycparser imported": True, "numba cffi support": True,
                     "extensions loaded": True, "cffi works": True}


WITH_CONFIG_FILE = r"""
import json, sys
from vlref.cli.commands import program_command
program_command(sys.argv[1])
import numba.core.config as config
state = {"yaml imported": "yaml" in sys.modules, "numba reads its file": config._HAVE_YAML,
         "threads": config.NUMBA_NUM_THREADS}
import yaml  # a complete import afterwards
state["yaml works"] = yaml.safe_load("a: 1") == {"a": 1}
print(json.dumps(state))
"""


def test_the_render_program_imports_numba_without_yaml_unless_numba_has_a_file_to_read(tmp_path):
    import os

    env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}  # the variable would override the file

    def state(command):
        proc = subprocess.run([sys.executable, "-c", WITH_CONFIG_FILE, command], capture_output=True, text=True,
                              check=True, cwd=tmp_path, env=env)
        return json.loads(proc.stdout.strip().splitlines()[-1])

    without = state("render")
    assert without["yaml imported"] is False and without["numba reads its file"] is False and without["yaml works"]
    (tmp_path / ".numba_config.yaml").write_text("num_threads: 1\n")  # Numba reads it: PyYAML is imported for it
    assert state("render") == {"yaml imported": True, "numba reads its file": True, "threads": 1,
                               "yaml works": True}
    (tmp_path / ".numba_config.yaml").unlink()
    assert state("scenes")["yaml imported"]  # another command: Numba's import as always


WITH_COVERAGE_INSTALLED = r"""
import json, sys
if sys.argv[2] == "measured":
    import coverage  # a measurement imports coverage.py before the code it measures
from vlref.cli.commands import program_command
program_command(sys.argv[1])
import numba.misc.coverage_support as support
state = {"coverage imported": "coverage" in sys.modules, "numba reports to coverage": support.coverage_available}
import coverage  # a complete import afterwards
state["coverage works"] = coverage.Coverage.current() is None
print(json.dumps(state))
"""


def test_the_render_program_imports_numba_without_coverage_unless_a_measurement_runs(tmp_path):
    package = tmp_path / "site" / "coverage"  # a stand-in for coverage.py, installed for these processes: the names
    package.mkdir(parents=True)               # Numba's coverage support reads
    (package / "__init__.py").write_text("from . import types\n\n\nclass Coverage:\n    @staticmethod\n"
                                         "    def current():\n        return None\n")
    (package / "types.py").write_text("class Tracer:\n    pass\n\n\ndef __getattr__(name):\n    return object\n")

    def state(command, measured):
        return _state(WITH_COVERAGE_INSTALLED, command, measured, site=tmp_path / "site")

    assert state("render", "not measured") == {"coverage imported": False, "numba reports to coverage": False,
                                               "coverage works": True}
    measured = {"coverage imported": True, "numba reports to coverage": True, "coverage works": True}
    assert state("render", "measured") == measured
    assert state("scenes", "not measured") == measured  # another command: Numba's import as always


WITH_COLORAMA_INSTALLED = r"""
import json, sys
from vlref.cli.commands import program_command
program_command(sys.argv[1])
import numba.core.errors as errors
state = {"colorama imported": "colorama" in sys.modules, "numba highlights": not hasattr(errors, "NOPColorScheme")}
import colorama  # a complete import afterwards
state["colorama works"] = colorama.Fore.RED == "red"
print(json.dumps(state))
"""


def test_the_render_program_imports_numba_without_colorama(tmp_path):
    package = tmp_path / "site" / "colorama"  # a stand-in for colorama, installed for these processes: the names
    package.mkdir(parents=True)               # Numba's error module reads
    (package / "__init__.py").write_text("__version__ = '0.4.6'\n\n\ndef init():\n    pass\n\n\n"
                                         "reinit = deinit = init\n\n\nclass Names:\n"
                                         "    def __getattr__(self, name):\n        return name.lower()\n\n\n"
                                         "Fore = Style = Names()\n")

    def state(command):
        return _state(WITH_COLORAMA_INSTALLED, command, site=tmp_path / "site")

    assert state("render") == {"colorama imported": False, "numba highlights": False, "colorama works": True}
    assert state("scenes") == {"colorama imported": True, "numba highlights": True, "colorama works": True}


WITH_CYTHON_INSTALLED = r"""
import json, sys
from vlref.cli.commands import program_command
program_command(sys.argv[1])
import scipy._lib._testutils as testutils  # imported by SciPy's import, which Numba's import makes
state = {"cython imported": "cython" in sys.modules, "scipy's test helper sees it": testutils.cython is not None}
import cython  # a complete import afterwards
state["cython works"] = cython.compiled is False
print(json.dumps(state))
"""


def test_the_render_program_imports_numba_without_cython(tmp_path):
    site = tmp_path / "site"  # a stand-in for Cython, installed for these processes: the names SciPy's import reads
    (site / "Cython" / "Compiler").mkdir(parents=True)
    (site / "Cython" / "__init__.py").write_text("")
    (site / "Cython" / "Compiler" / "__init__.py").write_text("")
    (site / "Cython" / "Compiler" / "Version.py").write_text("version = '3.1.0'\n")
    (site / "cython.py").write_text("compiled = False\n")

    def state(command):
        return _state(WITH_CYTHON_INSTALLED, command, site=site)

    assert state("render") == {"cython imported": False, "scipy's test helper sees it": False, "cython works": True}
    assert state("scenes") == {"cython imported": True, "scipy's test helper sees it": True, "cython works": True}


RUNTIME_KEPT = r"""
import hashlib, json, os, sys
from vlref.cli.commands import program_command
program_command(sys.argv[1])
import vlref.jit_init as jit_init
from numba.core.runtime import nrtdynmod
path = sys.argv[2]
jit_init.runtime_file = lambda codegen: path  # this test's file, beside the session's warm kernels
compiled, create = [], nrtdynmod.create_nrt_module
nrtdynmod.create_nrt_module = lambda ctx: compiled.append(1) or create(ctx)
from vlref.render import render
from vlref.scene import load_scene
result = render(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]))
import numpy as np
from numba import njit

@njit(cache=False)
def user_allocates(n):  # a compile afterwards whose arrays need the NRT
    return np.arange(n).sum()

print(json.dumps({"compiled": len(compiled), "file": os.path.isfile(path), "user": int(user_allocates(10)),
                  "final": hashlib.sha256(result.buffers["final"].tobytes()).hexdigest()}))
"""


def test_the_render_program_keeps_the_nrt_library_in_a_file(tmp_path):
    path = str(tmp_path / "runtime.nrt")
    first = _state(RUNTIME_KEPT, "render", path)  # no file: Numba's compile, then the file written
    assert first["compiled"] == 1 and first["file"] and first["user"] == 45
    second = _state(RUNTIME_KEPT, "render", path)  # the library from the file: nothing compiled
    assert second == dict(first, compiled=0)
    ordinary = _state(RUNTIME_KEPT, "scenes", str(tmp_path / "unused.nrt"))  # another command: Numba's own start
    assert ordinary == dict(first, file=False)  # the same render, no file
    data = bytearray(open(path, "rb").read())
    data[-1] ^= 1  # a damaged file: its digest does not check, and the library is compiled and written again
    open(path, "wb").write(bytes(data))
    assert _state(RUNTIME_KEPT, "render", path) == first
    assert _state(RUNTIME_KEPT, "render", path) == second


LAZY_METADATA = r"""
import json, sys
from vlref.cli.commands import program_command
program_command(sys.argv[1])
import numba.core.entrypoints as entrypoints  # Numba's import imported it, for the extension scan
state = {"imported": "importlib.metadata" in sys.modules,
         "executed": "importlib.metadata._meta" in sys.modules}  # a module its code imports
import numpy
state["works"] = entrypoints.importlib_metadata.version("numpy") == numpy.__version__  # its first use runs it
state["numba's and the import's"] = entrypoints.importlib_metadata is sys.modules["importlib.metadata"]
print(json.dumps(state))
"""


def test_the_render_program_imports_importlib_metadata_lazily():
    assert _state(LAZY_METADATA, "render") == {"imported": True, "executed": False, "works": True,
                                               "numba's and the import's": True}
    assert _state(LAZY_METADATA, "scenes") == {"imported": True, "executed": True, "works": True,
                                               "numba's and the import's": True}


AHEAD_PROCESS = r"""
import json, sys
import numba.core.entrypoints
import vlref.ahead as ahead
stages = []
ahead.compile_stage = lambda stage, scene: stages.append(stage)  # what it compiles: tests/test_progress_interrupts.py
ahead._compile_stage_process("march", None)
from numba.core.typing import cffi_utils
print(json.dumps({"stages": stages, "numba initialised": "numba.np.arraymath" in sys.modules,  # refresh() imports it
                  "cffi imported": "cffi" in sys.modules, "scipy.linalg": "scipy.linalg" in sys.modules,
                  "numba cffi support": cffi_utils.SUPPORTED,
                  "extensions loaded": numba.core.entrypoints._already_initialized}))
"""


def test_a_compile_ahead_process_initialises_numba_as_the_render_programs_own_process():
    """The process :func:`vlref.ahead.compile_ahead` starts runs vlref's kernels alone: Numba initialised before its
    stage compiles, without scipy.linalg, cffi and the extension scan (it starts behind the main process)."""
    assert _state(AHEAD_PROCESS) == {"stages": ["march"], "numba initialised": True, "cffi imported": False,
                                     "scipy.linalg": False, "numba cffi support": False, "extensions loaded": True}


LOADING_ONLY = r"""
import hashlib, json, sys, tempfile
from pathlib import Path
from vlref.cli.commands import program_command
render_to_folder = program_command("render").render_to_folder
from numba.core import event, registry
from vlref.scene import load_scene


class Compiles(event.Listener):
    count = 0

    def on_start(self, ev):
        Compiles.count += 1

    def on_end(self, ev):
        pass


event.register("numba:compile", Compiles())
context = registry.cpu_target.target_context
with tempfile.TemporaryDirectory() as folder:
    render_to_folder(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]), folder + "/out")
    final = hashlib.sha256(Path(folder, "out", "final.exr").read_bytes()).hexdigest()
state = {"compiles": Compiles.count, "deferred": "refresh" in vars(context), "final": final,
         "registries installed": len(context._registries) + len(context.typing_context._registries),
         "scipy.linalg": "scipy.linalg" in sys.modules}
import numpy as np
from numba import njit


@njit(cache=False)
def user_code(a, word):  # a compile in the same process afterwards: lowering registrations, strings, BLAS
    return np.dot(a, a), len(word.upper())


dot, n = user_code(np.arange(4.0), "abc")
state.update({"user code": [float(dot), n], "deferred after": "refresh" in vars(context),
              "registries installed after": len(context._registries) + len(context.typing_context._registries),
              "cffi imported": "cffi" in sys.modules})
print(json.dumps(state))
"""


def test_the_render_programs_process_loads_cached_kernels_without_the_registrations_until_a_compile():
    first = _state(LOADING_ONLY)  # fills the cache where it is cold (then it compiled, the registrations installed)
    warm = _state(LOADING_ONLY)
    # from the cache: nothing compiled, the registrations (and their modules) left out, the same bytes
    assert warm["compiles"] == 0 and warm["deferred"] is True and warm["registries installed"] == 0
    assert warm["scipy.linalg"] is False  # Numba's BLAS check ran with the extension alone
    assert warm["final"] == first["final"]
    # a compile afterwards installs them first: it works, without cffi (module docstring)
    for state in (first, warm):
        assert state["user code"] == [14.0, 3]  # 0 + 1 + 4 + 9; len("ABC")
        assert state["deferred after"] is False and state["registries installed after"] > 10
        assert state["cffi imported"] is False


LINKED_ON_DEMAND = r"""
import hashlib, json, tempfile
import numpy as np
from vlref.cli.commands import program_command
render_to_folder = program_command("render").render_to_folder
from vlref import jit_init
from vlref.post.composite import _sum_composite
from vlref.scene import load_scene

loaded = []  # (library, the names its object file defines, its bitcode still unparsed)
load = jit_init._LinkedOnDemand._unserialize.__func__


def recorded(cls, codegen, state):
    library = load(cls, codegen, state)
    loaded.append((library, jit_init.object_symbols(state[2][0]), library._linking_bitcode is not None))
    return library


jit_init._LinkedOnDemand._unserialize = classmethod(recorded)
with tempfile.TemporaryDirectory() as folder:
    result, *_ = render_to_folder(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]),
                                  folder + "/out")
state = {"final": hashlib.sha256(np.ascontiguousarray(result.buffers["final"]).tobytes()).hexdigest(),
         "loads": len(loaded), "unparsed at load": all(unparsed for _, _, unparsed in loaded),
         "still unparsed": sum(library._linking_bitcode is not None for library, _, _ in loaded)}
from numba import njit


@njit(cache=False)
def user_code(per_light, scene, trans):  # a compile that links a loaded library: its bitcode parsed then
    inscatter, final = np.empty(scene.shape), np.empty(scene.shape)
    _sum_composite(per_light, scene, trans, inscatter, final)
    return inscatter, final


composite = [c.library for c in _sum_composite.overloads.values()]  # loaded from the cache above
before = [library._linking_bitcode is not None for library in composite]
rng = np.random.default_rng(1)
per_light, scene, trans = rng.random((2, 4, 5, 3)), rng.random((4, 5, 3)), rng.random((4, 5))
inscatter, final = user_code(per_light, scene, trans)
state["user code"] = bool(np.array_equal(inscatter, per_light[0] + per_light[1])
                          and np.array_equal(final, scene * trans[..., None] + inscatter))
state["composite unparsed before, after"] = [before, [library._linking_bitcode is not None for library in composite]]
same = []  # each library's names from its object file against Numba's own scan of its bitcode
for library, names, _ in loaded:
    module = library._shared_module
    scanned = {f.name for f in module.functions if not f.is_declaration}
    scanned |= {g.name for g in module.global_variables if not g.is_declaration}
    same.append(names == scanned)
state["names as Numba's scan"] = same
print(json.dumps(state))
"""


def test_the_render_programs_process_loads_libraries_without_parsing_their_linking_bitcode():
    """The program's own process defines a loaded library's names from its object file, the same names as Numba's
    scan of the library's bitcode, and parses that bitcode only when a compile links the library: the render the
    same bits as an ordinary process's, a compile afterwards that calls a loaded kernel works."""
    _state(LINKED_ON_DEMAND)  # fills the cache where it is cold (then nothing was loaded)
    state = _state(LINKED_ON_DEMAND)
    ordinary = render(load_scene(None, ["render.width=16", "render.height=9", "render.steps=2"]))
    assert state["final"] == hashlib.sha256(np.ascontiguousarray(ordinary.buffers["final"]).tobytes()).hexdigest()
    assert state["loads"] >= 10 and state["unparsed at load"] is True  # the stages' kernels and their work
    assert state["still unparsed"] == state["loads"]  # the render linked none of them
    assert state["user code"] is True
    assert state["composite unparsed before, after"] == [[True], [False]]
    assert state["names as Numba's scan"] == [True] * state["loads"]


def test_object_symbols_reads_only_elf64_little_endian_object_files():
    header = bytearray(64)
    header[:6] = b"\x7fELF\x02\x01"  # a 64-bit little-endian header
    header[0x3A:0x3C] = (64).to_bytes(2, "little")  # section headers of 64 bytes
    assert object_symbols(bytes(header)) is None  # no sections, so no symbol table
    header[0x28:0x30], header[0x3C:0x3E] = (64).to_bytes(8, "little"), (3).to_bytes(2, "little")
    assert object_symbols(bytes(header)) is None  # three sections past the file's end
    for other in (b"", b"\xcf\xfa\xed\xfe" + bytes(60), b"\x7fELF\x01\x01" + bytes(58), b"\x7fELF\x02\x02" + bytes(58)):
        assert object_symbols(other) is None  # empty, Mach-O, 32-bit ELF, big-endian ELF
