"""What a CLI audit found giving a traceback, a silent change or lost data: each is now
one line and exit 2, or the data kept as written."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng


@pytest.fixture
def device(cli, workdir):
    """A device file and a PLS model fitted on it, in the work directory."""
    ng.simulate("paper", 8, 3, seed=0).frame.to_csv(workdir / "d.csv", index=False)
    code, _, err = cli("fit", "--model", "pls", "--data", "d.csv", "--out", "m.json",
                       "--cv-folds", 0, "--adc-bits", 12)
    assert code == 0, err
    return pd.read_csv(workdir / "d.csv")


def test_predictions_never_overwrite_the_measurements(cli, workdir, device):
    before = (workdir / "d.csv").read_bytes()
    code, _, err = cli("predict", "--model", "m.json", "--data", "d.csv", "--out", "./d.csv")
    assert_one_line_error(code, err, contains=["is the --data file"])
    assert (workdir / "d.csv").read_bytes() == before


def test_a_blank_subject_id_is_named_not_a_traceback(cli, workdir, device):
    device.astype({"subject_id": object}).assign(
        subject_id=lambda f: f["subject_id"].where(f.index != 2, None)
    ).to_csv(workdir / "blank.csv", index=False)
    for args in (("fit", "--model", "pls", "--data", "blank.csv", "--out", "m2.json"),
                 ("predict", "--model", "m.json", "--data", "blank.csv", "--out", "p.csv")):
        code, _, err = cli(*args)
        assert_one_line_error(code, err, contains=["column 'subject_id' is empty at line 4"])


def test_ids_are_written_back_as_read(cli, workdir, device):
    device.assign(subject_id="007").to_csv(workdir / "ids.csv", index=False)
    code, _, err = cli("predict", "--model", "m.json", "--data", "ids.csv", "--out", "p.csv")
    assert code == 0, err
    assert set(pd.read_csv(workdir / "p.csv", dtype=str)["subject_id"]) == {"007"}
    # plain integers stay integers, as in a Parquet copy of the same file
    assert ng.load_dataset(workdir / "d.csv", adc_bits=12).frame["subject_id"].dtype.kind == "i"


def test_calibration_ids_of_another_kind_are_refused(cli, workdir, device):
    device.head(3).assign(subject_id=lambda f: "P" + f["subject_id"].astype(str)).to_csv(
        workdir / "cal.csv", index=False)
    code, _, err = cli("predict", "--model", "m.json", "--data", "d.csv", "--out", "p.csv",
                       "--calibration", "cal.csv")
    assert_one_line_error(code, err, contains=["spell subject_id differently"])


def test_a_nan_training_range_in_a_model_file_is_refused(cli, workdir, device):
    doc = json.loads((workdir / "m.json").read_text())
    doc["state"]["schema_"]["train_min"][0] = float("nan")
    (workdir / "nan.json").write_text(json.dumps(doc))
    code, _, err = cli("predict", "--model", "nan.json", "--data", "d.csv", "--out", "p.csv")
    assert_one_line_error(code, err, contains=["training range has NaN"])


@pytest.mark.parametrize("folds", [-1, 1])
def test_cv_folds_must_be_zero_or_two_and_more(cli, workdir, device, folds):
    code, _, err = cli("fit", "--model", "pls", "--data", "d.csv", "--out", "m3.json",
                       "--cv-folds", folds)
    assert_one_line_error(code, err, contains=[f"--cv-folds {folds}"])
    assert not (workdir / "m3.json").exists()


def test_text_in_a_worn_device_time_is_one_line(cli, workdir):
    frame = ng.simulate_wear("paper", 4, 1, 120, seed=0).frame.astype({"time_min": object})
    frame.loc[2, "time_min"] = "abc"
    frame.to_csv(workdir / "worn.csv", index=False)
    code, _, err = cli("wear-benchmark", "--out", "w", "--data", "worn.csv", "--models",
                       "mean", "--schedules", "factory", "--folds", 2, "--resamples", 100)
    assert_one_line_error(code, err, contains=["column 'time_min' has text cells ('abc')"])


def test_report_refuses_text_in_a_metric_and_a_garbage_sweep(cli, workdir):
    from nirglucose.evaluation.sweep.run import load_sweep

    (workdir / "b").mkdir()
    pd.DataFrame({"model": ["pls"], "rmse_mgdl": [20.0], "rmse_ci_high": ["abc"]}).to_csv(
        workdir / "b" / "metrics.csv", index=False)
    pd.DataFrame({"model": ["pls"], "reference_mgdl": [100.0], "predicted_mgdl": [110.0]}
                 ).to_parquet(workdir / "b" / "predictions.parquet")
    code, _, err = cli("report", "b", "--out", "r.html")
    assert_one_line_error(code, err, contains=["column 'rmse_ci_high' has text 'abc'"])
    (workdir / "s").mkdir()
    (workdir / "s" / "sweep.csv").write_text("garbage\n1\n")
    (workdir / "s" / "sweep_meta.json").write_text("{}")
    with pytest.raises(ng.DataError, match="sweep.csv in .* lacks column"):
        load_sweep(workdir / "s")


def test_simulation_options_with_data_are_refused(cli, workdir, device):
    code, _, err = cli("benchmark", "--out", "b", "--data", "d.csv", "--subjects", 5,
                       "--preset", "wearable", "--models", "pls")
    assert_one_line_error(code, err, contains=["--preset, --subjects describe a simulation"])
    assert not (workdir / "b").exists()


def test_a_header_only_file_says_so(cli, workdir, device):
    (workdir / "h.csv").write_text((workdir / "d.csv").read_text().splitlines()[0] + "\n")
    code, _, err = cli("benchmark", "--out", "b", "--data", "h.csv", "--models", "pls")
    assert_one_line_error(code, err, contains=["holds no measurements"])


@pytest.mark.parametrize("args, says", [
    (("export-onnx", "--model", "m.json", "--out", "m.txt"), "written as .onnx"),
    (("simulate", "--out", "z.csv", "--subjects", 2, "--set", "leds.band_points=true"),
     "leds.band_points: takes a number, not true"),
])
def test_wrong_suffixes_and_booleans_for_numbers(cli, workdir, device, args, says):
    code, _, err = cli(*args)
    assert_one_line_error(code, err, contains=[says])


def test_report_output_must_be_html_and_figures_a_directory(cli, workdir, device):
    # checked before the results are read
    code, _, err = cli("report", "b", "--out", "r.txt")
    assert_one_line_error(code, err, contains=["written as .html"])
    code, _, err = cli("report", "b", "--figures", "d.csv")
    assert_one_line_error(code, err, contains=["--figures 'd.csv' is a file"])


def test_a_bad_data_file_deletes_no_previous_results(cli, workdir, device):
    (workdir / "w").mkdir()
    (workdir / "w" / "wear_schedules.csv").write_text("a previous run's table\n")
    code, _, err = cli("wear-benchmark", "--out", "w", "--data", "d.csv")  # no time_min
    assert_one_line_error(code, err, contains=["has no time_min column"])
    assert (workdir / "w" / "wear_schedules.csv").exists()
    code, _, err = cli("wear-benchmark", "--out", "w", "--data", "d.csv", "--wear-days", 2)
    assert_one_line_error(code, err, contains=["--wear-days describe a simulation"])


def test_several_presets_clear_every_preset_and_the_comparison_first(tmp_path):
    from nirglucose.cli._common import clear_previous_runs

    runs = [("paper", tmp_path / "paper"), ("wearable", tmp_path / "wearable")]
    for _, d in runs:
        d.mkdir()
        (d / "metrics.csv").write_text("old")
        (d / "notes.txt").write_text("the user's")
    (tmp_path / "report.html").write_text("old")
    clear_previous_runs(runs[:1], tmp_path, ("metrics.csv",))  # one run clears its own later
    assert (tmp_path / "report.html").exists()
    clear_previous_runs(runs, tmp_path, ("metrics.csv",))
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["notes.txt"] * 2


def test_the_oracle_on_a_device_file_says_what_it_needs(cli, workdir, device):
    code, _, err = cli("fit", "--model", "oracle", "--data", "d.csv", "--out", "o.json")
    assert_one_line_error(code, err, contains=["carries no scenario", "`nirglucose simulate`"])
    assert "nirglucose.simulate or" not in err  # no Python advice for a command-line user


def test_folds_beyond_the_subjects_name_the_option(cli, workdir, device):
    code, _, err = cli("benchmark", "--out", "b", "--data", "d.csv", "--folds", 50,
                       "--models", "pls", "--adc-bits", 12)
    assert_one_line_error(code, err, contains=["--folds 50 exceeds the 8 subjects"])
