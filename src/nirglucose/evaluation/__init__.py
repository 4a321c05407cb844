"""Evaluation: subject-grouped splits, the benchmark, statistics, timing, drop-one LEDs.

The benchmark computes and returns tidy DataFrames; plotting and reporting read them.
Submodules are imported on first attribute access so that ``import nirglucose`` stays
light.
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
    "measure_latency": "nirglucose.evaluation.timing",
    "drop_one_table": "nirglucose.evaluation.drop_one",
    "without_led": "nirglucose.evaluation.drop_one",
}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'nirglucose.evaluation' has no attribute {name!r}")
