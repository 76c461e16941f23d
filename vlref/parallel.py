"""What the parallel kernels need beyond ``prange``: tasks handed out on demand, and arrays without reference counts.

**Tasks on demand** (:func:`take`). ``prange`` splits its iterations into one contiguous block per thread
when the loop starts (Numba's ``parallel_chunksize`` has no effect under the OpenMP threading layer, the
one installed here, as Numba's tracker says at github.com/numba/numba/issues/8284; measured too: the same
blocks for every chunk size). A march's
pixels cost between nothing (outside every light) and hundreds of samples, so equal blocks leave most
threads idle while one finishes the bright part of the frame. A kernel that loops ``prange`` over its
threads, each taking the next task from a shared counter with :func:`take` until none is left, keeps
every thread busy to the last task. The loop runs over :data:`WORKERS` iterations, more than any
machine's threads (a kernel that asks Numba for its thread count cannot be cached): each thread's first
iteration takes tasks until none is left, and its other iterations find none. Which thread marches which
task changes no result: tasks are independent and each writes only its own pixels.

**One iteration per thread** (:func:`workers`). An iteration that finds no task still calls the work function
with all its arguments (a ray cast's ~50 arrays: their structs copied, their reference counts added and
dropped): the 1024 iterations of :data:`WORKERS` cost a ray cast at 80x45 ~0.3 ms on one thread, more than its
rays. The kernels of small images (the ray cast, the scene colour, the quadrature reference) take their
iteration count as an argument instead, :func:`workers`: one per thread, no more than the tasks. Numba's thread
count is left as it is: lowering it for a small launch (``numba.set_num_threads``) made the OpenMP runtime resize
its team before the launch and again before the next, and measured slower on the device than every thread
(BENCHMARKS.md "The reference's fixed costs").

**Arrays without reference counts** (:func:`borrowed`). Numba counts references to every array passed to
a compiled function, with an atomic add on a counter stored beside the array's data. When 16 threads
pass the same input arrays (the light, shadow and medium records) to small functions on every step,
they contend for those counters' cache lines. A borrowed view has no counter, so counting its references
does nothing. It does not keep its memory alive either: borrow only inside the kernel that received the
array as an argument (its owner outlives the call).

**Calls that carry arrays** (``inline="always"``). A borrowed array still costs its calls: every call from one
compiled function to another passes each array of its arguments (tuples' included) and calls Numba's runtime twice
per array (``NRT_incref``, ``NRT_decref``), which does nothing for a borrowed array but is never inlined, not even
where LLVM inlines the callee (``forceinline``). A small function called per sample with a record of ~30 arrays (the
reference's integrand and its context) spends more in those calls than in its arithmetic (12 % of the quadrature's
samples; BENCHMARKS.md "The integrand compiled into the quadrature's loop"). Such functions are compiled into their
callers' Numba IR instead (``inline="always"``), which removes the call and the counts; each call site is then a
copy of the code, so their callers keep one call site each.

**Work called by address** (:func:`work`). A ``parallel=True`` kernel is a thin shell: a ``prange`` whose
body calls the function that does the work (the row or task function). Called as Numba calls any compiled
function, that function's whole call tree is linked into the caller's LLVM module, and Numba optimises and
generates machine code for each module it builds, callees included: a ``prange`` builds four (the loop body's
gufunc, its two wrappers, the kernel), so the work's call tree was optimised and code-generated four more
times in every parallel kernel (a cold compile of the march: 4.9 s of its 12 s of LLVM; BENCHMARKS.md "Cold first
render on two cores, second round"). The kernels take the work as an argument instead, a Numba first-class
function (:class:`Work`: the address of its C wrapper, compiled once for the kernel's argument types; the work
function is declared ``vlref.jit.njit(..., by_address=True)``, which compiles that wrapper and no CPython one): the
shell calls it through that address, and only the work's own module holds its code. The work runs its own
module's machine code (optimised once instead of again in every caller: IEEE arithmetic either way, the same
bits), one indirect call per worker. The work borrows its arrays itself (a ``borrowed`` tuple in the ``prange``
body cost the gufunc 0.4-0.9 s of LLVM function passes). It must not raise: through its C wrapper an exception
is printed, not propagated (the kernels check their arguments before the ``prange``).
"""

from __future__ import annotations

import numba
import numpy as np
from numba.core import cgutils, types
from numba.core.errors import TypingError
from numba.core.types.function_type import WrapperAddressProtocol
from numba.core.typing import signature
from numba.core.typing.typeof import typeof_impl
from numba.extending import intrinsic

from .jit import njit

try:  # Numba's own typing cache key: what its dispatcher looks up a value's type by, in C (~0.2 µs)
    from numba._dispatcher import compute_fingerprint
except ImportError:  # a Numba without it: the key is the type itself
    compute_fingerprint = None

__all__ = ["WORKERS", "COUNTER", "task_counter", "take", "workers", "borrowed", "Work", "work"]

WORKERS = 1024  # prange iterations of a kernel whose threads take tasks (module docstring)
COUNTER = types.Array(types.int64, 1, "C")
"""The Numba type of the task counter of :func:`take` (:func:`task_counter`), for :func:`work`."""


