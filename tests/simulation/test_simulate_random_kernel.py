"""The truncated normal's compiled pass equals its NumPy form bit for bit.

:func:`nirglucose.simulation._random.truncated_normal` with one SD runs one compiled pass
(:mod:`nirglucose.simulation.kernels.random_kernel`), its normal CDF
(:func:`~nirglucose.simulation.kernels.random_kernel.ndtr`) and inverse
(:func:`~nirglucose.simulation.kernels.random_kernel.ndtri`) held equal to SciPy's
``ndtr`` and ``ndtri`` bit for bit; ``compiled=False`` is the NumPy form, the reference.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit
from scipy.special import ndtr as scipy_ndtr
from scipy.special import ndtri as scipy_ndtri

from nirglucose.simulation import _random
from nirglucose.simulation.kernels import random_kernel as rk

N = 30_000
_RNG = np.random.default_rng(12)
_GROUP = np.repeat(np.arange(N // 3), 3)

#: (mean, sd, low, high, group): one mean, one per value, one per group; limits near
#: and far from the mean (probabilities clipped at 1e-15 and 1 - 1e-15), one-sided mass.
CASES = {
    "scalar mean": (np.asarray(70.0), 5.0, 40.0, 150.0, None),
    "mean per value": (_RNG.uniform(40, 150, N), 7.0, 40.0, 150.0, None),
    "mean per group": (_RNG.uniform(10, 40, N // 3), 2.0, 10.0, 40.0, _GROUP),
    "mean at the upper limit": (np.asarray(1.0), 3.0, 0.5, 1.0, None),
    "far tails (clipped probabilities)": (_RNG.uniform(-50, 50, N), 0.5, -1.0, 1.0, None),
    "tiny range": (np.asarray(0.0), 1.0, -1e-12, 1e-12, None),
    # a and b in every branch of ndtr: (limit - mean) / sd over (-70, 70), both tails
    # (0 below about -38.5, 1 above about 8.3) included
    "CDF tails, mean per value": (_RNG.uniform(-60, 60, N), 1.0, -10.0, 10.0, None),
    "CDF tails, mean per group": (_RNG.uniform(-60, 60, N // 3), 1.0, -10.0, 10.0, _GROUP),
    "CDF lower tails, one mean": (np.asarray(0.0), 1.0, -39.0, 0.5, None),
    "CDF upper tails, one mean": (np.asarray(0.0), 1.0, -2.0, 12.0, None),
    "CDF both tails, one mean": (np.asarray(1.0), 0.25, -7.0, 40.0, None),
}


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_truncated_normal_equals_the_numpy_form(case):
    mean, sd, low, high, group = CASES[case]
    u = np.random.default_rng(3).random(N)
    want = _random._truncated_normal_scalar_sd(u, mean, sd, low, high, N, group,
                                               compiled=False)
    got = _random._truncated_normal_scalar_sd(u, mean, sd, low, high, N, group)
    assert got.dtype == want.dtype == np.float64 and got.shape == want.shape
    assert got.tobytes() == want.tobytes()
    assert np.all((got >= low) & (got <= high))


def test_truncated_normal_through_a_stream_is_unchanged_by_the_kernels():
    # the public entry draws one uniform per value either way
    streams = _random.RandomStreams(5, 2)
    a = _random.truncated_normal(streams("x"), 120.0, 15.0, 60.0, 400.0, size=1000)
    assert streams.n_variates == 1000
    u = _random.RandomStreams(5, 2)("x").random(size=1000)
    b = _random._truncated_normal_scalar_sd(u, np.asarray(120.0), 15.0, 60.0, 400.0, 1000,
                                            compiled=False)
    assert a.tobytes() == b.tobytes()


@njit
def _ndtri_each(y, out):  # pragma: no cover - compiled
    for i in range(y.shape[0]):
        out[i] = rk.ndtri(y[i])


def _assert_as_scipys(x, scipy_fn, forms):
    """Each compiled form (value by value, by blocks) gives SciPy's bits on ``x``."""
    want = scipy_fn(x)
    for each in forms:
        got = np.empty_like(x)
        each(x, got)
        differ = got.view(np.uint64) != want.view(np.uint64)
        assert not differ.any(), (each, x[differ][:5], got[differ][:5], want[differ][:5])


def _assert_ndtri_is_scipys(y):
    """Value by value (:func:`rk.ndtri`) and by blocks (:func:`rk.ndtri_into`, its
    vectorised central part), SciPy's bits."""
    _assert_as_scipys(y, scipy_ndtri, (_ndtri_each, rk.ndtri_into))


def _neighbours(x, n):
    """x and the n doubles either side of it."""
    out = [x]
    below = above = x
    for _ in range(n):
        below, above = np.nextafter(below, -np.inf), np.nextafter(above, np.inf)
        out += [below, above]
    return out


def test_ndtri_equals_scipys_on_a_million_uniforms():
    rng = np.random.default_rng(20)
    _assert_ndtri_is_scipys(rng.random(1_000_000))
    # the tails, log-uniform down to 1e-300 and up to 1 - 1e-16
    _assert_ndtri_is_scipys(np.exp(rng.uniform(math.log(1e-300), math.log(0.14), 200_000)))
    _assert_ndtri_is_scipys(1.0 - np.exp(rng.uniform(math.log(1e-16), math.log(0.14),
                                                     200_000)))


