"""The task engine shared by the benchmark, the sweeps and the worn-device study.

* :mod:`~nirglucose.evaluation.engine.tasks`: task keys, seeds and the resumable cache
  (``OUT/.tasks``);
* :mod:`~nirglucose.evaluation.engine.executors`: where the pending tasks run (this
  process, local worker processes or a Dask cluster);
* :mod:`~nirglucose.evaluation.engine.progress`: progress bars and per-task hooks.

It knows nothing of models or metrics: the verbs above it plan their tasks and hand the
engine functions to run.
"""

from __future__ import annotations

__all__: list[str] = []
