"""``ng.predict``: the prediction table as a library call (issue 33), the one that
``nirglucose predict`` writes."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.calibration.conformal import attach
from nirglucose.cli import app
from nirglucose.exceptions import ConfigError, DataError

COLUMNS = ["measurement_id", "subject_id", "predicted_glucose_mgdl", "glucose_lower_mgdl",
           "glucose_upper_mgdl", "flag", "outside_training"]
#: Half-widths of the hand-made calibration below. [mg/dL]
HALF_90, HALF_OFFSET_90 = 10.0, 4.0


@pytest.fixture(scope="module")
def fitted():
    train = ng.simulate("paper", n_subjects=12, per_subject=2, seed=0)
    new = ng.simulate("paper", n_subjects=3, per_subject=3, seed=1)
    model = ng.models.make_model("ebl").fit(train)
    return model, new


@pytest.fixture(scope="module")
def calibrated(fitted):
    model, new = fitted
    doc = {"method": "split", "half_width_mgdl": {"90": HALF_90},
           "half_width_offset1_mgdl": {"90": HALF_OFFSET_90}}
    return attach(ng.models.make_model("ebl").fit(ng.simulate("paper", 12, 2, seed=0)), doc)


class _Constant:
    """A stand-in estimator predicting fixed values (no schema, no calibration)."""

    def __init__(self, values):
        self.values = np.asarray(values, dtype=float)

    def predict(self, data):
        return self.values[: len(data)]


def test_columns_and_predictions_are_the_models(fitted):
    model, new = fitted
    result = ng.predict(model, new)
    assert list(result.frame.columns) == COLUMNS
    np.testing.assert_array_equal(result.frame["predicted_glucose_mgdl"], model.predict(new))
    assert not result.has_intervals and result.frame["glucose_lower_mgdl"].isna().all()
    assert result.n_calibrated is None and result.glucose_unit == "mg/dL"


def test_a_model_file_a_frame_and_a_data_file_give_the_same_table(fitted, tmp_path):
    model, new = fitted
    model.save(tmp_path / "m.json")
    new.save(tmp_path / "new.parquet")
    want = ng.predict(model, new).frame
    for m, d in ((tmp_path / "m.json", new), (str(tmp_path / "m.json"), new.frame),
                 (model, tmp_path / "new.parquet")):
        pd.testing.assert_frame_equal(ng.predict(m, d).frame, want)


def test_interval_is_the_stored_half_width_clipped_to_the_meter(calibrated, fitted):
    """Both bounds inside the meter's 20-600 mg/dL, the range of the flags (issue 43)."""
    _, new = fitted
    result = ng.predict(calibrated, new)
    p = result.frame["predicted_glucose_mgdl"].to_numpy()
    assert result.has_intervals
    np.testing.assert_allclose(result.frame["glucose_upper_mgdl"],
                               np.clip(p + HALF_90, 20.0, 600.0))
    np.testing.assert_allclose(result.frame["glucose_lower_mgdl"],
                               np.clip(p - HALF_90, 20.0, 600.0))
    low = ng.predict(attach(_Constant([5.0, 100.0, 900.0]),
                                {"method": "split", "half_width_mgdl": {"90": HALF_90}}),
                     new.rows([0, 1, 2]))
    assert low.frame["glucose_lower_mgdl"].tolist() == [20.0, 90.0, 600.0]
    assert low.frame["glucose_upper_mgdl"].tolist() == [20.0, 110.0, 600.0]
    assert low.frame["flag"].tolist() == ["LO", "", "HI"]


def test_flags_mark_meter_range_and_keep_the_number(fitted):
    _, new = fitted
    result = ng.predict(_Constant([10.0, 100.0, 700.0]), new.rows([0, 1, 2]))
    assert result.frame["flag"].tolist() == ["LO", "", "HI"]
    assert result.frame["predicted_glucose_mgdl"].tolist() == [10.0, 100.0, 700.0]
    assert result.n_flagged == 2 and result.n_outside_training == 0


