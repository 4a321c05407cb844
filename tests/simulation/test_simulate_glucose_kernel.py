"""The compiled glucose snapshots equal the NumPy reference bit for bit.

:func:`nirglucose.simulation.glucose.sample_glucose` runs, after its draws, one compiled
pass (:mod:`nirglucose.simulation.kernels.glucose_kernel`); ``compiled=False`` is the
NumPy form it replaces. Same draws, same bytes, over configurations that reflect often
at either limit.
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.simulation._random import RandomStreams
from nirglucose.simulation.glucose import reflect_into_range, sample_glucose

CASES = {
    "paper": ("paper", {}),
    "wearable": ("wearable", {}),
    "lab": ("lab", {}),
    "narrow range (reflected often, both ends)": ("paper", {"glucose.range_mgdl": [95.0, 130.0]}),
    "always stressed": ("paper", {"glucose.stress_prob": 1.0}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_glucose_equals_the_numpy_reference(case):
    preset, overrides = CASES[case]
    cfg = ng.resolve_config(preset, overrides)
    want_s, got_s = RandomStreams(4, 9), RandomStreams(4, 9)
    want = sample_glucose(cfg, 3000, 4, want_s, compiled=False)
    got = sample_glucose(cfg, 3000, 4, got_s)
    assert got_s.n_variates == want_s.n_variates
    assert list(got) == list(want)
    glucose = got["glucose_mgdl"]
    assert got.pop("diabetes_status").equals(want.pop("diabetes_status"))
    for col in want:
        a, b = np.asarray(want[col]), np.asarray(got[col])
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), col
    lo, hi = cfg.glucose.range_mgdl
    assert np.all((glucose >= lo) & (glucose <= hi))


def test_the_kernel_mod_is_numpy_mod():
    from nirglucose.simulation.kernels.glucose_kernel import _mod

    a = np.concatenate([np.random.default_rng(1).uniform(-2000, 2000, 5000),
                        [0.0, -0.0, 680.0, -680.0, 1360.0, -1e-300, 1e-300, np.nan]])
    want = np.mod(a, 680.0)
    got = np.array([_mod(x, 680.0) for x in a])
    assert got.tobytes() == want.tobytes()
    assert reflect_into_range(np.array([50.0]), 60.0, 400.0)[0] == 70.0
