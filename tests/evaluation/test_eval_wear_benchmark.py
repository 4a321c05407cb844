"""The worn benchmark's engine on a series made of snapshots (mechanics, not drift)."""

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.dataset import Dataset
from nirglucose.evaluation.wear import run_wear_benchmark
from nirglucose.exceptions import ConfigError, DataError


@pytest.fixture(scope="module")
def series():
    ds = ng.simulate("paper", n_subjects=16, per_subject=24, seed=0)
    f = ds.frame.copy()
    f["time_min"] = f.groupby("subject_id").cumcount() * 60.0  # one reading an hour
    return Dataset(f, ds.config, ds.seed, ds.metadata)


@pytest.fixture(scope="module")
def result(series):
    return run_wear_benchmark(series, ["ebl", "mean"], preset="paper", n_splits=4, seed=0,
                              train_readings_per_subject=12, n_boot=100)


def test_every_model_variant_and_schedule_is_scored(result, series):
    s = result.schedules
    assert len(s) == 2 * 2 * 5  # models x (raw, smoothed) x schedules
    assert set(s["variant"]) == {"raw", "smoothed"}
    p = result.predictions
    assert len(p) == 2 * 2 * len(series.frame)  # every held-out reading, never thinned
    r = s[(s["schedule"] == "day1-1") & (s["variant"] == "raw")].set_index("model")["rmse_mgdl"]
    assert r["ebl"] < 0.5 * r["mean"]  # calibrated, the paper preset's signal carries glucose


def test_the_smoother_is_tuned_per_fold_on_training_subjects(result):
    sm = result.smoothers
    assert len(sm) == 2 * 4 and {"measurement_sd_mgdl", "rmse_mgdl"} <= set(sm.columns)


def test_it_is_deterministic_and_saves(result, series, tmp_path):
    again = run_wear_benchmark(series, ["ebl", "mean"], preset="paper", n_splits=4, seed=0,
                               train_readings_per_subject=12, n_boot=100)
    assert np.array_equal(again.schedules["rmse_mgdl"], result.schedules["rmse_mgdl"])
    result.save(tmp_path)
    assert (tmp_path / "wear_schedules.csv").exists() and (tmp_path / "wear_meta.json").exists()


def test_bad_inputs_are_one_line(series):
    with pytest.raises(DataError, match="time_min"):
        run_wear_benchmark(series.frame.drop(columns="time_min"), ["mean"])
    with pytest.raises(ConfigError):
        run_wear_benchmark(series, ["no-such-model"])
    with pytest.raises(ConfigError, match="train_readings_per_subject"):
        run_wear_benchmark(series, ["mean"], train_readings_per_subject=1)


def test_the_standards_of_a_worn_monitor_are_computed_per_schedule(result):
    st = result.standards
    assert len(st) == 2 * 2 * 5
    assert {"mard_pct", "icgm_passed", "trend_agreement_pct", "lag_median_min",
            "dts_a_pct", "n_below_70"} <= set(st.columns)
    assert (st["icgm_passed"] <= st["icgm_criteria"]).all()
    assert set(result.icgm["criterion"]) >= {"A", "B", "C"}
    day1 = st[(st["schedule"] == "day1-1") & (st["variant"] == "raw")].set_index("model")
    assert day1.loc["ebl", "mard_pct"] < day1.loc["mean", "mard_pct"]

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