def test_ndtri_equals_scipys_at_the_edges():
    e = math.exp(-2.0)  # where the central approximation hands over to the tails
    tail_split = math.exp(-32.0)  # sqrt(-2 log y) = 8: the tail's P1/Q1 to P2/Q2
    split_neighbours = _neighbours(tail_split, 300)
    t = [math.sqrt(-2.0 * math.log(y)) for y in split_neighbours]
    assert min(t) < 8.0 <= max(t)  # both of the tail's approximations are reached
    y = np.array([
        0.0, -0.0, 1.0, 0.5, 5e-324, 1e-300, 1e-15, 1 - 1e-15, _random._P_EDGE,
        1 - _random._P_EDGE, 2.2250738585072014e-308, np.nextafter(1.0, 0.0),
        *_neighbours(e, 3), *_neighbours(1 - e, 3), *split_neighbours,
        # outside [0, 1] and NaN: NaN as SciPy gives it (a NaN input's sign flipped)
        -1e-300, np.nextafter(1.0, 2.0), 2.0, np.inf, -np.inf, np.nan, -np.nan,
    ])
    _assert_ndtri_is_scipys(y)


@njit
def _ndtr_each(t, out):  # pragma: no cover - compiled
    for i in range(t.shape[0]):
        out[i] = rk.ndtr(t[i])


def _assert_ndtr_is_scipys(t):
    """Value by value (:func:`rk.ndtr`) and by blocks (:func:`rk.ndtr_into`, its
    branches as choices), SciPy's bits."""
    _assert_as_scipys(t, scipy_ndtr, (_ndtr_each, rk.ndtr_into))


def test_ndtr_equals_scipys_on_a_million_values():
    rng = np.random.default_rng(21)
    _assert_ndtr_is_scipys(rng.uniform(-40.0, 40.0, 500_000))
    _assert_ndtr_is_scipys(rng.uniform(-3.0, 3.0, 500_000))


def test_ndtr_equals_scipys_at_the_edges():
    # the thresholds in x = a / sqrt(2) (a M_SQRT1_2): erf to erfc at |x| = 1, erfc's
    # P/Q to R/S at |x| = 8, erfc's underflow to 0 at x^2 = MAXLOG (a about -37.68; just
    # above it, subnormal results); each with its neighbours, so both sides are reached
    split = [x / rk._SQRT1_2 for x in (1.0, 8.0, math.sqrt(rk._MAXLOG))]
    t = [v for x in split for s in (1.0, -1.0) for v in _neighbours(s * x, 40)]
    x = np.abs(np.array(t) * rk._SQRT1_2)
    for edge in (1.0, 8.0):
        assert (x < edge).any() and (x >= edge).any()
    assert (-x * x < -rk._MAXLOG).any() and (-x * x >= -rk._MAXLOG).any()
    cdf = scipy_ndtr(np.array(t))
    assert (cdf == 0.0).any() and ((cdf > 0.0) & (cdf < 2.2250738585072014e-308)).any()
    t += list(np.linspace(-38.6, -37.0, 4001))
    t += [
        0.0, -0.0, np.inf, -np.inf, np.nan, -np.nan, 5e-324, -5e-324, 1e-300, -1e-300,
        2.2250738585072014e-308, -2.2250738585072014e-308, 1e300, -1e300, 1.7976931348623157e308,
        -1.7976931348623157e308, *_neighbours(0.0, 3), *_neighbours(38.5, 3),
        *_neighbours(-38.5, 3), *_neighbours(-37.519379347, 3),  # Cephes' UTHRESH
    ]
    _assert_ndtr_is_scipys(np.array(t))


def _cdf_limits(rng, n):
    """n pairs a <= b of normal CDF values: from the far lower tail, the middle and the
    far upper tail, so that a + u (b - a) falls below 1e-15 and above 1 - 1e-15 too."""
    def draw():
        tiny = np.exp(rng.uniform(math.log(1e-30), math.log(1e-3), n))
        pick = rng.integers(0, 3, n)
        return np.choose(pick, [tiny, rng.random(n), 1.0 - tiny])

    v, w = draw(), draw()
    return np.minimum(v, w), np.maximum(v, w)


@pytest.mark.parametrize("mode", [0, 1, 2])
def test_fused_kernel_equals_the_three_passes(mode):
    """``mode`` 0: one a, b and mean; 1: one per value; 2: one per group (the module
    docstring of :mod:`nirglucose.simulation.kernels.random_kernel`)."""
    n = 30_000
    rng = np.random.default_rng(30 + mode)
    u = rng.random(n)
    n_par = {0: 1, 1: n, 2: n // 4}[mode]
    group = rng.integers(0, n_par, n) if mode == 2 else np.empty(0, np.int64)
    sd, low, high = 1.5, -2.0, 2.5
    if mode == 0:  # values in 0.25 + 1.5 (-2.05, 2.33): clipped at both limits too
        mean, a, b = np.array([0.25]), np.array([0.02]), np.array([0.99])
    else:
        mean, (a, b) = rng.uniform(-3.0, 3.0, n_par), _cdf_limits(rng, n_par)
    p_low, p_high = _random._P_EDGE, 1 - _random._P_EDGE
    want = np.empty(n)
    rk.probabilities(u, a, b, group, mode, p_low, p_high, want)
    clipped = (want == p_low).any() and (want == p_high).any()
    scipy_ndtri(want, out=want)
    rk.scale_and_clip(want, sd, mean, group, mode, low, high)
    got = np.empty(n)
    rk.truncated_normal(u, a, b, group, mode, p_low, p_high, sd, mean, low, high, got)
    assert got.tobytes() == want.tobytes()
    assert (got == low).any() and (got == high).any() and ((got > low) & (got < high)).any()
    assert clipped or mode == 0
