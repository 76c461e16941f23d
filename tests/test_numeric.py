"""vlref.numeric: ``exp`` and ``expm1`` written for vectorised lane loops, against libm (NumPy's ``exp`` /
``expm1``), and ``cast``."""

import decimal
import math
import platform

import numpy as np
import pytest
from hypothesis import given, strategies as st
from numba import njit

from vlref.numeric import (_GEXP_TABLE, arrays_do_not_overlap, cast, exp, expm1, fma, glibc_exp, glibc_exp_normal,
                           is_float64, prefer_wide_vectors)


@njit(cache=True)
def _both(xs, e, em1):
    for i in range(xs.size):
        e[i] = exp(xs[i])
        em1[i] = expm1(xs[i])


def _ulp(got, ref):
    return np.abs(got - ref) / np.spacing(np.abs(ref))


@pytest.mark.parametrize("lo, hi", [(-1e-9, 1e-9), (-0.4, 0.4), (-1.0, 1.0), (-40.0, 40.0), (-700.0, 700.0)])
def test_within_one_ulp_of_libm_for_exp_and_two_for_expm1(lo, hi):
    xs = np.random.default_rng(7).uniform(lo, hi, 200_000)
    e, em1 = np.empty_like(xs), np.empty_like(xs)
    _both(xs, e, em1)
    assert _ulp(e, np.exp(xs)).max() <= 1.0
    assert _ulp(em1, np.expm1(xs)).max() <= 2.0


@given(st.floats(-708.0, 709.0))
def test_any_argument_in_range(x):
    assert abs(exp(x) - math.exp(x)) <= np.spacing(math.exp(x))
    assert abs(expm1(x) - math.expm1(x)) <= 2 * np.spacing(abs(math.expm1(x)))


def test_small_arguments_keep_their_relative_accuracy():
    xs = np.array([1e-300, -1e-300, 1e-17, -3e-12, 2.5e-8, -0.34])
    e, em1 = np.empty_like(xs), np.empty_like(xs)
    _both(xs, e, em1)
    assert np.all(_ulp(em1, np.expm1(xs)) <= 1.0)


def test_edges_zero_overflow_underflow_and_nan():
    xs = np.array([0.0, -800.0, 800.0, -708.5, math.inf, -math.inf, math.nan])
    e, em1 = np.empty_like(xs), np.empty_like(xs)
    _both(xs, e, em1)
    assert e[0] == 1.0 and em1[0] == 0.0
    assert e[1] == 0.0 and em1[1] == -1.0
    assert e[2] == math.inf and em1[2] == math.inf
    assert e[3] == 0.0 and em1[3] == -1.0  # below 2^-1022: flushed
    assert e[4] == math.inf and e[5] == 0.0 and em1[5] == -1.0
    assert math.isnan(e[6]) and math.isnan(em1[6])


def test_float32_arguments_give_the_rounded_float64_value():
    xs = np.random.default_rng(3).uniform(-80.0, 80.0, 20_000).astype(np.float32)
    e, em1 = np.empty_like(xs), np.empty_like(xs)
    _both(xs, e, em1)
    assert e.dtype == np.float32
    x64 = xs.astype(np.float64)
    assert _ulp(e, np.exp(x64).astype(np.float32)).max() <= 1.0
    assert _ulp(em1, np.expm1(x64).astype(np.float32)).max() <= 1.0
    assert np.mean(e == np.exp(x64).astype(np.float32)) > 0.999


def test_cast_keeps_the_float_type():
    assert cast(np.float32(1.0), 2.5) == np.float32(2.5) and isinstance(cast(np.float32(1.0), 2.5), np.float32)
    assert isinstance(cast(1.0, 2), float)


@njit(fastmath=False)  # not cached: Numba inspects only code it compiled in this process
def _float64_only_shortcut(a):
    return a[0] if is_float64(a) else math.sqrt(a[0])


def test_is_float64_is_a_constant_of_each_compile():
    """True for a float64 array, False for float32, in Python and in njit code, where it is a constant: the
    float64 compile keeps no trace of the other branch (no square root), the float32 compile keeps it."""
    a64, a32 = np.array([4.0]), np.array([4.0], np.float32)
    assert is_float64(a64) and not is_float64(a32)
    assert _float64_only_shortcut(a64) == 4.0 and _float64_only_shortcut(a32) == 2.0
    ir = {sig[0].dtype.name: text for sig, text in _float64_only_shortcut.inspect_llvm().items()}
    assert "sqrt" not in ir["float64"] and "sqrt" in ir["float32"]


