"""Issue 43: real files as they come -- cohorts judged against their own mean, units as
declared, intervals inside the meter's range, per-channel converters, one-line refusals."""

from __future__ import annotations

import pytest
from cli_helpers import assert_one_line_error

from real_files import ac_coupled_ppg_frame, one_led_mmoll_frame, two_converter_frame


@pytest.fixture
def one_led(tmp_path):
    path = tmp_path / "one_led.csv"
    one_led_mmoll_frame().to_csv(path, index=False)
    return path


@pytest.fixture
def two_converters(tmp_path):
    path = tmp_path / "two.csv"
    two_converter_frame().to_csv(path, index=False)
    return path


def test_fit_judges_each_cohort_against_its_own_mean(cli, two_converters, tmp_path):
    code, out, err = cli("fit", "--model", "pls", "--data", two_converters, "--out",
                         tmp_path / "m.json", "--adc-bits", "18")
    assert code == 0, err
    lines = [ln for ln in out.splitlines() if ln.strip().startswith("diabetic ")]
    assert len(lines) == 2 and all("this group's own training mean" in ln for ln in lines)
    # the file's channels carry the group only: inside neither group does it beat the mean
    assert "the pooled skill is mostly the offset between diabetic groups" in err
    # the correlation is read on the channel that carries the pooled one
    assert "r(adc_" in lines[0]


def test_group_by_names_a_column_of_the_file(cli, two_converters, tmp_path):
    code, _, err = cli("fit", "--model", "pls", "--data", two_converters, "--out",
                       tmp_path / "m.json", "--adc-bits", "18", "--group-by", "visit")
    assert_one_line_error(code, err, contains=("--group-by", "'visit'"))


def test_fit_prints_in_the_reference_columns_unit(cli, one_led, tmp_path):
    code, out, err = cli("fit", "--model", "pls", "--data", one_led, "--out",
                         tmp_path / "m.json", "--adc-bits", "10")
    assert code == 0, err
    cv = next(ln for ln in out.splitlines() if ln.startswith("grouped"))
    assert "mmol/L" in cv and "mg/dL" not in cv
    code, out, err = cli("fit", "--model", "pls", "--data", one_led, "--out",
                         tmp_path / "m.json", "--adc-bits", "10", "--glucose-unit", "mmol/L")
    assert code == 0, err


def test_benchmark_and_report_judge_cohorts_against_their_own_mean(cli, two_converters,
                                                                   tmp_path):
    from nirglucose.report.cohorts import cohorts_section
    from nirglucose.report.figures import load_results

    out_dir = tmp_path / "b"
    code, out, err = cli("benchmark", "--data", two_converters, "--out", out_dir, "--models",
                         "pls", "--adc-bits", "18", "--repeats", "1", "--resamples", "100",
                         "--no-ablation", "--no-references", "--jobs", "1")
    assert code == 0, err
    assert "no skill is each group's own training mean" in out
    assert "diabetic no:" in out and "diabetic yes:" in out
    assert "PLS: the pooled skill is mostly the offset between diabetic groups" in err
    html = cohorts_section([load_results(out_dir)])
    assert 'id="cohorts"' in html and "no skill (own mean)" in html
    assert "mostly the offset between diabetic groups" in html


def test_per_channel_converters_are_declared_stored_and_read(cli, two_converters, tmp_path):
    import json

    model = tmp_path / "m.json"
    code, out, err = cli("fit", "--model", "pls", "--data", two_converters, "--out", model,
                         "--adc-bits", "adc_940=10,adc_1050=18", "--cv-folds", "0")
    assert code == 0, err
    assert "adc_940 10 bits, adc_1050 18 bits" in out
    assert "quarter" not in err
    schema = json.loads(model.read_text())["state"]["schema_"]
    assert schema["channel_bits"] == [10, 18]
    assert schema["channel_full_scale"] == [1023.0, 262143.0]
    pred = tmp_path / "p.csv"
    code, out, err = cli("predict", "--model", model, "--data", two_converters, "--out", pred)
    assert code == 0, err
    # one converter for both: the 10-bit channel is read at 18 bits, and said so in one line
    code, out, err = cli("fit", "--model", "pls", "--data", two_converters, "--out", model,
                         "--adc-bits", "18", "--cv-folds", "0")
    assert code == 0, err
    warn = [ln for ln in err.splitlines() if "quarter" in ln]
    assert len(warn) == 1 and "'adc_940'" in warn[0] and "adc_940=10" in warn[0]


@pytest.mark.parametrize(("bits", "contains"), [
    ("adc_940=10", ("no resolution for adc_1050",)),
    ("adc_940=10,adc_1050=16", ("'adc_1050'", "above 65535", "adc_1050=18")),
    ("adc_940=10,adc_850=18", ("adc_850, not a channel",)),
    ("adc_940=ten", ("'ten' is not a number",)),
])
def test_per_channel_mistakes_are_one_line(cli, two_converters, tmp_path, bits, contains):
    code, _, err = cli("fit", "--model", "pls", "--data", two_converters, "--out",
                       tmp_path / "m.json", "--adc-bits", bits)
    assert_one_line_error(code, err, contains=contains)


