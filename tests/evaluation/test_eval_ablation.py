"""Benchmark: reference rows, tuned-parameter hook, physics ablation, study orderings."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.evaluation import benchmark as bm
from nirglucose.evaluation.benchmark import (
    ABLATION_COLUMNS,
    NO_PHYSICS,
    REFERENCE_MODELS,
    run_benchmark,
)


@pytest.fixture(scope="module")
def data():
    return ng.simulate("paper", n_subjects=12, per_subject=2, seed=0)


def _run(data, tmp_path, **kw):
    kw.setdefault("n_boot", 50)
    kw.setdefault("importance_repeats", 1)
    kw.setdefault("oracle_reference", False)
    return run_benchmark(data, protocol="grouped-cv", n_splits=2, repeats=1, seed=3,
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
        model_params={"original-pinn": {"max_epochs": 5}},
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
    import nirglucose.models as models

    calls = []

    def tuned(name, preset):
        calls.append((name, preset))
        return {"alphas": [3.0]} if name == "ebl" else {}

    monkeypatch.setattr(models, "tuned_params", tuned, raising=False)
    assert bm._model_params("ebl", "paper") == {"alphas": [3.0]}
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

    assert bm._model_params("sdnn", "paper") == tuned_params("sdnn", "paper") != {}
    assert bm._model_params("sdnn", None) == {}  # a user's data: no preset, defaults
