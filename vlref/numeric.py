"""Numeric helpers shared by the kernels: the float-type helpers :func:`cast` and :func:`zero_one`, and
:func:`exp` / :func:`expm1` written out so that LLVM can vectorise the loops that call them, and :func:`glibc_exp`,
libm's ``exp`` bit for bit (glibc's algorithm, written out the same way; its docstring).

``exp`` and ``expm1`` (float64 arithmetic; a float32 argument gives the float32 rounding of the float64 value):
the argument is reduced as ``x = n ln2 + r``, ``n = round(x / ln2)``, ``|r| <= ln2/2``, with ``ln2`` split in
two parts (Cody & Waite 1980, *Software Manual for the Elementary Functions*; the split constants are
fdlibm's ``ln2_hi``/``ln2_lo``), then ``p = e^r - 1`` is the Taylor polynomial of degree 13 (truncation below
``0.35^14/14! ≈ 4e-18``), ``p = r + r² q(r)`` with ``q`` evaluated by Estrin's scheme (pairs of terms, then
pairs of pairs: a dependency chain of four multiply-adds where Horner's rule has eleven), every multiply-add
fused (:func:`fma`, rounded once: half the operations, the same bits on every machine), and

    exp(x)   = 2^n + 2^n p
    expm1(x) = p                      (n = 0: r = x exactly, so small arguments keep their relative accuracy)
             = (2^n - 1) + 2^n p      (otherwise; 2^n - 1 is exact for the n that occur)

``n`` is read from the bits of ``x/ln2 + 1.5·2^52`` and ``2^n`` built from its bits: no table, no float→int
conversion and no branch (selects only), which is what keeps a lane loop vectorisable where libm's ``exp``
(a call) is not. Measured against libm on 2·10⁶ arguments per range in [-700, 700]: ``exp`` within 1 ulp
(more than half an ulp away on 5.4-11.4 % of the arguments of a range; 5.4-11.7 % before the multiply-adds were
fused), ``expm1`` within 2 ulp (tests/test_numeric.py). Results below ``2^-1022`` flush to 0 (``expm1``: -1); above
``709.78`` they are ``inf``; NaN stays NaN. The results do not depend on ``fastmath`` or on vectorisation
(no reassociation: the same operations in the same order in every lane).
"""

from __future__ import annotations

import decimal
import math

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic, overload

from .jit import njit

__all__ = ["cast", "zero_one", "is_float64", "exp", "expm1", "fma", "prefer_wide_vectors", "arrays_do_not_overlap",
           "glibc_exp", "glibc_exp_normal"]


def cast(like, value):
    """``value`` in the float type of ``like``; inside njit code float32 stays float32.

    Python float literals are float64 in Numba and would promote float32 arithmetic, so a
    kernel compiled for float32 writes ``cast(x, 2.0)`` where it means "2 in x's precision".
    """
    return type(like)(value)


@overload(cast)
def _cast_impl(like, value):
    if like == types.float32:
        return lambda like, value: np.float32(value)
    return lambda like, value: np.float64(value)


def zero_one(like):
    """``(0, 1)`` in the float type of the array ``like``; inside njit code float32 stays float32.

    The one way a kernel compiled for float64 and float32 inputs names its precision: ``zero, one =
    zero_one(buffer)`` from the array it computes in, then ``cast(one, value)`` for any other constant
    (never a witness element such as ``table[0, 0]``, which an empty table would not have).
    """
    t = np.asarray(like).dtype.type
    return t(0.0), t(1.0)


@overload(zero_one)
def _zero_one_impl(like):
    if not isinstance(like, types.Array) or not isinstance(like.dtype, types.Float):
        return None
    if like.dtype == types.float32:
        return lambda like: (np.float32(0.0), np.float32(1.0))
    return lambda like: (np.float64(0.0), np.float64(1.0))


def is_float64(like):
    """Whether the array or float ``like`` holds float64 values. Inside njit code a constant of the compile (each
    precision compiles its own), so a kernel can take a float64-only shortcut with no run-time branch."""
    return np.asarray(like).dtype == np.float64


@overload(is_float64)
def _is_float64_impl(like):
    dtype = like.dtype if isinstance(like, types.Array) else like
    if not isinstance(dtype, types.Float):
        return None
    if dtype == types.float64:
        return lambda like: True
    return lambda like: False


