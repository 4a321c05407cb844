"""Intervals and calibration of a fitted model: what prediction may add to a model's
output, below :func:`nirglucose.predict` and the evaluation.

* :mod:`~nirglucose.calibration.conformal`: subject-grouped conformal prediction
  intervals (split conformal for a model file; out-of-fold for the benchmark);
* :mod:`~nirglucose.calibration.personal`: personal calibration, a person's first
  readings with a fingerstick calibrate the rest (offset, carry-forward,
  difference-ridge);
* :mod:`~nirglucose.calibration.schedules`: the calibration schedules of a device worn
  for days (factory, day-1, every 24 h or 12 h).

The package imports the models, the features, the dataset and the metrics' resampling,
never the evaluation: using a fitted model does not load the study engine. The names
below are imported on first access.
"""

from __future__ import annotations

import importlib

__all__ = [
    "LEVELS",
    "attach",
    "calibration_of",
    "interval",
    "split_conformal",
    "apply_offset",
    "calibration_mask",
    "personal_calibration",
    "SCHEDULES",
    "apply_schedule",
    "calibration_times",
]

_LAZY = {
    **dict.fromkeys(("LEVELS", "attach", "calibration_of", "interval", "split_conformal"),
                    "nirglucose.calibration.conformal"),
    **dict.fromkeys(("apply_offset", "calibration_mask", "personal_calibration"),
                    "nirglucose.calibration.personal"),
    **dict.fromkeys(("SCHEDULES", "apply_schedule", "calibration_times"),
                    "nirglucose.calibration.schedules"),
}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
