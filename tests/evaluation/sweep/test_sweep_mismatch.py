"""The model-mismatch sweep study: every (data model, assumed model) pair, references once."""

from __future__ import annotations

import numpy as np

from nirglucose.evaluation.sweep import studies
from nirglucose.evaluation.sweep.run import plan_sweep, run_sweep, study_scenarios


def test_every_pair_of_forward_models():
    sc = study_scenarios("mismatch")
    fm = studies.MISMATCH_FORWARD_MODELS
    assert {"beer-lambert", "diffusion", "rte-lut"} <= set(fm)
    assert len(sc) == len(fm) ** 2
    pairs = {(s.labels["data_model"], s.labels["assumed_model"]) for s in sc}
    assert pairs == {(a, b) for a in fm for b in fm}
    for s in sc:
        assert s.overrides["optics.model"] == s.labels["data_model"]
        assert s.labels["mismatched"] == (s.labels["data_model"] != s.labels["assumed_model"])


def test_plan_gives_the_subject_its_assumed_model_and_shares_reference_tasks():
    sc = study_scenarios("mismatch")
    specs = plan_sweep(sc, seeds=[0], models=["physics-inversion", "ebl"],
                       model_params={"physics-inversion": {"n_em": 3}})
    inv = [s for s in specs if s["model"] == "physics-inversion"]
    for s, scenario in zip(inv, sc, strict=True):
        # the sweep's parameters kept, the scenario's assumed model added
        assert s["model_params"] == {"n_em": 3,
                                     "forward_model": scenario.labels["assumed_model"]}
        assert s["overrides"]["optics.model"] == scenario.labels["data_model"]
    from nirglucose.evaluation.engine.tasks import task_key

    ebl = {task_key(s) for s in specs if s["model"] == "ebl"}
    assert len(ebl) == len(studies.MISMATCH_FORWARD_MODELS)  # once per data model
    assert len({task_key(s) for s in inv}) == len(sc)


def test_run_pairs_data_and_assumption(monkeypatch, tmp_path):
    monkeypatch.setattr(studies, "MISMATCH_FORWARD_MODELS", ("beer-lambert", "diffusion"))
    res = run_sweep(study="mismatch", models=["ebl"], seeds=[0], n_subjects=12,
                    per_subject=2, n_splits=2, repeats=1, n_boot=20, jobs=1,
                    model_params={"physics-inversion": {"n_em": 3}}, out=tmp_path / "s")
    f = res.frame
    assert set(f["model"]) == {"physics-inversion", "ebl"}  # the subject always runs
    assert res.meta["tasks_total"] == 4 + 2
    assert {"data_model", "assumed_model", "mismatched"} <= set(f.columns)
    e = f[f["model"] == "ebl"].groupby("data_model")["rmse_mgdl"].nunique()
    assert (e == 1).all()  # one reference task per data model
    inv = f[f["model"] == "physics-inversion"].set_index(["data_model", "assumed_model"])
    r = inv["rmse_mgdl"]
    assert np.isfinite(r).all()
    # the assumed model changes the estimate on the same data
    assert r[("diffusion", "diffusion")] != r[("diffusion", "beer-lambert")]
    assert r[("beer-lambert", "beer-lambert")] != r[("beer-lambert", "diffusion")]
