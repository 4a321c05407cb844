"""The inverse task: tissue-state estimates scored against the truth (inverse.csv)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.inverse import (
    INVERSE_COLUMNS,
    INVERSE_QUANTITIES,
    inverse_table,
)
from nirglucose.evaluation.benchmark.run import run_benchmark
from nirglucose.evaluation.splits import make_splits


def _frame(n_subjects=10, per=3, seed=0):
    rng = np.random.default_rng(seed)
    n = n_subjects * per
    f = pd.DataFrame({"subject_id": np.repeat(np.arange(n_subjects), per)})
    for col, _ in INVERSE_QUANTITIES.values():
        if col.endswith("*"):
            for k in (1, 2):
                f[col[:-1] + str(k)] = rng.normal(size=n)
        else:
            f[col] = rng.normal(size=n)
    return f


def _runs(frame, estimate):
    splits = make_splits(frame["subject_id"].to_numpy(), "grouped-cv", n_splits=2, repeats=1,
                         seed=0)
    return [({"model": "m"}, s, {"state": {q: list(estimate(q, s.test))
                                           for q in INVERSE_QUANTITIES}})
            for s in splits] + [({"model": "plain"}, s, {"state": None}) for s in splits]


def test_hand_computed_errors():
    f = _frame()

    def truth(q, idx):
        col = INVERSE_QUANTITIES[q][0]
        if col.endswith("*"):
            return f[[c for c in f if c.startswith(col[:-1])]].to_numpy().mean(axis=1)[idx]
        return f[col].to_numpy()[idx]

    exact = inverse_table(f, _runs(f, truth), ["m", "plain"], n_boot=50)
    assert list(exact.columns) == list(INVERSE_COLUMNS)
    assert set(exact["model"]) == {"m"}  # a model without state has no row
    assert set(exact["quantity"]) == set(INVERSE_QUANTITIES)
    assert np.allclose(exact["rmse"], 0) and np.allclose(exact["pearson_r"], 1)
    assert (exact["n"] == len(f)).all()
    off = inverse_table(f, _runs(f, lambda q, i: truth(q, i) + 0.1), ["m"], n_boot=50)
    assert np.allclose(off["rmse"], 0.1) and np.allclose(off["bias"], 0.1)
    assert np.allclose(off["rmse_ci_low"], 0.1) and np.allclose(off["rmse_ci_high"], 0.1)
    rng = np.random.default_rng(1)
    noisy = inverse_table(f, _runs(f, lambda q, i: truth(q, i) + rng.normal(size=len(i))),
                          ["m"], n_boot=200)
    assert (noisy["rmse_ci_low"] <= noisy["rmse"]).all()
    assert (noisy["rmse"] <= noisy["rmse_ci_high"]).all()


def test_benchmark_writes_the_inversion_state_error(tmp_path):
    ds = ng.simulate("paper", n_subjects=12, per_subject=2, seed=0)
    res = run_benchmark(ds, ["physics-inversion", "ebl"],
                        protocol=Protocol(n_splits=2, repeats=1, seed=0, resamples=50),
                        drop_one_models="none",
                        oracle_reference=False, out=tmp_path / "r",
                        model_params={"physics-inversion": {"n_em": 3}})
    inv = pd.read_csv(tmp_path / "r" / "inverse.csv")
    assert list(inv.columns) == list(INVERSE_COLUMNS)
    assert set(inv["model"]) == {"physics-inversion"}
    assert {"blood_fraction", "water_fraction", "melanin_fraction",
            "skin_thickness_mm"} <= set(inv["quantity"])
    assert (inv["n"] == len(ds.frame)).all()
    assert np.isfinite(inv["rmse"]).all() and (inv["rmse"] >= 0).all()
    pd.testing.assert_frame_equal(inv, res.inverse.reset_index(drop=True), check_dtype=False)


def test_no_truth_no_rows():
    f = pd.DataFrame({"subject_id": [0, 0, 1, 1]})
    runs = _runs(_frame(2, 2), lambda q, i: np.zeros(len(i)))
    assert inverse_table(f, runs, ["m"]).empty


def test_report_section_renders_the_csv(tmp_path):
    from nirglucose.report.figures import load_results
    from nirglucose.report.inverse import inverse_section

    ds = ng.simulate("paper", n_subjects=8, per_subject=2, seed=1)
    run_benchmark(ds, ["physics-inversion"],
                  protocol=Protocol(n_splits=2, repeats=1, seed=0, resamples=20),
                  drop_one_models="none", oracle_reference=False,
                  out=tmp_path / "r", model_params={"physics-inversion": {"n_em": 2}})
    html = inverse_section([load_results(tmp_path / "r")])
    assert 'id="inverse-paper"' in html and "skin thickness under the probe" in html
    t = pd.read_csv(tmp_path / "r" / "inverse.csv")
    assert html.count("<tr><td>") == len(t)
    (tmp_path / "r" / "inverse.csv").unlink()
    assert inverse_section([load_results(tmp_path / "r")]) == ""

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
