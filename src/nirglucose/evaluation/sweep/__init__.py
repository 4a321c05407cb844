"""Sweeps: scenarios x seeds x models, the built-in studies, and what they show.

One verb, one package:

* :mod:`~nirglucose.evaluation.sweep.run`: :func:`run_sweep` plans the tasks, runs them
  on the engine (:mod:`nirglucose.evaluation.engine`) and gathers one row per task;
* :mod:`~nirglucose.evaluation.sweep.scenarios`, :mod:`~nirglucose.evaluation.sweep.studies`:
  the scenarios and the built-in studies;
* :mod:`~nirglucose.evaluation.sweep.analysis`: summaries, effects and crossings;
* :mod:`~nirglucose.evaluation.sweep.wavelengths`, :mod:`~nirglucose.evaluation.sweep.fleet`,
  :mod:`~nirglucose.evaluation.sweep.transfer`: the LED-design, fleet-tolerance and
  calibration-transfer studies.

The names below (:mod:`~nirglucose.evaluation.sweep.run`'s) are imported on first access
(``from nirglucose.evaluation.sweep import run_sweep``), so that the command line and
the report load the sweep only when they run or read one.
"""

from __future__ import annotations

import importlib

__all__ = [
    "STUDIES",
    "STUDY_GRIDS",
    "COHORT_SHIFTS",
    "DEFAULT_MODELS",
    "SWEEP_METRICS",
    "CALIBRATION_METRICS",
    "SUMMARY_METRICS",
    "SWEEP_FILES",
    "TASK_FORMAT",
    "source_digest",
    "Scenario",
    "SweepResult",
    "parse_vary",
    "grid_scenarios",
    "study_scenarios",
    "plan_sweep",
    "run_sweep_task",
    "run_sweep",
    "load_sweep",
    "summarize_sweep",
    "ablation_effects",
    "shift_effects",
    "threshold_crossing",
    "ranking_crossings",
    "DATA_SIZE_SUBJECTS",
    "DATA_SIZE_TEST_SUBJECTS",
    "DATA_SIZE_PRESETS",
]

_LAZY = {
    "STUDIES": "nirglucose.evaluation.sweep.run",
    "STUDY_GRIDS": "nirglucose.evaluation.sweep.run",
    "COHORT_SHIFTS": "nirglucose.evaluation.sweep.run",
    "DEFAULT_MODELS": "nirglucose.evaluation.sweep.run",
    "SWEEP_METRICS": "nirglucose.evaluation.sweep.run",
    "CALIBRATION_METRICS": "nirglucose.evaluation.sweep.run",
    "SUMMARY_METRICS": "nirglucose.evaluation.sweep.run",
    "SWEEP_FILES": "nirglucose.evaluation.sweep.run",
    "TASK_FORMAT": "nirglucose.evaluation.sweep.run",
    "source_digest": "nirglucose.evaluation.sweep.run",
    "Scenario": "nirglucose.evaluation.sweep.run",
    "SweepResult": "nirglucose.evaluation.sweep.run",
    "parse_vary": "nirglucose.evaluation.sweep.run",
    "grid_scenarios": "nirglucose.evaluation.sweep.run",
    "study_scenarios": "nirglucose.evaluation.sweep.run",
    "plan_sweep": "nirglucose.evaluation.sweep.run",
    "run_sweep_task": "nirglucose.evaluation.sweep.run",
    "run_sweep": "nirglucose.evaluation.sweep.run",
    "load_sweep": "nirglucose.evaluation.sweep.run",
    "summarize_sweep": "nirglucose.evaluation.sweep.run",
    "ablation_effects": "nirglucose.evaluation.sweep.run",
    "shift_effects": "nirglucose.evaluation.sweep.run",
    "threshold_crossing": "nirglucose.evaluation.sweep.run",
    "ranking_crossings": "nirglucose.evaluation.sweep.run",
    "DATA_SIZE_SUBJECTS": "nirglucose.evaluation.sweep.run",
    "DATA_SIZE_TEST_SUBJECTS": "nirglucose.evaluation.sweep.run",
    "DATA_SIZE_PRESETS": "nirglucose.evaluation.sweep.run",
}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
