"""Simulation-based calibration in `make test`: 30 synthetic devices (the benchmark runs
100 with the default training budget, studies/twin_calibration.py)."""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.twin.calibration import calibrate
from nirglucose.twin.device import device_of
from nirglucose.twin.inference import load_or_train
from nirglucose.twin.parameters import fitted_parameters

from .conftest import TEST_SETTINGS

N_DEVICES = 30


@pytest.fixture(scope="module")
def sbc(gain11_file, twin_cache, twin11):
    mp = pytest.MonkeyPatch()
    mp.setenv("NIRGLUCOSE_CACHE", str(twin_cache))
    try:
        device = device_of(ng.load_dataset(gain11_file, adc_bits=10), adc_bits=10)
        params = fitted_parameters(device)
        est, cached = load_or_train(device, params, TEST_SETTINGS)
    finally:
        mp.undo()
    assert cached  # the session's estimator (twin11 trained it)
    return calibrate(device, params, est, n_devices=N_DEVICES, n_draws=200, seed=1)


def test_identified_parameters_cover_the_truth(sbc):
    assert sbc["n_devices"] >= N_DEVICES - 2
    ident = {k: v for k, v in sbc["parameters"].items() if v["identified"]}
    # the code level and the glucose gain are identified on most devices
    assert "leds.emitters.0.power_mw" in ident and "leds.emitters.0.glucose_gain" in ident
    for key, v in ident.items():
        # 30 devices: a calibrated 90 % interval covers 23-30 of them (99 % binomial)
        assert v["coverage"] >= 0.75, (key, v["coverage"])


def test_ranks_are_not_piled_at_the_ends(sbc):
    """An overconfident or biased posterior puts the truth's rank at 0 or n_draws."""
    for key, v in sbc["parameters"].items():
        ranks = np.asarray(v["ranks"])
        ends = np.mean((ranks == 0) | (ranks == sbc["n_draws"]))
        assert ends < 0.25, (key, ends)

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
