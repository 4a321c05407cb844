"""The model-mismatch sweep study: every (data model, assumed model) pair, references once."""

from __future__ import annotations

import numpy as np
import pytest

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
    dev = plan_sweep(sc, seeds=[0], models=["device-inversion"])
    for s, scenario in zip(dev, sc, strict=True):  # the deployable one, its table as the data's
        assert s["model_params"] == {"forward_model": scenario.labels["assumed_model"],
                                     "lut_solver": "diffusion"}
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
    # the subjects always run: the privileged and the deployable inversion
    assert set(f["model"]) == {"physics-inversion", "device-inversion", "ebl"}
    assert res.meta["tasks_total"] == 4 + 4 + 2
    assert res.meta["tuning"]["ebl"].startswith("re-tuned per dataset")
    e = res.effects  # the table across seeds: one row per reference and data model
    assert len(e[e["model"] == "ebl"]) == 2 and len(e[e["model"] == "device-inversion"]) == 4
    assert {"data_model", "assumed_model", "mismatched"} <= set(f.columns)
    e = f[f["model"] == "ebl"].groupby("data_model")["rmse_mgdl"].nunique()
    assert (e == 1).all()  # one reference task per data model
    inv = f[f["model"] == "physics-inversion"].set_index(["data_model", "assumed_model"])
    r = inv["rmse_mgdl"]
    assert np.isfinite(r).all()
    # the assumed model changes the estimate on the same data
    assert r[("diffusion", "diffusion")] != r[("diffusion", "beer-lambert")]
    assert r[("beer-lambert", "beer-lambert")] != r[("beer-lambert", "diffusion")]


def test_references_re_tune_on_each_dataset_and_given_parameters_win():
    from nirglucose.models.tuning import N_CONFIGS, N_FOLDS

    params, how = studies.study_model_params(
        "mismatch", ["physics-inversion", "ebl", "pls", "gp", "gbr", "mean"],
        {"pls": {"n_components": 2}})
    # EBL: the tuning's 12 penalties scored by 3 subject-grouped inner folds, never the
    # preset's single tuned penalty (1e-6 on paper, which gave 91.5 mg/dL on diffusion data)
    assert len(params["ebl"]["alphas"]) == N_CONFIGS and params["ebl"]["cv"] == N_FOLDS
    assert 100.0 in params["ebl"]["alphas"]
    assert params["pls"] == {"n_components": 2} and how["pls"].startswith("as given")
    assert params["gp"] == {"kernel": "bic"} and how["gp"].startswith("re-tuned per dataset")
    assert how["gbr"].startswith("the preset's tuned")  # no inner selection: said so
    assert how["physics-inversion"].startswith("the preset's tuned")
    assert how["mean"] == "nothing to tune"
    assert studies.study_model_params("noise-scale", ["ebl"], None) == ({}, {})


def test_mismatch_table_pairs_each_row_with_no_skill_by_seed():
    import pandas as pd

    from nirglucose.evaluation.sweep.analysis import mismatch_table

    rows = []
    for seed, (inv, ebl, mean, ebl_lo) in enumerate([(10, 70, 60, 65), (20, 50, 60, 40)]):
        for assumed in ("a", "b"):
            rows += [
                dict(data_model="a", assumed_model=assumed, model="physics-inversion",
                     seed=seed, rmse_mgdl=inv if assumed == "a" else 40, rmse_ci_low=0),
                dict(data_model="a", assumed_model=assumed, model="ebl", seed=seed,
                     rmse_mgdl=ebl, rmse_ci_low=ebl_lo),
                dict(data_model="a", assumed_model=assumed, model="mean", seed=seed,
                     rmse_mgdl=mean, rmse_ci_low=50),
            ]
    t = mismatch_table(pd.DataFrame(rows), ["physics-inversion"])
    assert len(t) == 2 + 2  # the inversion per assumed model, each reference once
    e = t[t["model"] == "ebl"].iloc[0]
    assert e["rmse_mean"] == 60 and e["delta_no_skill"] == 0
    assert e["seeds_below_no_skill"] == 1 and e["seeds_worse_beyond_ci"] == 1
    m = t[(t["model"] == "physics-inversion") & (t["assumed_model"] == "a")].iloc[0]
    assert bool(m["matched"]) and m["rmse_mean"] == 15 and m["delta_no_skill"] == -45
    assert m["rmse_min"] == 10 and m["rmse_max"] == 20 and m["seeds_below_no_skill"] == 2


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_no_reference_is_worse_than_no_skill_beyond_its_ci(monkeypatch, seed):
    # Issue 39: with the paper preset's tuned values EBL scored 91.5 mg/dL [64.5, 125.2]
    # on diffusion data against no skill's 59.9 (seed 0, 40 subjects, grouped 3-fold),
    # the GP 66.3 [56.4, 77.4] against 52.2 (seed 1). Re-tuned on each task's training
    # subjects, no reference is worse than no skill beyond its own subject-bootstrap
    # interval, on any data model, at the study's default size (60 subjects: at 40,
    # EBL's 80 training rows for 67 coefficients sit at ridge's interpolation threshold
    # and it scored 85.1 [53.9, ...] against 52.2 on rte-lut data, seed 1; at 60 none
    # fails on seeds 0-5). The inversions are not what this checks: they are left out
    # (the study otherwise always runs them).
    from nirglucose.evaluation.sweep import run as sweep_run

    monkeypatch.setattr(sweep_run, "MISMATCH_SUBJECTS", ())
    monkeypatch.setattr(studies, "MISMATCH_SUBJECTS", ())
    res = run_sweep(study="mismatch", models=["ebl", "gp", "mean"], seeds=[seed], n_subjects=60,
                    per_subject=3, n_splits=3, repeats=1, n_boot=500, jobs=1)
    e = res.effects
    assert set(e["model"]) == {"ebl", "gp", "mean"} and len(e) == 3 * 3
    refs = e[e["model"] != "mean"]
    assert (refs["seeds_worse_beyond_ci"] == 0).all(), refs.to_string()

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
