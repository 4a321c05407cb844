"""`nirglucose benchmark`: files written, --data, resume, bad arguments -> one line, exit 2."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.cli import main
from nirglucose.models._base import as_measurements
from nirglucose.models.registry import register


@register("cli-ridge")
class CliRidge:
    """A ridge on log absorbances and the physiological vector (test-only)."""

    def __init__(self, alpha: float = 1.0):
        self.alpha = alpha

    def _z(self, Xa):
        return np.column_stack([np.log(Xa[:, 4:8] / Xa[:, :4]), Xa[:, 8:]])

    def fit(self, X, y=None):
        Xa, y, _ = as_measurements(X, y, require_target=True)
        Z = self._z(Xa)
        self.mu_, self.sd_ = Z.mean(0), Z.std(0) + 1e-9
        Z = (Z - self.mu_) / self.sd_
        self.ym_ = y.mean()
        self.coef_ = np.linalg.solve(
            Z.T @ Z + self.alpha * np.eye(Z.shape[1]), Z.T @ (y - self.ym_)
        )
        return self

    def predict(self, X):
        Xa, _, _ = as_measurements(X)
        return (self._z(Xa) - self.mu_) / self.sd_ @ self.coef_ + self.ym_

    @property
    def n_parameters(self) -> int:
        return self.coef_.size + 1


@register("cli-mean")
class CliMean(CliRidge):
    """Predicts the training mean (test-only)."""

    def fit(self, X, y=None):
        super().fit(X, y)
        self.coef_ = np.zeros_like(self.coef_)
        return self


BASE = [
    "benchmark",
    "--models",
    "cli-ridge,cli-mean",
    "--subjects",
    "12",
    "--per-subject",
    "2",
    "--folds",
    "3",
    "--repeats",
    "1",
    "--resamples",
    "100",
    "--no-references",
]


def test_benchmark_writes_every_output(tmp_path, capsys):
    out = tmp_path / "results"
    assert main([*BASE, "--out", str(out), "--set", "noise_scale=0.5"]) == 0
    for name in (
        "metrics.csv",
        "metrics.json",
        "table.md",
        "predictions.parquet",
        "comparisons.csv",
        "histories.json",
        "drop_one.csv",
        "dataset.parquet",
        "meta.json",
    ):
        assert (out / name).is_file(), name
    metrics = pd.read_csv(out / "metrics.csv")
    assert sorted(metrics["model"]) == ["cli-mean", "cli-ridge"]
    meta = json.loads((out / "meta.json").read_text())
    assert meta["config"]["noise_scale"] == 0.5 and meta["n_subjects"] == 12
    assert meta["repeats"] == 1 and meta["n_splits"] == 3
    printed = capsys.readouterr().out
    n = meta["tasks_total"]
    assert "cli-ridge" in printed and f"{n} tasks computed, 0 reused" in printed
    if "oracle" in meta["auxiliary_models"]:  # fitted for the ratio, not reported as a row
        assert n == 9 and metrics["rmse_vs_oracle"].notna().all()
    else:
        assert n == 6 and meta["oracle_note"]
    assert main([*BASE, "--out", str(out), "--set", "noise_scale=0.5"]) == 0
    assert f"0 tasks computed, {n} reused" in capsys.readouterr().out


def test_benchmark_on_a_saved_csv_dataset(tmp_path, capsys):
    data = tmp_path / "data.csv"
    ng.simulate("paper", n_subjects=10, per_subject=2, seed=3).save(data)
    out = tmp_path / "r"
    argv = ["benchmark", "--data", str(data), "--models", "cli-ridge", "--resamples", "50",
            "--protocol", "paper-split", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    meta = json.loads((out / "meta.json").read_text())
    assert meta["protocol"] == "paper-split" and meta["n_snapshots"] == 20
    assert meta["n_splits"] == 1 and meta["repeats"] == 1
    assert meta["dataset_hash"] == ng.load_dataset(data).content_hash()
    # a CSV carries no scenario config: no oracle, and the result says so
    assert "no scenario config" in meta["oracle_note"]
    assert "no scenario config" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--models", "cli-ridge,nope"], "unknown model 'nope'; valid:"),
        (["--repeats", "0"], "--repeats must be a positive integer"),
        (["--protocol", "loo"], "unknown protocol 'loo'; valid: grouped-cv, paper-split"),
        (["--folds", "0"], "--folds must be a positive integer"),
        (["--set", "no.such.key=1"], "no.such.key"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(tmp_path, capsys, extra, message):
    argv = ["benchmark", "--out", str(tmp_path / "o"), "--subjects", "6", *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and message in err and "\n" not in err
    assert not (tmp_path / "o").exists()


def test_missing_parent_and_data_with_set_exit_2(tmp_path, capsys):
    assert main(["benchmark", "--out", str(tmp_path / "a" / "b"), "--models", "cli-ridge"]) == 2
    assert "does not exist" in capsys.readouterr().err
    data = tmp_path / "d.parquet"
    ng.simulate("paper", n_subjects=4, per_subject=2, seed=0).save(data)
    argv = [
        "benchmark",
        "--out",
        str(tmp_path / "o"),
        "--data",
        str(data),
        "--set",
        "noise_scale=2",
    ]
    assert main(argv) == 2
    assert "--set" in capsys.readouterr().err


@pytest.mark.slow  # two presets benchmarked and reported end to end: 20 s
def test_two_presets_write_one_directory_each_and_one_report(tmp_path, capsys):
    out = tmp_path / "results"
    argv = [*BASE, "--preset", "paper,lab", "--no-ablation", "--out", str(out)]
    assert main(argv) == 0
    for preset in ("paper", "lab"):
        meta = json.loads((out / preset / "meta.json").read_text())
        assert meta["preset"] == preset
        assert (out / preset / "ablation.csv").is_file()
    assert not (out / "metrics.csv").exists()
    assert main(["report", str(out), "--out", str(tmp_path / "report.html")]) == 0
    page = (tmp_path / "report.html").read_text()
    assert 'id="presets-table"' in page
    assert "Full reproduced table and significance statements on <code>lab</code>" in page
    assert "settings differ between <code>paper</code> and <code>lab</code>" in page


def test_two_presets_bad_arguments_exit_2(tmp_path, capsys):
    out = tmp_path / "results"
    assert main([*BASE, "--preset", "paper,nope", "--out", str(out)]) == 2
    assert "nope" in capsys.readouterr().err
    assert not out.exists()  # nothing ran
    data = tmp_path / "d.csv"
    ng.simulate("paper", n_subjects=4, per_subject=2, seed=0).save(data)
    assert main([*BASE, "--preset", "paper,lab", "--data", str(data), "--out", str(out)]) == 2


def test_preset_models_runs_another_set_on_one_preset(tmp_path, capsys):
    out = tmp_path / "results"
    argv = [*BASE, "--preset", "paper,lab", "--no-ablation", "--drop-one", "none",
            "--preset-models", "lab=cli-mean", "--out", str(out)]
    assert main(argv) == 0
    assert sorted(pd.read_csv(out / "paper" / "metrics.csv")["model"]) == ["cli-mean",
                                                                           "cli-ridge"]
    assert list(pd.read_csv(out / "lab" / "metrics.csv")["model"]) == ["cli-mean"]


@pytest.mark.parametrize(
    ("given", "message"),
    [
        ("lab", "write PRESET=NAMES"),
        ("field=cli-mean", "'field' is not among the presets benchmarked (paper, lab)"),
        ("lab=", "names no model"),
        ("lab=cli-mean,nope", "unknown model 'nope'; valid:"),
    ],
)
def test_preset_models_bad_values_exit_2_before_anything_is_cleared(tmp_path, capsys, given,
                                                                    message):
    out = tmp_path / "results"
    (out / "paper").mkdir(parents=True)
    (out / "paper" / "metrics.csv").write_text("model\nold\n")
    argv = [*BASE, "--preset", "paper,lab", "--preset-models", given, "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and message in err and "\n" not in err
    assert (out / "paper" / "metrics.csv").read_text() == "model\nold\n"  # kept


def test_preset_models_twice_or_with_data_exit_2(tmp_path, capsys):
    argv = [*BASE, "--preset", "paper,lab", "--preset-models", "lab=cli-mean",
            "--preset-models", "lab=cli-ridge", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert "names 'lab' twice" in capsys.readouterr().err
    data = tmp_path / "d.csv"
    ng.simulate("paper", n_subjects=4, per_subject=2, seed=0).save(data)
    argv = ["benchmark", "--data", str(data), "--models", "cli-ridge", "--preset-models",
            "lab=cli-mean", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert "with --data give --models" in capsys.readouterr().err


def test_adc_bits_sets_the_simulated_devices_resolution(tmp_path):
    out = tmp_path / "r"
    assert main([*BASE, "--models", "cli-mean", "--no-ablation", "--drop-one", "none",
                 "--adc-bits", "10", "--out", str(out)]) == 0
    meta = json.loads((out / "meta.json").read_text())
    assert meta["config"]["hardware"]["adc_bits"] == 10
