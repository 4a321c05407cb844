"""The benchmark: output columns, determinism (any jobs), resume, the oracle ratio."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.run import (
    COMPARISON_COLUMNS,
    DROP_ONE_COLUMNS,
    METRIC_COLUMNS,
    OUTPUT_FILES,
    PREDICTION_COLUMNS,
    run_benchmark,
)
from nirglucose.exceptions import ConfigError
from nirglucose.models._base import as_measurements
from nirglucose.models.registry import register


def _features(Xa):
    return np.column_stack([np.log(Xa[:, 4:8] / Xa[:, :4]), Xa[:, 8:]])


@register("test-ridge")
class RidgeModel:
    """A ridge on log absorbances and the physiological vector (test-only)."""

    fail_on_fit: int | None = None  # raise on the n-th fit (simulated crash)
    fits = 0

    def __init__(self, alpha: float = 1.0, random_state: int | None = None):
        self.alpha = alpha
        self.random_state = random_state

    def fit(self, X, y=None):
        type(self).fits += 1
        if type(self).fail_on_fit is not None and type(self).fits >= type(self).fail_on_fit:
            raise RuntimeError("simulated crash")
        Xa, y, _ = as_measurements(X, y, require_target=True)
        Z = _features(Xa)
        self.mu_, self.sd_ = Z.mean(0), Z.std(0) + 1e-9
        Z = (Z - self.mu_) / self.sd_
        # random_state only jitters the penalty, so seeding shows in the results
        a = self.alpha * (1.0 + 0.01 * np.random.default_rng(self.random_state).random())
        self.ym_ = y.mean()
        self.coef_ = np.linalg.solve(Z.T @ Z + a * np.eye(Z.shape[1]), Z.T @ (y - self.ym_))
        self.history_ = [{"epoch": 0, "train_loss": float(np.mean(y**2))}]
        return self

    def predict(self, X):
        Xa, _, _ = as_measurements(X)
        return (_features(Xa) - self.mu_) / self.sd_ @ self.coef_ + self.ym_

    @property
    def n_parameters(self) -> int:
        return self.coef_.size + 1


@register("test-biased")
class BiasedModel(RidgeModel):
    """A worse model: the ridge plus 120 mg/dL; records the size of its validation set."""

    def fit(self, X, y=None, *, X_val=None, y_val=None):
        super().fit(X, y)
        self.ym_ += 120.0
        self.history_ = [{"epoch": 0, "val_rows": -1 if X_val is None else len(X_val)}]
        return self


MODELS = ["test-ridge", "test-biased"]
FOUR_BY_TWO = Protocol(n_splits=4, repeats=2, seed=0, resamples=200)
THREE_BY_TWO = Protocol(n_splits=3, repeats=2, resamples=200)
FAST = {
    "timing": {"n_single": 5, "min_single": 1, "warmup": 1, "batch_rows": 200, "batch_repeats": 1},
    "oracle_reference": False,
}


@pytest.fixture(scope="module")
def data():
    return ng.simulate("paper", n_subjects=20, per_subject=3, seed=0)


def _stable(metrics: pd.DataFrame) -> pd.DataFrame:
    timed = ("latency_single_ms", "latency_single_p90_ms", "throughput_per_s", "fit_time_s")
    return metrics.drop(columns=list(timed))


@pytest.fixture(scope="module")
def result(data, tmp_path_factory):
    out = tmp_path_factory.mktemp("bench") / "results"
    return out, run_benchmark(data, MODELS, protocol=FOUR_BY_TWO, out=out, **FAST)


def test_result_frames_have_the_documented_columns(result):
    _, res = result
    assert list(res.metrics.columns) == list(METRIC_COLUMNS)
    assert list(res.predictions.columns) == list(PREDICTION_COLUMNS)
    assert list(res.comparisons.columns) == list(COMPARISON_COLUMNS)
    assert list(res.drop_one.columns) == list(DROP_ONE_COLUMNS)
    assert sorted(res.metrics["model"]) == sorted(MODELS)
    assert len(res.predictions) == 2 * 2 * 60  # models x repeats x snapshots
    assert res.metrics["rmse_mgdl"].is_monotonic_increasing
    m = res.metrics.set_index("model")
    assert (m["rmse_ci_low"] <= m["rmse_mgdl"]).all() and (
        m["rmse_mgdl"] <= m["rmse_ci_high"]
    ).all()
    assert (m["n_parameters"] == 17).all() and (m["latency_input"] == "array").all()
    assert set(res.histories) == set(MODELS) and res.histories["test-ridge"][0]["epoch"] == 0
    # no default drop-one model among these test models: no refit
    assert res.drop_one.empty and res.meta["drop_one_models"] == []
    assert res.meta["tasks_total"] == 16 and res.meta["tasks_computed"] == 16
    assert res.meta["best_model"] == "test-ridge"
    vs_best = res.comparisons[res.comparisons["family"] == "vs_best"]
    assert vs_best["model"].tolist() == ["test-biased"] and bool(vs_best["significant"].iloc[0])


def test_files_are_written(result):
    out, res = result
    for name in OUTPUT_FILES:
        assert (out / name).is_file(), name
    csv = pd.read_csv(out / "metrics.csv")
    required = [
        "model",
        "rmse_mgdl",
        "rmse_ci_low",
        "rmse_ci_high",
        "mard_pct",
        "mard_ci_low",
        "mard_ci_high",
        "clarke_a_pct",
        "clarke_ab_pct",
        "parkes_a_pct",
        "within15_pct",
        "iso15197_pct",
        "bias_mgdl",
        "loa_low_mgdl",
        "loa_high_mgdl",
        "n_parameters",
        "latency_single_ms",
        "throughput_per_s",
        "rmse_vs_oracle",
    ]
    assert set(required) <= set(csv.columns)
    doc = json.loads((out / "metrics.json").read_text())
    for key in (
        "protocol",
        "n_splits",
        "repeats",
        "seed",
        "preset",
        "dataset_hash",
        "n_subjects",
        "n_snapshots",
        "version",
        "config",
    ):
        assert key in doc["meta"], key
    assert doc["meta"]["preset"] == "paper" and len(doc["metrics"]) == 2
    preds = pd.read_parquet(out / "predictions.parquet")
    assert {
        "model",
        "subject_id",
        "measurement_id",
        "repeat",
        "fold",
        "reference_mgdl",
        "predicted_mgdl",
    } <= set(preds.columns)
    comp = pd.read_csv(out / "comparisons.csv")
    assert {
        "model",
        "reference_model",
        "rmse_diff_mgdl",
        "ci_low",
        "ci_high",
        "p_value",
        "p_holm",
        "significant",
    } <= set(comp.columns)
    assert set(json.loads((out / "histories.json").read_text())) == set(MODELS)
    assert ng.load_dataset(out / "dataset.parquet").content_hash() == res.meta["dataset_hash"]
    table = (out / "table.md").read_text()
    assert "| Model | RMSE mg/dL | study |" in table and "Significant rankings" in table
    assert "rmse_vs_oracle is NaN" in table


def test_no_subject_is_tested_in_a_fold_it_was_trained_on(result, data):
    _, res = result
    p = res.predictions
    # each subject is tested in exactly one fold per repeat and model
    assert (p.groupby(["model", "repeat", "subject_id"])["fold"].nunique() == 1).all()
    assert (p.groupby(["model", "repeat"]).size() == len(data)).all()


def test_same_seed_same_metrics_for_any_jobs(result, data):
    _, res = result
    again = run_benchmark(data, MODELS, protocol=FOUR_BY_TWO, jobs=2, **FAST)
    pd.testing.assert_frame_equal(_stable(res.metrics), _stable(again.metrics))
    pd.testing.assert_frame_equal(res.predictions, again.predictions)
    pd.testing.assert_frame_equal(res.comparisons, again.comparisons)
    other = run_benchmark(data, MODELS, protocol=Protocol(n_splits=4, repeats=1, seed=1,
                                                          resamples=200), **FAST)
    assert not np.allclose(other.metrics["rmse_mgdl"], res.metrics["rmse_mgdl"])


def test_rerun_reuses_tasks_and_recomputes_deleted_or_corrupt_ones(result, data):
    out, res = result
    tasks = sorted((out / ".tasks").glob("*.json"))
    assert len(tasks) == 16
    tasks[0].unlink()
    tasks[1].unlink()
    tasks[2].write_text(tasks[2].read_text()[:100])  # truncated
    doc = json.loads(tasks[3].read_text())
    doc["result"]["predicted_mgdl"][0] += 1.0  # tampered: checksum no longer matches
    tasks[3].write_text(json.dumps(doc))
    seen = []
    with pytest.warns(UserWarning, match="corrupt"):
        again = run_benchmark(
            data,
            MODELS,
            protocol=FOUR_BY_TWO,
            out=out,
            on_task=lambda spec, cached: seen.append(cached),
            **FAST,
        )
    assert again.meta["tasks_computed"] == 4 and again.meta["tasks_cached"] == 12
    assert again.meta["tasks_corrupt"] == 2 and seen.count(False) == 4
    pd.testing.assert_frame_equal(res.predictions, again.predictions)
    pd.testing.assert_frame_equal(_stable(res.metrics), _stable(again.metrics))


def test_interrupted_run_resumes_without_recomputing_finished_tasks(data, tmp_path):
    out = tmp_path / "run"
    # a previous, finished run in the same directory (another seed, say)
    run_benchmark(data, ["test-ridge"],
                  protocol=Protocol(n_splits=3, repeats=1, seed=7, resamples=200), out=out,
                  **FAST)
    (out / "report.html").write_text("<html>the previous run</html>")
    RidgeModel.fits, RidgeModel.fail_on_fit = 0, 4
    try:
        with pytest.raises(RuntimeError, match="simulated crash"):
            run_benchmark(data, ["test-ridge"], protocol=THREE_BY_TWO, out=out, **FAST)
    finally:
        RidgeModel.fail_on_fit = None
    # nothing left that looks like this run's results: only the task files (and the
    # data, which may be what this run reads)
    assert sorted(p.name for p in out.iterdir()) == [".tasks", "dataset.parquet"]
    assert len(list((out / ".tasks").glob("*.json"))) == 3 + 3
    RidgeModel.fits = 0
    res = run_benchmark(data, ["test-ridge"], protocol=THREE_BY_TWO, out=out, **FAST)
    assert RidgeModel.fits == 3
    assert res.meta["tasks_cached"] == 3 and res.meta["tasks_computed"] == 3


def test_paper_split_gives_the_validation_part_to_models_that_take_it(tmp_path):
    ds = ng.simulate("paper", n_subjects=80, per_subject=3, seed=0)
    res = run_benchmark(ds, MODELS, protocol=Protocol("paper-split", resamples=200), **FAST)
    assert res.meta["n_splits"] == 1 and res.meta["repeats"] == 1
    assert (res.predictions.groupby("model").size() == 48).all()
    assert res.histories["test-biased"][0]["val_rows"] == 48
    assert res.predictions["subject_id"].nunique() == 16


def test_without_truth_columns_the_oracle_ratio_is_nan_and_said(data):
    frame = data.frame[[c for c in data.frame.columns if not c.startswith("true_")]]
    with pytest.warns(UserWarning, match="no true_"):
        res = run_benchmark(
            ng.Dataset(frame, config=data.config),
            ["test-ridge"],
            n_splits=3,
            repeats=1,
            **{**FAST, "oracle_reference": True},
        )
    assert res.metrics["rmse_vs_oracle"].isna().all()
    assert "no true_*" in res.meta["oracle_note"]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"models": ["nope"]}, "unknown model 'nope'; valid: .*test-ridge"),
        ({"repeats": 0}, "repeats must be a positive integer"),
        ({"protocol": "loo"}, "valid: grouped-cv, paper-split"),
        ({"model_params": {"other": {}}}, "model_params for models not benchmarked"),
    ],
)
def test_bad_arguments_raise_config_error(data, kwargs, match):
    kwargs = {"models": ["test-ridge"], **kwargs}
    with pytest.raises(ConfigError, match=match):
        run_benchmark(data, **kwargs)


def test_declared_adc_bits_reach_the_models_in_every_fold():
    from device_data import simulate_device

    ds = simulate_device(3, 14, n_subjects=6, per_subject=4)
    user = ng.Dataset(ds.frame, metadata={"adc_bits": 14})  # a file with no scenario
    res = run_benchmark(user, ["pls"], protocol=Protocol(n_splits=3, repeats=1, resamples=200),
                        **FAST)
    assert len(res.predictions) == len(user)
    part = user.rows(np.array([2, 5]))
    assert part.metadata["adc_bits"] == 14 and part.frame.index.tolist() == [0, 1]
