"""Calibration schedules of a worn device, on series whose drift is known."""

import numpy as np
import pandas as pd
import pytest

from nirglucose.calibration.schedules import (
    SCHEDULES,
    apply_schedule,
    calibration_times,
    schedule_table,
)
from nirglucose.exceptions import ConfigError, DataError


def _worn(n_subjects=8, days=4, every_min=30, drift_mgdl_per_day=15.0, noise=3.0, seed=0):
    """Predictions = reference + a per-subject offset + a linear drift + noise."""
    rng = np.random.default_rng(seed)
    rows = []
    for s in range(n_subjects):
        t = np.arange(0, days * 1440, every_min, dtype=float)
        ref = 140 + 40 * np.sin(2 * np.pi * t / 1440 + s)
        drift = drift_mgdl_per_day * t / 1440
        pred = ref + rng.normal(0, 30) + drift + rng.normal(0, noise, t.size)
        rows.append(pd.DataFrame({"subject_id": s, "time_min": t, "glucose_mgdl": ref,
                                  "predicted_glucose_mgdl": pred}))
    return pd.concat(rows, ignore_index=True)


def test_calibration_times_follow_the_schedule():
    t = np.arange(0, 3 * 1440, 60.0) + 7.0
    assert calibration_times("factory", t).size == 0
    assert list(calibration_times("day1-1", t)) == [0]
    assert list(calibration_times("day1-2", t)) == [0, 12]
    assert list(calibration_times("every-24h", t)) == [0, 24, 48]
    assert len(calibration_times("every-12h", t)) == 6


def test_a_fingerstick_removes_the_offset_at_that_reading():
    f = _worn(noise=0.0)
    a = apply_schedule(f, "day1-1")
    first = f.groupby("subject_id")["time_min"].transform("min") == f["time_min"]
    assert np.allclose(a.loc[first, "calibrated_mgdl"], f.loc[first, "glucose_mgdl"])
    assert a["is_calibration"].sum() == f["subject_id"].nunique()


def test_more_fingersticks_track_the_drift_better():
    summary, by_day = schedule_table(_worn(), n_boot=200)
    r = summary.set_index("schedule")["rmse_mgdl"]
    assert r["every-12h"] < r["every-24h"] < r["day1-1"] < r["factory"]
    assert summary["n_scored"].nunique() == 1  # paired: the same readings for all
    f = summary.set_index("schedule")
    assert f.loc["every-12h", "rmse_ci_low"] <= r["every-12h"] <= f.loc["every-12h", "rmse_ci_high"]
    assert f.loc["every-24h", "fingersticks_per_day"] == pytest.approx(1.0, abs=0.05)
    d = by_day[by_day["schedule"] == "day1-1"].set_index("days_since_calibration")["rmse_mgdl"]
    assert d.is_monotonic_increasing and len(d) == 4  # stale with the days since


def test_without_drift_a_schedule_buys_only_the_offset():
    summary, _ = schedule_table(_worn(drift_mgdl_per_day=0.0), n_boot=100)
    r = summary.set_index("schedule")["rmse_mgdl"]
    assert r["day1-1"] < 0.5 * r["factory"]
    assert abs(r["every-12h"] - r["day1-1"]) < 2.0


def test_unknown_schedules_and_short_runs_are_refused():
    with pytest.raises(ConfigError, match="unknown calibration schedule"):
        schedule_table(_worn(), ["weekly"])
    with pytest.raises(DataError, match="columns"):
        schedule_table(pd.DataFrame({"x": [1.0]}))
    one = _worn().groupby("subject_id").head(1)
    with pytest.raises(DataError, match="no reading is left"):
        schedule_table(one)
    assert set(SCHEDULES) >= {"factory", "day1-1", "day1-2", "every-12h", "every-24h"}
