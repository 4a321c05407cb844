"""The truncated normal's compiled passes equal its NumPy form bit for bit.

:func:`nirglucose.simulation._random.truncated_normal` with one SD runs its passes before
and after SciPy's ``ndtri`` compiled (:mod:`nirglucose.simulation.kernels.random_kernel`);
``compiled=False`` is the NumPy form, the reference.
"""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.simulation import _random

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

