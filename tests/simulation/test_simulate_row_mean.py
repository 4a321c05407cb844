"""The simulator's row mean (the LEDs' mean temperature) equals NumPy's mean bit for bit."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.mark.parametrize("k", range(1, 9))
def test_row_mean_equals_numpy_mean_bit_for_bit(k):
    from nirglucose.simulation.simulator import row_mean

    rng = np.random.default_rng(k)
    x = rng.normal(20, 10, (4000, k)) * rng.choice([1.0, 1e-300, 1e300, 1e-5], (4000, k))
    x[rng.random((4000, k)) < 0.1] = -0.0
    x[rng.random((4000, k)) < 0.1] = 0.0
    x[:7] = -0.0
    for a in (x, np.asfortranarray(x)):
        assert row_mean(a).tobytes() == a.mean(axis=1).tobytes()