def test_calibration_adds_each_persons_mean_error(calibrated, fitted):
    _, new = fitted
    frame = new.frame
    first = frame["subject_id"] != frame["subject_id"].iloc[-1]  # the last person: none
    cal = new.rows(np.flatnonzero(first.to_numpy()))
    cal.frame["glucose_mgdl"] = cal.frame["glucose_mgdl"] + 7.0  # fingersticks differ
    new_readings = new.frame.assign(measurement_id=new.frame["measurement_id"] + 10_000)
    raw = ng.predict(calibrated, new_readings).frame
    result = ng.predict(calibrated, new_readings, calibration=cal)
    err = (cal.frame["glucose_mgdl"] - calibrated.predict(cal)).groupby(
        cal.frame["subject_id"].to_numpy()).mean()
    offset = frame["subject_id"].map(err).fillna(0.0).to_numpy()
    got = result.frame
    np.testing.assert_allclose(got["predicted_glucose_mgdl"],
                               raw["predicted_glucose_mgdl"] + offset)
    assert got["calibrated"].tolist() == first.tolist() and result.n_calibrated == first.sum()
    width = (got["glucose_upper_mgdl"] - got["predicted_glucose_mgdl"]).to_numpy()
    np.testing.assert_allclose(width, np.where(first, HALF_OFFSET_90, HALF_90))


def test_calibrating_on_the_predicted_readings_warns(fitted):
    model, new = fitted
    with pytest.warns(UserWarning, match=f"{len(new)} of the {len(new)} readings"):
        ng.predict(model, new, calibration=new)


def test_mmol_per_litre_columns(fitted):
    model, new = fitted
    mgdl = ng.predict(model, new).frame
    mmoll = ng.predict(model, new, glucose_unit="mmol/L").frame
    assert "predicted_glucose_mmoll" in mmoll and "predicted_glucose_mgdl" not in mmoll
    np.testing.assert_allclose(mmoll["predicted_glucose_mmoll"] * 18.016,
                               mgdl["predicted_glucose_mgdl"])


def test_bad_input_is_one_clear_error(fitted, tmp_path):
    model, new = fitted
    with pytest.raises(ConfigError, match="fitted estimator or the path"):
        ng.predict(42, new)
    with pytest.raises(ConfigError, match="Dataset, a DataFrame or a file path"):
        ng.predict(model, [1, 2])
    with pytest.raises(DataError, match="subject_id"):
        ng.predict(model, new, calibration=new.frame.drop(columns="subject_id"))
    with pytest.raises(DataError, match="no such model file"):
        ng.predict(tmp_path / "none.json", new)
    with pytest.raises(DataError, match="unknown glucose unit"):
        ng.predict(model, new, glucose_unit="g/L")
    # readings without their fingerstick value would silently calibrate nobody
    cal = new.frame.iloc[:4].assign(glucose_mgdl=np.nan)
    with pytest.raises(DataError, match="no reference glucose at rows 1, 2, 3, 4"):
        ng.predict(model, new, calibration=cal)


def test_the_cli_writes_what_predict_returns(calibrated, fitted, tmp_path):
    from typer.testing import CliRunner

    _, new = fitted
    calibrated.save(tmp_path / "m.json")
    new.save(tmp_path / "new.csv")
    run = CliRunner().invoke(app, ["predict", "--model", str(tmp_path / "m.json"), "--data",
                                   str(tmp_path / "new.csv"), "--out", str(tmp_path / "p.csv"),
                                   "--calibration", str(tmp_path / "new.csv")])
    assert run.exit_code == 0, run.output
    assert "9 of the 9 readings predicted are also calibration readings" in run.output
    written = pd.read_csv(tmp_path / "p.csv", keep_default_na=False)
    with pytest.warns(UserWarning, match="also calibration readings"):
        want = ng.predict(tmp_path / "m.json", tmp_path / "new.csv",
                          calibration=tmp_path / "new.csv").frame
    pd.testing.assert_frame_equal(written, want, check_dtype=False)
