"""The categorical draw equals NumPy's ``Generator.choice`` with ``p``, draw for draw.

:func:`nirglucose.simulation._random.categorical` replaces ``rng.choice(k, p=p,
size=n)`` in the simulator with the same uniform draws and a compiled look-up
(:func:`nirglucose.simulation.kernels.random_kernel.count_at_or_below`); ``compiled=False``
is ``searchsorted``, NumPy's own look-up.
"""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.simulation import _random

PROBS = {
    "fitzpatrick": (0.15, 0.3, 0.25, 0.15, 0.1, 0.05),
    "with zeros": (0.0, 0.5, 0.0, 0.5, 0.0),
    "one category": (1.0,),
    "uneven thirds": (1 / 3, 1 / 3, 1 / 3),
    "near the tolerance": (0.5, 0.5 + 1e-9),
}


@pytest.mark.parametrize("case", list(PROBS))
@pytest.mark.parametrize("compiled", [True, False])
def test_categorical_equals_choice(case, compiled):
    p = PROBS[case]
    for seed in range(5):
        want = np.random.default_rng(seed).choice(len(p), p=p, size=20_000)
        rng = np.random.default_rng(seed)
        got = _random.categorical(rng, p, 20_000, compiled=compiled)
        assert got.dtype == want.dtype == np.int64 and got.tobytes() == want.tobytes()
        # the same draws consumed: the generator's next value agrees
        assert rng.random() == np.random.default_rng(seed).random(20_001)[-1]


def test_count_at_or_below_equals_searchsorted_at_the_edges():
    from nirglucose.simulation.kernels.random_kernel import count_at_or_below

    cdf = np.array([0.0, 0.25, 0.25, 0.5, 1.0])
    u = np.array([0.0, np.nextafter(0.25, 0), 0.25, 0.5, np.nextafter(1.0, 0), 0.7])
    out = np.empty(len(u), np.int64)
    count_at_or_below(u, cdf, out)
    assert out.tolist() == cdf.searchsorted(u, side="right").tolist()


@pytest.mark.parametrize("bad", [(0.5, 0.6), (-0.1, 1.1), (np.nan, 1.0)])
def test_categorical_rejects_what_choice_rejects(bad):
    with pytest.raises(ValueError):
        np.random.default_rng(0).choice(len(bad), p=bad, size=3)
    with pytest.raises(ValueError):
        _random.categorical(np.random.default_rng(0), bad, 3)
