"""`nirglucose sweep`: a tiny end-to-end run, and bad input -> one line, exit status 2."""

from __future__ import annotations

import pandas as pd
import pytest

from nirglucose.cli import main

TINY = ["--models", "pls", "--subjects", "24", "--per-subject", "2", "--protocol",
        "paper-split", "--resamples", "50", "--jobs", "1"]


def test_sweep_end_to_end(tmp_path, capsys):
    out = tmp_path / "sweep"
    rc = main(["sweep", "--vary", "noise_scale=0.5,2", "--seeds", "2", "--out", str(out),
               *TINY])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    frame = pd.read_csv(out / "sweep.csv")
    assert len(frame) == 4
    assert {"noise_scale", "seed", "model", "rmse_mgdl", "mard_pct"} <= set(frame.columns)
    assert (out / "figures" / "sweep_rmse.png").exists()
    text = " ".join(captured.out.split())
    assert "pls: MARD" in text and "4 tasks computed, 0 reused" in text
    rc = main(["sweep", "--vary", "noise_scale=0.5,2", "--seeds", "2", "--out", str(out),
               "--no-figures", *TINY])
    assert rc == 0
    assert "0 tasks computed, 4 reused" in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("args, match", [
    (["--vary", "no_such_key=1,2"], "unknown config key"),
    (["--vary", "noise_scale=a,b"], "not a number"),
    (["--vary", "noise_scale="], "lists no values"),
    (["--vary", "noise_scale"], "key=v1,v2"),
    (["--vary", "noise_scale=1,,2"], "empty value"),
    (["--vary", "noise_scale=-1"], "noise_scale"),
    (["--vary", "noise_scale=1", "--vary", "noise_scale=2"], "given twice"),
    (["--vary", "hardware.adc_bits=12.5"], "adc_bits"),
    ([], "--vary"),
    (["--study", "nope"], "unknown study"),
    (["--study", "ablation", "--vary", "noise_scale=1,2"], "cannot be combined"),
    (["--vary", "noise_scale=1,2", "--models", "nope"], "unknown model"),
    (["--vary", "noise_scale=1,2", "--scheduler", "localhost:8786"], "not an address"),
    (["--vary", "noise_scale=1,2", "--seeds", "0"], "--seeds"),
])
def test_bad_input_exit_2_one_line(tmp_path, capsys, args, match):
    rc = main(["sweep", "--out", str(tmp_path / "s"), *args, "--models", "pls"]
              if "--models" not in args else ["sweep", "--out", str(tmp_path / "s"), *args])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1 and err.startswith("error:")
    assert match in err
    assert not (tmp_path / "s" / "sweep.csv").exists()


def test_sweep_data_size(tmp_path, capsys):
    out = tmp_path / "size"
    rc = main(["sweep", "--study", "data-size", "--preset", "paper,lab", "--vary",
               "n_train_subjects=4,16", "--models", "mean,ebl", "--resamples", "20",
               "--jobs", "1", "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    frame = pd.read_csv(out / "sweep.csv")
    assert len(frame) == 2 * 2 * 2  # presets x sizes x models, one seed by default
    assert set(frame["preset"]) == {"paper", "lab"}
    assert (out / "figures" / "sweep_data_size.png").exists()
    text = " ".join(captured.out.split())
    assert "overtakes" in text or "no two models swap places" in text
    assert main(["sweep", "--study", "data-size", "--preset", "paper,nope", "--out",
                 str(tmp_path / "bad")]) == 2


def test_sweep_help_names_every_study():
    from nirglucose.cli import _STUDY_NAMES
    from nirglucose.evaluation.sweep.run import STUDIES

    assert _STUDY_NAMES.split(", ") == list(STUDIES)
