"""Floating point that gives the same bits on every x86-64 CPU.

Two things in a NumPy program change the last bits of a result with the CPU that runs
it, though the code, the seed and the installed packages are the same:

* **OpenBLAS picks its matrix kernel from the CPU** (``Haswell``, ``SkylakeX``, ``Zen``,
  ``Prescott``, ...; ``threadpoolctl.threadpool_info()`` shows which, and
  ``OPENBLAS_CORETYPE`` overrides it). The kernels sum a matrix product in different
  orders and with or without fused multiply-adds, so ``a @ b`` differs by an ulp or two.
* **NumPy picks its elementary-function loops from the CPU** (``np.show_runtime()``:
  ``X86_V2`` ... ``X86_V4``, ``AVX512_ICL``): on a CPU with AVX-512, ``np.exp``,
  ``np.log``, ``np.power``, ``np.log10``, ``np.tanh``, ``np.arctan``, ... run NumPy's own
  vectorised approximations (SVML and hand-written AVX-512 code), elsewhere the C
  library's. Both are accurate to about one ulp, but they are different functions
  (``NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL"`` shows it on an AVX-512 machine).

An ulp is nothing physically, but a dataset's bytes are its identity: a seed must give
the same file on a laptop and on a CI runner. The simulator and the optics therefore
compute through this module:

* :func:`dot_last` and :func:`matmul` sum products in index order with NumPy's
  element-wise multiply and add, each correctly rounded by IEEE 754 whatever the SIMD
  width, never a fused multiply-add; no BLAS.
* :func:`exp`, :func:`log`, ... are NumPy ufuncs compiled by numba around Python's
  :mod:`math` functions, which call the C library's scalar routines (glibc's, picked
  once per CPU *family*: every x86-64 CPU with AVX2 and FMA, x86-64-v3, runs the same
  code), never NumPy's per-CPU loops.

Sums (``np.sum``), ``sqrt``, ``+ - * /`` and NumPy's random generators are already
exact or CPU-independent and need nothing here (NumPy's random distributions call the C
library too).

References
----------
.. [1] IEEE Std 754-2019, *Standard for Floating-Point Arithmetic*, clause 5.4: the basic
   operations (+, -, x, /, sqrt) are correctly rounded, hence identical on every
   conforming machine; elementary functions (clause 9) are only recommended, not
   required, to be.
.. [2] NumPy, "CPU/SIMD optimizations", https://numpy.org/doc/stable/reference/simd/
   (runtime dispatch of ufunc loops by CPU feature).
.. [3] OpenBLAS, ``OPENBLAS_CORETYPE`` (runtime kernel selection by CPU; README,
   "Setting the number of threads / Runtime CPU detection").
"""

from __future__ import annotations

import math

import numpy as np


def dot_last(x, w) -> np.ndarray:
    """Sum of ``x * w`` over the last axis, in index order, without BLAS.

    ``x`` and ``w`` broadcast against each other; the result has their broadcast shape
    less the last axis. Each product and each partial sum is one correctly rounded
    IEEE 754 operation [1]_, so the result is the same on every CPU (``np.dot`` and
    ``@`` call BLAS, whose kernel and summation order depend on the CPU).

    Examples
    --------
    >>> dot_last(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([10.0, 1.0]))
    array([12., 34.])
    """
    x = np.asarray(x, dtype=float)
    w = np.asarray(w, dtype=float)
    k = x.shape[-1]
    if w.shape[-1] != k:
        raise ValueError(f"dot_last: last axes differ ({k} and {w.shape[-1]})")
    shape = np.broadcast_shapes(x.shape[:-1], w.shape[:-1])
    if shape == () and k:
        # one long vector (a band integral over a fine grid): the running sum in C,
        # the same operations in the same order as the loop below
        return np.asarray(np.add.accumulate(x * w)[-1])
    out = np.zeros(shape)
    if k:
        np.multiply(x[..., 0], w[..., 0], out=out)
        term = np.empty(shape)
        for i in range(1, k):
            np.multiply(x[..., i], w[..., i], out=term)
            out += term
    return out


def matmul(a, b) -> np.ndarray:
    """``a @ b`` for a 2-D (or 1-D) ``b``, summed in index order (:func:`dot_last`).

    Examples
    --------
    >>> matmul(np.array([[1.0, 2.0]]), np.array([[1.0, 0.0], [0.5, 1.0]]))
    array([[2., 2.]])
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if b.ndim == 1:
        return dot_last(a, b)
    if b.ndim != 2:
        raise ValueError(f"matmul: b must be 1-D or 2-D, got {b.ndim}-D")
    return dot_last(a[..., None, :], b.T)


#: Elementary functions routed through the C library (NumPy name -> :mod:`math` name).
UFUNC_NAMES = {
    "exp": "exp",
    "expm1": "expm1",
    "log": "log",
    "log1p": "log1p",
    "log10": "log10",
    "sin": "sin",
    "cos": "cos",
    "tanh": "tanh",
    "arctan": "atan",
    "power": "pow",
}

__all__ = ["dot_last", "matmul", "UFUNC_NAMES", *UFUNC_NAMES]


def _compile(name: str) -> np.ufunc:
    """The NumPy ufunc for ``name`` (a key of :data:`UFUNC_NAMES`), compiled by numba
    around the :mod:`math` function."""
    import numba  # heavy: compiled on first use, so ``import nirglucose`` does not need it

    fn = getattr(math, UFUNC_NAMES[name])

    def binary(x, y):
        return fn(x, y)

    def unary(x):
        return fn(x)

    kernel, signature = ((binary, "float64(float64, float64)") if name == "power"
                         else (unary, "float64(float64)"))
    kernel.__name__ = kernel.__qualname__ = name
    return numba.vectorize([signature])(kernel).ufunc


def __getattr__(name: str) -> np.ufunc:
    """``exp``, ``log``, ..., ``power``: compiled on first access, then a plain module
    attribute (a real NumPy ufunc: ``out=``, ``where=``, broadcasting as ``np.exp``).

    Examples
    --------
    >>> from nirglucose import portable
    >>> float(portable.exp(0.0)), float(portable.power(10.0, 2.0))
    (1.0, 100.0)
    """
    if name not in UFUNC_NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = ufunc = _compile(name)
    return ufunc
