"""Benchmark: reference rows, tuned-parameter hook, physics ablation, study orderings."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark import run as bm
from nirglucose.evaluation.benchmark.run import (
    ABLATION_COLUMNS,
    NO_PHYSICS,
    REFERENCE_MODELS,
    run_benchmark,
)
from nirglucose.models import tuning


@pytest.fixture(scope="module")
def data():
    return ng.simulate("paper", n_subjects=12, per_subject=2, seed=0)


def _run(data, tmp_path, n_boot=50, **kw):
    kw.setdefault("drop_one_models", "none")
    kw.setdefault("oracle_reference", False)
    return run_benchmark(data, protocol=Protocol(n_splits=2, repeats=1, seed=3, resamples=n_boot),
                         out=tmp_path / "r", **kw)


def test_reference_rows_are_added(data, tmp_path):
    res = _run(data, tmp_path, models=["ebl"], references=True)
    assert set(res.metrics["model"]) == {"ebl", *REFERENCE_MODELS}
    assert res.meta["references"] == list(REFERENCE_MODELS)
    assert res.ablation.empty
    assert list(pd.read_csv(tmp_path / "r" / "ablation.csv").columns) == list(ABLATION_COLUMNS)


def test_no_reference_rows_by_default_in_the_library(data, tmp_path):
    res = _run(data, tmp_path, models=["ebl"])
    assert list(res.metrics["model"]) == ["ebl"]


def test_ablation_rows_are_paired(data, tmp_path):
    seen = []
    res = _run(
        data, tmp_path, models=["ebl", "original-pinn"], ablation=True,
        model_params={"original-pinn": {"max_epochs": 5, "lambda_phys": 1.0}},
        on_task=lambda spec, cached: seen.append(spec),
    )
    off = "original-pinn" + NO_PHYSICS
    assert set(res.metrics["model"]) == {"ebl", "original-pinn", off}
    specs = {(s["model"], s["fold"]): s for s in seen}
    for fold in (0, 1):
        on, ab = specs[("original-pinn", fold)], specs[(off, fold)]
        # everything identical except the physics weight
        assert ab["seed_model"] == on["seed_model"] == "original-pinn"
        assert ab["params"] == {**on["params"], "lambda_phys": 0.0}
        assert on["params"]["max_epochs"] == 5
    p = res.predictions
    a = p[p["model"] == "original-pinn"][["measurement_id", "fold"]].to_numpy()
    b = p[p["model"] == off][["measurement_id", "fold"]].to_numpy()
    np.testing.assert_array_equal(a, b)
    row = res.ablation.iloc[0]
    assert (row["model"], row["ablated_model"]) == ("original-pinn", off)
    rm = res.metrics.set_index("model")["rmse_mgdl"]
    assert row["rmse_diff_mgdl"] == pytest.approx(rm["original-pinn"] - rm[off], abs=1e-9)
    assert row["ci_low"] <= row["rmse_diff_mgdl"] <= row["ci_high"]
    assert bool(row["physics_helps"]) == (row["rmse_diff_mgdl"] < 0)
    doc = json.loads((tmp_path / "r" / "metrics.json").read_text())
    assert doc["ablation"][0]["model"] == "original-pinn"
    assert "## Physics ablation" in (tmp_path / "r" / "table.md").read_text()
    # the study ordering EBL < Original PINN is stated, once
    so = doc["meta"]["study_orderings"]
    assert so["n_pairs"] == 1
    assert so["pairs"][0]["better"] == "ebl" and so["pairs"][0]["worse"] == "original-pinn"
    assert so["n_hold"] == int(rm["original-pinn"] > rm["ebl"])


def test_no_physics_changes_the_network():
    """lambda_phys=0 is a different fit: the ablation can find a difference."""
    ds = ng.simulate("paper", n_subjects=10, per_subject=2, seed=4)
    on = ng.models.make_model("original-pinn", max_epochs=5, lambda_phys=10.0, random_state=0)
    off = ng.models.make_model("original-pinn", max_epochs=5, lambda_phys=0.0, random_state=0)
    assert not np.allclose(on.fit(ds).predict(ds), off.fit(ds).predict(ds))


def test_tuned_parameters_hook(data, tmp_path, monkeypatch):
    calls = []

    def tuned(name, preset):
        calls.append((name, preset))
        return {"alphas": [3.0]} if name == "ebl" else {}

    monkeypatch.setattr(tuning, "tuned_params", tuned)  # the name preset_params looks up
    assert tuning.preset_params("ebl", "paper") == {"alphas": [3.0]}
    seen = []
    _run(data, tmp_path, models=["ebl"], on_task=lambda s, c: seen.append(s))
    assert ("ebl", "paper") in calls
    assert all(s["params"] == {"alphas": [3.0]} for s in seen)
    # explicit parameters win over tuned ones
    seen.clear()
    _run(data, tmp_path, models=["ebl"], model_params={"ebl": {"alphas": [1.0]}},
         on_task=lambda s, c: seen.append(s))
    assert all(s["params"] == {"alphas": [1.0]} for s in seen)


def test_model_params_are_the_packaged_tuned_ones():
    from nirglucose.models import tuned_params
    from nirglucose.models.tuning import untuned_params

    assert tuning.preset_params("sdnn", "paper") == tuned_params("sdnn", "paper") != {}
    # a user's data: no preset, the networks' small-data rule (early stopping)
    assert tuning.preset_params("sdnn", None) == untuned_params("sdnn") != {}
    assert tuning.preset_params("ebl", None) == {}


def test_lambda_zero_gets_no_verdict_and_best_positive_lambda_is_tested(data, tmp_path,
                                                                        monkeypatch):
    """Where tuning chose λ = 0, the PINN is its no-physics fit: no Δ, no p, no verdict;
    the PINN is also run at the tuning curve's best λ > 0, paired against no-physics."""
    from nirglucose.models.labels import lambda_row

    tuned = {"original-pinn": {"max_epochs": 5, "lambda_phys": 0.0},
             "optimized-pinn": {"max_epochs": 5, "lambda_phys": 1.0}}
    monkeypatch.setattr(bm, "preset_params", lambda name, preset: dict(tuned.get(name, {})))
    monkeypatch.setattr(bm, "best_positive_lambda",
                        lambda name, preset: {"original-pinn": 10.0}.get(name))
    seen = []
    res = _run(data, tmp_path, models=["original-pinn", "optimized-pinn"], ablation=True,
               on_task=lambda spec, cached: seen.append(spec))
    on, off = "original-pinn", "original-pinn" + NO_PHYSICS
    at = lambda_row(on, 10.0)
    assert at == "original-pinn/lambda=10"
    assert set(res.metrics["model"]) == {on, off, at, "optimized-pinn",
                                         "optimized-pinn" + NO_PHYSICS}
    specs = {(s["model"], s["fold"]): s for s in seen}
    for fold in (0, 1):  # the λ row differs from the no-physics fit (here the PINN's own,
        # shared: λ = 0) in λ only
        assert (off, fold) not in specs
        assert specs[(at, fold)]["params"] == {**specs[(on, fold)]["params"],
                                               "lambda_phys": 10.0}
        assert specs[(on, fold)]["params"]["lambda_phys"] == 0.0
        assert specs[(at, fold)]["seed_model"] == specs[(on, fold)]["seed_model"] == on
    a = res.ablation.set_index("model")
    assert list(res.ablation.columns) == list(ABLATION_COLUMNS)
    untested = a.loc[on]
    assert not untested["tested"] and untested["lambda_phys"] == 0.0
    assert untested["verdict"] == "physics off by tuning"
    assert np.isnan(untested["rmse_diff_mgdl"]) and np.isnan(untested["p_holm"])
    assert not untested["significant"] and untested["physics_helps"] is None
    row = a.loc[at]
    assert row["tested"] and row["ablated_model"] == off and row["lambda_phys"] == 10.0
    assert row["lambda_source"] == "best > 0 on the tuning curve"
    rm = res.metrics.set_index("model")["rmse_mgdl"]
    assert rm[at] != rm[off]  # a different fit: a real comparison
    assert row["rmse_diff_mgdl"] == pytest.approx(rm[at] - rm[off], abs=1e-9)
    assert row["ci_low"] <= row["rmse_diff_mgdl"] <= row["ci_high"]
    assert np.isfinite(row["p_holm"]) and row["p_holm"] >= row["p_value"]
    assert row["verdict"] in ("physics helps", "physics hurts", "no significant difference")
    assert a.loc["optimized-pinn", "tested"] and a.loc["optimized-pinn", "verdict"] != (
        "physics off by tuning")
    table = (tmp_path / "r" / "table.md").read_text().split("## Physics ablation")[1]
    line = next(x for x in table.splitlines() if x.startswith("| Original PINN |"))
    assert "physics off by tuning" in line and "no significant" not in line and "—" in line
    assert "Holm over the 2 tested pairs" in table
    doc = json.loads((tmp_path / "r" / "meta.json").read_text())
    assert {p["model"] for p in doc["ablation_pairs"]} == {on, at, "optimized-pinn"}


