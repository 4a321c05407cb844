"""CLI `simulate`: happy path, and every bad input exits 2 with one line, writing nothing."""

from __future__ import annotations

import pytest

import nirglucose as ng
from nirglucose.cli import main


def run(args, capsys):
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_simulate_writes_parquet(tmp_path, capsys):
    out = tmp_path / "d.parquet"
    code, stdout, _ = run(
        [
            "simulate",
            "--preset",
            "paper",
            "--subjects",
            "10",
            "--per-subject",
            "3",
            "--seed",
            "0",
            "--out",
            str(out),
            "--set",
            "hardware.adc_bits=14",
        ],
        capsys,
    )
    assert code == 0
    ds = ng.load_dataset(out)
    assert len(ds) == 30 and ds.config.hardware.adc_bits == 14
    assert "glucose_mgdl" in stdout


def test_simulate_csv_and_partitioned(tmp_path, capsys):
    assert run(["simulate", "--subjects", "4", "--out", str(tmp_path / "d.csv")], capsys)[0] == 0
    assert run(["simulate", "--subjects", "4", "--out", str(tmp_path / "big")], capsys)[0] == 0
    assert len(ng.load_dataset(tmp_path / "big")) == 12


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--preset", "nope"], "unknown preset 'nope'; valid: paper"),
        (["--set", "hardware.adc_bitz=14"], "unknown config key 'hardware.adc_bitz'"),
        (["--set", "hardware.adc_bits=3"], "hardware.adc_bits"),
        (["--set", "noadequals"], "must look like key=value"),
        (["--subjects", "-3"], "--subjects must be a positive integer"),
        (["--per-subject", "0"], "--per-subject must be a positive integer"),
        (["--subjects", "abc"], "--subjects"),
        (["--seed", "-1"], "--seed must be non-negative"),
        (["--set", "environment.temperature_c=[30, 10]"], "low < high"),
        (["--set", "environment.humidity_pct=[10, 120]"], "humidity_pct"),
        (["--set", "physiology.skin_thickness_mm=[0.1, 4]"], "skin_thickness_mm"),
        (["--set", "leds.wavelengths_nm=[600, 940, 1050, 1150]"], "out of range"),
    ],
)
def test_bad_input_exit_2_one_line(tmp_path, capsys, args, needle):
    out = tmp_path / "d.parquet"
    code, _, err = run(["simulate", "--out", str(out), *args], capsys)
    assert code == 2
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert needle in err
    assert not out.exists()
    assert not list(tmp_path.iterdir())


def test_missing_output_directory(tmp_path, capsys):
    code, _, err = run(["simulate", "--out", str(tmp_path / "no" / "d.parquet")], capsys)
    assert code == 2 and "does not exist" in err


def test_bad_suffix(tmp_path, capsys):
    code, _, err = run(["simulate", "--out", str(tmp_path / "d.txt")], capsys)
    assert code == 2 and ".parquet or .csv" in err
