"""Issue 28's remaining bad inputs: forged model files and a string of overrides end in
one line (they were tracebacks)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng
from nirglucose.exceptions import ConfigError


@pytest.fixture(scope="module")
def device_file(tmp_path_factory):
    """25 people, one 940 nm reading on a 10-bit ADC, an age column."""
    rng = np.random.default_rng(5)
    glucose = rng.uniform(80.0, 300.0, 25)
    path = tmp_path_factory.mktemp("dev") / "dev.csv"
    pd.DataFrame({"subject_id": np.arange(25), "glucose_mgdl": glucose.round(1),
                  "adc_940": (500.0 + 0.5 * glucose + rng.normal(0, 5, 25)).round(2),
                  "age_yr": rng.integers(25, 70, 25)}).to_csv(path, index=False)
    return path


def _fit(cli, name, data, out):
    code, _, err = cli("fit", "--model", name, "--data", data, "--out", out,
                       "--adc-bits", "10", "--cv-folds", "0")
    assert code == 0, err


@pytest.mark.parametrize("name", ["ebl", "sdnn"])
def test_a_model_name_that_is_a_list_is_one_line(cli, device_file, tmp_path, name):
    model = tmp_path / "m.json"
    _fit(cli, name, device_file, model)
    doc = json.loads(model.read_text())
    doc["model"] = [name]
    model.write_text(json.dumps(doc))
    for cmd in (["predict", "--data", device_file, "--out", tmp_path / "p.csv"],
                ["export-c", "--out", tmp_path / "fw"], ["models"]):
        code, _, err = cli(*cmd, "--model", model)
        assert_one_line_error(code, err, contains=("'model' must be a model name", "list"))


@pytest.mark.parametrize("part", ["nir", "pmf"])
def test_a_network_scaler_shorter_than_its_inputs_is_one_line(cli, device_file, tmp_path,
                                                              part):
    model = tmp_path / "m.json"
    _fit(cli, "sdnn", device_file, model)
    forged = tmp_path / "forged.json"
    doc = json.loads(model.read_text())
    doc["weights_file"] = "forged.safetensors"
    doc["scaler"][f"{part}_mean"] = []
    doc["scaler"][f"{part}_scale"] = []
    forged.write_text(json.dumps(doc))
    shutil.copy(model.with_suffix(".safetensors"), tmp_path / "forged.safetensors")
    code, _, err = cli("predict", "--model", forged, "--data", device_file, "--out",
                       tmp_path / "p.csv")
    assert_one_line_error(code, err, contains=(f"scaler.{part}_mean has 0 values",
                                               "needs 1", "refit"))


def test_overrides_as_a_string_is_one_config_error():
    with pytest.raises(ConfigError, match="overrides must be a dict.*got a str"):
        ng.simulate("paper", 2, 1, seed=0, overrides="hardware.adc_bits=14")


def test_fit_on_identical_rows_is_refused(cli, tmp_path):
    path = tmp_path / "same.csv"
    pd.DataFrame({"subject_id": np.arange(50), "glucose_mgdl": 120.0,
                  "adc_940": 600.0}).to_csv(path, index=False)
    code, _, err = cli("fit", "--model", "ebl", "--data", path, "--out", tmp_path / "m.json",
                       "--adc-bits", "10")
    assert_one_line_error(code, err, contains=("holds one value", "nothing to learn"))
    assert not (tmp_path / "m.json").exists()