def test_predict_clips_intervals_to_the_meter_and_answers_in_the_models_unit(cli, tmp_path):
    import pandas as pd

    train = tmp_path / "train.csv"
    one_led_mmoll_frame(n_subjects=60, seed=5).to_csv(train, index=False)
    model = tmp_path / "m.json"
    code, _, err = cli("fit", "--model", "pls", "--data", train, "--out", model,
                       "--adc-bits", "10", "--cv-folds", "0", "--intervals", "split")
    assert code == 0, err
    new = one_led_mmoll_frame(seed=1).drop(columns=["glucose_mmoll"])
    new.loc[0, "adc_940"] = 300.0  # far below: a negative estimate
    path = tmp_path / "new.csv"
    new.to_csv(path, index=False)
    out_csv = tmp_path / "p.csv"
    code, out, err = cli("predict", "--model", model, "--data", path, "--out", out_csv)
    assert code == 0, err
    t = pd.read_csv(out_csv, keep_default_na=False)
    assert "predicted_glucose_mmoll" in t.columns  # the training file's unit
    lo, hi = 20.0 / 18.016, 600.0 / 18.016
    assert t.loc[0, "flag"] == "LO" and t.loc[0, "predicted_glucose_mmoll"] < lo
    for col in ("glucose_lower_mmoll", "glucose_upper_mmoll"):
        v = pd.to_numeric(t[col])
        assert v.min() >= lo - 1e-9 and v.max() <= hi + 1e-9
    assert "clipped to the meter's range" in out
    assert "fitted on" not in err  # new readings
    # the rows the model was fitted on: said in one note
    code, out, err = cli("predict", "--model", model, "--data", train, "--out", out_csv)
    assert code == 0, err
    note = [ln for ln in err.splitlines() if "rows the model was fitted on" in ln]
    assert len(note) == 1 and note[0].startswith("note: 96 of the 120 readings")


def test_a_refusal_prints_no_warning_about_the_run_that_will_not_happen(cli, tmp_path):
    import pandas as pd

    path = tmp_path / "one_person.csv"
    pd.DataFrame({"subject_id": [1] * 6, "glucose_mgdl": [90, 120, 150, 180, 110, 140],
                  "adc_940": [2100, 2000, 1900, 1800, 2050, 1950]}).to_csv(path, index=False)
    code, _, err = cli("fit", "--model", "pls", "--data", path, "--out", tmp_path / "m.json")
    assert_one_line_error(code, err, contains=("too few subjects",))


def test_a_study_and_vary_of_its_own_key_are_refused_together(cli, tmp_path):
    code, _, err = cli("sweep", "--study", "noise-scale", "--vary", "noise_scale=1,2",
                       "--out", tmp_path / "s", "--seeds", "1", "--subjects", "10")
    assert_one_line_error(code, err, contains=("--study noise-scale runs its own",
                                               "give --vary alone"))
    assert not (tmp_path / "s").exists()


def test_equal_to_no_skill_within_its_interval_is_no_better(cli, tmp_path):
    import numpy as np

    f = one_led_mmoll_frame(n_subjects=40, seed=7)
    rng = np.random.default_rng(0)  # a trace of glucose under the noise: RMSE just below
    f["adc_940"] = np.round(650 + 2.0 * (f["glucose_mmoll"] - 9) + rng.normal(0, 20, len(f)))
    path = tmp_path / "noise.csv"
    f.to_csv(path, index=False)
    code, out, err = cli("fit", "--model", "pls", "--data", path, "--out", tmp_path / "m.json",
                         "--adc-bits", "10")
    assert code == 0, err
    assert "no better than no skill (equal within its 95 % interval)" in err
    assert "above no skill" not in err


def test_a_near_miss_physiology_column_gets_the_nearest_name(cli, one_led, tmp_path):
    import pandas as pd

    f = pd.read_csv(one_led).assign(bmi=24.0, diabetic="no")
    path = tmp_path / "bmi.csv"
    f.to_csv(path, index=False)
    code, out, err = cli("fit", "--model", "pls", "--data", path, "--out", tmp_path / "m.json",
                         "--adc-bits", "10", "--cv-folds", "0")
    assert code == 0, err
    hint = [ln for ln in err.splitlines() if "'bmi'" in ln]
    assert len(hint) == 1 and "'bmi_kgm2'" in hint[0] and "kg/m^2" in hint[0]
    assert "'diabetic'" not in err  # a grouping column is no near miss


