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

Cost that does not depend on the machine
    :func:`count_macs` counts the multiply-accumulates one prediction takes, from the
    fitted model (what is counted is returned beside the count); :func:`machine_info`
    records where the timings were taken (CPU model, cores, library versions).
"""

from __future__ import annotations

import os
import platform
import time
import warnings
from typing import Any

import numpy as np
import pandas as pd

from ...dataset import Dataset
from ...models._base import MEASURED_COLUMNS, predict_input

__all__ = ["count_macs", "machine_info", "measure_latency", "timing_inputs", "tile_rows"]


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
        ``n_single`` [-], ``throughput_per_s`` [samples/s], ``batch_rows`` [-];
        ``macs_per_prediction`` [-] and ``macs_counted`` from :func:`count_macs`;
        ``machine`` from :func:`machine_info`.
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
    macs, counted = count_macs(model, singles[0])
    return {
        "latency_single_ms": float(np.median(t_ms)),
        "latency_single_p90_ms": float(np.quantile(t_ms, 0.9)),
        "n_single": float(len(t_ms)),
        "throughput_per_s": float(batch_rows / max(best / 1e9, 1e-12)),
        "batch_rows": float(batch_rows),
        "macs_per_prediction": macs,
        "macs_counted": counted,
        "machine": machine_info(),
    }


def machine_info() -> dict[str, Any]:
    """Where timings are taken: CPU model, logical cores (and those usable), versions."""
    import numpy  # noqa: F401 - version below

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            names = [ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")]
        cpu = names[0] if names else cpu
    except OSError:
        pass
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    try:
        import torch

        torch_version: str | None = str(torch.__version__)
    except ImportError:  # pragma: no cover - torch is a dependency
        torch_version = None
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "cores_usable": usable,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "torch": torch_version,
        "platform": platform.platform(),
    }


def count_macs(model: Any, row: Any = None) -> tuple[float, str]:
    """Multiply-accumulates one prediction of the fitted ``model`` takes, and what counts.

    Counted from the fitted state, so the number is the same on every machine:

    * linear models (EBL, PLS): one per folded coefficient;
    * torch networks: ``in x out`` of every ``Linear`` layer run on one row (physics
      branches included when they are ``Linear`` layers), attention as its four
      projections plus query-key and weight-value products; activations, norms and
      the element-wise physics are not counted;
    * Gaussian process: ``rows x (inputs + 1)`` (the scaled distance to every kept
      training row, then the weighted sum);
    * gradient boosting: ``trees x depth`` threshold comparisons (not MACs: said so);
    * hybrids: the backbone's count plus the residual GP's;
    * the training mean: 0; iterative solvers (oracle, physics inversion): NaN, their
      cost depends on the iterations each reading takes; any other model: NaN.

    Parameters
    ----------
    model : fitted estimator
    row : array, DataFrame or Dataset, optional
        One row in the form ``model.predict`` takes; needed for torch networks.

    Returns
    -------
    (float, str)
        The count [-] (NaN when not counted) and a short statement of what was counted.
    """
    backbone, residual = getattr(model, "backbone_", None), getattr(model, "residual_", None)
    if backbone is not None and residual is not None:
        (a, what_a), (b, what_b) = count_macs(backbone, row), count_macs(residual, row)
        return a + b, f"{what_a} + residual {what_b}"
    if getattr(model, "module_", None) is not None:
        return _torch_macs(model, row), "Linear in×out (+attention) on one row"
    if "X_train_" in model.__dict__ and "alpha_" in model.__dict__:
        n, p = np.shape(model.X_train_)
        return float(n * (p + 1)), f"GP: {n} rows × ({p} inputs + 1)"
    if "value_" in model.__dict__ and "depth_" in model.__dict__:
        trees = int(np.shape(model.value_)[0])
        return float(trees * int(model.depth_)), f"comparisons: {trees} trees × depth"
    if "coef_" in model.__dict__:
        return float(np.size(model.coef_)), "one per coefficient"
    if "mean_" in model.__dict__:
        return 0.0, "none (a constant)"
    if "max_iter" in model.__dict__:
        return float("nan"), "not counted (iterative solver: cost varies per reading)"
    return float("nan"), "not counted (no rule for this model)"


def _torch_macs(model: Any, row: Any) -> float:
    """MACs of ``model.module_`` on one row, counted by forward hooks."""
    import torch
    from torch import nn


    nir, pmf = model._inputs32(predict_input(model, row)[:1])
    total = [0]

    def linear(mod: nn.Linear, inp: tuple, _out: Any) -> None:
        total[0] += int(inp[0].numel()) * int(mod.out_features)

    def attention(mod: nn.MultiheadAttention, inp: tuple, _out: Any) -> None:
        tokens, d = int(inp[0].numel()) // int(mod.embed_dim), int(mod.embed_dim)
        total[0] += 4 * tokens * d * d + 2 * tokens * tokens * d

    hooks = [
        m.register_forward_hook(attention if isinstance(m, nn.MultiheadAttention) else linear)
        for m in model.module_.modules()
        if isinstance(m, (nn.Linear, nn.MultiheadAttention))
        and not (isinstance(m, nn.Linear) and "out_proj" in _names(model.module_, m))
    ]
    try:
        model.module_.eval()
        with torch.inference_mode():
            model.module_(torch.from_numpy(nir), torch.from_numpy(pmf))
    finally:
        for h in hooks:
            h.remove()
    return float(total[0])


def _names(root: Any, module: Any) -> str:
    return next((name for name, m in root.named_modules() if m is module), "")
