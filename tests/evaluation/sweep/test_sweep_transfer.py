"""Calibration transfer: per-channel bias and slope/bias in absorbance."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from nirglucose.evaluation.sweep.transfer import absorbance, fit_transfer
from nirglucose.exceptions import ConfigError, DataError


def _frame(a_by_channel: dict[str, np.ndarray], ref: float = 3000.0) -> pd.DataFrame:
    cols = {}
    for w, a in a_by_channel.items():
        cols[f"adc_{w}"] = ref * 10.0 ** (-np.asarray(a))
        cols[f"adc_ref_{w}"] = np.full(len(a), ref)
    return pd.DataFrame(cols)


def test_absorbance_worked_example():
    f = pd.DataFrame({"adc_850": [300.0, 30.0], "adc_ref_850": [3000.0, 3000.0]})
    np.testing.assert_allclose(absorbance(f)["850"], [1.0, 2.0])


def test_slope_bias_recovers_a_known_line_and_maps_readings_back():
    rng = np.random.default_rng(0)
    a_master = {"850": rng.uniform(0.2, 0.6, 8), "940": rng.uniform(0.3, 0.9, 8)}
    # the unit reads A_unit = (A_master - b) / s per channel
    line = {"850": (0.05, 1.2), "940": (-0.03, 0.9)}
    a_unit = {w: (a - line[w][0]) / line[w][1] for w, a in a_master.items()}
    t = fit_transfer(_frame(a_unit), _frame(a_master), "slope-bias")
    np.testing.assert_allclose(t.bias, [0.05, -0.03], atol=1e-12)
    np.testing.assert_allclose(t.slope, [1.2, 0.9], atol=1e-12)
    # new readings of the unit come out as the master's codes
    new_master = {"850": np.array([0.25, 0.5]), "940": np.array([0.4, 0.8])}
    new_unit = _frame({w: (a - line[w][0]) / line[w][1] for w, a in new_master.items()})
    out = t.apply(new_unit, 12)
    np.testing.assert_allclose(out["adc_850"], _frame(new_master)["adc_850"], rtol=1e-10)
    np.testing.assert_allclose(out["adc_940"], _frame(new_master)["adc_940"], rtol=1e-10)
    assert out["adc_ref_850"].equals(new_unit["adc_ref_850"])


def test_bias_fits_the_mean_offset_only():
    a = np.array([0.2, 0.3, 0.5])
    t = fit_transfer(_frame({"850": 1.1 * a}), _frame({"850": a + 0.1}), "bias")
    assert t.slope[0] == 1.0
    assert t.bias[0] == pytest.approx(np.mean(a + 0.1 - 1.1 * a))


def test_codes_stay_in_the_adc_range():
    t = fit_transfer(_frame({"850": [0.1, 0.2]}), _frame({"850": [5.0, 5.1]}), "bias")
    out = t.apply(_frame({"850": [0.1]}), 12)
    assert out["adc_850"].iloc[0] == 1.0  # clipped at the lowest valid code


def test_bad_inputs():
    f = _frame({"850": [0.1, 0.2]})
    with pytest.raises(ConfigError, match="transfer method"):
        fit_transfer(f, f, "pds-7")
    with pytest.raises(DataError, match="pair row by row"):
        fit_transfer(f, _frame({"850": [0.1, 0.2, 0.3]}))
    with pytest.raises(DataError, match="at least two"):
        fit_transfer(f.iloc[:1], f.iloc[:1])
    with pytest.raises(DataError, match="adc_ref"):
        absorbance(pd.DataFrame({"adc_850": [1.0]}))
