"""Permutation importance per wavelength, with and without reference codes."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from nirglucose.dataset import Dataset
from nirglucose.evaluation.importance import permutation_importance
from nirglucose.exceptions import DataError


class _ReadsOneChannel:
    """Predicts glucose from adc_940 alone (a known importance pattern)."""

    def predict(self, data):
        return data.frame["adc_940"].to_numpy(float) / 4.0


def _frame(with_refs: bool) -> pd.DataFrame:
    rng = np.random.default_rng(0)
    n = 50
    adc = rng.integers(300, 900, size=(n, 2))
    f = pd.DataFrame({"adc_850": adc[:, 0], "adc_940": adc[:, 1]})
    f["glucose_mgdl"] = f["adc_940"] / 4.0
    if with_refs:
        f["adc_ref_850"], f["adc_ref_940"] = 1000, 1000
    return f


@pytest.mark.parametrize("with_refs", [True, False])
def test_only_the_channel_the_model_reads_matters(with_refs):
    out = permutation_importance(_ReadsOneChannel(), Dataset(_frame(with_refs)), n_repeats=3)
    inc = dict(zip(out.wavelength_nm, out.rmse_increase_mgdl, strict=True))
    assert inc[850.0] == 0.0 and inc[940.0] > 10.0


def test_a_wavelength_without_codes_is_one_line():
    with pytest.raises(DataError, match="no column 'adc_1050'"):
        permutation_importance(_ReadsOneChannel(), Dataset(_frame(True)), wavelengths_nm=[1050])