@njit(cache=True, fastmath=False)
def task_counter():
    """A new task counter for :func:`take` (a 1-element int64 array holding 0). A kernel calls it rather than
    writing ``np.zeros(1, dtype=np.int64)``: in a ``parallel=True`` function Numba turns ``np.zeros`` into a parfor
    of its own, one more gufunc to compile per kernel (BENCHMARKS.md "A cold render compiles fewer wrappers and
    parfors"), while a call is compiled once, here, without ``parallel``."""
    counter = np.empty(1, dtype=np.int64)
    counter[0] = 0
    return counter


@intrinsic
def take(typingctx, counter):
    """``counter[0]`` before adding 1 to it, atomically: every call gets a different number, 0, 1, 2, …
    across all threads. ``counter`` a 1-element int64 array (C order). njit only."""
    if not (isinstance(counter, types.Array) and counter.dtype == types.int64 and counter.ndim == 1):
        raise TypingError(f"take: the counter must be a 1-d int64 array, not {counter}")

    def codegen(context, builder, signature, args):
        array = context.make_array(signature.args[0])(context, builder, value=args[0])
        one = context.get_constant(types.int64, 1)
        return builder.atomic_rmw("add", array.data, one, "monotonic")

    return types.int64(counter), codegen


def _check_borrowable(ty):
    if isinstance(ty, types.Array):
        return
    if isinstance(ty, types.BaseTuple):
        for t in ty.types:
            _check_borrowable(t)
        return
    if not isinstance(ty, (types.Number, types.Boolean, types.NoneType)):
        raise TypingError(f"borrowed: cannot borrow a {ty}")


def _borrow(context, builder, ty, value):
    if isinstance(ty, types.Array):
        view = context.make_array(ty)(context, builder, value=value)
        view.meminfo = cgutils.get_null_value(view.meminfo.type)
        view.parent = cgutils.get_null_value(view.parent.type)
        return view._getvalue()
    if isinstance(ty, types.BaseTuple):
        out = value
        for index, t in enumerate(ty.types):
            out = builder.insert_value(out, _borrow(context, builder, t, builder.extract_value(value, index)), index)
        return out
    return value


@intrinsic
def borrowed(typingctx, value):
    """``value`` (an array, or a tuple or NamedTuple of arrays, numbers and None) with every array's reference
    counter removed: the same type, data, shape and strides. njit only."""
    _check_borrowable(value)

    def codegen(context, builder, signature, args):
        return _borrow(context, builder, signature.args[0], args[0])

    return value(value), codegen


class Work(WrapperAddressProtocol):
    """A compiled function passed to a parallel kernel by address (module docstring): Numba types it as a
    first-class function of ``sig`` (the type made once, :func:`_typeof_work`); the kernel calls it through the
    address of its C wrapper."""

    def __init__(self, function, sig):
        self._sig = sig
        self.numba_type = types.FunctionType(sig)
        result = function.get_compile_result(sig)  # compiles or loads from the cache now, not while unboxing
        self._address = result.library.get_pointer_to_function(result.fndesc.llvm_cfunc_wrapper_name)
        if not self._address:  # a call through it would jump to address 0
            raise TypeError(f"work: {function.py_func.__qualname__} has no C wrapper: compile it with "
                            "vlref.jit.njit(..., by_address=True)")

    def __wrapper_address__(self) -> int:
        return self._address

    def signature(self):
        return self._sig


@typeof_impl.register(Work)
def _typeof_work(value, context):
    """A :class:`Work`'s Numba type, made when the work was: Numba's own rule for a function by address
    (``typeof_function_type``, registered for any :class:`WrapperAddressProtocol`) makes the same ``FunctionType``
    anew at every kernel call, ~8 µs of the call (dev box), 9 of a 66 µs ray-cast launch at 80x45 on one thread."""
    return value.numba_type


_WORK: dict = {}


def _type_key(value):
    """What :func:`work` keys a value's Numba type by: the type itself where given, else the fingerprint Numba's
    dispatcher types its arguments by (one fingerprint, one type), else ``numba.typeof``."""
    if isinstance(value, types.Type):
        return value
    if compute_fingerprint is not None:
        try:
            return compute_fingerprint(value)
        except NotImplementedError:
            pass
    return numba.typeof(value)


def work(function, *args) -> Work:
    """``function`` (an ``njit`` dispatcher returning nothing) as a :class:`Work` for arguments of the types of
    ``args`` (values, or Numba types such as :data:`COUNTER`): pass it to the kernel whose workers call it with
    arguments of these types (borrowed views have their arrays' types). One per function and types, kept; found
    again by the arguments' fingerprints (:func:`_type_key`): ``numba.typeof`` of the records of a ray cast took
    ~0.2 ms a call, a fifth of a 320x180 ray cast on 16 threads (BENCHMARKS.md "The work's look-up by fingerprint")."""
    key = (function, tuple(_type_key(a) for a in args))
    if key not in _WORK:
        argtypes = tuple(a if isinstance(a, types.Type) else numba.typeof(a) for a in args)
        _WORK[key] = Work(function, signature(types.none, *argtypes))
    return _WORK[key]


def workers(tasks: int) -> int:
    """The ``prange`` iterations of a kernel whose threads take ``tasks`` tasks (module docstring): one per thread
    of Numba's thread count, no more than the tasks, at least one. Which thread takes which task changes no result."""
    return max(1, min(numba.get_num_threads(), int(tasks)))
