"""Issue 28 acceptance: a real device's file, end to end.

25 people, one reading each, one 940 nm LED on a 10-bit ADC (50-sample means, so
non-integer codes), glucometer references in mmol/L, a cohort label, no reference
codes; written as a spreadsheet in a decimal-comma locale exports it (``;`` delimiter,
``5,6``) with untidy headers. Driven through fit, predict, benchmark, report and
export-c: exit statuses, one-line messages, no traceback, no significance claim from
too few subjects, and the declared 10-bit resolution recorded in every output.
"""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest
from cli_helpers import assert_one_line_error

GCC = shutil.which("gcc")
N_SUBJECTS = 25


def _device_frame(seed: int = 28) -> pd.DataFrame:
    """One reading per subject; glucose [mmol/L]; codes of a 10-bit ADC, non-integer."""
    rng = np.random.default_rng(seed)
    cohort = np.where(np.arange(N_SUBJECTS) < 12, "control", "t2d")
    glucose = np.where(cohort == "control", rng.uniform(4.5, 8.0, N_SUBJECTS),
                       rng.uniform(8.0, 22.0, N_SUBJECTS))
    adc = 520.0 + 9.0 * glucose + rng.normal(0.0, 6.0, N_SUBJECTS)
    return pd.DataFrame({
        "subject_id": np.arange(N_SUBJECTS),
        "measurement_id": np.arange(N_SUBJECTS),
        "Cohort": cohort,
        "Glucose_mmoll": np.round(glucose, 1),
        "ADC_940 ": np.round(adc, 2),
        "age_yr": rng.integers(25, 70, N_SUBJECTS),
    })


def _write_semicolon(frame: pd.DataFrame, path) -> None:
    frame.to_csv(path, sep=";", decimal=",", index=False)


@pytest.fixture
def device(tmp_path):
    path = tmp_path / "device.csv"
    _write_semicolon(_device_frame(), path)
    assert "5," in path.read_text() or "6," in path.read_text()  # decimal commas indeed
    return path


def _find(doc, key):
    """The first value of ``key`` anywhere in a JSON document."""
    if isinstance(doc, dict):
        if key in doc:
            return doc[key]
        doc = list(doc.values())
    for v in doc if isinstance(doc, list) else []:
        found = _find(v, key)
        if found is not None:
            return found
    return None


def _no_traceback(*texts):
    for t in texts:
        assert "Traceback" not in t


def test_fit_needs_the_resolution_then_reports_cv_and_records_it(cli, device, tmp_path):
    model = tmp_path / "m.json"
    code, out, err = cli("fit", "--model", "ebl", "--data", device, "--out", model)
    assert_one_line_error(code, err, contains=("10-, 12-", "--adc-bits"))
    assert not model.exists()

    code, out, err = cli("fit", "--model", "ebl", "--data", device, "--out", model,
                         "--adc-bits", "10")
    assert code == 0, err
    _no_traceback(out, err)
    assert "at 10 bits" in out
    assert "grouped 5-fold CV over 25 subjects: RMSE" in out and "no skill" in out
    assert "Cohort control:" in out and "Cohort t2d:" in out  # per-group breakdown
    # the file was read, and said how: delimiter, decimal commas, renames, unit
    assert "';'-delimited with decimal commas" in err
    assert "'ADC_940 ' as 'adc_940'" in err and "mmol/L" in err
    schema = _find(json.loads(model.read_text()), "schema_")
    assert schema["adc_bits"] == 10
    assert len(schema["train_max"]) == 2 and schema["train_max"][0] < 1023


