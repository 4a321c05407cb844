"""Cluster-bootstrap intervals cover at the nominal rate; paired tests find planted
differences and not null ones."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from nirglucose.exceptions import DataError
from nirglucose.metrics import summary
from nirglucose.metrics.resampling import (
    CI_METRICS,
    bootstrap_weights,
    cluster_bootstrap_metrics,
    compare_models,
    holm,
    metric_draws,
    subject_sums,
)


def _problem(rng, n_sub=60, per=3, sd_subject=8.0, sd_noise=6.0, shift=0.0, ref=None):
    ref = rng.uniform(70.0, 300.0, n_sub * per) if ref is None else ref
    groups = np.repeat(np.arange(n_sub), per)
    err = rng.normal(0, sd_subject, n_sub)[groups] + rng.normal(0, sd_noise, n_sub * per)
    return ref, np.maximum(ref + err + shift, 1.0), groups


def test_point_estimates_equal_metrics_summary():
    rng = np.random.default_rng(1)
    ref, pred, groups = _problem(rng, sd_subject=20, sd_noise=15)
    out = cluster_bootstrap_metrics(ref, pred, groups, n_boot=50)
    s = summary(ref, pred)
    for k in CI_METRICS:
        assert out[k] == pytest.approx(s[k], rel=1e-12, abs=1e-12), k
        stem = k.rsplit("_", 1)[0]
        assert out[f"{stem}_ci_low"] <= out[k] + 1e-9 <= out[f"{stem}_ci_high"] + 2e-9


def test_repeats_are_scored_separately_and_averaged():
    rng = np.random.default_rng(2)
    ref, p1, groups = _problem(rng)
    _, p2, _ = _problem(rng)
    both = cluster_bootstrap_metrics(
        np.r_[ref, ref],
        np.r_[p1, p2],
        np.r_[groups, groups],
        np.r_[np.zeros(len(ref)), np.ones(len(ref))],
        n_boot=20,
    )
    expected = (summary(ref, p1)["rmse_mgdl"] + summary(ref, p2)["rmse_mgdl"]) / 2
    assert both["rmse_mgdl"] == pytest.approx(expected)


@pytest.mark.slow  # make test-slow (CI runs it)
def test_rmse_interval_covers_the_true_value_at_about_the_nominal_rate():
    rng = np.random.default_rng(3)
    true_rmse = np.hypot(8.0, 6.0)  # subject effect and noise
    hits = 0
    n_draws = 200
    for _ in range(n_draws):
        ref, pred, groups = _problem(rng, sd_subject=8.0, sd_noise=6.0)
        out = cluster_bootstrap_metrics(
            ref, pred, groups, n_boot=1000, seed=int(rng.integers(1 << 30))
        )
        hits += out["rmse_ci_low"] <= true_rmse <= out["rmse_ci_high"]
    assert 0.90 <= hits / n_draws <= 0.99


def test_cluster_interval_is_wider_than_an_iid_one_when_subjects_matter():
    rng = np.random.default_rng(4)
    ref, pred, groups = _problem(rng, sd_subject=12.0, sd_noise=2.0)
    clustered = cluster_bootstrap_metrics(ref, pred, groups, n_boot=1000)
    iid = cluster_bootstrap_metrics(ref, pred, np.arange(len(ref)), n_boot=1000)
    width = clustered["rmse_ci_high"] - clustered["rmse_ci_low"]
    assert width > 1.3 * (iid["rmse_ci_high"] - iid["rmse_ci_low"])


def test_weights_are_seeded_multinomial_counts():
    w = bootstrap_weights(7, 100, seed=3)
    assert w.shape == (100, 7) and np.all(w.sum(axis=1) == 7)
    assert np.array_equal(w, bootstrap_weights(7, 100, seed=3))
    assert not np.array_equal(w, bootstrap_weights(7, 100, seed=4))
    sums = subject_sums([100.0, 200.0], [110.0, 190.0], [0, 1])
    assert metric_draws(sums, np.ones((1, 2)))["rmse_mgdl"][0] == pytest.approx(10.0)


def _frame(models: dict[str, np.ndarray], ref, groups) -> pd.DataFrame:
    return pd.concat(
        [
            pd.DataFrame(
                {"model": m, "subject_id": groups, "reference_mgdl": ref, "predicted_mgdl": p}
            )
            for m, p in models.items()
        ],
        ignore_index=True,
    )


def test_paired_test_finds_a_planted_difference():
    rng = np.random.default_rng(5)
    ref, good, groups = _problem(rng, sd_subject=6.0, sd_noise=6.0)
    bad = np.maximum(ref + 1.6 * (good - ref) + rng.normal(0, 3, len(ref)), 1.0)
    same = np.maximum(ref + (good - ref) + rng.normal(0, 0.5, len(ref)), 1.0)
    out = compare_models(_frame({"good": good, "bad": bad, "same": same}, ref, groups), seed=1)
    assert set(out["reference_model"]) <= {"good", "same"}
    row = out.set_index("model")
    assert row.loc["bad", "significant"] and row.loc["bad", "rmse_diff_mgdl"] > 0
    assert row.loc["bad", "ci_low"] > 0 and row.loc["bad", "p_wilcoxon_holm"] < 0.05
    other = ({"good", "same"} - {out["reference_model"].iloc[0]}).pop()
    assert not row.loc[other, "significant"]


@pytest.mark.slow  # make test-slow (CI runs it)
def test_paired_test_false_positive_rate_under_the_null():
    rng = np.random.default_rng(6)
    rejections = 0
    n_draws = 100
    for k in range(n_draws):
        ref, a, groups = _problem(rng, n_sub=40)
        _, b, _ = _problem(rng, n_sub=40, ref=ref)  # same error distribution, other draws
        out = compare_models(_frame({"a": a, "b": b}, ref, groups), n_boot=500, seed=k)
        rejections += bool(out["significant"].iloc[0])
    assert rejections / n_draws <= 0.12


def test_oracle_is_never_the_reference_and_explicit_pairs_work():
    rng = np.random.default_rng(7)
    ref, a, groups = _problem(rng)
    frame = _frame({"oracle": ref + 0.1, "a": a, "b": a + 5}, ref, groups)
    out = compare_models(frame, n_boot=200)
    assert set(out["reference_model"]) == {"a"}
    pairs = compare_models(frame, pairs=[("b", "a")], n_boot=200)
    assert pairs["model"].tolist() == ["b"] and pairs["rmse_diff_mgdl"].iloc[0] > 0


def test_holm_matches_hand_computation():
    assert holm([0.01, 0.04, 0.03]).tolist() == pytest.approx([0.03, 0.06, 0.06])
    assert holm([0.5, 0.9]).tolist() == pytest.approx([1.0, 1.0])
    assert holm([]).size == 0


def test_models_on_different_subjects_raise():
    frame = pd.DataFrame(
        {
            "model": ["a", "a", "b", "b"],
            "subject_id": [0, 1, 0, 2],
            "reference_mgdl": 100.0,
            "predicted_mgdl": 100.0,
        }
    )
    with pytest.raises(DataError, match="other subjects"):
        compare_models(frame)
