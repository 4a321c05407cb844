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
never the evaluation: using a fitted model does not load the study engine.
"""

from __future__ import annotations

from .conformal import LEVELS, attach, calibration_of, interval, split_conformal
from .personal import apply_offset, calibration_mask, personal_calibration
from .schedules import SCHEDULES, apply_schedule, calibration_times

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
