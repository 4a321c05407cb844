"""Calibration schedules of a worn device: how often must a user calibrate?

A device worn for days (:mod:`nirglucose.simulation.wear`) drifts: the LED ages, the
skin's temperature follows the day, each re-seating changes the contact. A schedule
says when the user takes a fingerstick; each fingerstick's reference glucose sets a
one-point offset (the reference minus the model's prediction at that reading), applied
to every later reading until the next calibration — the offset calibration of
:mod:`~nirglucose.calibration.personal`, now in time.

Schedules (:data:`SCHEDULES`):

``factory``
    No fingerstick: the model's prediction as it is.
``day1-1``
    One fingerstick, the subject's first reading.
``day1-2``
    Two on day 1: the first reading and the first one 12 h later; after the second,
    the offset is the mean of both.
``every-24h`` / ``every-12h``
    A fingerstick at the first reading and at the first reading at or after every
    further 24 (12) hours of wear.

Every schedule is scored on the same readings, paired: those after the subject's first
reading that no schedule uses as a calibration (so no reading is scored against the
fingerstick that calibrated it). The error is also given by whole days since the last
calibration (``factory``: since the start of wear). Confidence intervals are
percentile intervals of a cluster bootstrap over subjects (Davison & Hinkley 1997,
*Bootstrap Methods and their Application*, §3.8), the same draws for every schedule.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from ..constants import MINUTES_PER_DAY
from ..exceptions import ConfigError, DataError
from ..metrics.resampling import subject_draws

__all__ = ["SCHEDULES", "calibration_times", "apply_schedule", "schedule_table"]

#: Schedules by name: hours between fingersticks (None: only those listed) and the
#: offsets into wear [h] of the listed ones.
SCHEDULES: dict[str, tuple[float | None, tuple[float, ...]]] = {
    "factory": (None, ()),
    "day1-1": (None, (0.0,)),
    "day1-2": (None, (0.0, 12.0)),
    "every-24h": (24.0, ()),
    "every-12h": (12.0, ()),
}
_MIN_PER_H = 60.0


def _check_schedules(schedules: Sequence[str]) -> list[str]:
    unknown = [s for s in schedules if s not in SCHEDULES]
    if unknown:
        raise ConfigError(f"unknown calibration schedule(s) {unknown}; known: {list(SCHEDULES)}")
    return list(schedules)


def calibration_times(schedule: str, time_min: np.ndarray) -> np.ndarray:
    """Indices (into one subject's time-sorted ``time_min``) of the schedule's fingersticks.

    Each is the first reading at or after its planned time (the planned times are
    counted from the subject's first reading); a planned time after the last reading is
    dropped.
    """
    every_h, listed_h = SCHEDULES[_check_schedules([schedule])[0]]
    t = np.asarray(time_min, dtype=float)
    if t.size == 0:
        return np.empty(0, dtype=np.int64)
    span = t[-1] - t[0]
    planned = [h * _MIN_PER_H for h in listed_h]
    if every_h is not None:
        planned = list(np.arange(0.0, span + 1e-9, every_h * _MIN_PER_H))
    idx = np.searchsorted(t - t[0], np.asarray(planned, dtype=float), side="left")
    return np.unique(idx[idx < t.size]).astype(np.int64)


def apply_schedule(frame: pd.DataFrame, schedule: str, *,
                   prediction: str = "predicted_glucose_mgdl",
                   reference: str = "glucose_mgdl", time: str = "time_min",
                   subject: str = "subject_id") -> pd.DataFrame:
    """Calibrated predictions of one schedule, in ``frame``'s row order.

    Returns
    -------
    DataFrame
        ``calibrated_mgdl`` (the prediction plus the offset in force; before the first
        calibration and for ``factory``, the prediction), ``is_calibration`` (the reading
        is one of the schedule's fingersticks), ``min_since_calibration`` (since the last
        fingerstick at or before the reading; ``factory``: since the first reading).
    """
    _check_columns(frame, (prediction, reference, time, subject))
    out = pd.DataFrame(index=frame.index, columns=["calibrated_mgdl", "is_calibration",
                                                   "min_since_calibration"])
    out["calibrated_mgdl"] = frame[prediction].to_numpy(float)
    out["is_calibration"] = False
    out["min_since_calibration"] = np.nan
    for _, g in frame.sort_values([subject, time], kind="stable").groupby(subject, sort=False):
        t = g[time].to_numpy(float)
        pred, ref = g[prediction].to_numpy(float), g[reference].to_numpy(float)
        cal = calibration_times(schedule, t)
        offset = np.zeros(t.size)
        since = t - t[0]
        if cal.size:
            errors = ref[cal] - pred[cal]
            last = np.searchsorted(cal, np.arange(t.size), side="right") - 1  # cal in force
            has = last >= 0
            use = errors if schedule != "day1-2" else np.cumsum(errors) / np.arange(1, cal.size + 1)
            offset[has] = use[last[has]]
            since = np.where(has, t - t[cal[np.maximum(last, 0)]], np.nan)
        out.loc[g.index, "calibrated_mgdl"] = pred + offset
        out.loc[g.index, "is_calibration"] = np.isin(np.arange(t.size), cal)
        out.loc[g.index, "min_since_calibration"] = since
    return out.astype({"calibrated_mgdl": float, "is_calibration": bool,
                       "min_since_calibration": float})


def _check_columns(frame: pd.DataFrame, columns) -> None:
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise DataError(f"calibration schedules need the columns {missing}; got "
                        f"{list(frame.columns)}")


def schedule_table(frame: pd.DataFrame, schedules: Sequence[str] = tuple(SCHEDULES), *,
                   prediction: str = "predicted_glucose_mgdl",
                   reference: str = "glucose_mgdl", time: str = "time_min",
                   subject: str = "subject_id", n_boot: int = 1000,
                   seed: int = 0,
                   applied: dict[str, pd.DataFrame] | None = None,
                   ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Every schedule scored on the same readings, overall and by days since calibration.

    Parameters
    ----------
    frame : DataFrame
        A worn run's held-out predictions: subject, time [min], reference and
        prediction [mg/dL].
    schedules : sequence of str
        Names of :data:`SCHEDULES`.
    n_boot, seed : int
        Cluster-bootstrap resamples over subjects and their seed.
    applied : dict, optional
        :func:`apply_schedule` of each schedule on ``frame``, where the caller has them
        already (computed here otherwise).

    Returns
    -------
    summary : DataFrame
        Per schedule: ``rmse_mgdl`` with ``rmse_ci_low``/``rmse_ci_high``, ``mard_pct``,
        ``fingersticks_per_day`` (mean over subjects), ``n_scored``, ``n_subjects``.
    by_day : DataFrame
        Per schedule and whole day since calibration (``days_since_calibration``):
        ``rmse_mgdl``, ``mard_pct``, ``n_scored``.
    """
    names = _check_schedules(schedules)
    if not names:
        raise ConfigError("no calibration schedule given; known: " + ", ".join(SCHEDULES))
    if int(n_boot) < 1:
        raise ConfigError(f"n_boot = {n_boot!r} is invalid; expected an integer >= 1")
    _check_columns(frame, (prediction, reference, time, subject))
    applied = {s: (applied or {}).get(s) for s in names}
    applied = {s: a if a is not None else
               apply_schedule(frame, s, prediction=prediction, reference=reference,
                              time=time, subject=subject) for s, a in applied.items()}
    first = frame.groupby(subject)[time].transform("min")
    used = np.zeros(len(frame), dtype=bool)
    for a in applied.values():
        used |= a["is_calibration"].to_numpy()
    scored = (frame[time] > first).to_numpy() & ~used
    if not scored.any():
        raise DataError("no reading is left to score after the calibrations; the run needs "
                        "more than one reading per subject")
    ref = frame[reference].to_numpy(float)[scored]
    subj = frame[subject].to_numpy()[scored]
    days = (frame[time] - first).to_numpy(float)[scored] / MINUTES_PER_DAY
    codes, sid = np.unique(subj, return_inverse=True)
    draws = subject_draws(codes.size, int(n_boot), [int(seed), 31])
    span_days = (frame.groupby(subject)[time].agg(lambda x: x.max() - x.min())
                 / MINUTES_PER_DAY).clip(lower=1.0)  # fingersticks per day of at least a day
    summary, by_day = [], []
    for s in names:
        a = applied[s]
        est = a["calibrated_mgdl"].to_numpy(float)[scored]
        sq = (est - ref) ** 2
        sums = np.bincount(sid, sq, minlength=codes.size)
        cnt = np.bincount(sid, minlength=codes.size).astype(float)
        boot = np.sqrt(sums[draws].sum(1) / cnt[draws].sum(1))
        n_cal = a["is_calibration"].groupby(frame[subject]).sum()
        summary.append({
            "schedule": s,
            "rmse_mgdl": float(np.sqrt(sq.mean())),
            "rmse_ci_low": float(np.quantile(boot, 0.025)),
            "rmse_ci_high": float(np.quantile(boot, 0.975)),
            "mard_pct": float(100 * np.mean(np.abs(est - ref) / ref)),
            "fingersticks_per_day": float((n_cal / span_days).mean()),
            "n_scored": int(scored.sum()),
            "n_subjects": int(codes.size),
        })
        since = a["min_since_calibration"].to_numpy(float)[scored]
        day_bin = np.floor(np.where(np.isnan(since), days, since / MINUTES_PER_DAY)).astype(int)
        for d in np.unique(day_bin):
            m = day_bin == d
            by_day.append({"schedule": s, "days_since_calibration": int(d),
                           "rmse_mgdl": float(np.sqrt(sq[m].mean())),
                           "mard_pct": float(100 * np.mean(np.abs(est[m] - ref[m]) / ref[m])),
                           "n_scored": int(m.sum())})
    return pd.DataFrame(summary), pd.DataFrame(by_day)