def test_lambda_zero_given_by_the_caller_is_physics_off(data, tmp_path):
    res = _run(data, tmp_path, models=["original-pinn"], ablation=True,
               model_params={"original-pinn": {"max_epochs": 5, "lambda_phys": 0.0}})
    row = res.ablation.iloc[0]
    assert not row["tested"] and row["verdict"] in ("physics off", "physics off by tuning")
    assert np.isnan(row["rmse_diff_mgdl"])


def test_no_physics_row_of_a_pinn_at_lambda_zero_shares_its_fit(data, tmp_path):
    seen = []
    res = _run(data, tmp_path, models=["original-pinn"], ablation=True,
               model_params={"original-pinn": {"max_epochs": 5, "lambda_phys": 0.0}},
               on_task=lambda spec, cached: seen.append(spec))
    models = [s["model"] for s in seen]
    assert models.count("original-pinn") == 2  # two folds, fitted once for both rows
    assert "original-pinn" + NO_PHYSICS not in models
    p = res.predictions
    np.testing.assert_array_equal(
        p[p["model"] == "original-pinn"]["predicted_mgdl"].to_numpy(),
        p[p["model"] == "original-pinn" + NO_PHYSICS]["predicted_mgdl"].to_numpy())
    assert res.meta["tasks_total"] == len(seen)  # (a /lambda= row, if any, is its own fit)


def test_drop_one_none_runs_no_refit(data, tmp_path):
    seen = []
    res = _run(data, tmp_path, models=["ebl"], drop_one_models="none",
               on_task=lambda spec, cached: seen.append(spec))
    assert res.drop_one.empty and len(res.metrics) == 1
    assert len(seen) == 2 and not any("drop_nm" in s for s in seen)

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
