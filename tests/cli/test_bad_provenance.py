"""No false provenance: labels always match the data that was made (issue 20)."""

from __future__ import annotations

import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng
from nirglucose.config import valid_keys
from nirglucose.dataset import load_dataset
from nirglucose.exceptions import ConfigError


def test_set_preset_is_refused(cli, workdir):
    code, _, err = cli("simulate", "--out", "a.parquet", "--subjects", 2, "--set", "preset=lab")
    assert_one_line_error(code, err, contains=["--preset"])
    assert not list(workdir.iterdir())


def test_preset_is_not_a_settable_key(cli):
    assert "preset" not in valid_keys()
    code, out, _ = cli("keys")
    assert code == 0
    assert not any(line.startswith("preset ") for line in out.splitlines())


def test_api_refuses_preset_override():
    with pytest.raises(ConfigError, match="preset"):
        ng.simulate("paper", 2, 1, seed=0, overrides={"preset": "lab"})


@pytest.mark.parametrize("preset", ["paper", "lab"])
def test_saved_label_is_the_preset_simulated(cli, workdir, preset):
    code, _, err = cli("simulate", "--out", "a.parquet", "--subjects", 2, "--preset", preset)
    assert code == 0, err
    assert load_dataset(workdir / "a.parquet").config.preset == preset


def test_sweep_study_with_unrelated_vary_is_refused(cli, workdir):
    code, _, err = cli("sweep", "--out", "s", "--study", "noise-scale",
                       "--vary", "hardware.adc_bits=12,14", "--no-figures")
    assert_one_line_error(code, err, contains=["--study noise-scale"])
    assert not list(workdir.iterdir())