@njit(cache=True)
def _fma_and_product(a, b, c):
    return fma(a, b, c), a * b + c


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_fma_rounds_once(dtype):
    """(1 + e)(1 - e) - 1 = -e² exactly with one rounding; the product rounded first gives 0."""
    e = np.finfo(dtype).eps
    fused, unfused = _fma_and_product(dtype(1 + e), dtype(1 - e), dtype(-1))
    assert fused == -(np.float64(e) ** 2) and unfused == 0.0
    assert type(fused) is type(unfused)


@njit(fastmath=False)  # not cached: Numba inspects only code it compiled in this process
def _scaled_exp_wide(xs, out):
    prefer_wide_vectors()
    for i in range(xs.size):
        out[i] = exp(xs[i]) * 0.5 + xs[i]


@njit(fastmath=False)
def _scaled_exp(xs, out):
    for i in range(xs.size):
        out[i] = exp(xs[i]) * 0.5 + xs[i]


def test_prefer_wide_vectors_marks_the_function_and_keeps_the_bits():
    """The caller's LLVM function carries "prefer-vector-width"="512" (LLVM may use 512-bit vectors in its loops
    where the CPU has them); what each lane computes does not change."""
    xs = np.random.default_rng(5).uniform(-30.0, 30.0, 1003)
    wide, narrow = np.empty_like(xs), np.empty_like(xs)
    _scaled_exp_wide(xs, wide)
    _scaled_exp(xs, narrow)
    assert wide.tobytes() == narrow.tobytes()
    assert '"prefer-vector-width"="512"' in _scaled_exp_wide.inspect_llvm(_scaled_exp_wide.signatures[0])
    assert "prefer-vector-width" not in _scaled_exp.inspect_llvm(_scaled_exp.signatures[0])


@njit(fastmath=False)  # not cached, as above
def _gather_add_declared(table, index, out):
    arrays_do_not_overlap()
    for i in range(out.size):
        out[i] = out[i] + table[index[i]] * 0.5


@njit(fastmath=False)
def _gather_add(table, index, out):
    for i in range(out.size):
        out[i] = out[i] + table[index[i]] * 0.5


def _header(fn) -> str:
    return next(line for line in fn.inspect_llvm(fn.signatures[0]).splitlines()
                if line.startswith("define") and fn.__name__ in line)


def test_arrays_do_not_overlap_marks_the_arguments_and_keeps_the_bits():
    """Every pointer argument of the caller's LLVM function is ``noalias`` (a loop that stores to one array and
    gathers from another may then be vectorised); what each element computes does not change."""
    rng = np.random.default_rng(6)
    table, index = rng.random(97), rng.integers(0, 97, 1001)
    start = rng.random(1001)
    declared, plain = start.copy(), start.copy()
    _gather_add_declared(table, index, declared)
    _gather_add(table, index, plain)
    assert declared.tobytes() == plain.tobytes() == (start + table[index] * 0.5).tobytes()
    # the return and exception pointers are noalias in both; the arrays' pointers only where declared
    assert _header(_gather_add_declared).count("noalias") > _header(_gather_add).count("noalias") == 2


@njit(cache=True)
def _glibc_exps(xs, out):
    for i in range(xs.size):  # a lane loop: vectorised, as the bilateral blur's weights are
        out[i] = glibc_exp(xs[i])


@njit(cache=True)
def _glibc_exps_normal(xs, out):
    for i in range(xs.size):  # a lane loop, as the bilateral blur's
        out[i] = glibc_exp_normal(xs[i])


def test_glibc_exp_normal_has_glibc_exps_bits_on_its_range():
    # [-708, 512): glibc's main path and, for x <= -512, its special case's rescaled sum; the edges of both, the
    # arguments that glibc sends to 1 + x, and where the rescaled sum is closest to 2^-1022
    rng = np.random.default_rng(20)
    tiny = rng.uniform(-(2.0**-54), 2.0**-54, 1000)
    edges = [-708.0, np.nextafter(-708.0, 0.0), -512.0, np.nextafter(-512.0, 0.0), np.nextafter(-512.0, -1.0),
             np.nextafter(512.0, 0.0), 0.0, -0.0, 2.0**-54, -(2.0**-54), 5e-324, -5e-324]
    xs = np.concatenate([rng.uniform(-708.0, 512.0, 200_000), rng.uniform(-708.0, -500.0, 100_000), tiny, edges])
    got, ref = np.empty_like(xs), np.empty_like(xs)
    _glibc_exps_normal(xs, got)
    _glibc_exps(xs, ref)
    assert xs[got.view(np.int64) != ref.view(np.int64)].size == 0
    assert np.all(got[xs <= -512.0] >= 2.0**-1022)


