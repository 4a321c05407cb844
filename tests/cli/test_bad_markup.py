"""User text and units are printed literally, never as Rich markup (issue 20)."""

from __future__ import annotations

import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng


@pytest.mark.parametrize("preset", ["[/x]", "[red]paper", "[bold]x[/bold]", "[link=x]y"])
def test_preset_text_is_literal(cli, workdir, preset):
    code, _, err = cli("simulate", "--out", "a.csv", "--subjects", 2, "--preset", preset)
    assert_one_line_error(code, err, contains=[f"unknown preset {preset!r}"])
    assert not list(workdir.iterdir())


def test_key_text_is_literal(cli, workdir):
    code, _, err = cli("simulate", "--out", "a.csv", "--set", "[red]noise=1")
    assert_one_line_error(code, err, contains=["'[red]noise'"])


def test_units_in_project_messages_survive(cli, workdir):
    ds = ng.simulate("paper", 3, 2, seed=0)
    frame = ds.frame.copy()
    frame.loc[0, "glucose_mgdl"] = -5.0
    frame.to_csv(workdir / "bad.csv", index=False)
    code, _, err = cli("fit", "--model", "ebl", "--data", "bad.csv", "--out", "m.json")
    assert_one_line_error(code, err, contains=["[mg/dL]"])
    assert not (workdir / "m.json").exists()


def test_model_name_is_literal(cli, workdir):
    code, _, err = cli("fit", "--model", "[red]ebl", "--data", "x.csv", "--out", "m.json")
    assert_one_line_error(code, err, contains=["'[red]ebl'"])