@intrinsic
def fma(typingctx, a, b, c):
    """``a·b + c`` rounded once (LLVM's ``llvm.fma``: one instruction with FMA hardware, else libm's ``fma``,
    the same bits either way). For njit code; all three arguments of one float type."""
    if not (isinstance(a, types.Float) and a == b == c):
        return None

    def codegen(context, builder, signature, args):
        t = args[0].type
        return builder.call(builder.module.declare_intrinsic("llvm.fma", [t], ir.FunctionType(t, [t, t, t])), args)

    return a(a, b, c), codegen


@intrinsic
def prefer_wide_vectors(typingctx):
    """Called first in an njit function: its loops may be vectorised with the widest vectors the CPU has (LLVM's
    function attribute ``"prefer-vector-width"="512"``). LLVM's tuning for Intel's server cores prefers 256-bit
    vectors even where AVX-512 is present; the attribute overrides that for this function alone (what the
    process-wide ``NUMBA_CPU_FEATURES=...,-prefer-256-bit`` does for every function). No effect on a CPU
    without AVX-512, or where the tuning already uses 512 bits (Zen 4). The same bits either way: the width
    changes how many lanes an instruction computes, not what a lane computes."""
    def codegen(context, builder, signature, args):
        attributes = builder.function.attributes
        try:  # llvmlite's attribute set takes only attribute names it knows; LLVM takes any string attribute
            set.add(attributes, '"prefer-vector-width"="512"')
        except (TypeError, AttributeError):  # an llvmlite that keeps them otherwise: its default width, the same bits
            pass
        return context.get_dummy_value()

    return types.none(), codegen


@intrinsic
def arrays_do_not_overlap(typingctx):
    """Called first in an njit function whose array arguments are distinct arrays (no two share memory): tells LLVM
    so (the ``noalias`` attribute on every pointer argument of the function being compiled, what Numba's internal
    ``noalias`` flag does). A loop that stores to one array and reads another at computed indices (a gather) can
    then be vectorised; without it LLVM must assume the store may change what a later lane reads. Calling it in a
    function that is passed overlapping arrays is undefined behaviour. The same bits where the promise holds: it
    allows reordering memory accesses, not changing arithmetic."""
    def codegen(context, builder, signature, args):
        for argument in context.call_conv.get_arguments(builder.function):
            if isinstance(argument.type, ir.PointerType):
                argument.add_attribute("noalias")
        return context.get_dummy_value()

    return types.none(), codegen


_INV_LN2 = 1.4426950408889634
_LN2_HI = 6.93147180369123816490e-01  # fdlibm ln2_hi: n * _LN2_HI is exact for |n| < 2^20
_LN2_LO = 1.90821492927058770002e-10
_SHIFTER = 6755399441055744.0  # 1.5 * 2^52: adding it rounds to an integer kept in the low mantissa bits
_SHIFTER_BITS = int(np.float64(_SHIFTER).view(np.int64))
_LO, _HI = -708.0, 709.782712893384  # exp(_LO) > 2^-1022; exp(_HI) < the largest float64
(_C2, _C3, _C4, _C5, _C6, _C7, _C8, _C9, _C10, _C11, _C12, _C13) = (1.0 / math.factorial(k) for k in range(2, 14))


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def _reduced(x):
    """``(n, 2^n, e^r - 1)`` for float64 ``x`` clamped to ``[_LO, _HI]`` (module docstring)."""
    x = min(max(x, _LO), _HI)
    k = x * _INV_LN2 + _SHIFTER
    nf = k - _SHIFTER
    n = np.float64(k).view(np.int64) - _SHIFTER_BITS
    r = fma(-nf, _LN2_LO, fma(-nf, _LN2_HI, x))
    # Estrin's scheme with fused multiply-adds: four levels deep instead of Horner's eleven (the lanes' loops are
    # bound by this chain's latency)
    r2 = r * r
    r4 = r2 * r2
    q01 = fma(fma(_C5, r, _C4), r2, fma(_C3, r, _C2))
    q23 = fma(fma(_C9, r, _C8), r2, fma(_C7, r, _C6))
    q45 = fma(fma(_C13, r, _C12), r2, fma(_C11, r, _C10))
    q = fma(q45, r4 * r4, fma(q23, r4, q01))
    p = fma(r2, q, r)
    two_n = np.int64((n + 1023) << 52).view(np.float64)
    return n, two_n, p


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def exp(x):
    """``e^x`` in the float type of ``x`` (module docstring)."""
    v = np.float64(x)
    n, two_n, p = _reduced(v)
    y = fma(two_n, p, two_n)
    y = 0.0 if v < _LO else y
    y = np.inf if v > _HI else y
    y = v if v != v else y
    return cast(x, y)


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def expm1(x):
    """``e^x - 1`` in the float type of ``x``, accurate near 0 (module docstring)."""
    v = np.float64(x)
    n, two_n, p = _reduced(v)
    y = p if n == 0 else fma(two_n, p, two_n - 1.0)
    y = -1.0 if v < _LO else y
    y = np.inf if v > _HI else y
    y = v if v != v else y
    return cast(x, y)