def _libm_exp(x: float) -> float:
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


def _same_bits_as_libm(xs) -> np.ndarray:
    """The arguments whose ``glibc_exp`` differs from ``math.exp`` in any bit (NaN matches NaN)."""
    got = np.empty_like(xs)
    _glibc_exps(xs, got)
    ref = np.array([_libm_exp(x) for x in xs])
    return xs[(got.view(np.int64) != ref.view(np.int64)) & ~(np.isnan(got) & np.isnan(ref))]


LIBM_IS_GLIBC = platform.libc_ver()[0] == "glibc"
needs_glibc = pytest.mark.skipif(not LIBM_IS_GLIBC, reason="glibc_exp reproduces glibc's exp; this libm is another")


@needs_glibc
@pytest.mark.parametrize("lo, hi", [(-746.0, 0.0), (-1.0, 1.0), (-760.0, 720.0), (-745.2, -708.3), (-1100, -1000)])
def test_glibc_exp_has_libms_bits_over_each_range(lo, hi):
    # (-746, 0]: the depth weights' arguments; (-745.2, -708.3): results below 2^-1022 (glibc's extra rounding)
    assert _same_bits_as_libm(np.random.default_rng(17).uniform(lo, hi, 100_000)).size == 0


@needs_glibc
def test_glibc_exp_has_libms_bits_on_any_float64_and_at_the_edges():
    rng = np.random.default_rng(18)
    anything = rng.integers(0, 2**63, 100_000, dtype=np.int64).view(np.float64)
    edges = [0.0, -0.0, 2.0**-54, -(2.0**-54), 2.0**-55, 5e-324, 512.0, -512.0, np.nextafter(512.0, 0.0),
             np.nextafter(-512.0, 0.0), 1024.0, -1024.0, 709.782712893384, 709.7827128933841, -708.3964185322641,
             -745.1332191019411, -745.1332191019412, -746.0, math.inf, -math.inf, math.nan, 1e308, -1e308]
    assert _same_bits_as_libm(np.concatenate([anything, -anything, edges])).size == 0


@needs_glibc
def test_glibc_exp_has_libms_bits_where_the_reduction_rounds_a_tie():
    # x·128/ln2 within 40 ulp of a half-integer: where k = round(x·128/ln2) depends on how the product is rounded
    # (glibc's build fuses it with the shifter's addition)
    shift = 128 / math.log(2)
    xs = []
    for k in np.random.default_rng(19).integers(-95_000, 90_000, 100):
        x = (k + 0.5) / shift
        xs += [x + i * np.spacing(x) for i in range(-40, 41)]
    assert _same_bits_as_libm(np.array(xs)).size == 0


@needs_glibc
@given(st.floats(allow_nan=True, allow_infinity=True))
def test_glibc_exp_any_argument(x):
    got, ref = glibc_exp(x), _libm_exp(x)
    assert got == ref or (math.isnan(got) and math.isnan(ref))
    assert math.isnan(ref) or math.copysign(1.0, got) == math.copysign(1.0, ref)  # a NaN's sign: not kept by LLVM


def test_the_exp_table_by_square_roots_equals_the_table_by_powers():
    """vlref.numeric's table of ``2^(k/128)`` (seven 60-digit square roots of ``2^k``) against 60-digit powers
    ``2^(k/128)``, the definition's other route: the same 256 integers."""
    expected = np.empty(256, np.int64)
    with decimal.localcontext() as context:
        context.prec = 60
        for k in range(128):
            power = decimal.Decimal(2) ** (decimal.Decimal(k) / 128)
            head = float(power)
            expected[2 * k] = np.float64(float((power - decimal.Decimal(head)) / decimal.Decimal(head))).view(np.int64)
            expected[2 * k + 1] = np.float64(head).view(np.int64) - (k << 45)
    assert np.array_equal(_GEXP_TABLE, expected)
    assert _GEXP_TABLE[1] == np.float64(1.0).view(np.int64) and _GEXP_TABLE[0] == 0  # k = 0: 2^0 = 1 exactly
