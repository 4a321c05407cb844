"""`nirglucose fit`, `predict` and `export-c` on a user's own files."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.cli import main
from nirglucose.dataset import measured_columns
from nirglucose.models import load_model


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("user")
    # the study's device (its 12-entry physiological vector): measured_columns()
    train = ng.simulate("wearable", 20, 3, seed=0)
    new = ng.simulate("wearable", 4, 2, seed=1)
    train.save(d / "train.parquet")
    # A user's CSV: measured columns and ids only, no truth, no reference glucose.
    new.frame[["measurement_id", "subject_id", *measured_columns()]].to_csv(
        d / "new.csv", index=False
    )
    return d, new


def _run(args, capsys):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_fit_predict_export_happy_path(files, capsys, tmp_path):
    d, new = files
    model = tmp_path / "model.json"
    code, out, err = _run(
        ["fit", "--model", "ebl", "--data", d / "train.parquet", "--out", model], capsys
    )
    assert code == 0, err
    assert "wrote" in out and model.exists()
    pred = tmp_path / "pred.csv"
    code, out, err = _run(
        ["predict", "--model", model, "--data", d / "new.csv", "--out", pred], capsys
    )
    assert code == 0, err
    table = pd.read_csv(pred)
    assert list(table.columns) == [
        "measurement_id",
        "subject_id",
        "predicted_glucose_mgdl",
        "glucose_lower_mgdl",
        "glucose_upper_mgdl",
        "flag",
        "outside_training",
    ]
    np.testing.assert_allclose(
        table["predicted_glucose_mgdl"], load_model(model).predict(new.frame), rtol=1e-12
    )
    code, out, err = _run(["export-c", "--model", model, "--out", tmp_path / "fw"], capsys)
    assert code == 0, err
    assert (tmp_path / "fw" / "nirglucose_model.c").exists()
    assert not list(tmp_path.glob(".*.tmp"))


def test_other_registered_models_use_the_same_path(files, capsys, tmp_path):
    d, _ = files
    model = tmp_path / "pls.json"
    assert (
        _run(["fit", "--model", "pls", "--data", d / "train.parquet", "--out", model], capsys)[0]
        == 0
    )
    code, _, err = _run(
        ["predict", "--model", model, "--data", d / "new.csv", "--out", tmp_path / "p.csv"], capsys
    )
    assert code == 0, err


def _one_line_exit_2(args, capsys, *patterns):
    code, _, err = _run(args, capsys)
    assert code == 2
    assert err.startswith("error: ") and err.strip().count("\n") == 0, err
    for p in patterns:
        assert p in err, err
    return err


def test_user_errors_exit_2_with_one_line(files, capsys, tmp_path):
    d, new = files
    model = tmp_path / "m.json"
    assert (
        _run(["fit", "--model", "ebl", "--data", d / "train.parquet", "--out", model], capsys)[0]
        == 0
    )
    _one_line_exit_2(
        ["fit", "--model", "nope", "--data", d / "train.parquet", "--out", tmp_path / "x.json"],
        capsys,
        "unknown model 'nope'",
        "ebl",
        "pls",
    )
    base = new.frame[measured_columns()].copy()

    def user_file(frame, name):
        path = tmp_path / name
        frame.to_csv(path, index=False)
        return path

    missing = user_file(
        base.drop(columns=["adc_1050"]).rename(columns={"skin_temp_c": "skin_temp"}), "missing.csv"
    )
    _one_line_exit_2(
        ["predict", "--model", model, "--data", missing, "--out", tmp_path / "p.csv"],
        capsys,
        "missing columns",
        "adc_1050",
        "skin_temp_c",
    )
    nan = base.copy()
    nan.loc[[1, 3], "heart_rate_bpm"] = np.nan
    _one_line_exit_2(
        [
            "predict",
            "--model",
            model,
            "--data",
            user_file(nan, "nan.csv"),
            "--out",
            tmp_path / "p.csv",
        ],
        capsys,
        "heart_rate_bpm",
        "empty or NaN cells at lines 3, 5 (line 1 is the header)",
    )
    text = base.astype(object)
    text.loc[2, "bmi_kgm2"] = "tall"
    _one_line_exit_2(
        [
            "predict",
            "--model",
            model,
            "--data",
            user_file(text, "text.csv"),
            "--out",
            tmp_path / "p.csv",
        ],
        capsys,
        "bmi_kgm2",
        "text cells ('tall')",
        "line 4 (line 1 is the header)",
    )
    codes = base.copy()
    codes.loc[0, "adc_850"] = 5000
    _one_line_exit_2(
        [
            "predict",
            "--model",
            model,
            "--data",
            user_file(codes, "codes.csv"),
            "--out",
            tmp_path / "p.csv",
        ],
        capsys,
        "adc_850",
        "above 4095",
        "line 2 (line 1 is the header)",
    )
    _one_line_exit_2(
        [
            "fit",
            "--model",
            "ebl",
            "--data",
            user_file(base, "noref.csv"),
            "--out",
            tmp_path / "x.json",
        ],
        capsys,
        "glucose_mgdl",
    )
    _one_line_exit_2(
        ["predict", "--model", d / "new.csv", "--data", d / "new.csv", "--out", tmp_path / "p.csv"],
        capsys,
        "not a nirglucose model",
    )
    _one_line_exit_2(
        [
            "predict",
            "--model",
            tmp_path / "absent.json",
            "--data",
            d / "new.csv",
            "--out",
            tmp_path / "p.csv",
        ],
        capsys,
        "no such model",
    )
    _one_line_exit_2(
        ["predict", "--model", model, "--data", d / "new.csv", "--out", tmp_path / "p.txt"],
        capsys,
        ".csv",
    )
    _one_line_exit_2(
        ["fit", "--model", "ebl", "--data", d / "absent.csv", "--out", tmp_path / "x.json"],
        capsys,
        "no such file",
    )
    _one_line_exit_2(
        [
            "fit",
            "--model",
            "ebl",
            "--data",
            d / "train.parquet",
            "--out",
            tmp_path / "no" / "x.json",
        ],
        capsys,
        "does not exist",
    )


def test_export_refuses_non_linear_models(files, capsys, tmp_path):
    d, _ = files
    oracle = tmp_path / "oracle.json"
    assert (
        _run(["fit", "--model", "oracle", "--data", d / "train.parquet", "--out", oracle], capsys)[
            0
        ]
        == 0
    )
    _one_line_exit_2(
        ["export-c", "--model", oracle, "--out", tmp_path / "fw"],
        capsys,
        "cannot be exported",
        "ebl, pls",
    )
    assert not (tmp_path / "fw").exists()
