"""Networks fitted where nothing was tuned (a team's device file) early-stop.

Issue 28: the untuned defaults train 300 epochs on every row, and on 25 readings the
SDNN (3,137 parameters) memorises them. The rule (:func:`untuned_params`) holds out a
fifth of the subjects and may return the training mean; on a file whose glucose has no
relation to the ADC the fit must then be no worse than no skill in grouped CV, and where
a signal exists it must still beat no skill clearly.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.model_selection import GroupKFold

from nirglucose.dataset import load_dataset
from nirglucose.models import make_model
from nirglucose.models.tuning import UNTUNED_NETWORK_PARAMS, untuned_params

N = 25


pytestmark = pytest.mark.usefixtures("torch_one_thread")  # tests/conftest.py


def _device_file(tmp_path, seed: int, signal: bool):
    """25 people, one 940 nm reading each on a 10-bit ADC, glucose [mmol/L]."""
    rng = np.random.default_rng(seed)
    glucose = rng.uniform(4.5, 15.0, N)
    adc = 600.0 + rng.normal(0.0, 6.0 if signal else 20.0, N) + (9.0 * glucose if signal else 0.0)
    path = tmp_path / f"d{seed}{signal}.csv"
    pd.DataFrame({"subject_id": np.arange(N), "glucose_mmoll": glucose.round(1),
                  "adc_940": adc.round(2), "age_yr": rng.integers(25, 70, N)}).to_csv(
        path, index=False)
    return load_dataset(path, adc_bits=10)


def _cv_and_no_skill(params: dict, ds) -> tuple[float, float]:
    """Grouped 5-fold CV RMSE of an SDNN and of the training mean. [mg/dL]"""
    y = ds.frame["glucose_mgdl"].to_numpy(float)
    pred, base = np.empty(N), np.empty(N)
    for tr, te in GroupKFold(5).split(y, y, ds.frame["subject_id"]):
        pred[te] = make_model("sdnn", random_state=0, **params).fit(ds.rows(tr)).predict(
            ds.rows(te))
        base[te] = y[tr].mean()
    return (float(np.sqrt(np.mean((pred - y) ** 2))), float(np.sqrt(np.mean((base - y) ** 2))))


def test_only_networks_get_the_rule():
    assert untuned_params("sdnn") == UNTUNED_NETWORK_PARAMS
    assert untuned_params("rte-pinn")["val_fraction"] > 0
    assert untuned_params("ebl") == {} and untuned_params("gbr") == {}
    untuned_params("sdnn")["patience"] = 1  # a copy: the rule itself is unchanged
    assert untuned_params("sdnn")["patience"] == UNTUNED_NETWORK_PARAMS["patience"]


@pytest.mark.parametrize("seed", [1, 2])
def test_small_untuned_fit_without_signal_is_no_worse_than_no_skill(tmp_path, seed):
    ds = _device_file(tmp_path, seed, signal=False)
    rmse, no_skill = _cv_and_no_skill(untuned_params("sdnn"), ds)
    assert rmse <= 1.02 * no_skill
    if seed == 1:  # the constructor defaults (300 epochs, no hold-out): what the rule prevents
        rmse_default, _ = _cv_and_no_skill({}, ds)
        assert rmse_default > 1.3 * no_skill


def test_small_untuned_fit_with_signal_still_learns_it(tmp_path):
    ds = _device_file(tmp_path, 0, signal=True)
    rmse, no_skill = _cv_and_no_skill(untuned_params("sdnn"), ds)
    assert rmse < 0.6 * no_skill

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = [pytestmark, pytest.mark.slow]