def test_predict_flags_extrapolation_and_answers_in_mmoll(cli, device, tmp_path):
    model = tmp_path / "m.json"
    assert cli("fit", "--model", "ebl", "--data", device, "--out", model,
               "--adc-bits", "10")[0] == 0
    new = _device_frame(seed=1).drop(columns=["Glucose_mmoll"])
    new.loc[0, "ADC_940 "] = 1000.5  # far above anything fitted
    path = tmp_path / "new.csv"
    _write_semicolon(new, path)
    pred = tmp_path / "p.csv"
    code, out, err = cli("predict", "--model", model, "--data", path, "--out", pred,
                         "--glucose-unit", "mmol/L")
    assert code == 0, err
    _no_traceback(out, err)
    table = pd.read_csv(pred, keep_default_na=False)
    assert "predicted_glucose_mmoll" in table.columns
    assert "predicted_glucose_mgdl" not in table.columns
    assert table.loc[0, "outside_training"] == "adc_940>"
    assert "outside the training range" in out
    typical = pd.to_numeric(table["predicted_glucose_mmoll"]).iloc[1:].median()
    assert 2.0 < typical < 30.0  # mmol/L, not mg/dL

    # code 0 and codes beyond the 10-bit full scale: one line each, file's line numbers
    for value, expect in ((0, "0 or below at line 3"), (1500, "above 1023")):
        bad = _device_frame().drop(columns=["Glucose_mmoll"])
        bad.loc[1, "ADC_940 "] = value
        _write_semicolon(bad, path)
        code, _, err = cli("predict", "--model", model, "--data", path, "--out", pred)
        assert_one_line_error(code, err, contains=(expect,))


def test_calibration_on_the_predicted_rows_is_warned(cli, device, tmp_path):
    model = tmp_path / "m.json"
    assert cli("fit", "--model", "ebl", "--data", device, "--out", model,
               "--adc-bits", "10")[0] == 0
    code, out, err = cli("predict", "--model", model, "--data", device, "--out",
                         tmp_path / "p.csv", "--calibration", device)
    assert code == 0, err
    assert "25 of the 25 readings predicted are also calibration readings" in err


@pytest.mark.slow  # make test-slow (CI runs it)
def test_benchmark_report_claim_no_significance_from_5_test_subjects(cli, device, tmp_path):
    out_dir = tmp_path / "bench"
    code, out, err = cli("benchmark", "--data", device, "--out", out_dir, "--models", "ebl,pls",
                         "--protocol", "paper-split", "--adc-bits", "10", "--glucose-unit",
                         "mmol/L", "--resamples", "200", "--no-ablation", "--jobs", "1")
    assert code == 0, err
    _no_traceback(out, err)
    assert "RMSE mmol/L" in out
    assert "no significance or best model claimed: only 5 test subjects" in out
    assert "significantly" not in out
    meta = json.loads((out_dir / "meta.json").read_text())
    assert meta["adc_bits"] == 10 and meta["best_model"] is None
    table = (out_dir / "table.md").read_text()
    assert "significantly" not in table and "no significance" in table
    assert pd.read_csv(out_dir / "comparisons.csv").empty

    code, out, err = cli("report", out_dir)
    assert code == 0, err
    _no_traceback(out, err)
    html = (out_dir / "report.html").read_text()
    assert "significantly better" not in html and "significantly worse" not in html
    assert "no significance or best model claimed" in html
    # user-data wording: nothing reproduced, no study claims, no oracle note unasked
    for text in (table, html):
        assert "Study orderings" not in text and "oracle was not run" not in text
    assert "Reproduced table" not in html and "Results table" in html
    assert "Tuned hyper-parameters" not in html
    assert meta["study_orderings"]["n_pairs"] == 0 and meta["oracle_note"] is None


def test_benchmark_refusals_come_before_any_task(cli, device, tmp_path):
    out_dir = tmp_path / "bench"
    code, _, err = cli("benchmark", "--data", device, "--out", out_dir, "--models", "ebl",
                       "--calibration", "1", "--adc-bits", "10")
    assert_one_line_error(code, err, contains=("--calibration 1", "no subject has more than 1"))
    assert not (out_dir / ".tasks").exists() or not any((out_dir / ".tasks").iterdir())
    code, _, err = cli("benchmark", "--data", device, "--out", out_dir, "--models", "ebl")
    assert_one_line_error(code, err, contains=("--adc-bits",))


