"""Preset calibration: the raw glucose-NIR correlation of each regime.

Raw correlation = max over the four channels of |Pearson r(glucose_mgdl, log adc)|.
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.dataset import adc_columns

N_SNAPSHOTS = 20_000


def raw_correlation(frame) -> float:
    g = frame["glucose_mgdl"].to_numpy()
    return max(abs(np.corrcoef(g, np.log(frame[c].to_numpy(float)))[0, 1]) for c in adc_columns())


def _corr(preset, seed):
    return raw_correlation(ng.simulate(preset, N_SNAPSHOTS // 4, 4, seed).frame)


@pytest.mark.parametrize("preset", ["paper", "wearable"])
def test_paper_and_wearable_reproduce_the_study_correlation(preset):
    # the study's 0.21 +/- 0.02 (README, "Presets and calibration")
    r = np.mean([_corr(preset, s) for s in (0, 1, 2)])
    assert 0.19 <= r <= 0.23, r


def test_lab_preset_high_snr():
    assert _corr("lab", 0) > 0.8


def test_field_is_harsher_than_paper():
    assert _corr("field", 0) < _corr("paper", 0) - 0.05


@pytest.mark.parametrize("preset", ["physical"])
def test_literature_magnitudes_give_almost_no_raw_correlation(preset):
    assert _corr(preset, 0) < 0.06
