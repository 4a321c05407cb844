"""Inference latency, measured the same way for every estimator.

Single sample
    After ``warmup`` calls, ``predict`` is called on one row, one call at a time, up to
    ``n_single`` times or until ``time_budget_s`` is spent (at least ``min_single``
    calls); the median wall time per call is reported (and the 90th percentile).
Batch
    ``predict`` on a batch of ``batch_rows`` rows (the held-out rows tiled) after one
    warm-up call, the best of up to ``batch_repeats`` calls (bounded by the same time
    budget), reported as samples per second.

Input form
    Every estimator is timed on the cheapest input its public ``predict`` accepts: a
    float array of the device's measured columns in the order the model was fitted on;
    an estimator that cannot predict from it (the oracle, which reads ``true_*``
    columns) is timed on a one-row :class:`~nirglucose.dataset.Dataset`. The form used is
    reported as ``latency_input``.
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np
import pandas as pd

from ..dataset import Dataset

__all__ = ["measure_latency", "timing_inputs", "tile_rows"]


def tile_rows(data: Any, n_rows: int) -> Any:
    """``data`` (array, DataFrame or Dataset) repeated row-wise to exactly ``n_rows`` rows."""
    n = len(data)
    idx = np.resize(np.arange(n), int(n_rows))
    if isinstance(data, Dataset):
        return Dataset(
            data.frame.iloc[idx].reset_index(drop=True), config=data.config, seed=data.seed
        )
    if isinstance(data, pd.DataFrame):
        return data.iloc[idx].reset_index(drop=True)
    return np.asarray(data)[idx]


def _row(data: Any, k: int) -> Any:
    if isinstance(data, Dataset):
        return Dataset(
            data.frame.iloc[k : k + 1].reset_index(drop=True), config=data.config, seed=data.seed
        )
    if isinstance(data, pd.DataFrame):
        return data.iloc[k : k + 1].reset_index(drop=True)
    return np.asarray(data)[k : k + 1]


def timing_inputs(model: Any, rows: Dataset) -> tuple[str, Any]:
    """The input form to time ``model`` on: ``("array", X)`` or ``("dataset", rows)``.

    ``X`` is the columns the fitted ``model`` was fitted on (its ``feature_names_in_``:
    the device's raw columns; the study's 20 when it records none) of ``rows`` as a float
    array; it is used when the model predicts from it.
    """
    from ..models._base import MEASURED_COLUMNS

    names = getattr(model, "feature_names_in_", None)
    cols = [str(c) for c in names] if names is not None else list(MEASURED_COLUMNS)
    if set(cols) <= set(rows.frame.columns):
        X = rows.frame[cols].to_numpy(dtype=float)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out = np.asarray(model.predict(X[:1]), dtype=float)
            if out.shape == (1,):
                return "array", X
        except Exception:  # noqa: BLE001 - any failure means: time on the Dataset instead
            pass
    return "dataset", rows


def measure_latency(
    model: Any,
    data: Any,
    *,
    n_single: int = 200,
    min_single: int = 20,
    time_budget_s: float = 2.0,
    warmup: int = 5,
    batch_rows: int = 10_000,
    batch_repeats: int = 3,
) -> dict[str, float]:
    """Median single-sample latency and batch throughput of ``model.predict``.

    Parameters
    ----------
    model : fitted estimator
    data : numpy.ndarray, pandas.DataFrame or Dataset
        Held-out rows in the form ``model.predict`` takes; single-sample calls cycle
        through them, the batch tiles them.
    n_single : int
        Single-sample calls at most. [-]
    min_single : int
        Single-sample calls at least, whatever the budget. [-]
    time_budget_s : float
        Budget of the single-sample loop (checked after each call). [s]
    warmup : int
        Untimed calls first (caches, lazy initialisation, torch kernels). [-]
    batch_rows : int
        Rows of the batch. [-]
    batch_repeats : int
        Timed batch calls at most (at least one, no more once ``time_budget_s`` is
        spent); the fastest counts. [-]

    Returns
    -------
    dict
        ``latency_single_ms`` (median) [ms], ``latency_single_p90_ms`` [ms],
        ``n_single`` [-], ``throughput_per_s`` [samples/s], ``batch_rows`` [-].
    """
    n = len(data)
    singles = [_row(data, k) for k in range(min(n, 16))]
    for k in range(warmup):
        model.predict(singles[k % len(singles)])
    times = []
    start = time.perf_counter()
    for k in range(max(int(n_single), 1)):
        t0 = time.perf_counter_ns()
        model.predict(singles[k % len(singles)])
        times.append(time.perf_counter_ns() - t0)
        if k + 1 >= min_single and time.perf_counter() - start > time_budget_s:
            break
    batch = tile_rows(data, batch_rows)
    model.predict(batch)  # warm-up at batch size
    best = np.inf
    start = time.perf_counter()
    for _ in range(max(int(batch_repeats), 1)):
        t0 = time.perf_counter_ns()
        model.predict(batch)
        best = min(best, time.perf_counter_ns() - t0)
        if time.perf_counter() - start > time_budget_s:
            break
    t_ms = np.asarray(times, dtype=float) / 1e6
    return {
        "latency_single_ms": float(np.median(t_ms)),
        "latency_single_p90_ms": float(np.quantile(t_ms, 0.9)),
        "n_single": float(len(t_ms)),
        "throughput_per_s": float(batch_rows / max(best / 1e9, 1e-12)),
        "batch_rows": float(batch_rows),
    }
