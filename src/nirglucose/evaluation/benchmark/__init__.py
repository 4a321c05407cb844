"""The benchmark: every model on the same subject-grouped splits, scored honestly.

One verb, one package:

* :mod:`~nirglucose.evaluation.benchmark.run`: :func:`run_benchmark` plans the tasks,
  runs them on the engine (:mod:`nirglucose.evaluation.engine`) and builds the result;
* :mod:`~nirglucose.evaluation.benchmark.aggregate`: the metrics, comparisons and
  ablation tables from the finished tasks;
* :mod:`~nirglucose.evaluation.benchmark.result`: :class:`BenchmarkResult`, its columns
  and files;
* :mod:`~nirglucose.evaluation.benchmark.drop_one`,
  :mod:`~nirglucose.evaluation.benchmark.inverse`,
  :mod:`~nirglucose.evaluation.benchmark.timing`: the drop-one-LED refits, the inverse
  task (tissue state) and the latency of every model;
* :mod:`~nirglucose.evaluation.benchmark.finding`,
  :mod:`~nirglucose.evaluation.benchmark.findings`,
  :mod:`~nirglucose.evaluation.benchmark.subgroups`: what a finished run says (the
  report reads them).

The names below are imported on first access (``from nirglucose.evaluation.benchmark
import run_benchmark``), so that the report, which reads results, does not load the
models.
"""

from __future__ import annotations

import importlib

__all__ = [
    "BenchmarkResult",
    "run_benchmark",
    "METRIC_COLUMNS",
    "PREDICTION_COLUMNS",
    "COMPARISON_COLUMNS",
    "DROP_ONE_COLUMNS",
    "OUTPUT_FILES",
    "TASK_FORMAT",
    "ORACLE",
    "REFERENCE_MODELS",
    "PINN_MODELS",
    "NO_PHYSICS",
    "ABLATION_COLUMNS",
]

_LAZY = {
    "BenchmarkResult": "nirglucose.evaluation.benchmark.result",
    "run_benchmark": "nirglucose.evaluation.benchmark.run",
    "METRIC_COLUMNS": "nirglucose.evaluation.benchmark.result",
    "PREDICTION_COLUMNS": "nirglucose.evaluation.benchmark.result",
    "COMPARISON_COLUMNS": "nirglucose.evaluation.benchmark.result",
    "DROP_ONE_COLUMNS": "nirglucose.evaluation.benchmark.result",
    "OUTPUT_FILES": "nirglucose.evaluation.benchmark.result",
    "TASK_FORMAT": "nirglucose.evaluation.engine.tasks",
    "ORACLE": "nirglucose.evaluation.benchmark.result",
    "REFERENCE_MODELS": "nirglucose.evaluation.benchmark.result",
    "PINN_MODELS": "nirglucose.evaluation.benchmark.result",
    "NO_PHYSICS": "nirglucose.evaluation.benchmark.result",
    "ABLATION_COLUMNS": "nirglucose.evaluation.benchmark.result",
}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
