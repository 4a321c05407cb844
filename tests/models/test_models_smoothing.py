"""The causal Kalman smoother of a worn device's predictions."""

import numpy as np
import pandas as pd
import pytest

from common_checks import non_finite_cases
from nirglucose.exceptions import ConfigError, DataError
from nirglucose.models.smoothing import SMOOTHER_GRID, CausalKalmanSmoother, tune_smoother


def _series(n_subjects=4, hours=24, every_min=5, noise_mgdl=25.0, seed=0):
    rng = np.random.default_rng(seed)
    rows = []
    for s in range(n_subjects):
        t = np.arange(0, hours * 60, every_min, dtype=float)
        g = 130 + 50 * np.sin(2 * np.pi * t / 300 + s)  # at most ~1 mg/dL/min
        rows.append(pd.DataFrame({"subject_id": s, "time_min": t, "glucose_mgdl": g,
                                  "predicted_glucose_mgdl": g + rng.normal(0, noise_mgdl, t.size)}))
    return pd.concat(rows, ignore_index=True)


def _rmse(a, b):
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def test_smoothing_noisy_predictions_lowers_the_error():
    f = _series()
    out = CausalKalmanSmoother(measurement_sd_mgdl=25.0, accel_psd=0.01).smooth(
        f["predicted_glucose_mgdl"], f["time_min"], f["subject_id"])
    raw = _rmse(f["predicted_glucose_mgdl"], f["glucose_mgdl"])
    assert _rmse(out, f["glucose_mgdl"]) < 0.7 * raw


def test_it_is_causal_and_keeps_the_input_order():
    f = _series(n_subjects=2).sample(frac=1.0, random_state=1)  # shuffled rows
    s = CausalKalmanSmoother()
    out = s.smooth(f["predicted_glucose_mgdl"], f["time_min"], f["subject_id"])
    later = f["time_min"] > 600
    g = f.copy()
    g.loc[later, "predicted_glucose_mgdl"] += 300.0  # the future changes ...
    out2 = s.smooth(g["predicted_glucose_mgdl"], g["time_min"], g["subject_id"])
    assert np.array_equal(out[~later.to_numpy()], out2[~later.to_numpy()])  # ... the past not
    assert not np.array_equal(out[later.to_numpy()], out2[later.to_numpy()])
    one = f[f["subject_id"] == 0].sort_values("time_min")
    alone = s.smooth(one["predicted_glucose_mgdl"], one["time_min"], one["subject_id"])
    assert np.array_equal(alone, pd.Series(out, index=f.index).loc[one.index].to_numpy())


def test_a_step_is_followed_no_faster_than_the_rate_limit():
    t = np.arange(0, 120, 5.0)
    z = np.where(t < 60, 100.0, 300.0)
    out = CausalKalmanSmoother(measurement_sd_mgdl=1.0, max_rate_mgdl_per_min=2.0).smooth(
        z, t, np.zeros(t.size))
    assert np.all(np.abs(np.diff(out)) <= 2.0 * 5.0 + 1e-9)
    assert out[-1] > out[len(out) // 2]  # it does follow
    free = CausalKalmanSmoother(measurement_sd_mgdl=1.0, max_rate_mgdl_per_min=np.inf).smooth(
        z, t, np.zeros(t.size))
    assert np.max(np.abs(np.diff(free))) > 50  # without the limit the step passes


def test_a_long_gap_restarts_the_filter():
    t = np.r_[np.arange(0, 60, 5.0), np.arange(600, 660, 5.0)]
    z = np.r_[np.full(12, 100.0), np.full(12, 250.0)]
    out = CausalKalmanSmoother(reset_after_min=120).smooth(z, t, np.zeros(t.size))
    assert out[12] == 250.0


def test_tuning_picks_from_the_grid_and_beats_raw():
    f = _series(seed=3)
    best, scores = tune_smoother(f)
    assert len(scores) == np.prod([len(v) for v in SMOOTHER_GRID.values()]) == 12
    assert scores["rmse_mgdl"].is_monotonic_increasing
    assert best.measurement_sd_mgdl in SMOOTHER_GRID["measurement_sd_mgdl"]
    assert scores["rmse_mgdl"].iloc[0] < _rmse(f["predicted_glucose_mgdl"], f["glucose_mgdl"])


@pytest.mark.parametrize("kw", [{"measurement_sd_mgdl": 0}, {"accel_psd": float("nan")},
                                {"max_rate_mgdl_per_min": -1}])
def test_bad_parameters_are_one_line(kw):
    (name, value), = kw.items()
    with pytest.raises(ConfigError, match=rf"^The '{name}' parameter of CausalKalmanSmoother "
                       rf"must be a float in the range \(0\.0, inf[)\]]\. Got {value} instead\.$"):
        CausalKalmanSmoother(**kw)


def test_bad_series_are_refused():
    s = CausalKalmanSmoother()
    with pytest.raises(DataError, match="finite"):
        s.smooth([1.0, np.nan], [0.0, 5.0], [0, 0])
    with pytest.raises(DataError, match="distinct"):
        s.smooth([1.0, 2.0], [5.0, 5.0], [0, 0])
    with pytest.raises(DataError, match="columns"):
        tune_smoother(pd.DataFrame({"x": [1]}))


def test_non_finite_parameters_are_refused_but_no_rate_limit_is_inf():
    cases = non_finite_cases(CausalKalmanSmoother())
    shown = {(p, "nan" if np.isnan(v) else v) for p, v in cases}
    assert ("max_rate_mgdl_per_min", np.inf) not in shown  # inf: no limit
    assert {("accel_psd", np.inf), ("max_rate_mgdl_per_min", "nan")} <= shown
    for param, value in cases:
        with pytest.raises(ConfigError, match=f"'{param}' parameter of CausalKalmanSmoother"):
            CausalKalmanSmoother(**{param: value})
    assert CausalKalmanSmoother(max_rate_mgdl_per_min=np.inf).max_rate_mgdl_per_min == np.inf