@pytest.mark.parametrize(
    ("edit", "contains"),
    [
        # a hyperglycaemic cohort in mmol/L under a mg/dL name: today's silent 20-33 "mg/dL"
        (lambda f: f.rename(columns={"Glucose_mmoll": "glucose_mgdl"}).assign(
            glucose_mgdl=np.linspace(20.0, 33.0, N_SUBJECTS)),
         ("looks like mmol/L", "--glucose-unit mmol/L")),
        (lambda f: f.rename(columns={"Glucose_mmoll": "Glucose_mgdl"}),
         ("looks like mmol/L",)),
        (lambda f: f.astype({"Glucose_mmoll": object}).assign(
            Glucose_mmoll=lambda g: g["Glucose_mmoll"].where(g.index != 4, "HI")),
         ("flag HI", "line 6 (line 1 is the header)")),
        (lambda f: f.astype({"ADC_940 ": object}).assign(
            **{"ADC_940 ": lambda g: g["ADC_940 "].where(g.index != 2, "err")}),
         ("text cells ('err')", "line 4")),
        (lambda f: f.rename(columns={"ADC_940 ": "adc940nm"}),
         ("no ADC columns", "columns read:", "nearest: 'adc940nm'")),
        (lambda f: f.drop(columns=["Glucose_mmoll"]),
         ("no reference glucose", "glucose_mmoll")),
        (lambda f: f.assign(**{"ADC_940 ": 600.0}),
         ("'adc_940' holds one value",)),
        (lambda f: f.assign(**{"ADC_940 ": f["ADC_940 "].where(f.index != 3)}),
         ("'adc_940' has empty or NaN cells at line 5",)),
        (lambda f: f.assign(Glucose_mmoll=f["Glucose_mmoll"].where(f.index != 0)),
         ("empty cells at line 2",)),
    ],
    ids=["hyper-mmol-as-mgdl", "mmol-as-mgdl", "meter-HI", "text-cell", "no-adc",
         "no-glucose", "zero-variance", "nan-adc", "blank-glucose"],
)
def test_bad_files_end_in_one_line(cli, tmp_path, edit, contains):
    path = tmp_path / "bad.csv"
    _write_semicolon(edit(_device_frame()), path)
    for cmd in (["fit", "--model", "ebl", "--out", tmp_path / "m.json"],
                ["benchmark", "--models", "ebl", "--out", tmp_path / "b"]):
        code, _, err = cli(*cmd, "--data", path, "--adc-bits", "10")
        assert_one_line_error(code, err, contains=contains)


@pytest.mark.skipif(GCC is None, reason="gcc is not installed")
def test_exported_c_records_10_bits_and_returns_a_status(cli, device, tmp_path):
    model = tmp_path / "m.json"
    assert cli("fit", "--model", "ebl", "--data", device, "--out", model,
               "--adc-bits", "10")[0] == 0
    fw = tmp_path / "fw"
    code, out, err = cli("export-c", "--model", model, "--out", fw)
    assert code == 0, err
    header = (fw / "nirglucose_model.h").read_text()
    assert "#define NIRGLUCOSE_ADC_BITS 10" in header
    assert "#define NIRGLUCOSE_FULL_SCALE 1023" in header
    frame = _device_frame()
    mid = float(frame["ADC_940 "].median())
    age = float(frame["age_yr"].median())
    (tmp_path / "drv.c").write_text(f"""#include <stdio.h>
#include "nirglucose_model.h"
int main(void) {{
    const float codes[4] = {{{mid}f, 0.0f, 1.0f, 2000.0f}};
    const float pmf[NIRGLUCOSE_N_PMF] = {{{age}f}};
    int i;
    for (i = 0; i < 4; ++i) {{
        float g = -1.0f;
        const float adc[1] = {{codes[i]}};
        int s = nirglucose_estimate(adc, pmf, &g);
        printf("%d %.4f\\n", s, g);
    }}
    return 0;
}}
""")
    exe = tmp_path / "drv"
    subprocess.run([GCC, "-std=c99", "-Wall", "-Werror", "-I", str(fw), str(tmp_path / "drv.c"),
                    str(fw / "nirglucose_model.c"), "-o", str(exe), "-lm"], check=True,
                   capture_output=True)
    lines = subprocess.run([str(exe)], check=True, capture_output=True,
                           text=True).stdout.split("\n")
    status = [int(ln.split()[0]) for ln in lines if ln]
    values = [float(ln.split()[1]) for ln in lines if ln]
    assert status[0] == 0 and 50.0 < values[0] < 500.0  # inside: OK, a mg/dL estimate
    assert status[1] == 1 and values[1] == 0.0  # code 0: invalid, no NaN
    assert status[2] & 2  # code 1: far below the training range
    assert status[3] == 1  # above 1023: invalid
    assert all(np.isfinite(values))