def _glibc_exp_table() -> np.ndarray:
    """glibc's ``__exp_data.tab`` (``EXP_TABLE_BITS = 7``), from its definition: for ``k = 0..127``,
    ``2^(k/128) ~= H_k (1 + T_k)`` with ``H_k`` the float64 nearest ``2^(k/128)`` and ``T_k`` the float64 nearest
    ``2^(k/128) / H_k - 1``; entry ``2k`` holds the bits of ``T_k``, entry ``2k + 1`` those of ``H_k`` less ``k << 45``
    (so that adding ``ki << 45`` to it builds ``2^(ki/128)``'s exponent). ``2^(k/128)`` is ``2^k`` under seven
    square roots, each correctly rounded to 60 significant digits (a relative error below 1e-58, where the float64
    roundings need 1e-33; 1.3 ms, against 12 ms for 60-digit powers ``2^(k/128)``: a share of every process's
    import). The result equals the table that glibc's ``exp_data.c`` lists (tests/test_numeric.py: against the
    powers and through ``math.exp``'s bits)."""
    with decimal.localcontext() as context:
        context.prec = 60
        table = np.empty(256, np.int64)
        for k in range(128):
            power = decimal.Decimal(2 ** k)
            for _ in range(7):
                power = power.sqrt()
            head = float(power)
            table[2 * k] = np.float64(float((power - decimal.Decimal(head)) / decimal.Decimal(head))).view(np.int64)
            table[2 * k + 1] = np.float64(head).view(np.int64) - (k << 45)
    return table


_GEXP_TABLE = _glibc_exp_table()
_GEXP_INV_LN2_N = float.fromhex("0x1.71547652b82fep0") * 128
_GEXP_NEG_LN2_HI_N = -float.fromhex("0x1.62e42fefa0000p-8")
_GEXP_NEG_LN2_LO_N = -float.fromhex("0x1.cf79abc9e3b3ap-47")
_GEXP_C2, _GEXP_C3, _GEXP_C4, _GEXP_C5 = (float.fromhex(c) for c in (
    "0x1.ffffffffffdbdp-2", "0x1.555555555543cp-3", "0x1.55555cf172b91p-5", "0x1.1111167a4d017p-7"))
_TWO_1009, _TWO_M1022 = 2.0 ** 1009, 2.0 ** -1022


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def _glibc_exp_parts(x):
    """``(ki, sbits, tmp, down, y_down)`` of glibc's ``exp`` for float64 ``x``: the reduction's ``k`` as the shifter's
    bits, the bits of ``2^(k/128)`` before any special-case rescaling, ``tmp`` with ``e^x ~= s + s tmp``
    (:func:`glibc_exp`), and its ``specialcase()`` for ``k < 0`` before the final scaling: ``s' = 2^1022 s`` and
    ``y_down = s' + s' tmp`` (the product rounded on its own: the source uses it twice)."""
    kd = fma(np.float64(x), _GEXP_INV_LN2_N, _SHIFTER)
    ki = np.float64(kd).view(np.int64)
    kd = kd - _SHIFTER
    r = fma(kd, _GEXP_NEG_LN2_LO_N, fma(kd, _GEXP_NEG_LN2_HI_N, x))
    idx = 2 * (ki & 127)
    tail = np.int64(_GEXP_TABLE[idx]).view(np.float64)
    sbits = _GEXP_TABLE[idx + 1] + (ki << 45)
    r2 = r * r
    tmp = fma(r2 * r2, fma(r, _GEXP_C5, _GEXP_C4), fma(r2, fma(r, _GEXP_C3, _GEXP_C2), tail + r))
    down = np.int64(sbits + (1022 << 52)).view(np.float64)
    return ki, sbits, tmp, down, down + down * tmp


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def glibc_exp_normal(x):
    """:func:`glibc_exp` for ``-708 <= x < 512``, where the result is a normal number: the same bits there, without
    the branches for overflow, for results below ``2^-1022`` (glibc's extra rounding) and for ``|x| >= 1024``, inf and
    NaN, which the lanes of a vector loop of :func:`glibc_exp` all compute (about half its work). ``|x| < 2^-54``
    needs no branch either: ``1 + x`` and the main path both round to 1. Any other argument gives a meaningless
    value (no trap), so a lane loop may call it on every lane and redo the others with :func:`glibc_exp`."""
    _, sbits, tmp, _, y_down = _glibc_exp_parts(x)
    scale = np.int64(sbits).view(np.float64)
    return _TWO_M1022 * y_down if x <= -512.0 else fma(scale, tmp, scale)


