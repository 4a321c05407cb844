"""Latency is measured the same way for every model: warm-up, median, batch throughput."""

from __future__ import annotations

import time

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.timing import measure_latency, tile_rows, timing_inputs
from nirglucose.models._base import MEASURED_COLUMNS


class _Counting:
    """Predicts a constant; counts calls and rows; optionally sleeps per call."""

    def __init__(self, sleep_s: float = 0.0, arrays: bool = True):
        self.sleep_s, self.arrays, self.calls, self.rows = sleep_s, arrays, [], 0

    def predict(self, X):
        if not self.arrays and not isinstance(X, ng.Dataset):
            raise TypeError("needs a Dataset")
        if self.sleep_s:
            time.sleep(self.sleep_s)
        self.calls.append(len(X))
        return np.full(len(X), 100.0)


@pytest.fixture(scope="module")
def small():
    return ng.simulate("wearable", n_subjects=6, per_subject=2, seed=0)


def test_latency_keys_and_counts(small):
    model = _Counting()
    X = small.frame[list(MEASURED_COLUMNS)].to_numpy(float)
    out = measure_latency(model, X, n_single=50, warmup=3, batch_rows=1000, batch_repeats=2)
    assert set(out) == {
        "latency_single_ms",
        "latency_single_p90_ms",
        "n_single",
        "throughput_per_s",
        "batch_rows",
        "macs_per_prediction",
        "macs_counted",
        "machine",
    }
    assert np.isnan(out["macs_per_prediction"]) and "no rule" in out["macs_counted"]
    assert {"cpu", "cores", "numpy", "torch"} <= set(out["machine"])
    assert out["machine"]["numpy"] == np.__version__
    assert out["n_single"] == 50 and out["batch_rows"] == 1000
    assert 0 < out["latency_single_ms"] <= out["latency_single_p90_ms"]
    assert out["throughput_per_s"] > 0
    # warm-up + singles of one row, then batches of 1000 rows (one warm-up + 2 timed)
    assert model.calls.count(1) == 53 and model.calls.count(1000) == 3


def test_time_budget_bounds_the_single_sample_loop(small):
    model = _Counting(sleep_s=0.004)
    out = measure_latency(
        model,
        small,
        n_single=200,
        min_single=5,
        time_budget_s=0.03,
        warmup=1,
        batch_rows=20,
        batch_repeats=1,
    )
    assert 5 <= out["n_single"] < 20
    assert out["latency_single_ms"] >= 4.0


def test_timing_inputs_prefers_arrays_and_falls_back_to_the_dataset(small):
    form, X = timing_inputs(_Counting(), small)
    assert form == "array" and X.shape == (len(small), len(MEASURED_COLUMNS))
    form, data = timing_inputs(_Counting(arrays=False), small)
    assert form == "dataset" and data is small


def test_tile_rows_keeps_the_type(small):
    assert len(tile_rows(small, 25)) == 25 and isinstance(tile_rows(small, 25), ng.Dataset)
    assert tile_rows(np.arange(3), 7).tolist() == [0, 1, 2, 0, 1, 2, 0]


@pytest.mark.parametrize("name", ["ebl", "pls", "gp", "gbr", "mean", "oracle", "sdnn"])
def test_macs_are_counted_from_the_fitted_model(small, name):
    from nirglucose.evaluation.benchmark.timing import count_macs
    from nirglucose.models import make_model

    kw = {"max_epochs": 1} if name == "sdnn" else {}
    model = make_model(name, **kw).fit(small)
    macs, what = count_macs(model, small.rows(np.arange(1)))
    if name in ("ebl", "pls"):  # one multiply-accumulate per coefficient
        assert macs == np.size(model.coef_) == model.n_parameters - 1
    elif name == "gp":  # distance to every kept row over every input, then the weights
        n, p = model.X_train_.shape
        assert macs == n * (p + 1) and f"{n} rows" in what
    elif name == "gbr":
        assert macs == model.value_.shape[0] * model.depth_ and "comparisons" in what
    elif name == "mean":
        assert macs == 0
    elif name == "oracle":
        assert np.isnan(macs) and "iterative" in what
    else:  # a network: every Linear layer's in x out on one row, no more
        import torch

        linear = [m for m in model.module_.modules() if isinstance(m, torch.nn.Linear)]
        assert macs == sum(m.in_features * m.out_features for m in linear)
        assert macs < model.n_parameters  # biases are parameters, not MACs


def test_benchmark_records_macs_and_the_timing_machine(small, tmp_path):
    import json

    from nirglucose.evaluation import run_benchmark

    res = run_benchmark(small, ["ebl", "mean"],
                        protocol=Protocol(n_splits=3, repeats=1, resamples=20, seed=0),
                        out=tmp_path / "r", drop_one_models="none",
                        timing={"n_single": 5, "min_single": 2, "batch_rows": 50,
                                "batch_repeats": 1})
    m = res.metrics.set_index("model")
    assert m.at["mean", "macs_per_prediction"] == 0
    ebl_macs = m.at["ebl", "macs_per_prediction"]
    assert ebl_macs == m.at["ebl", "n_parameters"] - 1  # coefficients, not the intercept
    assert m.at["ebl", "macs_counted"] == "one per coefficient"
    meta = json.loads((tmp_path / "r" / "meta.json").read_text())
    assert meta["timing_machine"]["numpy"] == np.__version__
    table = (tmp_path / "r" / "table.md").read_text()
    assert "MACs / prediction" in table and f"| {ebl_macs:,.0f} |" in table
