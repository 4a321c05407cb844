"""`fit` intervals, `predict --calibration`, `benchmark --calibration` and `sweep`."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.cli import main
from nirglucose.dataset import measured_columns
from nirglucose.evaluation.sweep.run import run_sweep
from nirglucose.models import load_model


def _run(args, capsys):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("people")
    ng.simulate("wearable", 60, 3, seed=0).save(d / "train.parquet")
    new = ng.simulate("wearable", 5, 4, seed=3).frame
    cols = ["measurement_id", "subject_id", *measured_columns()]
    first = new.groupby("subject_id").head(1)
    first[[*cols, "glucose_mgdl"]].to_csv(d / "fingersticks.csv", index=False)
    rest = new.drop(first.index)
    rest[cols].to_csv(d / "new.csv", index=False)
    return d, first, rest


def test_fit_saves_intervals_and_predict_writes_them(files, capsys, tmp_path):
    d, first, rest = files
    model = tmp_path / "m.json"
    code, out, err = _run(
        ["fit", "--model", "pls", "--data", d / "train.parquet", "--out", model], capsys
    )
    assert code == 0, err
    assert "90 % interval" in out and "12 held-out subjects" in out
    m = load_model(model)
    half = m.conformal_["half_width_mgdl"]["90"]
    pred = tmp_path / "p.csv"
    code, out, err = _run(
        ["predict", "--model", model, "--data", d / "new.csv", "--out", pred], capsys
    )
    assert code == 0, err
    t = pd.read_csv(pred)
    np.testing.assert_allclose(t["glucose_upper_mgdl"] - t["predicted_glucose_mgdl"], half)
    assert (t["glucose_lower_mgdl"] <= t["predicted_glucose_mgdl"]).all()

    # one fingerstick per person shifts that person's later predictions by its error
    cal = tmp_path / "pc.csv"
    code, out, err = _run(
        [
            "predict",
            "--model",
            model,
            "--data",
            d / "new.csv",
            "--out",
            cal,
            "--calibration",
            d / "fingersticks.csv",
        ],
        capsys,
    )
    assert code == 0, err
    c = pd.read_csv(cal)
    assert c["calibrated"].all() and "calibrated by their person" in out
    err_first = first["glucose_mgdl"].to_numpy() - m.predict(first[measured_columns()])
    shift = (c["predicted_glucose_mgdl"] - t["predicted_glucose_mgdl"]).groupby(c["subject_id"])
    np.testing.assert_allclose(shift.mean().to_numpy(), err_first, atol=1e-9)


def test_fit_without_enough_subjects_has_no_interval(tmp_path, capsys):
    ng.simulate("wearable", 20, 3, seed=0).save(tmp_path / "small.parquet")
    code, out, err = _run(
        [
            "fit",
            "--model",
            "pls",
            "--data",
            tmp_path / "small.parquet",
            "--out",
            tmp_path / "m.json",
        ],
        capsys,
    )
    assert code == 0 and "no intervals" in out
    code, _, err = _run(
        [
            "fit",
            "--model",
            "pls",
            "--data",
            tmp_path / "small.parquet",
            "--out",
            tmp_path / "m2.json",
            "--intervals",
            "split",
        ],
        capsys,
    )
    assert code == 2 and "too few" in err and err.count("\n") == 1


def test_benchmark_calibration_option(tmp_path, capsys):
    code, out, err = _run(
        [
            "benchmark",
            "--preset",
            "wearable",
            "--models",
            "pls",
            "--no-references",
            "--subjects",
            "30",
            "--per-subject",
            "3",
            "--folds",
            "3",
            "--repeats",
            "1",
            "--resamples",
            "100",
            "--calibration",
            "1",
            "--out",
            tmp_path / "b",
        ],
        capsys,
    )
    assert code == 0, err
    c = pd.read_csv(tmp_path / "b" / "calibration.csv")
    assert {"none", "offset", "difference-ridge"} <= set(c["method"])
    assert "pls offset" in out
    code, _, err = _run(
        ["benchmark", "--per-subject", "2", "--calibration", "2", "--out", tmp_path / "c"], capsys
    )
    assert code == 2 and "--per-subject" in err


def test_sweep_calibration_columns():
    res = run_sweep(
        {"noise_scale": [1.0]},
        preset="wearable",
        seeds=1,
        models="pls",
        n_splits=3,
        repeats=1,
        n_subjects=30,
        per_subject=3,
        n_boot=50,
        jobs=1,
        calibration=1,
    )
    row = res.frame.iloc[0]
    assert row["offset_rmse_mgdl"] > 0 and np.isfinite(row["difference_ridge_rmse_mgdl"])
    assert row["offset_gain_mgdl"] == pytest.approx(
        row["later_rmse_mgdl"] - row["offset_rmse_mgdl"]
    )
    assert "coverage90_pct" in res.frame

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
