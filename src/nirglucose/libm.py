"""The C library's elementary functions written out in numba: the same bits, inlined.

Today ``exp`` (:func:`exp_into` for arrays, vectorised; :func:`exp1` for one value), and
the bitcasts between a float64 and its bits that such code needs (:func:`float_bits`,
:func:`from_bits`).

The simulator's optics take two exponentials per snapshot, LED and band node (the share
of light in the dermis and the attenuation, :mod:`nirglucose.optics.kernels.band_kernel`).
Through :mod:`math` each is a call into the C library, which a compiled loop cannot
vectorise, and those calls were the largest cost of a snapshot after its random draws.
This module computes the same function inline, so numba (LLVM) vectorises the loop.

"The same function" is meant bit for bit: the simulator's outputs are hashed, and
:mod:`nirglucose.portable` fixes its elementary functions to the C library's. On x86-64
with AVX2 and FMA (x86-64-v3) glibc 2.28 and later runs ``__exp_fma``: the algorithm of
Szabolcs Nagy (Arm Optimized Routines, ``sysdeps/ieee754/dbl-64/e_exp.c``), compiled
with fused multiply-adds. :func:`exp_into` is that code operation for operation,
read from the machine code of glibc 2.36's ``__ieee754_exp_fma``: x = k ln2/N + r with
N = 128, exp(x) = 2^(k/N) exp(r), 2^(k/N) from a table of N entries, exp(r) - 1 by a
degree-5 polynomial, and the same eight fused multiply-adds (each one IEEE 754 operation,
correctly rounded: LLVM's ``llvm.fma`` is one instruction on an FMA CPU and a correctly
rounded library call elsewhere, so every x86-64 CPU gets these bits, which is more than
the C library itself gives: a CPU without FMA runs glibc's other build). Outside the
fast path (abs(x) < 2^-54, abs(x) >= 512, inf, NaN) glibc takes special cases: :func:`exp_into`
hands those values to the C library itself.

A test holds :func:`exp_into` equal to :func:`math.exp` on a million arguments and the
edges (``tests/test_libm.py``); the NumPy paths that the compiled kernels are
held to keep calling :mod:`nirglucose.portable`. (Numba's on-disk cache keys a kernel
by its own file only: after editing this module, delete the ``__pycache__/*.nbi`` and
``*.nbc`` files of the kernels that inline it, or they keep the old code.)

References
----------
.. [1] Nagy, S. (2018). ``e_exp.c`` and ``exp_data.c``, Arm Optimized Routines
   (MIT / Apache-2.0), in the GNU C Library since 2.28; the constants below are
   ``__exp_data`` of that file (``invln2N``, ``shift``, ``negln2hiN``, ``negln2loN``,
   ``poly``) and its table is 2^(i/N) as below.
.. [2] IEEE Std 754-2019, clause 5.4.1: fusedMultiplyAdd is one correctly rounded
   operation.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext
from fractions import Fraction

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

__all__ = ["exp", "exp1", "exp_into", "exp_table", "float_bits", "from_bits"]

#: log2 of the table's size N (``EXP_TABLE_BITS`` of [1]_).
TABLE_BITS = 7
_N = 1 << TABLE_BITS
#: N / ln 2, the shift 1.5 x 2^52 that rounds to an integer, and -ln 2 / N split in a
#: high part (trailing zero bits, so k x it is exact) and the rest ([1]_, ``__exp_data``).
_INVLN2N = float.fromhex("0x1.71547652b82fep7")
_SHIFT = float.fromhex("0x1.8p52")
_NEGLN2HIN = float.fromhex("-0x1.62e42fefa0000p-8")
_NEGLN2LON = float.fromhex("-0x1.cf79abc9e3b3ap-47")
#: exp(r) - 1 - r ~ C2 r^2 + C3 r^3 + C4 r^4 + C5 r^5 on abs(r) <= ln 2 / 2N ([1]_, ``poly``).
_C2 = float.fromhex("0x1.ffffffffffdbdp-2")
_C3 = float.fromhex("0x1.555555555543cp-3")
_C4 = float.fromhex("0x1.55555cf172b91p-5")
_C5 = float.fromhex("0x1.1111167a4d017p-7")
#: The bits of the shift, as an integer: k = bits(x N/ln2 + shift) - this.
_SHIFT_BITS = int(np.float64(_SHIFT).view(np.int64))
#: The fast path's exponent field range: 2^-54 <= abs(x) < 512 ([1]_: ``abstop - top12(0x1p-54)
#: < top12(512) - top12(0x1p-54)``).
_TOP_LOW, _TOP_SPAN = 0x3C9, 0x3F


def exp_table() -> np.ndarray:
    """The table of [1]_, (2N,) int64: for i < N, entry 2i is the bits of ``tail`` and
    entry 2i + 1 the bits of ``scale`` less i << (52 - 7), where scale is 2^(i/N)
    rounded to a double and tail = 2^(i/N) / scale - 1 rounded (so scale (1 + tail)
    is 2^(i/N) to about 2^-106).

    Computed here from its definition (50 significant digits, then rounded once to the
    nearest double); it equals glibc 2.36's ``__exp_data.tab`` entry for entry (a test
    holds it to that table's digest).

    Examples
    --------
    >>> t = exp_table()
    >>> float(t[:2].view(np.float64)[1]), int(t[0])  # 2^0: scale 1, tail 0
    (1.0, 0)
    """
    out = np.empty(2 * _N, np.int64)
    with localcontext() as ctx:
        ctx.prec = 50
        for i in range(_N):
            exact = Decimal(2) ** (Decimal(i) / _N)
            scale = float(exact)  # correctly rounded (Decimal -> float)
            tail = float(Fraction(exact) / Fraction(scale) - 1)
            out[2 * i] = np.float64(tail).view(np.int64)
            out[2 * i + 1] = int(np.float64(scale).view(np.int64)) - (i << (52 - TABLE_BITS))
    return out


_TABLE = exp_table()


@intrinsic
def _fma(typingctx, a, b, c):
    """a b + c rounded once (``llvm.fma.f64``)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(fn, args)

    return sig, codegen


