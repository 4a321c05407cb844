"""The compiled measurement layer equals the NumPy reference bit for bit.

:func:`nirglucose.simulation.measurement.measure_physiology` and
:func:`~nirglucose.simulation.measurement.measure_ppg` run, after their draws, compiled
passes (:mod:`nirglucose.simulation.kernels.measurement_kernel`); ``compiled=False`` is
the NumPy form they replace. Same draws, same bytes, with exact and measured physiology
and noise scaled until the clips bite; the kernel's clip is NumPy's, signed zeros and
NaN included.
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.simulation._random import RandomStreams
from nirglucose.simulation.measurement import _TRUTH, measure_physiology, measure_ppg

CASES = {
    "paper": ("paper", {}),
    "wearable": ("wearable", {}),
    "exact": ("paper", {"device.physiology": "exact"}),
    "scaled noise (clips bite)": ("paper", {"noise_scale": 50.0}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_measurement_equals_the_numpy_reference(case):
    cfg = ng.resolve_config(*CASES[case])
    rng = np.random.default_rng(5)
    n = 6000
    truth = {col: rng.uniform(-5.0, 300.0, n) for col in _TRUTH.values()}
    truth["true_fitzpatrick_type"] = rng.integers(1, 7, n)
    truth["true_age_yr"] = rng.uniform(18.0, 90.0, n)
    for fn, args in ((measure_physiology, (truth,)),
                     (measure_ppg, (rng.uniform(-0.1, 2.0, n), rng.uniform(-0.2, 1.2, n)))):
        want_s, got_s = RandomStreams(4, 9), RandomStreams(4, 9)
        want = fn(cfg, *args, want_s, compiled=False)
        got = fn(cfg, *args, got_s)
        assert got_s.n_variates == want_s.n_variates
        assert list(got) == list(want)
        for col in want:
            a, b = np.asarray(want[col]), np.asarray(got[col])
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), (fn.__name__, col)


def test_the_kernel_clip_is_numpy_clip():
    from nirglucose.simulation.kernels.measurement_kernel import measured_row

    x = np.tile([-0.0, 0.0, -1.0, 1.0, 100.0, 100.5, np.nan, np.inf, -np.inf, -1e-300], 100)
    for lo, hi in ((0.0, 100.0), (-0.0, 100.0), (0.0, 0.0), (-0.0, -0.0), (1.0, 1.0),
                   (-1.0, -0.0), (-1.0, 0.0)):
        want = np.clip(x.copy(), lo, hi)
        got = x.copy()
        measured_row(got, 1.0, np.full(len(x), -0.0), lo, hi)  # x 1 + -0.0 is x
        assert want.tobytes() == got.tobytes(), (lo, hi)