@njit(cache=True, fastmath=False, error_model="numpy", forceinline=True)
def glibc_exp(x):
    """``e^x`` of a float64 with the bits of glibc's ``exp`` (glibc >= 2.28 on x86-64 CPUs with FMA: its
    ``__exp_fma``, the ``exp`` that ``math.exp`` and Numba's ``math.exp`` call there),
    written so that LLVM can vectorise a loop that calls it (a table read, selects, no branch, no call).

    The algorithm (Szabolcs Nagy's, ARM optimized-routines; glibc's ``sysdeps/ieee754/dbl-64/e_exp.c``, musl's
    ``exp.c``): ``x = k ln2/128 + r``, ``k = round(128 x / ln2)`` by the ``1.5·2^52`` shifter, ``|r| <= ln2/256``;
    ``2^(k/128) = 2^(k>>7) H (1 + T)`` from :func:`_glibc_exp_table`; ``e^x ~= s + s (T + r + r² (C2 + C3 r) +
    r⁴ (C4 + C5 r))``, ``s = 2^(k/128)``, error < 0.51 ulp (the source's bound). Each operation as GCC compiles the
    source for FMA hardware (``a·b + c`` fused, :func:`fma`, where the product has no other use; the special case's
    ``scale * tmp``, used twice, is rounded on its own); the arguments that source sends
    to its special cases (``|x| >= 512``: the result's exponent scaled in two steps, results below ``2^-1022``
    rounded once more against double rounding; ``|x| < 2^-54``: ``1 + x``; ``|x| >= 1024``, inf, NaN) take the same
    arithmetic here as selects. Checked bit for bit against ``math.exp`` in tests/test_numeric.py (over the whole
    float64 range, at the branch edges and where the reduction's ``k`` meets a tie). On a libm with another
    algorithm or build (macOS, glibc without FMA hardware) ``math.exp`` may differ from it by an ulp; its own bits
    are the same on every machine. A NaN comes back as a NaN whose sign LLVM does not keep.
    """
    bits = np.float64(x).view(np.int64)
    abstop = (bits >> 52) & 0x7FF
    ki, sbits, tmp, down, y_down = _glibc_exp_parts(x)
    scale = np.int64(sbits).view(np.float64)
    y = fma(scale, tmp, scale)
    # |x| in [512, 1024): glibc's specialcase(), both signs of k
    up = np.int64(sbits - (1009 << 52)).view(np.float64)
    y_up = _TWO_1009 * fma(up, tmp, up)
    lo = (down - y_down) + down * tmp
    hi = 1.0 + y_down
    lo = ((1.0 - hi) + y_down) + lo
    y_sub = (hi + lo) - 1.0
    y_down = _TWO_M1022 * ((0.0 if y_sub == 0.0 else y_sub) if y_down < 1.0 else y_down)
    y_big = y_up if (ki & 0x80000000) == 0 else y_down
    y = y_big if abstop >= 0x408 else y
    y = (0.0 if x < 0.0 else np.inf) if abstop >= 0x409 else y
    y = 1.0 + x if abstop >= 0x7FF or abstop < 0x3C9 else y
    return 0.0 if x == -np.inf else y