@intrinsic
def float_bits(typingctx, x):
    """The IEEE 754 bits of a float64 as an int64 (a bitcast: free, and vectorisable)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def from_bits(typingctx, i):
    """The float64 with the given IEEE 754 bits (a bitcast)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@njit(cache=True, inline="always")
def _on_path(x):
    """Whether ``__exp_fma`` [1]_ takes its fast path: 2^-54 <= abs(x) < 512."""
    top = (float_bits(x) >> 52) & 0x7FF
    return (top >= _TOP_LOW) & (top < _TOP_LOW + _TOP_SPAN)


@njit(cache=True, inline="always")
def _reduce(x):
    """``(k, r)``: x = k ln2/N + r, k = round(x N / ln 2) read from the shift's bits and r
    in two fused steps (ln2/N in a high and a low part)."""
    kd = _fma(x, _INVLN2N, _SHIFT)
    k = float_bits(kd) - _SHIFT_BITS
    kd = kd - _SHIFT
    r = _fma(kd, _NEGLN2HIN, x)
    return k, _fma(kd, _NEGLN2LON, r)


@njit(cache=True, inline="always")
def _scale_bits(k):
    """``(tail, bits of scale)``: 2^(k/N) = scale (1 + tail), from the table."""
    j = 2 * (k & (_N - 1))
    return from_bits(_TABLE[j]), _TABLE[j + 1] + (k << (52 - TABLE_BITS))


@njit(cache=True, inline="always")
def _finish(r, tail, scale_bits):
    """scale + scale (tail + exp(r) - 1), exp(r) - 1 by the polynomial."""
    p23 = _fma(r, _C3, _C2)
    p45 = _fma(r, _C5, _C4)
    r2 = r * r
    tmp = _fma(r2, p23, r + tail)
    tmp = _fma(r2 * r2, p45, tmp)
    scale = from_bits(scale_bits)
    return _fma(scale, tmp, scale)


@njit(cache=True, inline="always")
def exp1(x):  # pragma: no cover - compiled
    """exp(x) of one value with the bits of the C library's ``exp``, for compiled loops
    that cannot vectorise anyway (they call other C-library functions): the table
    look-up inline instead of a call, about five times cheaper."""
    if not _on_path(x):
        return math.exp(x)
    k, r = _reduce(x)
    tail, bits = _scale_bits(k)
    return _finish(r, tail, bits)


@njit(cache=True, nogil=True)
def exp_into(x, out, r, tail, k):  # pragma: no cover - compiled
    """``out[i] = exp(x[i])`` with the bits of the C library's ``exp`` (1-D float64).

    ``out`` must not be ``x``; ``r`` and ``tail`` (float64) and ``k`` (int64) are work
    arrays of at least ``x``'s length (a caller looping over many rows allocates them
    once). Three loops free of calls and branches, which LLVM vectorises (a table
    look-up between them, which it would not: gathers): x = k ln2/N + r; 2^(k/N) from
    the table; then exp(r) - 1 and the product, each step as ``__exp_fma`` [1]_ does it.
    Values off the fast path (abs(x) < 2^-54, abs(x) >= 512, inf, NaN) are computed as if
    x were 0 and then replaced by the C library's own ``exp`` (:mod:`math`).
    """
    n = x.shape[0]
    on_path = True
    for i in range(n):
        ok = _on_path(x[i])
        on_path &= ok
        k[i], r[i] = _reduce(x[i] if ok else 0.0)
    for i in range(n):
        tail[i], k[i] = _scale_bits(k[i])
    for i in range(n):
        out[i] = _finish(r[i], tail[i], k[i])
    if not on_path:  # the C library's special cases, value by value
        for i in range(n):
            if not _on_path(x[i]):
                out[i] = math.exp(x[i])


def exp(x) -> np.ndarray:
    """``exp(x)`` of a float64 array with the bits of the C library's ``exp``
    (:func:`exp_into` with its work arrays allocated here).

    Examples
    --------
    >>> x = np.array([-1.0, 0.0, 1e-300, 0.5, 710.0, -np.inf])
    >>> y = exp(x)
    >>> bool((y[:4] == np.array([math.exp(v) for v in x[:4]])).all()), float(y[4]), float(y[5])
    (True, inf, 0.0)
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    flat = x.reshape(-1)
    out = np.empty_like(flat)
    n = flat.shape[0]
    exp_into(flat, out, np.empty(n), np.empty(n), np.empty(n, np.int64))
    return out.reshape(x.shape)
