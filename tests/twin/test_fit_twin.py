"""fit_twin end to end on the user guide's kind of file (one LED, 10 bits, mmol/L, 25
people): the hidden gain is recovered or said unidentified, what the file cannot tell is
said, a file the simulator cannot make is named, a second file of the device is fast; the
CLI's twin, simulate --twin and report run with exit 0."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.cli import main

from .conftest import TEST_SETTINGS, TEST_SIMULATIONS

GAIN = "leds.emitters.0.glucose_gain"


def test_gain_11_is_bracketed_and_identified(twin11):
    e = twin11.entry(GAIN)
    assert e["identified"], e
    assert e["lower"] <= 11.0 <= e["upper"], e
    assert e["upper"] / e["lower"] < 30  # informative: the prior spans 1000x


def test_level_and_measurement_error_of_age(twin11):
    power = twin11.entry("leds.emitters.0.power_mw")
    assert power["identified"] and power["upper"] / power["lower"] < 1.5
    age = twin11.entry("measurement.age_yr")  # within-person spread of a fixed trait
    assert age["identified"]


def test_what_the_file_cannot_tell_is_said(twin11):
    for key in ("measurement.bmi_kgm2", "leds.emitters.0.ageing_per_1000h"):
        e = twin11.entry(key)
        assert not e["identified"] and not e["fitted"] and e["reason"]
    loose = [e["key"] for e in twin11.parameters if e["fitted"] and not e["identified"]]
    if loose:
        line = next(w for w in twin11.warnings if w.startswith("not identified"))
        assert all(k in line for k in loose) and "\n" not in line
    assert twin11.info["caught"] == twin11.warnings  # each warned once, as one line


def test_posterior_predictive_reproduces_the_file(twin11):
    ppc = twin11.info["ppc"]["summaries"]
    for name in ("level_940", "between_940", "within_940"):
        s = ppc[name]
        assert 0.01 < s["p_below"] < 0.99, (name, s)
    codes = twin11.info["ppc"]["codes"]["940"]
    assert abs(codes["file"][2] - codes["twin"][2]) < 0.2 * codes["file"][2]


def test_bound_and_file_errors_recorded(twin11):
    b, e = twin11.info["bound"], twin11.info["file_errors_mgdl"]
    assert 0 < b["oracle_mgdl"] <= b["device_mgdl"]
    assert set(e) == {"ebl", "pls", "mean"} and all(v > 0 for v in e.values())


def test_second_file_of_the_device_is_cached_and_gain_1_is_bracketed_or_unidentified(
        gain1_file, use_twin_cache, twin11):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        twin = ng.fit_twin(gain1_file, adc_bits=10, settings=TEST_SETTINGS, ppc_devices=40)
    assert twin.info["timing"]["cached_estimator"]
    e = twin.entry(GAIN)
    assert (not e["identified"]) or e["lower"] <= 1.0 <= e["upper"], e
    assert e["lower"] < 11.0 * 0.5  # and it is not the gain-11 twin's answer


def test_a_file_the_simulator_cannot_make_is_named(gain11_file, use_twin_cache, twin11,
                                                    tmp_path):
    f = pd.read_csv(gain11_file)
    # the code falls by a third across the glucose range: no gain in the prior does that
    f["adc_940"] = (900 - 40 * f["glucose_mmoll"]).round().clip(1, 1023).astype(int)
    path = tmp_path / "impossible.csv"
    f.to_csv(path, index=False)
    with pytest.warns(UserWarning, match="the twin is not a twin") as rec:
        ng.fit_twin(path, adc_bits=10, settings=TEST_SETTINGS, ppc_devices=20)
    line = next(str(w.message) for w in rec if "not a twin" in str(w.message))
    assert "slope_940" in line and "\n" not in line


def test_cli_twin_simulate_report(gain11_file, use_twin_cache, twin11, tmp_path, capsys):
    out = tmp_path / "twin"
    code = main(["twin", "--data", str(gain11_file), "--out", str(out), "--adc-bits", "10",
                 "--simulations", str(TEST_SIMULATIONS), "--jobs", "1"])
    stdout, err = capsys.readouterr()
    assert code == 0, err
    assert "wrote" in stdout and "cached estimator" in stdout
    assert all(ln.startswith("warning: ") for ln in err.splitlines() if ln.strip())
    doc = json.loads((out / "twin.json").read_text())
    assert doc["device"]["adc_bits"] == 10 and doc["settings"]["n_simulations"] == 2000
    for mode in ("map", "posterior"):
        sim = tmp_path / f"sim_{mode}.csv"
        code = main(["simulate", "--twin", str(out / "twin.json"), "--twin-mode", mode,
                     "--subjects", "6", "--per-subject", "3", "--out", str(sim)])
        capsys.readouterr()
        assert code == 0
        codes = pd.read_csv(sim)["adc_940"]
        assert codes.max() <= 1023 and np.isfinite(codes).all()
    code = main(["report", str(out)])
    stdout, err = capsys.readouterr()
    assert code == 0, err
    page = (out / "report.html").read_text()
    for words in ("Glucose signal", "Posterior of each parameter", "Posterior predictive",
                  "Device bound", GAIN, "published"):
        assert words in page


@pytest.mark.parametrize("args, words", [
    (["--twin-mode", "mode"], "--twin-mode 'mode'"),
    (["--preset", "wearable"], "--twin replaces --preset"),
])
def test_simulate_twin_bad_options_one_line(twin11, tmp_path, capsys, args, words):
    twin11.save(tmp_path / "tw")
    code = main(["simulate", "--twin", str(tmp_path / "tw"), "--out",
                 str(tmp_path / "x.csv"), *args])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err


def test_cli_twin_bad_twin_file_one_line(tmp_path, capsys):
    bad = tmp_path / "twin.json"
    bad.write_text('{"format": "nope"}')
    code = main(["simulate", "--twin", str(bad), "--out", str(tmp_path / "x.csv")])
    _, err = capsys.readouterr()
    assert code == 2 and err.startswith("error: twin file") and len(err.splitlines()) == 1

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
