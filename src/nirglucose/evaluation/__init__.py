"""Evaluation: how the estimators are judged, one room per verb.

* the shared pieces: :mod:`~nirglucose.evaluation.protocol` (the :class:`Protocol`),
  :mod:`~nirglucose.evaluation.splits` (subject-grouped splits),
  :mod:`~nirglucose.evaluation.estimators` (names, objects and their seeding) and
  :mod:`~nirglucose.evaluation.reference` (the study's own table);
* :mod:`nirglucose.evaluation.engine`: tasks, their cache, executors and progress;
* :mod:`nirglucose.evaluation.benchmark`: :func:`run_benchmark` and its result;
* :mod:`nirglucose.evaluation.sweep`: scenarios x seeds x models and the studies;
* :mod:`~nirglucose.evaluation.wear`: the benchmark and sweep of a device worn for days.

Statistics live in :mod:`nirglucose.metrics.resampling`, intervals and calibration in
:mod:`nirglucose.calibration`. The benchmark computes and returns tidy DataFrames;
plotting and reporting read them. The names below are imported on first attribute
access so that ``import nirglucose`` stays light.
"""

from __future__ import annotations

import importlib

__all__ = [
    "PROTOCOLS",
    "Protocol",
    "STUDY_TABLE",
    "BenchmarkResult",
    "run_benchmark",
    "make_splits",
    "cluster_bootstrap_metrics",
    "compare_models",
    "measure_latency",
    "drop_one_table",
    "without_led",
]

_LAZY = {
    "PROTOCOLS": "nirglucose.evaluation.splits",
    "Protocol": "nirglucose.evaluation.protocol",
    "make_splits": "nirglucose.evaluation.splits",
    "STUDY_TABLE": "nirglucose.evaluation.reference",
    "BenchmarkResult": "nirglucose.evaluation.benchmark",
    "run_benchmark": "nirglucose.evaluation.benchmark",
    "cluster_bootstrap_metrics": "nirglucose.metrics.resampling",
    "compare_models": "nirglucose.metrics.resampling",
    "measure_latency": "nirglucose.evaluation.benchmark.timing",
    "drop_one_table": "nirglucose.evaluation.benchmark.drop_one",
    "without_led": "nirglucose.evaluation.benchmark.drop_one",
}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'nirglucose.evaluation' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
