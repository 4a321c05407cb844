"""Subject-grouped conformal intervals and personal calibration."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.calibration.conformal import (
    grouped_conformal_quantile,
    out_of_fold_intervals,
    split_conformal,
)
from nirglucose.calibration.personal import (
    CALIBRATION_COLUMNS,
    apply_offset,
    calibration_mask,
    personal_calibration,
)
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.run import METRIC_COLUMNS, PREDICTION_COLUMNS, run_benchmark
from nirglucose.exceptions import ConfigError, DataError
from nirglucose.models import PLSBaseline, load_model


def test_quantile_weighs_subjects_not_readings():
    # subject 0 has 9 tiny residuals, subjects 1..9 one large each: by readings the
    # 50 % quantile is tiny; by subjects it is large
    r = np.r_[np.full(9, 0.1), np.arange(1.0, 10.0)]
    g = np.r_[np.zeros(9, int), np.arange(1, 10)]
    assert grouped_conformal_quantile(r, g, 0.5) >= 4.0
    assert np.quantile(r, 0.5) < 1.0


def test_quantile_finite_sample_rule():
    r = np.arange(1.0, 11.0)  # 10 subjects, one residual each
    g = np.arange(10)
    assert grouped_conformal_quantile(r, g, 0.9) == 10.0  # ceil(11 * 0.9) = 10th
    assert grouped_conformal_quantile(r, g, 0.8) == 9.0  # ceil(11 * 0.8) = 9th
    assert math.isinf(grouped_conformal_quantile(r[:5], g[:5], 0.9))
    with pytest.raises(ConfigError):
        grouped_conformal_quantile(r, g, 1.5)


def test_split_conformal_covers_new_people():
    data = ng.simulate("wearable", 200, 3, seed=0)
    model = split_conformal(PLSBaseline(), data, seed=0)
    new = ng.simulate("wearable", 200, 3, seed=5)
    pred = model.predict(new)
    half = model.conformal_["half_width_mgdl"]["90"]
    err = np.abs(new.frame["glucose_mgdl"].to_numpy() - pred)
    cover = np.mean(err <= half)
    assert 0.84 <= cover <= 0.97, cover
    assert model.conformal_["n_calibration_subjects"] == 40


def test_split_conformal_too_few_subjects():
    with pytest.raises(DataError, match="too few"):
        split_conformal(PLSBaseline(), ng.simulate("wearable", 20, 3, seed=0))


def test_saved_calibration_is_validated(tmp_path):
    model = split_conformal(PLSBaseline(), ng.simulate("wearable", 60, 3, seed=0))
    path = model.save(tmp_path / "m.json")
    assert load_model(path).conformal_ == model.conformal_
    text = path.read_text().replace('"method": "split"', '"method": "magic"')
    (tmp_path / "bad.json").write_text(text)
    with pytest.raises(DataError, match="malformed conformal"):
        load_model(tmp_path / "bad.json")


def test_out_of_fold_uses_only_other_folds():
    p = pd.DataFrame(
        {
            "model": "m",
            "subject_id": np.arange(40),
            "repeat": 0,
            "fold": np.repeat([0, 1], 20),
            "reference_mgdl": 100.0,
            "scored_mgdl": 100.0 + np.r_[np.zeros(20), np.full(20, 50.0)],
        }
    )
    out = out_of_fold_intervals(p)
    # fold 0 is calibrated by fold 1's residuals (50) and vice versa (0)
    assert np.all(out.loc[out["fold"] == 0, "half90_mgdl"] == 50.0)
    assert np.all(out.loc[out["fold"] == 1, "half90_mgdl"] == 0.0)


@pytest.fixture(scope="module")
def bench():
    ds = ng.simulate("wearable", 60, 3, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_benchmark(
            ds, ["pls", "mean"], protocol=Protocol(repeats=1, resamples=200, calibration=1),
            drop_one_models="none",
        )


def test_benchmark_reports_coverage_and_width(bench):
    m = bench.metrics
    assert list(m.columns) == list(METRIC_COLUMNS)
    for _, r in m.iterrows():
        assert 70 <= r["coverage90_pct"] <= 100
        assert r["coverage90_ci_low"] <= r["coverage90_pct"] <= r["coverage90_ci_high"]
        assert r["coverage80_pct"] <= r["coverage90_pct"]
        assert 0 < r["width80_mgdl"] < r["width90_mgdl"]
    # no skill needs the widest interval
    w = m.set_index("model")["width90_mgdl"]
    assert w["mean"] > w["pls"]
    p = bench.predictions
    assert list(p.columns) == list(PREDICTION_COLUMNS)
    inside = (p["reference_mgdl"] >= p["lower90_mgdl"]) & (p["reference_mgdl"] <= p["upper90_mgdl"])
    got = m.set_index("model")["coverage90_pct"]
    for name, g in p.assign(inside=inside).groupby("model"):
        assert 100 * g["inside"].mean() == pytest.approx(got[name])


def test_benchmark_personal_calibration(bench):
    c = bench.calibration
    assert list(c.columns) == list(CALIBRATION_COLUMNS)
    assert set(c["method"]) == {"none", "offset", "carry-forward", "difference-ridge"}
    # later readings only: 2 of 3 per subject
    assert set(c["n_scored"]) == {120}
    none = c[(c["model"] == "pls") & (c["method"] == "none")]["rmse_mgdl"].iloc[0]
    off = c[(c["model"] == "pls") & (c["method"] == "offset")]
    assert off["gain_mgdl"].iloc[0] == pytest.approx(none - off["rmse_mgdl"].iloc[0])
    # the mean model plus an offset is carrying the calibration value forward
    carry = c[c["method"] == "carry-forward"]["rmse_mgdl"].iloc[0]
    mean_off = c[(c["model"] == "mean") & (c["method"] == "offset")]["rmse_mgdl"].iloc[0]
    assert carry == pytest.approx(mean_off)


def test_calibration_mask_and_offset():
    f = pd.DataFrame({"subject_id": [1, 1, 1, 2, 2], "measurement_id": [7, 3, 5, 9, 8]})
    assert calibration_mask(f, 1).tolist() == [False, True, False, False, True]
    out, has = apply_offset(
        np.array([100.0, 100.0, 50.0]),
        np.array([1, 3, 2]),
        np.array([90.0, 60.0]),
        np.array([100.0, 50.0]),
        np.array([1, 2]),
    )
    assert out.tolist() == [110.0, 100.0, 40.0] and has.tolist() == [True, False, True]


def test_personal_calibration_refuses_bad_k(bench):
    with pytest.raises(ConfigError, match="0, 1 or 2"):
        personal_calibration(bench.dataset, bench.predictions, [], 3)
    with pytest.raises(ConfigError):
        run_benchmark(bench.dataset, ["mean"], protocol=Protocol(calibration=-1), )


@pytest.mark.slow  # make test-slow (CI runs it)
def test_network_carries_its_calibration(tmp_path):
    from nirglucose.models import make_model

    data = ng.simulate("wearable", 60, 3, seed=0)
    net = split_conformal(make_model("sdnn", max_epochs=5, random_state=0), data)
    path = net.save(tmp_path / "net.json")
    again = load_model(path)
    assert again.conformal_ == net.conformal_
    np.testing.assert_allclose(again.predict(data), net.predict(data), rtol=1e-6)