def test_an_empty_drop_one_says_why(cli, one_led, tmp_path):
    import pandas as pd

    out_dir = tmp_path / "b"
    code, out, err = cli("benchmark", "--data", one_led, "--out", out_dir, "--models", "pls",
                         "--adc-bits", "10", "--repeats", "1", "--resamples", "100",
                         "--no-ablation", "--no-references", "--jobs", "1")
    assert code == 0, err
    assert pd.read_csv(out_dir / "drop_one.csv").empty
    assert "drop_one.csv is empty: the device has one LED" in out
    assert "RMSE mmol/L" in out  # the reference column's unit, undeclared
    from nirglucose.report.figures import load_results
    from nirglucose.report.tables import main_table

    html = main_table(load_results(out_dir))  # the report's table in the file's unit too
    assert "RMSE [mmol/L]" in html and "RMSE [mg/dL]" not in html


def test_an_ac_coupled_file_is_said_so_in_fit_predict_benchmark_and_report(cli, tmp_path):
    from nirglucose.report import build_report

    path = tmp_path / "ppg.csv"
    ac_coupled_ppg_frame().to_csv(path, index=False)
    model = tmp_path / "m.json"
    code, out, err = cli("fit", "--model", "pls", "--data", path, "--out", model,
                         "--adc-bits", "12", "--cv-folds", "3")
    assert code == 0, err
    said = [ln for ln in err.splitlines() if "every reading sits at mid-scale" in ln]
    assert len(said) == 2 and all("AC-coupled" in ln for ln in said)
    assert "no better than no skill" in err  # the truth about such codes
    code, out, err = cli("predict", "--model", model, "--data", path, "--out",
                         tmp_path / "p.csv")
    assert code == 0, err
    assert err.count("every reading sits at mid-scale") == 2
    out_dir = tmp_path / "b"
    code, out, err = cli("benchmark", "--data", path, "--out", out_dir, "--models",
                         "pls,mean", "--adc-bits", "12", "--repeats", "1", "--resamples",
                         "100", "--no-ablation", "--no-references", "--jobs", "1")
    assert code == 0, err
    assert err.count("every reading sits at mid-scale") == 2
    html = build_report(out_dir, tmp_path / "r.html").read_text(encoding="utf-8")
    limits = html[html.index('id="limits"'):html.index('id="contents"')
                  if 'id="contents"' in html else None]
    assert "your data: measured by your device" in limits
    assert "Physiology</b>: none in the file" in limits
    assert limits.count("AC-coupled front end") == 2
    assert "no deployable estimator beats the training mean here" in limits
    assert "the study's reported RMSE" not in html  # measured on other data


def test_the_ac_check_leaves_simulated_devices_alone():
    import warnings

    import nirglucose as ng
    from nirglucose.dataset.adc import check_dc_level

    for preset in ("paper", "lab", "field", "physical"):
        frame = ng.simulate(preset, 30, 3, 0).frame
        cols = tuple(c for c in frame.columns if c.startswith("adc_")
                     and not c.startswith("adc_ref"))
        fs = float(2 ** ng.resolve_config(preset).hardware.adc_bits - 1)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert check_dc_level(frame, cols, (fs,) * len(cols)) == [], preset


def test_a_file_without_a_scenario_runs_the_deployable_models_by_default():
    from nirglucose import Dataset, simulate
    from nirglucose.evaluation.benchmark.run import default_models
    from nirglucose.models import available_models, privileged_knowledge

    sim = simulate("paper", 4, 2, 0)
    assert default_models(sim) == available_models()
    plain = default_models(Dataset(ac_coupled_ppg_frame()))
    assert "oracle" not in plain and "physics-inversion" not in plain
    assert plain == [m for m in available_models() if privileged_knowledge(m) is None]
    assert {"ebl", "pls", "mean", "device-inversion"} <= set(plain)


def test_a_twin_of_an_ac_coupled_file_is_refused_in_one_line(cli, tmp_path):
    path = tmp_path / "ppg.csv"
    ac_coupled_ppg_frame().to_csv(path, index=False)
    code, _, err = cli("twin", "--data", path, "--adc-bits", "12", "--out",
                       tmp_path / "twin.json")
    assert_one_line_error(code, err, contains=("adc_880, adc_940", "AC-coupled",
                                               "DC-coupled readings"))
    assert not (tmp_path / "twin.json").exists()


def test_the_note_names_exactly_the_models_a_file_without_a_scenario_leaves_out(capsys):
    from nirglucose import Dataset
    from nirglucose.cli.benchmark_command import _say_privileged_left_out
    from nirglucose.models import available_models, privileged_knowledge

    _say_privileged_left_out(Dataset(ac_coupled_ppg_frame()))
    said = capsys.readouterr()
    line = (said.out + said.err).strip()
    left = [m for m in available_models() if privileged_knowledge(m) is not None]
    assert line.startswith("note: the privileged references (" + ", ".join(left) + ")")