def test_fit_warns_when_the_pooled_skill_is_a_cohort_offset(cli, tmp_path):
    """Within each cohort the ADC falls as glucose rises; pooled, it rises (an offset)."""
    f = _device_frame()
    t2d = (f["Cohort"] == "t2d").to_numpy()
    g = f["Glucose_mmoll"].to_numpy()
    f["ADC_940 "] = np.round(np.where(t2d, 800.0, 550.0) - 4.0 * (g - np.where(t2d, 15, 6)), 2)
    path = tmp_path / "offset.csv"
    _write_semicolon(f, path)
    code, out, err = cli("fit", "--model", "pls", "--data", path, "--out", tmp_path / "m.json",
                         "--adc-bits", "10")
    assert code == 0, err
    assert "opposite sign of the pooled one" in err and "t2d" in err
    assert "warning: the model has" not in err  # pls: fewer parameters than readings


@pytest.mark.parametrize("name", ["ebl", "sdnn", "gbr"])
def test_export_onnx_records_10_bits_and_flags_codes(cli, device, tmp_path, name):
    """A linear model, a network and the trees: fitted on the file, exported to ONNX,
    run by onnxruntime: what `predict` answers, 10 bits in the metadata, codes outside
    (0, 1023] flagged."""
    ort = pytest.importorskip("onnxruntime")
    onnx = pytest.importorskip("onnx")
    from nirglucose.dataset import load_dataset

    model = tmp_path / "m.json"
    code, out, err = cli("fit", "--model", name, "--data", device, "--out", model,
                         "--adc-bits", "10", "--cv-folds", "0")
    assert code == 0, err
    _no_traceback(out, err)
    code, out, err = cli("models", "--model", model)
    assert code == 0 and "LEDs 940 nm at 10 bits" in out and "2 input columns" in out
    assert "56" not in out  # the study's feature count is not this device's
    pred = tmp_path / "p.csv"
    assert cli("predict", "--model", model, "--data", device, "--out", pred)[0] == 0
    onnx_file = tmp_path / "m.onnx"
    code, out, err = cli("export-onnx", "--model", model, "--out", onnx_file)
    assert code == 0, err
    _no_traceback(out, err)
    meta = {p.key: p.value for p in onnx.load(str(onnx_file)).metadata_props}
    assert meta["adc_bits"] == "10" and json.loads(meta["raw_columns"]) == ["adc_940", "age_yr"]
    raw = load_dataset(device, adc_bits=10).frame[["adc_940", "age_yr"]].to_numpy(np.float32)
    session = ort.InferenceSession(str(onnx_file))
    glucose, status = session.run(None, {"raw": raw})
    # predict answers in the file's unit (glucose_mmoll: mmol/L, issue 43); ONNX in mg/dL
    expect = pd.read_csv(pred)["predicted_glucose_mmoll"].to_numpy(float) * 18.016
    np.testing.assert_allclose(glucose, expect, atol=0.05)
    assert not status.any()
    bad = raw[:3].copy()
    bad[0, 0], bad[1, 0] = 0.0, 1023.5
    assert session.run(None, {"raw": bad})[1].tolist() == [1, 1, 0]
